"""Configurations that realise a task: Drake's InverseKinematics on the CoM, base attitude and
the task (the rows of end-effector pose and joint angles the robot's task tracks), polished by
Newton steps, and the hover inputs that hold such a configuration."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
from pydrake.multibody.inverse_kinematics import ComPositionConstraint, InverseKinematics
from pydrake.multibody.tree import JacobianWrtVariable
from pydrake.solvers import Solve

from aerial_drake.dynamics.decoupling import vee
from aerial_drake.robots.models import AerialManipulator
from aerial_drake.robots.task import POSE_ROWS, TaskLayout


class UnreachablePose(ValueError):
    """The requested CoM / base attitude / task cannot be realised by the model."""


@dataclass(frozen=True)
class ConfigurationResidual:
    com: float  # m
    ee_position: float  # m, over the task's position rows
    ee_orientation: float  # rad, over the task's orientation rows
    base_orientation: float  # rad
    joints: float  # rad, largest error of the task's joint components
    joint_limits: float  # rad beyond the arm's position limits (0 inside)

    def violations(self, tol_m: float, tol_rad: float, joint_limits: bool = True) -> list[str]:
        """Names of the constraints violated beyond the tolerances, with by how much."""
        failed = []
        checks = [("CoM position", self.com, tol_m),
                  ("end-effector position", self.ee_position, tol_m),
                  ("end-effector orientation", self.ee_orientation, tol_rad),
                  ("base orientation", self.base_orientation, tol_rad),
                  ("task joint angles", self.joints, tol_rad)]
        if joint_limits:
            checks.append(("arm joint limits", self.joint_limits, tol_rad))
        for name, value, tol in checks:
            if not value <= tol:
                failed.append(f"{name} (off by {value:.3g})")
        return failed


def _task(manip: AerialManipulator) -> TaskLayout:
    if manip.task is None:
        raise ValueError("the model's plant is not finalized: it has no task yet")
    return manip.task


def task_residual(manip: AerialManipulator, ctx, q: np.ndarray, p_WE, R_WE, q_j) -> np.ndarray:
    """The task's rows of ``[p_E - p_WE; vee(R_E R_WE^T); q_j(q) - q_j]`` at ``q``."""
    X_WE = manip.end_effector_frame.CalcPoseInWorld(ctx)
    task = _task(manip)
    full = np.concatenate([X_WE.translation() - p_WE,
                           vee(X_WE.rotation().matrix() @ np.asarray(R_WE).T),
                           q[list(task.joint_positions)] - np.asarray(q_j, dtype=float)])
    return full[list(task.rows)]


def solve_configuration(manip: AerialManipulator, *, p_WG: np.ndarray, R_WB: np.ndarray,
                        p_WE: np.ndarray, R_WE: np.ndarray, q_j=(),
                        q_guess: np.ndarray | None = None, tolerance: float = 1e-6,
                        respect_joint_limits: bool = True) -> np.ndarray:
    """Generalized positions with the system CoM at ``p_WG``, the base at orientation ``R_WB``
    and the task at ``(p_WE, R_WE, q_j)``: the rows of the end-effector pose and the joint
    angles ``q_j`` (task order) the robot's task holds.

    3 + n equations in 3 + n unknowns (base position, n joints): the solution is locally
    unique. Raises :class:`UnreachablePose` naming the constraints that the solution misses by
    more than ``tolerance`` (m or rad): the arm's joint limits among them unless
    ``respect_joint_limits`` is False (the continuous simulation does not enforce them, and
    the paper's task leaves them; docs/models.md).
    """
    plant = manip.plant
    task = _task(manip)
    q_j = np.asarray(q_j, dtype=float)
    if q_j.size != task.n_joints:
        raise ValueError(f"q_j has {q_j.size} angles for the task's {task.n_joints} joints "
                         f"({', '.join(task.joint_names) or 'none'})")
    ik = InverseKinematics(plant, with_joint_limits=respect_joint_limits)
    q = ik.q()
    prog = ik.get_mutable_prog()
    world = plant.world_frame()
    ik.AddOrientationConstraint(world, RotationMatrix(R_WB), manip.base_body.body_frame(),
                                RotationMatrix(), 0.0)
    free = np.full(3, np.inf)
    held = np.array([r in task.rows for r in range(3)])
    if held.any():
        ik.AddPositionConstraint(manip.end_effector_frame, np.zeros(3), world,
                                 np.where(held, p_WE, -free), np.where(held, p_WE, free))
    if task.has_full_orientation:
        ik.AddOrientationConstraint(world, RotationMatrix(R_WE), manip.end_effector_frame,
                                    RotationMatrix(), 0.0)
    r = prog.NewContinuousVariables(3, "p_WG")
    # The constraint gets a context of its own, not ik.context(): it sets the positions from
    # the decision variables at each evaluation either way, and one that keeps ik's context
    # alive ties the program into a cycle Python's collector cannot see (about 70 KB left
    # behind per solve, measured on drake 1.58; a study's arm-hold bound solves dozens of
    # postures per run).
    com_context = plant.CreateDefaultContext()
    prog.AddConstraint(ComPositionConstraint(plant, None, world, com_context),
                       np.concatenate([q, r]))
    prog.AddBoundingBoxConstraint(p_WG, p_WG, r)
    for index, angle in zip(task.joint_positions, q_j):
        prog.AddBoundingBoxConstraint(angle, angle, q[index])
    if q_guess is None:
        # The nominal posture, with the base placed so that its CoM lands on p_WG.
        q_guess = nominal_positions(manip, p_WB=np.zeros(3), R_WB=R_WB)
        guess_ctx = plant.CreateDefaultContext()
        plant.SetPositions(guess_ctx, q_guess)
        q_guess = nominal_positions(
            manip, p_WB=np.asarray(p_WG) - plant.CalcCenterOfMassPositionInWorld(guess_ctx),
            R_WB=R_WB)
    prog.SetInitialGuess(q, q_guess)
    prog.SetInitialGuess(r, p_WG)
    result = Solve(prog)
    q_sol = _newton_polish(manip, result.GetSolution(q), p_WG=p_WG, R_WB=R_WB, p_WE=p_WE,
                           R_WE=R_WE, q_j=q_j)
    residual = configuration_residual(manip, q_sol, p_WG=p_WG, R_WB=R_WB, p_WE=p_WE,
                                      R_WE=R_WE, q_j=q_j)
    failed = residual.violations(tol_m=tolerance, tol_rad=tolerance,
                                 joint_limits=respect_joint_limits)
    if failed:
        raise UnreachablePose(
            "no configuration meets the requested pose; failing constraints: "
            + ", ".join(failed) + f" (solver: {result.get_solver_id().name()}, "
            f"{result.get_solution_result()}). Move the end effector closer to the "
            "vehicle's CoM offset the arm supports (its nominal posture's).")
    return q_sol


