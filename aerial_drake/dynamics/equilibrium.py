"""Configurations that realise a task: Drake's InverseKinematics on the CoM, base attitude,
end-effector pose and q3, and the hover inputs that hold such a configuration."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
from pydrake.multibody.inverse_kinematics import ComPositionConstraint, InverseKinematics
from pydrake.multibody.tree import JacobianWrtVariable
from pydrake.solvers import Solve

from aerial_drake.dynamics.decoupling import vee
from aerial_drake.robots.models import AerialManipulator


class UnreachablePose(ValueError):
    """The requested CoM / end-effector pose / q3 cannot be realised by the model."""


@dataclass(frozen=True)
class ConfigurationResidual:
    com: float  # m
    ee_position: float  # m
    ee_orientation: float  # rad
    base_orientation: float  # rad
    q3: float  # rad
    joint_limits: float  # rad beyond the arm's position limits (0 inside)

    def violations(self, tol_m: float, tol_rad: float, joint_limits: bool = True) -> list[str]:
        """Names of the constraints violated beyond the tolerances, with by how much."""
        failed = []
        checks = [("CoM position", self.com, tol_m),
                  ("end-effector position", self.ee_position, tol_m),
                  ("end-effector orientation", self.ee_orientation, tol_rad),
                  ("base orientation", self.base_orientation, tol_rad), ("q3", self.q3, tol_rad)]
        if joint_limits:
            checks.append(("arm joint limits", self.joint_limits, tol_rad))
        for name, value, tol in checks:
            if not value <= tol:
                failed.append(f"{name} (off by {value:.3g})")
        return failed


def solve_configuration(manip: AerialManipulator, *, p_WG: np.ndarray, R_WB: np.ndarray,
                        p_WE: np.ndarray, R_WE: np.ndarray, q3: float,
                        q_guess: np.ndarray | None = None, tolerance: float = 1e-6,
                        respect_joint_limits: bool = True) -> np.ndarray:
    """Generalized positions with the system CoM at ``p_WG``, the base at orientation ``R_WB``,
    the end-effector frame at ``(p_WE, R_WE)`` and joint 3 at ``q3``.

    Ten equations in ten unknowns (base position, seven joints): the solution is locally
    unique. Raises :class:`UnreachablePose` naming the constraints that the solution misses by
    more than ``tolerance`` (m or rad): the arm's joint limits among them unless
    ``respect_joint_limits`` is False (the continuous simulation does not enforce them, and
    the paper's task leaves them; docs/models.md).
    """
    plant = manip.plant
    ik = InverseKinematics(plant, with_joint_limits=respect_joint_limits)
    q = ik.q()
    prog = ik.get_mutable_prog()
    world = plant.world_frame()
    ik.AddOrientationConstraint(world, RotationMatrix(R_WB), manip.base_body.body_frame(),
                                RotationMatrix(), 0.0)
    ik.AddPositionConstraint(manip.end_effector_frame, np.zeros(3), world, p_WE, p_WE)
    ik.AddOrientationConstraint(world, RotationMatrix(R_WE), manip.end_effector_frame,
                                RotationMatrix(), 0.0)
    r = prog.NewContinuousVariables(3, "p_WG")
    prog.AddConstraint(ComPositionConstraint(plant, None, world, ik.context()),
                       np.concatenate([q, r]))
    prog.AddBoundingBoxConstraint(p_WG, p_WG, r)
    i3 = manip.arm_joints[2].position_start()
    prog.AddBoundingBoxConstraint(q3, q3, q[i3])
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
                           R_WE=R_WE, q3=q3)
    residual = configuration_residual(manip, q_sol, p_WG=p_WG, R_WB=R_WB, p_WE=p_WE,
                                      R_WE=R_WE, q3=q3)
    failed = residual.violations(tol_m=tolerance, tol_rad=tolerance,
                                 joint_limits=respect_joint_limits)
    if failed:
        raise UnreachablePose(
            "no configuration meets the requested pose; failing constraints: "
            + ", ".join(failed) + f" (solver: {result.get_solver_id().name()}, "
            f"{result.get_solution_result()}). Move the end effector closer to the "
            "helicopter's CoM offset the model supports (docs/models.md).")
    return q_sol


def _newton_polish(manip: AerialManipulator, q: np.ndarray, *, p_WG, R_WB, p_WE, R_WE, q3,
                   iterations: int = 8) -> np.ndarray:
    """Newton steps on the square system (CoM, EE pose, q3 in base position and joints), with
    the base attitude set exactly: IK's orientation constraints are only met to ~1e-5 rad."""
    plant = manip.plant
    ctx = plant.CreateDefaultContext()
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
    i3 = manip.arm_joints[2]
    world, frame = plant.world_frame(), manip.end_effector_frame
    kV = JacobianWrtVariable.kV
    for _ in range(iterations):
        plant.SetPositions(ctx, q)
        X_WE = frame.CalcPoseInWorld(ctx)
        r = np.concatenate([
            plant.CalcCenterOfMassPositionInWorld(ctx) - p_WG,
            X_WE.translation() - p_WE,
            vee(X_WE.rotation().matrix() @ np.asarray(R_WE).T),
            [q[i3.position_start()] - q3]])
        if np.abs(r).max() < 1e-13:
            break
        J = np.zeros((10, plant.num_velocities()))
        J[0:3] = plant.CalcJacobianCenterOfMassTranslationalVelocity(ctx, kV, world, world)
        Jv = plant.CalcJacobianSpatialVelocity(ctx, kV, frame, np.zeros(3), world, world)
        J[3:6], J[6:9] = Jv[3:], Jv[:3]
        J[9, i3.velocity_start()] = 1.0
        step = np.linalg.lstsq(J[:, cols], r, rcond=None)[0]
        q[unknowns] -= step
    return q


def _rpy(R: np.ndarray) -> np.ndarray:
    return RollPitchYaw(RotationMatrix(R)).vector()


def configuration_residual(manip: AerialManipulator, q: np.ndarray, *, p_WG: np.ndarray,
                           R_WB: np.ndarray, p_WE: np.ndarray, R_WE: np.ndarray,
                           q3: float) -> ConfigurationResidual:
    plant = manip.plant
    ctx = plant.CreateDefaultContext()
    plant.SetPositions(ctx, q)
    X_WE = manip.end_effector_frame.CalcPoseInWorld(ctx)
    R_actual = plant.EvalBodyPoseInWorld(ctx, manip.base_body).rotation()
    lower, upper = manip.arm_position_limits()
    q_arm = q[manip.arm_position_indices]

    def angle(Ra: RotationMatrix, Rb: np.ndarray) -> float:
        return float(Ra.InvertAndCompose(RotationMatrix(Rb)).ToAngleAxis().angle())

    return ConfigurationResidual(
        com=float(np.linalg.norm(plant.CalcCenterOfMassPositionInWorld(ctx) - p_WG)),
        ee_position=float(np.linalg.norm(X_WE.translation() - p_WE)),
        ee_orientation=angle(X_WE.rotation(), R_WE),
        base_orientation=angle(R_actual, R_WB),
        q3=abs(float(q[manip.arm_joints[2].position_start()]) - q3),
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
