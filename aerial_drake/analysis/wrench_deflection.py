"""The paper law's steady task error under a constant end-effector wrench (docs/baselines.md,
"Why the paper's law gives way more under the end-effector wrench").

A wrench ``w = [f; t]`` (World, at the end-effector point) is the generalized force
``G = J_E^T w`` on (1); in the coordinates of (3) it is ``T^-T G = [G1; G2; G3]``, and with
the task ``y = [p_E; orientation; q_j]`` (every pose row in the task) it is the task-space
force ``F`` with ``J^T F = T^-T G``: ``F = [f; t; 0]``, ``G1 = J1^T F`` (= f: moving
``x_g`` with ``w_b`` and ``rho`` held is a pure translation), ``G2 = J2^T F``, ``G3 = J3^T F``.
Under the law (22) the plant's (5) becomes, exactly (the controller's model being the plant):

    m x_g''  = u1 R e3 - m g e3 + G1            (the law's (9a) value lacks G1 / m)
    w_b'     = w_b'(16) + Lambda22^-1 G2         (the law's (16) value lacks the second term)
    Lambda_z z~' + (Gamma_z + K_z) z~ = J3^-T G3 - Lambda_z (J1 da + J2 dw)

where ``da = -G1 / m`` and ``dw = -Lambda22^-1 G2`` are the model's accelerations in (20)
less the true ones. So the task loop is driven by

    F + Lambda_z (J1 J1^T / m + J2 Lambda22^-1 J2^T) F = Lambda_z Lambda_y^-1 F,

with ``Lambda_y^-1 = J Lambda^-1 J^T = J1 J1^T / m + J2 Lambda22^-1 J2^T + Lambda_z^-1``
(Lambda block diagonal). At rest ``Gamma_z = 0`` and ``z~ = y~' + K_y y~ = K_y y~``, so

    y~ = K_y^-1 K_z^-1 Lambda_z Lambda_y^-1 F            (K_y, K_z diagonal: either order),

against ``y~ = K_y^-1 K_z^-1 F`` with the true accelerations in (20) (and for the baselines,
whose fixed-base arm law balances ``J_a^T K_z K_y y~ = J_a^T F`` at rest).
``Lambda_z Lambda_y^-1 = E + Lambda_z P`` with ``P`` positive semidefinite of rank <= 6, so
its eigenvalues are real, >= 1, and one is 1 for a 7-row task.

The expression holds at the equilibrium the wrench moves the robot to, whose posture differs
from the reference's (``Lambda_z`` depends on it: 106 mm at the equilibrium against 138 mm at
the reference posture on the hover of the test): :func:`wrench_equilibrium` finds it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from pydrake.common.eigen_geometry import Quaternion
from pydrake.math import RotationMatrix

from aerial_drake.control.controller import make_controller, task_jacobian
from aerial_drake.control.law import Gains
from aerial_drake.control.reference_pose import mass_and_gravity, realising_targets
from aerial_drake.dynamics.decoupling import DecoupledDynamics, hat
from aerial_drake.dynamics.equilibrium import solve_configuration, track_configuration
from aerial_drake.robots.models import AerialManipulator
from aerial_drake.robots.task import POSE_ROWS
from aerial_drake.trajectories.base import ReferenceSource
from aerial_drake.trajectories.reference import ReferenceSample


@dataclass(frozen=True)
class WrenchDeflection:
    """The steady task errors under a constant end-effector wrench, at one posture."""

    y_tilde: np.ndarray  # the law as implemented: model accelerations in (20)
    y_tilde_true_accelerations: np.ndarray  # (K_y K_z)^-1 F: true accelerations in (20)
    task_force: np.ndarray  # F (task rows; N, N m, and 0 on joint rows)
    amplification: np.ndarray  # Lambda_z Lambda_y^-1 (n, n)
    rows: tuple[int, ...]  # the task's rows of y_full

    @property
    def amplification_eigenvalues(self) -> np.ndarray:
        """The eigenvalues of ``Lambda_z Lambda_y^-1``, ascending (real, >= 1)."""
        return np.sort(np.linalg.eigvals(self.amplification).real)

    def ee_position_error(self, true_accelerations: bool = False) -> float:
        """|p_E - p_ed| at rest (m): the norm of the position rows of the steady y~."""
        y = self.y_tilde_true_accelerations if true_accelerations else self.y_tilde
        return float(np.linalg.norm([y[i] for i, r in enumerate(self.rows) if r < 3]))


def steady_task_error(model: AerialManipulator, q: np.ndarray, gains: Gains,
                      force: np.ndarray, torque: np.ndarray) -> WrenchDeflection:
    """The steady task error of the module docstring at positions ``q`` of ``model`` (exact
    when ``q`` is the closed loop's equilibrium under the wrench), for the wrench ``force``
    (N) and ``torque`` (N m), World axes, at the end-effector point."""
    task = model.task
    assert task is not None  # a finalized model
    w = np.concatenate([force, torque]).astype(float)
    missing = [r for r in range(POSE_ROWS) if w[r] != 0.0 and r not in task.rows]
    if missing:
        raise ValueError(f"the wrench acts along end-effector rows {missing} that the task "
                         f"{list(task.components)} does not track; the steady error is "
                         "defined here for tasks holding every row the wrench acts on")
    F = np.array([w[r] if r < POSE_ROWS else 0.0 for r in task.rows])
    amplification = amplification_matrix(model, q)
    K = np.asarray(gains.K_y, dtype=float) * np.asarray(gains.K_z, dtype=float)
    return WrenchDeflection(y_tilde=amplification @ F / K, y_tilde_true_accelerations=F / K,
                            task_force=F, amplification=amplification, rows=task.rows)


def amplification_matrix(model: AerialManipulator, q: np.ndarray, *,
                         dynamics: DecoupledDynamics | None = None, context=None) -> np.ndarray:
    """``Lambda_z Lambda_y^-1`` (n, n) at positions ``q`` (at rest): ``Lambda_z`` of (19),
    ``Lambda_y^-1 = J Lambda^-1 J^T`` with ``J = J_y T^-1`` (17). ``dynamics``, ``context``:
    reused if given (a loop over postures)."""
    plant, task = model.plant, model.task
    assert task is not None  # a finalized model
    dynamics = dynamics or DecoupledDynamics(plant, model.base_body)
    ctx = context or plant.CreateDefaultContext()
    plant.SetPositionsAndVelocities(ctx, np.concatenate([q, np.zeros(plant.num_velocities())]))
    d = dynamics.compute(ctx)
    J6, J6_dot = dynamics.frame_jacobian(d, model.end_effector_frame)
    J_y, _ = task_jacobian(task, J6, J6_dot, plant.num_velocities())
    J = J_y @ d.T_inv
    J3_inv = np.linalg.inv(J[:, 6:])
    Lambda_z = J3_inv.T @ d.Lambda[6:, 6:] @ J3_inv  # (19)
    return Lambda_z @ (J @ np.linalg.solve(d.Lambda, J.T))


def amplification_along_reference(reference: ReferenceSource, model: AerialManipulator,
                                  times: np.ndarray) -> np.ndarray:
    """The eigenvalues of ``Lambda_z Lambda_y^-1`` (rows: ``times``; ascending) at the
    postures that realise ``reference`` (CoM on x_d, base at R_d, end effector on its pose,
    the task joints on q_jd), each tracked from the last by Newton steps
    (:func:`~aerial_drake.dynamics.equilibrium.track_configuration`, the full solve as the
    fallback), as the reference checks do (:mod:`aerial_drake.simulation.feasibility`)."""
    plant = model.plant
    ctx = plant.CreateDefaultContext()
    dynamics = DecoupledDynamics(plant, model.base_body)
    mass_gravity = mass_and_gravity(model)
    samples = reference.sample(np.asarray(times, dtype=float))
    q: np.ndarray | None = None
    out = []
    for k in range(len(times)):
        ref = ReferenceSample(**{f.name: getattr(samples, f.name)[k]
                                 for f in dataclasses.fields(samples)})
        targets = realising_targets(model, ref, mass_gravity)
        tracked: np.ndarray | None = (
            None if q is None else track_configuration(model, q, ctx, **targets))
        q = tracked if tracked is not None else solve_configuration(
            model, **targets, q_guess=q, respect_joint_limits=False)
        A = amplification_matrix(model, q, dynamics=dynamics, context=ctx)
        out.append(np.sort(np.linalg.eigvals(A).real))
    return np.array(out)


def moved_positions(q: np.ndarray, delta: np.ndarray) -> np.ndarray:
    """``q`` (quaternion base) moved by ``delta = [rotation vector (World); position;
    joints]``, a step along the generalized velocity's coordinates."""
    theta = float(np.linalg.norm(delta[:3]))
    K = hat(delta[:3] / theta) if theta > 0 else np.zeros((3, 3))
    step = np.eye(3) + np.sin(theta) * K + (1.0 - np.cos(theta)) * K @ K  # Rodrigues
    R_WB = RotationMatrix(Quaternion(q[:4] / np.linalg.norm(q[:4]))).matrix()
    out = np.concatenate([RotationMatrix(step @ R_WB).ToQuaternion().wxyz(),
                          q[4:] + delta[3:]])
    return out


def wrench_equilibrium(model: AerialManipulator, gains: Gains, references: tuple,
                       force: np.ndarray, torque: np.ndarray, q_start: np.ndarray, *,
                       steps: int = 10, tolerance: float = 1e-10, max_iterations: int = 30
                       ) -> np.ndarray:
    """The positions at which the paper's law (on ``model``, its own plant) holds the robot at
    rest under the constant wrench (``force``, ``torque``: World, at the end-effector point)
    and the constant ``references`` (the packed ``com``, ``task``, ``heading`` vectors of a
    hover): the generalized force balance of (1) at zero velocity,
    ``J_b^T [f e3; mu] + Q^T tau + J_E^T w - g = 0``, followed from ``q_start`` (the
    equilibrium without the wrench, e.g. the reference's posture) as the wrench grows in
    ``steps`` equal parts (the equilibrium moves far: about 1 rad on three joints for
    Table II's gains and the paper's 40 N / 20 N m), each by Newton's method with a central
    finite-difference Jacobian. A quaternion base only
    (:func:`external_force_equilibrium` with ``J_E^T w``).

    Raises:
        RuntimeError: a Newton solve does not converge to ``tolerance`` (the step's norm) in
            ``max_iterations``.
    """
    w = np.concatenate([force, torque]).astype(float)  # the rows [v_E; w_E] of J6

    def external(dynamics: DecoupledDynamics, d, fraction: float) -> np.ndarray:
        J6, _ = dynamics.frame_jacobian(d, model.end_effector_frame)
        return J6.T @ (fraction * w)

    return external_force_equilibrium(model, gains, references, external, q_start,
                                      steps=steps, tolerance=tolerance,
                                      max_iterations=max_iterations)


#: ``external(dynamics, d, fraction)``: the generalized force (nv, the plant's velocity
#: coordinates) of ``fraction`` (0 to 1) of a constant load at the positions of ``d`` (the
#: :class:`~aerial_drake.dynamics.decoupling.DecoupledDynamics` data there).
ExternalForce = Callable[[DecoupledDynamics, Any, float], np.ndarray]


def external_force_equilibrium(model: AerialManipulator, gains: Gains, references: tuple,
                               external: ExternalForce, q_start: np.ndarray, *,
                               steps: int = 10, tolerance: float = 1e-10,
                               max_iterations: int = 30, controller=None,
                               cache: dict | None = None) -> np.ndarray:
    """The positions at which the paper's law holds the robot at rest under a constant
    external generalized force ``G = external(dynamics, d, 1)`` (e.g. ``J_E^T w`` for an
    end-effector wrench, :func:`wrench_equilibrium`, or a force on the vehicle) and the
    constant ``references``: ``J_b^T [f e3; mu] + Q^T tau + G - g = 0`` at zero velocity,
    followed from ``q_start`` as the load grows in ``steps`` equal parts, each by Newton's
    method with a central finite-difference Jacobian. ``controller``: the law to hold it
    (default: :func:`~aerial_drake.control.controller.make_controller` on ``model`` and
    ``gains``, with its default assumption thresholds). ``cache``: a dict kept between the
    calls of a continuation, whose Newton steps then reuse the last Jacobian (chord steps,
    refreshed when they converge slowly). A quaternion base only.

    Raises:
        RuntimeError: a Newton solve does not converge to ``tolerance`` (the step's norm) in
            ``max_iterations``.
    """
    plant = model.plant
    if plant.num_positions() != plant.num_velocities() + 1:
        raise ValueError("the equilibrium needs a quaternion floating base "
                         f"(nq = nv + 1); got nq = {plant.num_positions()}, "
                         f"nv = {plant.num_velocities()}")
    controller = controller if controller is not None else make_controller(model, gains)
    dynamics = DecoupledDynamics(plant, model.base_body)
    ctx = plant.CreateDefaultContext()
    zero_v = np.zeros(plant.num_velocities())

    def residual(q: np.ndarray, fraction: float) -> np.ndarray:
        x = np.concatenate([q, zero_v])
        out = controller.solve(x, *references)
        plant.SetPositionsAndVelocities(ctx, x)
        d = dynamics.compute(ctx)
        base = np.concatenate([[0.0, 0.0, float(out.f)], out.mu])  # [f e3; mu] of (2)
        return (d.J_b.T @ base + d.Q.T @ out.tau + external(dynamics, d, fraction)
                - d.g)  # (1) at rest

    q = np.array(q_start, dtype=float)
    for fraction in np.arange(1, steps + 1) / steps:
        q = _newton(residual, fraction, q, tolerance, max_iterations, cache)
    return q


def _newton(residual, w, q: np.ndarray, tolerance: float, max_iterations: int,
            cache: dict | None = None) -> np.ndarray:
    """A zero of ``residual(., w)`` (nv) over the positions, from ``q``, stepping by
    :func:`moved_positions`. With ``cache`` (a dict kept between the solves of a
    continuation), the Jacobian of the last solve is reused (chord steps) and refreshed only
    when a step does not shrink to half the last one; without it, a fresh Jacobian at every
    step."""
    A = None if cache is None else cache.get("A")
    previous = np.inf
    for _ in range(max_iterations):
        r = residual(q, w)
        fresh = A is None or cache is None
        if A is None or cache is None:
            A = _jacobian(residual, w, q, r.size)
        step = -np.linalg.solve(A, r)
        if not fresh and np.linalg.norm(step) > 0.5 * previous:  # stale: converging slowly
            A = _jacobian(residual, w, q, r.size)
            step = -np.linalg.solve(A, r)
        q = moved_positions(q, step)
        previous = float(np.linalg.norm(step))
        if previous < tolerance:
            if cache is not None:
                cache["A"] = A
            return q
    if cache is not None:
        cache.pop("A", None)
    raise RuntimeError(f"wrench_equilibrium: no equilibrium found in {max_iterations} "
                       f"Newton steps (last step {np.linalg.norm(step):.3g}, residual "
                       f"{np.linalg.norm(r):.3g}): raise steps (smaller increments of the "
                       "wrench) or lower the wrench")


def _jacobian(residual, w, q: np.ndarray, size: int) -> np.ndarray:
    """d residual(., w) / d q along :func:`moved_positions`'s coordinates, central differences."""
    h = 1e-6
    return np.column_stack([(residual(moved_positions(q, h * e), w)
                             - residual(moved_positions(q, -h * e), w)) / (2.0 * h)
                            for e in np.eye(size)])
