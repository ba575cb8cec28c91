"""The configuration that realises the reference at one instant: where a run starts
(:func:`aerial_drake.simulation.runner.set_initial_state`) and what the baselines' body
reference is measured from (:func:`body_offset_in_heading_frame`). In the control layer: it
needs only the law's (10) and (13), the model and the reference, and the controller registry
(:mod:`aerial_drake.control.registry`) builds the baselines with it."""

from __future__ import annotations

from typing import Any

import numpy as np

from aerial_drake.control.law import desired_attitude, desired_force
from aerial_drake.dynamics.equilibrium import solve_configuration
from aerial_drake.robots.models import AerialManipulator
from aerial_drake.trajectories.base import ReferenceSource
from aerial_drake.trajectories.kinds import reference_of
from aerial_drake.trajectories.reference import ReferenceSample


def reference_configuration(scenario: Any, model: AerialManipulator, t: float = 0.0, *,
                            reference: ReferenceSource | None = None) -> np.ndarray:
    """Positions of ``model`` that realise ``scenario``'s reference at time ``t`` exactly: CoM
    on x_d, base attitude R_d of (13) for zero CoM error, end effector on (p_ed, R_ed),
    the task's joints at their targets. ``reference``: the run's reference (None: built from
    ``scenario.trajectory``). (``scenario`` a
    :class:`~aerial_drake.simulation.scenarios.Scenario`; not imported here: the scenarios
    are the simulation layer's, above this one.)"""
    if reference is None:
        reference = reference_of(scenario.trajectory, model.task_joint_nominal())
    ref = reference.evaluate(t)
    # Joint limits are not imposed: the simulated plant does not enforce them, and at t = 0 the
    # paper's reference needs joint 6 about 0.19 rad past its 120 deg (docs/control.md).
    return solve_configuration(model, **realising_targets(model, ref),
                               respect_joint_limits=False)


def realising_targets(model: AerialManipulator, ref: ReferenceSample,
                      mass_gravity: tuple[float, float] | None = None) -> dict[str, Any]:
    """The targets of :func:`~aerial_drake.dynamics.equilibrium.solve_configuration` that
    realise the reference sample ``ref`` (one time): CoM on x_d, base attitude R_d of (13)
    for zero CoM error, end effector on (p_ed, R_ed), the task's joints on q_jd.
    ``mass_gravity``: (m, g) of the model if known (:func:`mass_and_gravity`)."""
    m, g = mass_and_gravity(model) if mass_gravity is None else mass_gravity
    x = ref.com
    zero = np.zeros(3)
    # (10) with zero CoM error; its derivatives are then m times x_d's 3rd and 4th.
    f_d = desired_force(m, g, x, zero, zero, zero, zero)
    R_d = desired_attitude(f_d, m * x[3], m * x[4], ref.b1d)[0]
    return dict(p_WG=x[0], R_WB=R_d, p_WE=ref.p_ed, R_WE=ref.R_ed, q_j=ref.q_jd)


def mass_and_gravity(model: AerialManipulator) -> tuple[float, float]:
    """The model's total mass m (kg) and gravity g (m/s^2, along -z) of (9a)."""
    plant = model.plant
    return (plant.CalcTotalMass(plant.CreateDefaultContext()),
            -plant.gravity_field().gravity_vector()[2])


def body_offset_in_heading_frame(scenario: Any, model: AerialManipulator,
                                 reference: ReferenceSource | None = None) -> np.ndarray:
    """The CoM's offset from the vehicle body at the reference configuration of t = 0, in
    the heading frame [b1d, e3 x b1d, e3]: what the baselines' body reference keeps
    (:func:`aerial_drake.control.baselines.vehicle.body_reference`). ``reference``: the run's
    reference (None: built from ``scenario.trajectory``)."""
    if reference is None:
        reference = reference_of(scenario.trajectory, model.task_joint_nominal())
    plant = model.plant
    ctx = plant.CreateDefaultContext()
    plant.SetPositions(ctx, reference_configuration(scenario, model, reference=reference))
    p_b = plant.EvalBodyPoseInWorld(ctx, model.base_body).translation()
    offset = plant.CalcCenterOfMassPositionInWorld(ctx) - p_b
    b1 = reference.evaluate(0.0).b1d[0]
    H = np.column_stack([b1, np.cross([0.0, 0.0, 1.0], b1), [0.0, 0.0, 1.0]])
    return H.T @ offset
