"""The baselines as one Drake LeafSystem with the paper controller's ports
(:mod:`aerial_drake.control.interface`): :mod:`.vehicle` for ``[f, mu]``, :mod:`.arm` for
``tau``, on the controller's rigid model of the plant.

``uncoupled`` and ``static_compensation`` differ in one term: the latter adds the arm's
static moment about the body's centre of mass (:func:`.vehicle.static_arm_moment`) to the
body torques. Sampled (``period`` > 0) they hold their command between samples exactly as
:class:`aerial_drake.control.controller.DecoupledController` does.
"""

from __future__ import annotations

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import Frame, JacobianWrtVariable, RigidBody
from pydrake.systems.framework import Context, LeafSystem, ValueProducer

from aerial_drake.control.baselines.arm import fixed_base_task_torque
from aerial_drake.control.baselines.params import BASELINE_TYPES, BaselineParams
from aerial_drake.control.baselines.vehicle import (
    body_reference,
    geometric_vehicle_law,
    static_arm_moment,
)
from aerial_drake.control.controller import (
    NONFINITE_STATE,
    _at_time,
    _ControllerPorts,
    task_jacobian,
)
from aerial_drake.control.interface import error_diagnostics
from aerial_drake.control.law import (
    AssumptionViolation,
    GainMatrices,
    Gains,
    diagnostics_size,
    task_error,
)
from aerial_drake.robots.task import TaskLayout
from aerial_drake.trajectories.reference import (
    COM_REFERENCE_SIZE,
    HEADING_REFERENCE_SIZE,
    task_reference_size,
    unpack_com_reference,
    unpack_heading_reference,
    unpack_task_reference,
)


