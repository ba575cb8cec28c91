"""Checks of a scenario against its robot before anything is simulated: the reference within
the arm's reach, and Assumption 1 (J_3 nonsingular) at the start posture. Each failure is a
ScenarioError naming the time, the cause and the fields to change (exit status 2)."""

from __future__ import annotations

import numpy as np

from aerial_drake.control.controller import task_jacobian
from aerial_drake.dynamics.decoupling import DecoupledDynamics
from aerial_drake.robots.models import AerialManipulator, nominal_end_effector_offset
from aerial_drake.simulation.scenarios import Scenario, ScenarioError
from aerial_drake.trajectories.paper import sample_reference


def check_workspace(scenario: Scenario, model: AerialManipulator, *,
                    radius: float | None = None, rate: float = 50.0) -> None:
    """Raise ScenarioError if the reference leaves the arm's workspace at any sampled time.

    The arm holds the end effector at a fixed offset from the system CoM in the heading frame
    (x_d = x_c + R3(phi4) r_o, (33)); the task is feasible while the desired offset
    R3(phi4)^T (p_ed - x_d) stays within ``radius`` of the model's nominal one (default: the
    robot description's ``workspace_radius``).
    """
    radius = model.description.workspace_radius if radius is None else radius
    nominal = nominal_end_effector_offset(model)
    times = np.linspace(0.0, scenario.duration, int(scenario.duration * rate) + 1)
    ref = sample_reference(scenario.trajectory, times, model.task_joint_nominal())
    offset = ref.p_ed - ref.com[:, 0]
    b1 = ref.b1d[:, 0]  # heading direction (unit, horizontal)
    x_h = np.einsum("ti,ti->t", offset, b1)
    y_h = -offset[:, 0] * b1[:, 1] + offset[:, 1] * b1[:, 0]
    dev = np.linalg.norm(np.column_stack([x_h, y_h, offset[:, 2]]) - nominal, axis=1)
    worst = int(np.argmax(dev))
    if dev[worst] > radius:
        raise ScenarioError(
            f"trajectory: the desired end effector leaves the arm's workspace at t = "
            f"{times[worst]:.2f} s: it is {dev[worst]:.3f} m from its nominal offset "
            f"{np.round(nominal, 3).tolist()} m to the desired CoM (heading frame; limit "
            f"{radius} m, the robot's workspace_radius). Reduce trajectory.agile_amplitude "
            "or keep trajectory.com_offset near the model's nominal offset.", "trajectory")


def sigma_min_J3(model: AerialManipulator, x: np.ndarray) -> float:
    """sigma_min(J_3) of Assumption 1 at state ``x`` of ``model`` (J = J_y T^-1, (17))."""
    plant = model.plant
    ctx = plant.CreateDefaultContext()
    plant.SetPositionsAndVelocities(ctx, x)
    dynamics = DecoupledDynamics(plant)
    d = dynamics.compute(ctx)
    J6, J6_dot = dynamics.frame_jacobian(d, model.end_effector_frame)
    assert model.task is not None
    J_y, _ = task_jacobian(model.task, J6, J6_dot, plant.num_velocities())
    J3 = (J_y @ d.T_inv)[:, 6:]
    return float(np.linalg.svd(J3, compute_uv=False)[-1])


def check_start_posture(scenario: Scenario, model: AerialManipulator, x0: np.ndarray) -> None:
    """Raise ScenarioError if J_3 is singular (Assumption 1) at the start state ``x0`` of the
    controller's model. A non-finite ``x0`` is left to the run's non-finite check, which
    reports it at t = 0 (Drake's SetPositionsAndVelocities would abort on it here)."""
    if not np.all(np.isfinite(x0)):
        return
    sigma = sigma_min_J3(model, x0)
    limit = scenario.sigma_min_J3_limit
    if not sigma > limit:
        raise ScenarioError(
            f"initial: Assumption 1 fails at the start posture (t = 0): J_3 is singular, "
            f"sigma_min(J_3) = {sigma:.3g} (limit sigma_min_J3_limit = {limit:g}). The task "
            f"{list(model.task.components) if model.task else []} cannot be controlled from "
            "the posture that realises the reference at t = 0: move the reference's start "
            "(trajectory), change the task, or the robot's nominal_posture", "initial")
