"""The baselines as one controller on :class:`aerial_drake.control.base.ControllerBase` (the
paper controller's ports, hold and cache): :mod:`.vehicle` for ``[f, mu]``, :mod:`.arm` for
``tau``, on the controller's rigid model of the plant.

``uncoupled`` and ``static_compensation`` differ in one term: the latter adds the arm's
static moment about the body's centre of mass (:func:`.vehicle.static_arm_moment`) to the
body torques.
"""

from __future__ import annotations

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import Frame, JacobianWrtVariable, RigidBody

from aerial_drake.control.base import ControllerBase
from aerial_drake.control.baselines.arm import fixed_base_task_torque
from aerial_drake.control.baselines.params import BASELINE_TYPES, BaselineParams
from aerial_drake.control.baselines.vehicle import (
    body_reference,
    geometric_vehicle_law,
    static_arm_moment,
)
from aerial_drake.control.controller import task_jacobian
from aerial_drake.control.law import (
    AssumptionViolation,
    GainMatrices,
    Gains,
    rotation_angle,
    task_error,
)
from aerial_drake.robots.task import TaskLayout
from aerial_drake.trajectories.reference import (
    unpack_com_reference,
    unpack_heading_reference,
    unpack_task_reference,
)


def baseline_diagnostics_layout(n: int) -> tuple[tuple[str, int], ...]:
    """The baselines' diagnostics for a task of ``n`` rows: the vehicle's attitude errors
    ``e_R``, ``w_tilde`` (Lee et al.'s e_R, e_w) and ``base_attitude_error`` (angle of
    R_d^T R, R_d the attitude it commands), its desired force's norm ``f_d_norm``, the arm's
    task error ``y_tilde`` (:func:`aerial_drake.control.law.task_error`), sliding variable
    ``z_tilde`` (s of :func:`.arm.fixed_base_task_torque`) and ``sigma_min_arm``, the least
    singular value of its fixed-base task Jacobian."""
    return (("e_R", 3), ("w_tilde", 3), ("base_attitude_error", 1), ("f_d_norm", 1),
            ("y_tilde", n), ("z_tilde", n), ("sigma_min_arm", 1))


