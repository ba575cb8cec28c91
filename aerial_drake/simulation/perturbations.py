"""Model mismatch and payload: what the scenario's ``model_mismatch`` and ``payload`` sections
(:mod:`aerial_drake.simulation.scenarios.perturbations`) do to a run, and the start of a
perturbed run (:func:`start_perturbations`: those, then the sensor's delay line primed).

The inertial parameters are changed in the *simulated* plant's context only (Drake keeps each
body's mass, CoM and inertia as parameters of the context: no second model file); the
controller's own model (``ClosedLoop.controller_model``) keeps its nominal values, so the
controller is wrong by exactly the drawn amounts. Bodies come from the plant itself, so any
robot description gets the same treatment; the rotor bodies (children of the plant's rotor
joints) keep their CoM, and get an unbalance only when ``rotor_balance_grade`` asks for one
(:class:`~aerial_drake.simulation.scenarios.perturbations.ModelMismatch` says why).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from pydrake.math import RigidTransform
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import (
    BodyIndex,
    ModelInstanceIndex,
    RevoluteJoint,
    RigidBody,
    RotationalInertia,
    SpatialInertia,
)
from pydrake.systems.framework import Context

from aerial_drake.robots.models import AerialManipulator
from aerial_drake.simulation.diagram import ClosedLoop
from aerial_drake.simulation.scenarios import Scenario
from aerial_drake.simulation.scenarios.checks import check_body_names
from aerial_drake.simulation.scenarios.perturbations import ModelMismatch, Payload


def massive_bodies(plant: MultibodyPlant, context: Context,
                   exclude: Sequence[ModelInstanceIndex] = ()) -> list[RigidBody]:
    """The plant's bodies with mass, World and the ``exclude`` models' (the environment's)
    excepted, in index order (the order of draws)."""
    skip = {int(i) for i in exclude}
    bodies = [plant.get_body(BodyIndex(i)) for i in range(1, plant.num_bodies())]
    return [b for b in bodies if b.get_mass(context) > 0 and int(b.model_instance()) not in skip]


def perturbed_inertia(M_BBo_B: SpatialInertia, mass_factor: float, inertia_factor: float,
                      com_shift_B: np.ndarray) -> SpatialInertia:
    """``M_BBo_B`` with its mass times ``mass_factor``, its rotational inertia about its CoM
    times ``inertia_factor`` and its CoM moved by ``com_shift_B`` (body axes, m)."""
    m = M_BBo_B.get_mass()
    p_BoBcm_B = M_BBo_B.get_com()
    # The central inertia: scaling it by a positive factor keeps it physically valid.
    I_Bcm_B = M_BBo_B.Shift(p_BoBcm_B).CalcRotationalInertia().CopyToFullMatrix3()
    I_new = RotationalInertia(*_moments_and_products(inertia_factor * I_Bcm_B))
    return SpatialInertia.MakeFromCentralInertia(mass_factor * m, p_BoBcm_B + com_shift_B,
                                                 I_new)


def _moments_and_products(I: np.ndarray) -> tuple[float, ...]:
    return (I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2])


def radius_of_gyration(M_BBo_B: SpatialInertia) -> float:
    """sqrt(tr(I_cm) / 2m) (m): the length a CoM error is measured against."""
    I = M_BBo_B.Shift(M_BBo_B.get_com()).CalcRotationalInertia().CopyToFullMatrix3()
    return float(np.sqrt(np.trace(I) / (2.0 * M_BBo_B.get_mass())))


def apply_model_mismatch(mismatch: ModelMismatch, plant: MultibodyPlant, context: Context,
                         exclude: Sequence[ModelInstanceIndex] = (),
                         rotor_joints: Sequence[RevoluteJoint] = (),
                         rotor_speed: float = 0.0) -> dict[str, dict[str, float]]:
    """Set the inertial parameters in ``context`` (the simulated plant's) as ``mismatch`` says
    (its docstring): the bodies it names, else every massive body; ``rotor_joints``' child
    bodies never get a CoM error (balanced rotors), only the unbalance of
    ``rotor_balance_grade`` at ``rotor_speed`` (rad/s). Returns ``{body: {mass_factor,
    inertia_factor, com_shift_m}}`` (empty when the section is off: nothing is touched).

    Raises ScenarioError naming ``model_mismatch.bodies`` for a name that is not one of the
    plant's massive bodies (listing them)."""
    if not mismatch.active():
        return {}
    bodies = massive_bodies(plant, context, exclude)
    chosen = set(check_body_names(mismatch.bodies, [b.name() for b in bodies]))
    unbalance = rotor_unbalance(mismatch, rotor_joints, rotor_speed)
    rng = np.random.default_rng(mismatch.seed)
    applied = {}
    for body in bodies:
        M = body.CalcSpatialInertiaInBodyFrame(context)
        # Draw all three for every body, whichever errors are on and whichever bodies are
        # named, so that turning one error off (or naming fewer bodies) leaves the others'
        # draws as they were.
        e_m, e_I = rng.uniform(-1.0, 1.0, size=2)
        d = rng.uniform(-1.0, 1.0, size=3)
        named = body.name() in chosen and mismatch.body_errors()
        # A rotor's CoM moves by its unbalance alone (its d drawn, not applied).
        shift = unbalance.get(int(body.index()))
        if not (named or (shift is not None and shift.any())):
            continue
        mass_factor, inertia_factor = 1.0, 1.0
        if named:
            mass_factor = mismatch.mass_scale * (1.0 + mismatch.mass_error * e_m)
            inertia_factor = mismatch.inertia_scale * (1.0 + mismatch.inertia_error * e_I)
        if shift is None:
            shift = (np.asarray(mismatch.com_offset, dtype=float)
                     + mismatch.com_error * radius_of_gyration(M) * d)
        body.SetSpatialInertiaInBodyFrame(
            context, perturbed_inertia(M, mass_factor, inertia_factor, shift))
        applied[body.name()] = {"mass_factor": float(mass_factor),
                                "inertia_factor": float(inertia_factor),
                                "com_shift_m": float(np.linalg.norm(shift))}
    return applied


#: The second entry of the seed of the rotors' unbalance phases (``default_rng([seed, 1])``),
#: a stream apart from the bodies' draws (``default_rng(seed)``).
UNBALANCE_STREAM = 1


def rotor_unbalance(mismatch: ModelMismatch, rotor_joints: Sequence[RevoluteJoint],
                    rotor_speed: float) -> dict[int, np.ndarray]:
    """The CoM shift of each rotor's child body (its body axes, m), by body index: the
    permissible specific unbalance of ISO 21940-11, ``e = G / omega`` (G =
    ``rotor_balance_grade`` in mm/s, omega = ``|rotor_speed|`` in rad/s), perpendicular to the
    joint's axis at a phase uniform in [0, 2 pi) per rotor; zero shifts when G = 0."""
    grade = mismatch.rotor_balance_grade
    if grade > 0 and rotor_joints and rotor_speed == 0:  # (the validation refuses it)
        raise ValueError("rotor_unbalance: a balance grade needs a rotor speed other than 0")
    rng = np.random.default_rng([mismatch.seed, UNBALANCE_STREAM])
    shifts = {}
    for joint in rotor_joints:
        phase = rng.uniform(0.0, 2.0 * np.pi)
        if grade == 0:
            shifts[int(joint.child_body().index())] = np.zeros(3)
            continue
        e = grade * 1e-3 / abs(rotor_speed)  # (mm/s) / (rad/s) = mm, in m
        R_BM = joint.frame_on_child().GetFixedPoseInBodyFrame().rotation().matrix()
        a = R_BM @ joint.revolute_axis()  # the spin axis in the rotor's body axes
        u, v = _perpendicular_pair(a)
        shifts[int(joint.child_body().index())] = e * (np.cos(phase) * u + np.sin(phase) * v)
    return shifts


def _perpendicular_pair(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors perpendicular to the unit vector ``a`` and to each other."""
    helper = np.eye(3)[int(np.argmin(np.abs(a)))]
    u = np.cross(a, helper)
    u /= np.linalg.norm(u)
    return u, np.cross(a, u)


def payload_inertia(payload: Payload, X_BE: RigidTransform) -> SpatialInertia:
    """The payload's spatial inertia about the end-effector body's origin, body axes, from
    its CoM and principal moments in frame E (pose ``X_BE`` in the body)."""
    R_BE = X_BE.rotation()
    I_E = np.diag(np.asarray(payload.inertia, dtype=float))
    I_B = R_BE.matrix() @ I_E @ R_BE.matrix().T
    p_BoPcm_B = X_BE @ np.asarray(payload.offset, dtype=float)
    return SpatialInertia.MakeFromCentralInertia(
        payload.mass, p_BoPcm_B, RotationalInertia(*_moments_and_products(I_B)))


def apply_payload(payload: Payload, sim: AerialManipulator, context: Context) -> None:
    """Add ``payload``'s inertia to the end-effector body's parameters in ``context`` (the
    simulated plant's); nothing when the payload's mass is 0."""
    if not payload.active():
        return
    body = sim.end_effector_body
    X_BE = sim.end_effector_frame.GetFixedPoseInBodyFrame()
    M = body.CalcSpatialInertiaInBodyFrame(context)
    M += payload_inertia(payload, X_BE)
    body.SetSpatialInertiaInBodyFrame(context, M)


def apply_plant_perturbations(scenario: Scenario, sim: AerialManipulator,
                              context: Context) -> None:
    """The scenario's model mismatch, then its payload (itself exact: it is what is held), on
    the simulated plant's ``context``."""
    apply_model_mismatch(scenario.model_mismatch, sim.plant, context, sim.environment,
                         sim.rotor_joints, scenario.rotors.speed)
    apply_payload(scenario.payload, sim, context)


def start_perturbations(scenario: Scenario, loop: ClosedLoop, context: Context) -> None:
    """After the initial state is set (``context`` the root context): the simulated plant's
    model mismatch and payload, then the sensor's delay line filled with the initial state
    (what the controller measures before ``delay`` has passed). Nothing for a scenario
    without them."""
    sim = loop.simulated_plant
    plant_context = sim.plant.GetMyMutableContextFromRoot(context)
    apply_plant_perturbations(scenario, sim, plant_context)
    if loop.sensor is not None:
        x = sim.plant.GetPositionsAndVelocities(plant_context)[sim.rigid_state_indices]
        loop.sensor.prime(loop.sensor.GetMyMutableContextFromRoot(context), x)
