"""Hover equilibria: a configuration realising a task at rest (Drake's
``InverseKinematics`` through :func:`aerial_drake.dynamics.equilibrium.solve_configuration`)
and the inputs that hold it (:func:`hover_equilibrium`, :func:`hover_inputs`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from pydrake.math import RollPitchYaw, RotationMatrix

from aerial_drake.dynamics.equilibrium import UnreachablePose, solve_configuration
from aerial_drake.robots.models import (
    AerialManipulator,
    make_plant,
    nominal_end_effector_offset,
    set_nominal_posture,
)
from aerial_drake.trajectories.reference import ReferenceSample


# --- Hover equilibrium ----------------------------------------------------------------------
@dataclass(frozen=True)
class HoverEquilibrium:
    """A hover: the robot at rest with the CoM at ``p_WG``, the base level with heading
    ``yaw``, the end effector at ``(p_WE, R_WE)`` and the task's joints at ``q_j``, and the
    inputs that
    hold it (static balance ``F = g(q)`` through ``[J_b^T Q^T]``)."""

    model: AerialManipulator  # the plant ``q`` belongs to (quaternion or rpy base)
    q: np.ndarray
    p_WG: np.ndarray  # m, World
    yaw: float  # rad, heading of the base x axis about World z
    p_WE: np.ndarray  # m, World
    R_WE: np.ndarray
    q_j: np.ndarray  # rad, the task's joint components (task order)
    thrust: float  # f (N), along the base z axis
    body_torques: np.ndarray  # mu (N m), base frame
    joint_torques: np.ndarray  # tau (N m)
    horizontal_force_residual: float  # |base-frame x, y force| of the static balance (N)

    @property
    def R_WB(self) -> np.ndarray:
        return RotationMatrix.MakeZRotation(self.yaw).matrix()

    @property
    def state(self) -> np.ndarray:
        """``[q; v]`` with ``v = 0``."""
        return np.concatenate([self.q, np.zeros(self.model.plant.num_velocities())])

    @property
    def inputs(self) -> np.ndarray:
        """``[f, mu (3), tau (n)]``, the command layout of the controller."""
        return np.concatenate([[self.thrust], self.body_torques, self.joint_torques])

    def reference(self) -> ReferenceSample:
        """The constant reference that has this hover as its equilibrium: ``x_d = p_WG`` with
        zero derivatives, the task at ``(p_WE, R_WE, q_j)`` at rest, ``b1d`` along the
        heading."""
        z3 = np.zeros(3)
        b1d = np.zeros((3, 3))
        b1d[0] = [math.cos(self.yaw), math.sin(self.yaw), 0.0]
        return ReferenceSample(
            com=np.vstack([self.p_WG, np.zeros((4, 3))]), p_ed=self.p_WE.copy(), v_ed=z3,
            a_ed=z3, R_ed=self.R_WE.copy(), w_ed=z3, dw_ed=z3, q_jd=self.q_j.copy(),
            q_jd_dot=np.zeros_like(self.q_j), q_jd_ddot=np.zeros_like(self.q_j), b1d=b1d)

    def summary(self) -> dict:
        return {
            "p_WG_m": self.p_WG.tolist(), "yaw_rad": self.yaw, "p_WE_m": self.p_WE.tolist(),
            "rpy_WE_rad": RollPitchYaw(RotationMatrix(self.R_WE)).vector().tolist(),
            "task_joints_rad": self.q_j.tolist(), "q": self.q.tolist(),
            "base_position_coordinates": self.model.floating_base,
            "thrust_N": self.thrust, "body_torques_Nm": self.body_torques.tolist(),
            "joint_torques_Nm": self.joint_torques.tolist(),
            "horizontal_force_residual_N": self.horizontal_force_residual,
        }


def hover_inputs(model: AerialManipulator, q: np.ndarray) -> tuple[float, np.ndarray,
                                                                       np.ndarray, float]:
    """The inputs that hold configuration ``q`` at rest: ``g(q) = J_b^T [f e3; mu] + Q^T tau``.

    The base's generalized forces are the World torque and force at the base origin (design
    note 1), so ``mu = R^T g[0:3]``, ``[f_x, f_y, f] = R^T g[3:6]``, ``tau = g[arm]``. Returns
    ``(f, mu, tau, |(f_x, f_y)|)``; the last is zero only when the base is level (a helicopter
    cannot push sideways).
    """
    plant = model.plant
    ctx = plant.CreateDefaultContext()
    plant.SetPositions(ctx, q)
    g = -plant.CalcGravityGeneralizedForces(ctx)
    R = plant.EvalBodyPoseInWorld(ctx, model.base_body).rotation().matrix()
    base = model.base_velocity_indices
    mu = R.T @ g[base[:3]]
    force_b = R.T @ g[base[3:]]
    tau = g[model.arm_velocity_indices]
    return float(force_b[2]), mu, tau, float(np.linalg.norm(force_b[:2]))


def hover_equilibrium(p_WG: np.ndarray, p_WE: np.ndarray, R_WE: np.ndarray | None = None, *,
                      yaw: float = 0.0, q_j=None,
                      model: AerialManipulator | None = None,
                      q_guess: np.ndarray | None = None) -> HoverEquilibrium:
    """The hover with the CoM at ``p_WG`` (m), the base level with heading ``yaw`` (rad), the
    end effector at ``p_WE`` (m) with orientation ``R_WE`` (default: the heading's yaw) and
    the task's joint components at ``q_j`` (rad; default: the nominal posture's), on
    ``model`` (default: the paper's rigid model with an rpy base).

    Raises:
        UnreachablePose: no configuration realises the pose; the message names the failing
            constraints (CoM, end-effector position or orientation, joints) and what was asked.
    """
    model = model if model is not None else make_plant("rigid", floating_base="rpy")
    q_j = model.task_joint_nominal() if q_j is None else np.asarray(q_j, dtype=float)
    p_WG = np.asarray(p_WG, dtype=float).copy()
    p_WE = np.asarray(p_WE, dtype=float).copy()
    R_WB = RotationMatrix.MakeZRotation(yaw).matrix()
    if isinstance(R_WE, RotationMatrix):
        R_WE = R_WE.matrix()
    R_WE = R_WB if R_WE is None else np.asarray(R_WE, dtype=float)
    try:
        q = solve_configuration(model, p_WG=p_WG, R_WB=R_WB, p_WE=p_WE, R_WE=R_WE, q_j=q_j,
                                q_guess=q_guess)
    except UnreachablePose as err:
        raise UnreachablePose(
            f"no hover equilibrium with the CoM at {p_WG.round(4).tolist()} m, heading "
            f"{yaw:g} rad, end effector at {p_WE.round(4).tolist()} m (rpy "
            f"{RollPitchYaw(RotationMatrix(R_WE)).vector().round(4).tolist()} rad), "
            f"task joints {np.round(q_j, 4).tolist()} rad: {err}") from None
    f, mu, tau, residual = hover_inputs(model, q)
    return HoverEquilibrium(model=model, q=q, p_WG=p_WG, yaw=float(yaw), p_WE=p_WE,
                            R_WE=np.array(R_WE), q_j=q_j, thrust=f, body_torques=mu,
                            joint_torques=tau, horizontal_force_residual=residual)


#: How far the "turned" hover moves the end effector from its nominal offset (heading frame,
#: m): for the paper's robot to (0.35, 0.1, -0.55) m from the CoM.
TURNED_MOVE = np.array([0.05, 0.1, 0.05])


def nominal_end_effector_rotation(model: AerialManipulator) -> np.ndarray:
    """R_BE at the nominal posture (the vehicle level): the end effector's nominal
    orientation in the vehicle frame (the identity, to round-off, for the paper's robot)."""
    plant = model.plant
    ctx = plant.CreateDefaultContext()
    set_nominal_posture(model, ctx)
    R_WB = plant.EvalBodyPoseInWorld(ctx, model.base_body).rotation()
    R_WE = model.end_effector_frame.CalcPoseInWorld(ctx).rotation()
    R = R_WB.inverse().multiply(R_WE).matrix()
    # Round-off (1e-16) of the design pose kept out of the equilibria.
    return np.where(np.abs(R) < 1e-12, 0.0, np.where(np.abs(np.abs(R) - 1.0) < 1e-12,
                                                     np.sign(R), R))


def default_equilibria(model: AerialManipulator | None = None) -> dict[str, HoverEquilibrium]:
    """Two hovers used by the analysis and the tests: ``"nominal"`` (the end effector at the
    model's nominal offset from the CoM, :func:`nominal_end_effector_offset`, and its nominal
    orientation; for the paper's robot 0.3 m ahead and 0.6 m below, R_WE = I, the mount's
    design pose) and ``"turned"`` (heading 0.7 rad, the end effector moved by
    ``TURNED_MOVE`` from nominal in the heading frame and tilted, the task's joints 0.2 rad
    off nominal)."""
    model = model if model is not None else make_plant("rigid", floating_base="rpy")
    p_WG = np.array([0.0, 0.0, 2.0])
    yaw = 0.7
    R_yaw = RotationMatrix.MakeZRotation(yaw)
    turned_R_WE = (R_yaw @ RotationMatrix(RollPitchYaw(0.3, -0.2, 0.1))).matrix()
    nominal = nominal_end_effector_offset(model)
    R_nominal = nominal_end_effector_rotation(model)
    turned_R_WE = turned_R_WE @ R_nominal
    return {
        "nominal": hover_equilibrium(p_WG, p_WG + nominal, R_nominal, model=model),
        "turned": hover_equilibrium(p_WG, p_WG + R_yaw.matrix() @ (nominal + TURNED_MOVE),
                                    turned_R_WE, yaw=yaw,
                                    q_j=model.task_joint_nominal() + 0.2, model=model),
    }


