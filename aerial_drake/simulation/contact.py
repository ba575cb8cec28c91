"""The contact wrench on the end effector, from the simulated plant's contact results, and a
force sensor that measures it (docs/contact.md).

:class:`ContactWrench` reads the plant's ``contact_results`` (point pairs and hydroelastic
surfaces alike) and its body poses, and gives the total contact wrench on the end-effector
body, about the end-effector frame's origin, in World, with the contact point (the
force-weighted mean of the contacts' points) and the number of contacts. It is what Drake
computed, not an estimate: the log's ``contact_wrench``.

:class:`ForceSensor` is a wrist force sensor: at the controller's samples, the true contact
force through a first-order low-pass of the scenario's bandwidth, plus Gaussian noise drawn
per sample from a table made before the run (``default_rng(seed)``), held between samples.
The force task of ``paper_force`` (:mod:`aerial_drake.control.force`) reads it.
"""

from __future__ import annotations

import math

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.multibody.plant import ContactResults, MultibodyPlant
from pydrake.multibody.tree import RigidBody
from pydrake.systems.framework import Context, DiagramBuilder, LeafSystem, OutputPort

from aerial_drake.robots.models import AerialManipulator

#: The entries of ``contact_wrench`` (World): torque about the end-effector frame's origin
#: (N m), force on the end effector (N), the contact point (m; zeros without contact), and
#: the number of contacts.
CONTACT_WRENCH_LAYOUT = (("torque", 3), ("force", 3), ("point", 3), ("contacts", 1))
CONTACT_WRENCH_SIZE = sum(size for _, size in CONTACT_WRENCH_LAYOUT)


def contact_slices() -> dict[str, slice]:
    """Each entry of :data:`CONTACT_WRENCH_LAYOUT` as a slice of the 10-vector."""
    out, at = {}, 0
    for name, size in CONTACT_WRENCH_LAYOUT:
        out[name] = slice(at, at + size)
        at += size
    return out


def _sign_on(index, acted_on, other) -> float:
    """+1 if the body ``index`` is the one a contact force acts on, -1 if it is the other
    body (it gets the opposite force), 0 if neither."""
    if acted_on == index:
        return 1.0
    return -1.0 if other == index else 0.0


def _body_forces(plant: MultibodyPlant, results: ContactResults, body: RigidBody, inspector
                 ) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """(force on ``body``, its point of application, extra torque about that point), World,
    for every contact ``body`` takes part in."""
    index = body.index()
    out = []
    for i in range(results.num_point_pair_contacts()):
        info = results.point_pair_contact_info(i)
        # contact_force() acts on body B at the contact point; body A gets its opposite.
        sign = _sign_on(index, info.bodyB_index(), info.bodyA_index())
        if sign == 0.0:
            continue
        out.append((sign * info.contact_force(), info.contact_point(), np.zeros(3)))
    for i in range(results.num_hydroelastic_contacts()):
        info = results.hydroelastic_contact_info(i)
        surface = info.contact_surface()
        # F_Ac_W acts on the body of geometry M at the surface's centroid; N's gets minus it.
        body_M = plant.GetBodyFromFrameId(inspector.GetFrameId(surface.id_M()))
        body_N = plant.GetBodyFromFrameId(inspector.GetFrameId(surface.id_N()))
        F = info.F_Ac_W()
        sign = _sign_on(index, body_M.index(), body_N.index())
        if sign == 0.0:
            continue
        out.append((sign * F.translational(), surface.centroid(), sign * F.rotational()))
    return out


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b of two 3-vectors (numpy's cross costs ten times as much on these)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def contact_wrench(plant: MultibodyPlant, results: ContactResults, body: RigidBody,
                   p_WE: np.ndarray, inspector) -> np.ndarray:
    """The 10-vector of :data:`CONTACT_WRENCH_LAYOUT`: the contact wrench on ``body`` about
    the World point ``p_WE`` (the end-effector frame's origin)."""
    out = np.zeros(CONTACT_WRENCH_SIZE)
    forces = _body_forces(plant, results, body, inspector)
    if not forces:
        return out
    total, point = 0.0, np.zeros(3)
    for f, p, tau in forces:
        out[0:3] += _cross(p - p_WE, f) + tau
        out[3:6] += f
        weight = float(np.sqrt(f @ f))
        total += weight
        point += weight * p
    out[6:9] = point / total if total > 0 else np.mean([p for _, p, _ in forces], axis=0)
    out[9] = len(forces)
    return out