class BaselineController(_ControllerPorts, LeafSystem):
    """``uncoupled`` or ``static_compensation`` (docs/baselines.md) on ``plant``, the
    controller's rigid model.

    Args:
        plant, base_body, end_effector_frame, task: the model and its task (as
            :class:`~aerial_drake.control.controller.DecoupledController`).
        gains: Table II's gains: K_x, D_x for the body position, k_R, k_w for its attitude,
            K_y, K_z for the arm's task (``Lambda2_bar`` unused: the vehicle's inertia is).
        kind: one of :data:`BASELINE_TYPES`.
        body_offset_H: the CoM's offset from the body in the heading frame that the body's
            reference keeps (:func:`.vehicle.body_reference`).
        params: :class:`BaselineParams`.
        period: sampling period (s); 0 for continuous feedback.
    """

    def __init__(self, plant: MultibodyPlant, base_body: RigidBody, end_effector_frame: Frame,
                 task: TaskLayout, gains: Gains, *,
                 kind: str, body_offset_H: np.ndarray, params: BaselineParams | None = None,
                 period: float = 0.0):
        super().__init__()
        if kind not in BASELINE_TYPES:
            raise ValueError(f"unknown baseline '{kind}'; valid: {BASELINE_TYPES}")
        if not period >= 0.0:
            raise ValueError(f"period must be >= 0 (s); got {period}")
        self.kind = kind
        self._params = (params or BaselineParams()).validate()
        self._plant, self._base, self._frame = plant, base_body, end_effector_frame
        self._ctx = plant.CreateDefaultContext()
        nv = plant.num_velocities()
        self._n = nv - 6
        self._K = GainMatrices.from_gains(gains, n_task=self._n)
        self._task = task
        self._arm_v = np.arange(6, nv)
        self._offset_H = np.asarray(body_offset_H, dtype=float)
        self._m = float(plant.CalcTotalMass(self._ctx))
        self._g = float(-plant.gravity_field().gravity_vector()[2])
        inertia = np.asarray(self._params.vehicle_inertia, dtype=float)
        if inertia.size:
            self._J_v = np.diag(inertia)
        else:
            I_B = base_body.CalcSpatialInertiaInBodyFrame(self._ctx)
            self._J_v = I_B.CalcRotationalInertia().CopyToFullMatrix3()
        self._period = float(period)
        self.evaluations = 0
        nx = plant.num_positions() + nv
        self._state_port = self.DeclareVectorInputPort("state", nx)
        self._ref_ports = tuple(self.DeclareVectorInputPort(name, size) for name, size in (
            ("com_reference", COM_REFERENCE_SIZE),
            ("task_reference", task_reference_size(task.n_joints)),
            ("heading_reference", HEADING_REFERENCE_SIZE)))
        sizes = (4 + self._n, diagnostics_size(self._n))
        if self._period > 0.0:
            self._held = self._declare_held_outputs(sizes, self._sample)
            return
        self._solution = self.DeclareCacheEntry(
            description="baseline law", value_producer=ValueProducer(
                allocate=AbstractValue.Make(object()).Clone, calc=self._calc_solution),
            prerequisites_of_calc={self.all_input_ports_ticket(), self.time_ticket()})
        for i, (name, size) in enumerate(zip(("command", "diagnostics"), sizes)):
            self.DeclareVectorOutputPort(
                name, size, lambda c, o, i=i: o.SetFromVector(self._solution.Eval(c)[i]),
                prerequisites_of_calc={self._solution.ticket()})

    # --- The law ------------------------------------------------------------------------
    def evaluate(self, x: np.ndarray, com: np.ndarray, task: np.ndarray, heading: np.ndarray,
                 ) -> tuple[np.ndarray, np.ndarray]:
        """``(command, diagnostics)`` at state ``x`` and the packed references.

        Raises:
            FloatingPointError: a non-finite state.
            AssumptionViolation: the arm's task Jacobian is singular, or |F| vanishes.
        """
        if not np.all(np.isfinite(x)):
            raise FloatingPointError(NONFINITE_STATE)
        self.evaluations += 1
        plant, ctx, K = self._plant, self._ctx, self._K
        world = plant.world_frame()
        plant.SetPositionsAndVelocities(ctx, x)
        X_WB = plant.EvalBodyPoseInWorld(ctx, self._base)
        V_WB = plant.EvalBodySpatialVelocityInWorld(ctx, self._base)
        R, p_b = X_WB.rotation().matrix(), X_WB.translation()
        w_b = R.T @ V_WB.rotational()
        x_g = plant.CalcCenterOfMassPositionInWorld(ctx)
        x_g_dot = plant.CalcCenterOfMassTranslationalVelocityInWorld(ctx)
        X_WE = self._frame.CalcPoseInWorld(ctx)
        com_ref = unpack_com_reference(com)
        t = unpack_task_reference(task)
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
        y_t, _ = task_error(X_WE.translation(), X_WE.rotation().matrix(), q_j, t.p_ed, t.R_ed,
                            t.q_jd, rows)
        y_d_dot, y_d_ddot = t.full_dot[rows], t.full_ddot[rows]
        arm = fixed_base_task_torque(J_a, bias, M_aa, h_a, y_dot, y_t, y_d_dot, y_d_ddot,
                                     K.K_y, K.K_z)
        if not arm.sigma_min > self._params.sigma_min_limit:
            raise AssumptionViolation(
                f"the arm's fixed-base task Jacobian is singular, sigma_min = "
                f"{arm.sigma_min:.3g} (limit {self._params.sigma_min_limit:g})")

        command = np.concatenate([[veh.f], mu, arm.tau])
        diagnostics = error_diagnostics(
            task=self._task, x_g=x_g, x_g_dot=x_g_dot, com_reference=com_ref,
            p_WE=X_WE.translation(), R_WE=X_WE.rotation().matrix(), q_j=q_j, p_ed=t.p_ed,
            R_ed=t.R_ed, q_jd=t.q_jd,
            R_b=R, R_d=veh.R_d, e_R=veh.e_R, w_tilde=veh.e_w, z_tilde=arm.s,
            sigma_min_J3=arm.sigma_min, f_d_norm=veh.F_norm, thrust_residual=[0.0, 0.0])
        return command, diagnostics

    def law_at(self, context: Context) -> tuple[np.ndarray, np.ndarray]:
        """``(command, diagnostics)`` at this system's ``context``; errors name the time."""
        try:
            return self.evaluate(self._state_port.Eval(context),
                                 *(p.Eval(context) for p in self._ref_ports))
        except (AssumptionViolation, FloatingPointError) as err:
            raise _at_time(err, context) from None

    # --- Sampling -------------------------------------------------------------------------
    def hold_sample(self, context: Context) -> None:
        """Run the law at ``context`` and hold it (as the periodic update does)."""
        if self._period <= 0.0:
            raise RuntimeError("hold_sample: this controller is continuous (period 0)")
        self._sample(context, context.get_mutable_discrete_state())

    def _sample(self, context: Context, discrete_state) -> None:
        command, diagnostics = self.law_at(context)
        discrete_state.set_value(self._held[0], command)
        discrete_state.set_value(self._held[1], diagnostics)

    def _calc_solution(self, context: Context, value: AbstractValue) -> None:
        value.set_value(self.law_at(context))

