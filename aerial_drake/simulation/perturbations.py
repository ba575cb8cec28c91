"""Model mismatch and payload: what the scenario's ``model_mismatch`` and ``payload`` sections
(:mod:`aerial_drake.simulation.scenarios.perturbations`) do to a run, and the start of a
perturbed run (:func:`start_perturbations`: those, then the sensor's delay line primed).

The inertial parameters are changed in the *simulated* plant's context only (Drake keeps each
body's mass, CoM and inertia as parameters of the context: no second model file); the
controller's own model (``ClosedLoop.controller_model``) keeps its nominal values, so the
controller is wrong by exactly the drawn amounts. Bodies come from the plant itself, so any
robot description gets the same treatment.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from pydrake.math import RigidTransform
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import (
    BodyIndex,
    ModelInstanceIndex,
    RigidBody,
    RotationalInertia,
    SpatialInertia,
)
from pydrake.systems.framework import Context

from aerial_drake.robots.models import AerialManipulator
from aerial_drake.simulation.diagram import ClosedLoop
from aerial_drake.simulation.scenarios import Scenario
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
                         exclude: Sequence[ModelInstanceIndex] = ()
                         ) -> dict[str, dict[str, float]]:
    """Set every massive body's inertial parameters in ``context`` (the simulated plant's) as
    ``mismatch`` says; returns ``{body: {mass_factor, inertia_factor, com_shift_m}}`` drawn
    (empty when the section is off: nothing is touched)."""
    if not mismatch.active():
        return {}
    rng = np.random.default_rng(mismatch.seed)
    applied = {}
    for body in massive_bodies(plant, context, exclude):
        M = body.CalcSpatialInertiaInBodyFrame(context)
        # Draw all three for every body, whichever errors are on, so that turning one error
        # off leaves the others' draws as they were.
        e_m, e_I = rng.uniform(-1.0, 1.0, size=2)
        d = rng.uniform(-1.0, 1.0, size=3)
        mass_factor = mismatch.mass_scale * (1.0 + mismatch.mass_error * e_m)
        inertia_factor = mismatch.inertia_scale * (1.0 + mismatch.inertia_error * e_I)
        shift = (np.asarray(mismatch.com_offset, dtype=float)
                 + mismatch.com_error * radius_of_gyration(M) * d)
        body.SetSpatialInertiaInBodyFrame(
            context, perturbed_inertia(M, mass_factor, inertia_factor, shift))
        applied[body.name()] = {"mass_factor": float(mass_factor),
                                "inertia_factor": float(inertia_factor),
                                "com_shift_m": float(np.linalg.norm(shift))}
    return applied


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
    apply_model_mismatch(scenario.model_mismatch, sim.plant, context, sim.environment)
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