class ContactWrench(LeafSystem):
    """The contact wrench on the end effector (module docstring).

    Inputs ``contact_results`` (the plant's) and ``body_poses`` (the plant's); output
    ``contact_wrench`` (:data:`CONTACT_WRENCH_LAYOUT`).

    Args:
        plant: the simulated plant (finalized; registered with a SceneGraph).
        body: the end-effector body; ``p_BE``: the end-effector frame's origin in it (m).
    """

    def __init__(self, plant: MultibodyPlant, body: RigidBody, p_BE: np.ndarray,
                 inspector) -> None:
        super().__init__()
        self._plant, self._body, self._p_BE = plant, body, np.asarray(p_BE, float)
        self._inspector = inspector  # hydroelastic contacts name geometries, not bodies
        self._results = self.DeclareAbstractInputPort(
            "contact_results", AbstractValue.Make(ContactResults()))
        self._poses = self.DeclareAbstractInputPort(
            "body_poses", plant.get_body_poses_output_port().Allocate())
        self.DeclareVectorOutputPort("contact_wrench", CONTACT_WRENCH_SIZE, self._calc)

    def _calc(self, context: Context, output) -> None:
        results = self._results.Eval(context)
        if not (results.num_point_pair_contacts() or results.num_hydroelastic_contacts()):
            output.SetZero()  # nothing touches: the poses are not needed
            return
        X_WB = self._poses.Eval(context)[int(self._body.index())]
        output.SetFromVector(contact_wrench(self._plant, results, self._body,
                                            X_WB.multiply(self._p_BE), self._inspector))


class ForceSensor(LeafSystem):
    """A wrist force sensor (module docstring): input ``contact_wrench``, output
    ``measured_contact_force`` (3, N, World), discrete at ``period``.

    Args:
        period: the sample period (s), the controller's.
        bandwidth: the low-pass cut-off (Hz); ``math.inf``: none.
        noise_std: the noise's standard deviation per axis and sample (N).
        seed: of the noise table; ``duration``: the run's length (s), the table's.
    """

    def __init__(self, period: float, bandwidth: float, noise_std: float, seed: int,
                 duration: float) -> None:
        super().__init__()
        self._period = float(period)
        # The discrete first-order low-pass y+ = y + a (f - y), a = 1 - exp(-2 pi fc T).
        self._a = 1.0 if math.isinf(bandwidth) else -math.expm1(-2 * math.pi * bandwidth
                                                                 * period)
        samples = int(math.floor(duration / period)) + 2
        self._noise = np.random.default_rng(seed).normal(size=(samples, 3)) * noise_std
        self._wrench = self.DeclareVectorInputPort("contact_wrench", CONTACT_WRENCH_SIZE)
        # Group 0: the filtered force; group 1: what the sensor gives, filtered + noise.
        self.DeclareDiscreteState(3)
        measured = self.DeclareDiscreteState(3)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._sample)
        self.DeclareStateOutputPort("measured_contact_force", measured)

    def _sample(self, context: Context, discrete_state) -> None:
        force = np.asarray(self._wrench.Eval(context))[3:6]
        old = context.get_discrete_state(0).value()[0:3]
        new = old + self._a * (force - old)
        k = min(int(round(context.get_time() / self._period)), len(self._noise) - 1)
        discrete_state.get_mutable_value(0)[:] = new
        discrete_state.get_mutable_value(1)[:] = new + self._noise[k]


def add_contact_sensing(builder: DiagramBuilder, scenario, sim: AerialManipulator,
                        controller) -> dict[str, OutputPort]:
    """The contact wrench on the end effector (``contact_wrench``) where the scenario has an
    environment to touch, and the force sensor (``measured_contact_force``) where the
    controller has a ``contact_force`` input (``paper_force``), wired to it. Returns the new
    output ports by name (none without an environment: a robot alone touches nothing, and
    the paper's runs add no system)."""
    if scenario.environment.model_directives() is None:
        return {}
    assert sim.scene_graph is not None
    plant = sim.plant
    wrench = builder.AddSystem(ContactWrench(
        plant, sim.end_effector_body,
        sim.end_effector_frame.GetFixedPoseInBodyFrame().translation(),
        sim.scene_graph.model_inspector()))
    wrench.set_name("contact_wrench")
    builder.Connect(plant.get_contact_results_output_port(),
                    wrench.GetInputPort("contact_results"))
    builder.Connect(plant.get_body_poses_output_port(), wrench.GetInputPort("body_poses"))
    outputs = {"contact_wrench": wrench.GetOutputPort("contact_wrench")}
    if controller.HasInputPort("contact_force"):
        spec = scenario.force_sensor
        sensor = builder.AddSystem(ForceSensor(
            scenario.controller_period, spec.bandwidth, spec.noise_std, spec.seed,
            scenario.duration))
        sensor.set_name("force_sensor")
        builder.Connect(outputs["contact_wrench"], sensor.GetInputPort("contact_wrench"))
        measured = sensor.GetOutputPort("measured_contact_force")
        builder.Connect(measured, controller.GetInputPort("contact_force"))
        outputs["measured_contact_force"] = measured
    return outputs