def _newton_polish(manip: AerialManipulator, q: np.ndarray, *, p_WG, R_WB, p_WE, R_WE, q_j,
                   iterations: int = 8, context=None) -> np.ndarray:
    """Newton steps on the square system (CoM and the task in base position and joints), with
    the base attitude set exactly: IK's orientation constraints are only met to ~1e-5 rad.
    ``context``: a context of ``manip.plant`` to work in (else a new one); on return it holds
    the result's positions."""
    plant = manip.plant
    ctx = plant.CreateDefaultContext() if context is None else context
    plant.SetPositions(ctx, q)
    p_WB = plant.EvalBodyPoseInWorld(ctx, manip.base_body).translation()
    q = nominal_positions(manip, p_WB=p_WB, R_WB=R_WB) if manip.floating_base == "quaternion" \
        else q.copy()
    q[manip.arm_position_indices] = plant.GetPositions(ctx)[manip.arm_position_indices]
    if manip.floating_base != "quaternion":
        plant.SetPositions(ctx, q)
        manip.base_joint.set_angles(ctx, _rpy(R_WB))
        q = plant.GetPositions(ctx)
    base_q = manip.base_position_indices[-3:]  # translation coordinates
    cols = np.concatenate([manip.base_velocity_indices[3:], manip.arm_velocity_indices])
    unknowns = np.concatenate([base_q, manip.arm_position_indices])
    for _ in range(iterations):
        plant.SetPositions(ctx, q)
        r = np.concatenate([plant.CalcCenterOfMassPositionInWorld(ctx) - p_WG,
                            task_residual(manip, ctx, q, p_WE, R_WE, q_j)])
        if np.abs(r).max() < 1e-13:
            break
        step = np.linalg.lstsq(_com_task_jacobian(manip, ctx)[:, cols], r, rcond=None)[0]
        q[unknowns] -= step
    plant.SetPositions(ctx, q)
    return q


def _com_task_jacobian(manip: AerialManipulator, ctx) -> np.ndarray:
    """[J_g; J_y] (3 + n, nv) at ``ctx``: the CoM's translational Jacobian over the task's
    rows of [v_E (World); w_E (World); q_j_dot] (the rows of (17)'s J_y)."""
    plant, task = manip.plant, _task(manip)
    world, kV = plant.world_frame(), JacobianWrtVariable.kV
    J = np.zeros((3 + task.n, plant.num_velocities()))
    J[0:3] = plant.CalcJacobianCenterOfMassTranslationalVelocity(ctx, kV, world, world)
    Jv = plant.CalcJacobianSpatialVelocity(ctx, kV, manip.end_effector_frame, np.zeros(3),
                                           world, world)
    J6 = np.vstack([Jv[3:], Jv[:3]])  # [v_E; w_E]
    for i, row in enumerate(task.rows):
        if row < POSE_ROWS:
            J[3 + i] = J6[row]
        else:
            J[3 + i, task.joint_velocities[row - POSE_ROWS]] = 1.0
    return J