class BaselineController(ControllerBase):
    """``uncoupled`` or ``static_compensation`` (docs/baselines.md) on ``plant``, the
    controller's rigid model.

    Args:
        plant, base_body, end_effector_frame, task: the model and its task (as
            :class:`~aerial_drake.control.controller.DecoupledController`).
        gains: Table II's gains: K_x, D_x for the body position, k_R, k_w for its attitude,
            K_y, K_z for the arm's task (``Lambda2_bar`` unused: the assumed inertia is).
        kind: one of :data:`BASELINE_TYPES`.
        body_offset_H: the CoM's offset from the body in the heading frame that the body's
            reference keeps (:func:`.vehicle.body_reference`).
        locked_inertia: the inertia (3, 3) the vehicle law assumes when
            ``params.vehicle_inertia`` is empty: the whole robot's, locked at the reference
            configuration of t = 0, about its CoM (:func:`.tuning.locked_inertia`).
        params: :class:`BaselineParams`.
        period: sampling period (s); 0 for continuous feedback.
    """

    def __init__(self, plant: MultibodyPlant, base_body: RigidBody, end_effector_frame: Frame,
                 task: TaskLayout, gains: Gains, *,
                 kind: str, body_offset_H: np.ndarray, locked_inertia: np.ndarray | None = None,
                 params: BaselineParams | None = None, period: float = 0.0):
        if kind not in BASELINE_TYPES:
            raise ValueError(f"unknown baseline '{kind}'; valid: {BASELINE_TYPES}")
        nv = plant.num_velocities()
        super().__init__(plant, task, period=period,
                         diagnostics_layout=baseline_diagnostics_layout(nv - 6))
        self.kind = kind
        self._params = (params or BaselineParams()).validate()
        self._plant, self._base, self._frame = plant, base_body, end_effector_frame
        self._ctx = plant.CreateDefaultContext()
        self._K = GainMatrices.from_gains(gains, n_task=nv - 6)
        self._task = task
        self._arm_v = np.arange(6, nv)
        self._offset_H = np.asarray(body_offset_H, dtype=float)
        self._m = float(plant.CalcTotalMass(self._ctx))
        self._g = float(-plant.gravity_field().gravity_vector()[2])
        inertia = np.asarray(self._params.vehicle_inertia, dtype=float)
        if inertia.size:
            self._J_v = np.diag(inertia)
        elif locked_inertia is not None and np.shape(locked_inertia) == (3, 3):
            self._J_v = np.array(locked_inertia, dtype=float)
        else:
            raise ValueError(
                "BaselineController needs the inertia its vehicle law assumes: pass "
                "locked_inertia (3, 3), e.g. baselines.tuning.locked_inertia(plant, base_body, "
                f"q) at the reference configuration of t = 0, or set "
                f"controller.baseline.vehicle_inertia; got locked_inertia={locked_inertia!r}")

    @property
    def assumed_inertia(self) -> np.ndarray:
        """The rotational inertia (3, 3, base frame, kg m^2) the vehicle law assumes."""
        return self._J_v.copy()

    # --- The law ------------------------------------------------------------------------
    def calc_command(self, t: float, x: np.ndarray, com: np.ndarray, task: np.ndarray,
                     heading: np.ndarray) -> tuple[np.ndarray, dict]:
        """The command at state ``x`` and the packed references, with the entries of
        :func:`baseline_diagnostics_layout`.

        Raises:
            AssumptionViolation: the arm's task Jacobian is singular, or |F| vanishes.
        """
        plant, ctx, K = self._plant, self._ctx, self._K
        world = plant.world_frame()
        plant.SetPositionsAndVelocities(ctx, x)
        X_WB = plant.EvalBodyPoseInWorld(ctx, self._base)
        V_WB = plant.EvalBodySpatialVelocityInWorld(ctx, self._base)
        R, p_b = X_WB.rotation().matrix(), X_WB.translation()
        w_b = R.T @ V_WB.rotational()
        x_g = plant.CalcCenterOfMassPositionInWorld(ctx)
        X_WE = self._frame.CalcPoseInWorld(ctx)
        com_ref = unpack_com_reference(com)
        ref = unpack_task_reference(task)
        b1d = unpack_heading_reference(heading)

        # The vehicle alone (Lee et al.), on its own body position and attitude.
        body_ref = body_reference(com_ref, b1d, self._offset_H)
        veh = geometric_vehicle_law(self._m, self._g, self._J_v, body_ref, b1d, p_b,
                                    V_WB.translational(), R, w_b, K.K_x, K.D_x, K.k_R, K.k_w)
        if not veh.F_norm > 1.0:
            raise AssumptionViolation(f"the vehicle's desired force vanishes, |F| = "
                                      f"{veh.F_norm:.3g} N")
        mu = veh.mu
        if self.kind == "static_compensation":
            mu = mu + static_arm_moment(self._m, self._g, x_g, p_b, R)

        # The arm on its fixed-base model: the base's velocity set to zero.
        v = x[plant.num_positions():]
        qdot = v[self._arm_v]
        v_fixed = np.zeros_like(v)
        v_fixed[self._arm_v] = qdot
        plant.SetVelocities(ctx, v_fixed)
        J = plant.CalcJacobianSpatialVelocity(ctx, JacobianWrtVariable.kV, self._frame,
                                              np.zeros(3), world, world)
        rows = list(self._task.rows)
        J_y, _ = task_jacobian(self._task, np.vstack([J[3:], J[:3]]), np.zeros((6, v.size)),
                               v.size)
        y_dot = J_y @ v  # the measured task velocity, World (as the paper's (17))
        A = plant.CalcBiasSpatialAcceleration(ctx, JacobianWrtVariable.kV, self._frame,
                                              np.zeros(3), world, world)
        J_a = J_y[:, self._arm_v]
        bias = np.concatenate([A.translational(), A.rotational(),
                               np.zeros(self._task.n_joints)])[rows]
        M_aa = plant.CalcMassMatrix(ctx)[np.ix_(self._arm_v, self._arm_v)]
        h_a = (plant.CalcBiasTerm(ctx) - plant.CalcGravityGeneralizedForces(ctx))[self._arm_v]
        q_j = x[list(self._task.joint_positions)]
        y_t, _ = task_error(X_WE.translation(), X_WE.rotation().matrix(), q_j, ref.p_ed, ref.R_ed,
                            ref.q_jd, rows)
        y_d_dot, y_d_ddot = ref.full_dot[rows], ref.full_ddot[rows]
        arm = fixed_base_task_torque(J_a, bias, M_aa, h_a, y_dot, y_t, y_d_dot, y_d_ddot,
                                     K.K_y, K.K_z)
        if not arm.sigma_min > self._params.sigma_min_limit:
            raise AssumptionViolation(
                f"the arm's fixed-base task Jacobian is singular, sigma_min = "
                f"{arm.sigma_min:.3g} (limit {self._params.sigma_min_limit:g})")

        command = np.concatenate([[veh.f], mu, arm.tau])
        return command, {"e_R": veh.e_R, "w_tilde": veh.e_w,
                         "base_attitude_error": rotation_angle(veh.R_d.T @ R),
                         "f_d_norm": veh.F_norm, "y_tilde": y_t, "z_tilde": arm.s,
                         "sigma_min_arm": arm.sigma_min}