def kinematic_J3(manip: AerialManipulator, ctx) -> np.ndarray:
    """J_3 of (17), (n, n), at the positions in ``ctx``, from kinematics alone.

    J = J_y T^-1 and T^-1's last n columns are Z^T = [0; -A_q; E_n] (Section II: J_g Z^T = 0,
    J_bw Z^T = 0 and N Z^T = (Z M Z^T)^-1 Z M Z^T = E_n), so J_3 = J_y Z^T: the task's rate
    when the joints move while the base translates to hold the CoM and keeps its attitude.
    No mass matrix: about a tenth of the cost of :class:`~.decoupling.DecoupledDynamics`
    (equal to its J_3 to round-off; tests/simulation/test_feasibility.py).
    """
    J = _com_task_jacobian(manip, ctx)
    lin, arm = manip.base_velocity_indices[3:], manip.arm_velocity_indices
    A_q = J[0:3, arm]
    return J[3:, arm] - J[3:, lin] @ A_q


def track_configuration(manip: AerialManipulator, q_guess: np.ndarray, context, *, p_WG,
                        R_WB, p_WE, R_WE, q_j=(), tolerance: float = 1e-6) -> np.ndarray | None:
    """The configuration of :func:`solve_configuration` by Newton steps alone from a nearby
    ``q_guess`` (e.g. the solution at the previous sample of a reference), in ``context``
    (left at the result); None if they do not meet the targets to ``tolerance`` (m, rad),
    and the caller falls back to :func:`solve_configuration`. A few Newton steps cost about
    a tenth of the full solve (no optimisation program is built)."""
    q = _newton_polish(manip, np.asarray(q_guess, dtype=float), p_WG=p_WG, R_WB=R_WB,
                       p_WE=p_WE, R_WE=R_WE, q_j=np.asarray(q_j, dtype=float),
                       context=context)
    plant = manip.plant
    r = np.concatenate([plant.CalcCenterOfMassPositionInWorld(context) - p_WG,
                        task_residual(manip, context, q, p_WE, R_WE, q_j)])
    return q if np.all(np.isfinite(q)) and np.abs(r).max() <= tolerance else None


def _rpy(R: np.ndarray) -> np.ndarray:
    return RollPitchYaw(RotationMatrix(R)).vector()


def configuration_residual(manip: AerialManipulator, q: np.ndarray, *, p_WG: np.ndarray,
                           R_WB: np.ndarray, p_WE: np.ndarray, R_WE: np.ndarray,
                           q_j=()) -> ConfigurationResidual:
    """How far ``q`` is from the CoM, base attitude and task of :func:`solve_configuration`
    (the end effector's rows only as far as the task holds them)."""
    plant = manip.plant
    task = _task(manip)
    ctx = plant.CreateDefaultContext()
    plant.SetPositions(ctx, q)
    R_actual = plant.EvalBodyPoseInWorld(ctx, manip.base_body).rotation()
    lower, upper = manip.arm_position_limits()
    q_arm = q[manip.arm_position_indices]
    residual = task_residual(manip, ctx, q, p_WE, R_WE, q_j)
    rows = np.array(task.rows)
    X_WE = manip.end_effector_frame.CalcPoseInWorld(ctx)

    def angle(Ra: RotationMatrix, Rb: np.ndarray) -> float:
        return float(Ra.InvertAndCompose(RotationMatrix(Rb)).ToAngleAxis().angle())

    orientation = (angle(X_WE.rotation(), R_WE) if task.has_full_orientation
                   else float(np.linalg.norm(residual[(rows >= 3) & (rows < POSE_ROWS)])))
    return ConfigurationResidual(
        com=float(np.linalg.norm(plant.CalcCenterOfMassPositionInWorld(ctx) - p_WG)),
        ee_position=float(np.linalg.norm(residual[rows < 3])),
        ee_orientation=orientation,
        base_orientation=angle(R_actual, R_WB),
        joints=float(np.max(np.abs(residual[rows >= POSE_ROWS]), initial=0.0)),
        joint_limits=float(np.max(np.maximum(lower - q_arm, q_arm - upper), initial=0.0)))


def nominal_positions(manip: AerialManipulator, p_WB: np.ndarray, R_WB: np.ndarray,
                      ) -> np.ndarray:
    """Generalized positions with the base at ``(p_WB, R_WB)`` and the arm at its nominal
    hover posture (docs/models.md)."""
    plant = manip.plant
    ctx = plant.CreateDefaultContext()
    if manip.floating_base == "quaternion":
        plant.SetFreeBodyPose(ctx, manip.base_body, RigidTransform(RotationMatrix(R_WB), p_WB))
    else:
        _set_rpy_base(manip, ctx, p_WB, R_WB)
    q = plant.GetPositions(ctx)
    q[manip.arm_position_indices] = manip.q_nominal_arm()
    return q


def _set_rpy_base(manip: AerialManipulator, ctx, p_WB, R_WB) -> None:
    joint = manip.base_joint
    joint.SetTranslation(ctx, p_WB)
    joint.set_angles(ctx, _rpy(R_WB))
