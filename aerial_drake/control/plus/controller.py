"""``paper_plus``: the paper's compiled law (10)-(22) with integral action (anti-windup) and
the vehicle-force feed-forward, by shaping the references it is handed
(:mod:`aerial_drake.control.plus.shaping`; docs/control.md, "paper_plus").

The law itself is the paper controller's (:class:`~aerial_drake.control.controller.
DecoupledController`'s ``evaluate_into``, the compiled kernel), unchanged: with every option
off, the command is the paper law's to the bit.
"""

from __future__ import annotations

import numpy as np
from pydrake.multibody.tree import JacobianWrtVariable
from pydrake.systems.framework import Context, InputPort

from aerial_drake.control.base import ControllerBase, at_time
from aerial_drake.control.controller import DecoupledController
from aerial_drake.control.gains import GainMatrices, Gains
from aerial_drake.control.law import (
    F_D_LIMIT,
    SIGMA_MIN_J3_LIMIT,
    AssumptionViolation,
    diagnostics_layout,
    diagnostics_slices,
)
from aerial_drake.control.plus.compensation import compensation
from aerial_drake.control.plus.params import PAPER_PLUS, PlusParams
from aerial_drake.control.plus.shaping import com_shift, shaped_references, task_shift
from aerial_drake.robots.models import AerialManipulator

#: The discrete state group of the integrators (after the base's command and diagnostics).
_INTEGRATOR = 2


def plus_diagnostics_layout(n: int) -> tuple[tuple[str, int], ...]:
    """The paper law's diagnostics (:func:`aerial_drake.control.law.diagnostics_layout`),
    then paper_plus's: the integral terms added to f_d (N) and to z_d, the force fed forward
    (N), whether integration was held at the sample (1) or not (0), the wrench
    compensation added to the vehicle moment (N m, body axes) and the arm torques, and the
    damping of J_3's inverse, lambda^2 / lambda_max^2 (0: exact inverse, 1: full damping;
    :meth:`~aerial_drake.control.law.SingularityRobust.damping_ratio`)."""
    return diagnostics_layout(n) + (
        ("com_integral_force", 3), ("task_integral_velocity", n),
        ("vehicle_force_feedforward", 3), ("integration_held", 1),
        ("compensation_moment", 3), ("compensation_torque", n), ("singularity_damping", 1))


class PaperPlusController(ControllerBase):
    """The paper's law with integral action and the vehicle-force feed-forward (module
    docstring). Sampled only: the integrators are discrete state at ``period``.

    Ports: the base's (:class:`~aerial_drake.control.base.ControllerBase`), and the optional
    input ``vehicle_force_estimate`` (3, N, World): an estimate of the external force on the
    vehicle, fed forward into f_d when ``params.vehicle_force_feedforward``; unconnected, it
    reads as zero (e.g. an observer's output can be wired to it); and the optional input
    ``generalized_force_estimate`` (nv, Drake's velocities): an estimate of the external
    generalized force, compensated when ``params.wrench_compensation``
    (:mod:`aerial_drake.control.plus.compensation`); unconnected, zero.

    The integrator state (discrete group 2, 9 + 2 n entries): the integrals s_x (3, m s) and
    s_y (n) of x~ and y~, and the rates the next sample's feed-forward uses, s_x' (3), s_x''
    (3) and s_y' (n). At each sample, after the law: if the command is inside
    ``limits`` on every channel, s += period * (x~, y~), clamped entrywise at the
    ``params`` bounds, and the rates are the increments' (x~, x~', y~ where not clamped);
    otherwise (conditional integration, anti-windup) s holds and the rates are zero.

    Args:
        model: the controller's rigid model (finalized, with its task).
        gains: Table II's gains.
        params: the ``controller.plus`` options (validated here for the model's task).
        limits: (lower, upper) of the applied command (:func:`aerial_drake.control.limits.
            command_limits`); infinite: no saturation.
        sigma_min_J3_limit, f_d_limit: the paper law's assumption checks.
        period: the sampling period (s), > 0.
        kernel: the paper law's compiled kernel, "exact" or "fast"
            (:class:`~aerial_drake.control.controller.DecoupledController`).
        extra_diagnostics: (name, size) pairs after paper_plus's, a subclass's own.
    """

    def __init__(self, model: AerialManipulator, gains: Gains, params: PlusParams,
                 limits: tuple[np.ndarray, np.ndarray], *,
                 sigma_min_J3_limit: float = SIGMA_MIN_J3_LIMIT, f_d_limit: float = F_D_LIMIT,
                 period: float = 1e-3, kernel: str = "exact",
                 extra_diagnostics: tuple[tuple[str, int], ...] = ()):
        task = model.task
        assert task is not None  # a finalized model
        if not period > 0:
            raise ValueError(f"controller.type {PAPER_PLUS} needs controller_period > 0 (its "
                             f"integrators are discrete state at that period); got {period}: "
                             "set controller_period, e.g. 0.001")
        n = task.n
        params.validate(n)
        super().__init__(model.plant, task, period=period,
                         diagnostics_layout=plus_diagnostics_layout(n) + extra_diagnostics)
        self._singularity = params.singularity()
        self._law = DecoupledController(
            model.plant, model.end_effector_frame, task, gains,
            sigma_min_J3_limit=sigma_min_J3_limit, f_d_limit=f_d_limit, period=period,
            singularity=self._singularity, kernel=kernel)
        self._force_port = self.DeclareVectorInputPort("vehicle_force_estimate", 3)
        plant = model.plant
        self._tau_port = self.DeclareVectorInputPort("generalized_force_estimate",
                                                     plant.num_velocities())
        # The plant's own context for the CoM Jacobian and the attitude the compensation
        # needs (the robot's instances only: an environment's welded bodies have no J_g).
        self._plant, self._plant_context = plant, plant.CreateDefaultContext()
        self._instances = list(model.model_instances)
        self._base = model.base_body
        self.DeclareDiscreteState(9 + 2 * n)  # group _INTEGRATOR (module constants)
        self._n, self._rows, self._h = n, task.rows, float(period)
        self._params = params
        self._integrates = params.integrates()
        K = GainMatrices.from_gains(gains, n_task=n)
        self._K_x, self._D_x, self._K_y = K.K_x, K.D_x, K.K_y
        self._k_x = np.asarray(params.com_gain(), float)
        self._k_y = np.asarray(params.task_gain(n), float)
        self._m = float(model.plant.CalcTotalMass(model.plant.CreateDefaultContext()))
        unstable = params.com_gain_error(self._m, self._K_x, self._D_x)
        if unstable:
            raise ValueError(unstable)
        # The integral states' bounds: |K_I,x s_x| / m <= com limit, |K_I,y s_y| <= task limit
        # (entries with a zero gain stay at zero).
        with np.errstate(divide="ignore"):
            self._bound = np.concatenate([
                np.where(self._k_x > 0, params.com_integral_limit * self._m / self._k_x, 0.0),
                np.where(self._k_y > 0, params.task_integral_limit / self._k_y, 0.0)])
        self._lower, self._upper = (np.asarray(a, float) for a in limits)
        self._slices = diagnostics_slices(list(self.diagnostics_layout))
        self._paper_size = sum(size for _, size in diagnostics_layout(n))
        # The integrator state, force and generalized force after the latest sample (for
        # evaluate).
        self._latest = (np.zeros(9 + 2 * n), np.zeros(3), np.zeros(plant.num_velocities()))

    @property
    def params(self) -> PlusParams:
        return self._params

    def get_vehicle_force_estimate_input_port(self) -> InputPort:
        return self._force_port

    def get_generalized_force_estimate_input_port(self) -> InputPort:
        return self._tau_port

    # --- The law on shaped references ---------------------------------------------------
    def _run(self, t: float, x: np.ndarray, com: np.ndarray, task: np.ndarray,
             heading: np.ndarray, state: np.ndarray, force: np.ndarray, tau_hat: np.ndarray,
             command: np.ndarray, diagnostics: np.ndarray) -> None:
        """The law at the integrator ``state``, fed-forward ``force`` and compensated
        ``tau_hat``, into ``command`` and ``diagnostics`` (the paper's entries, then the
        integral terms, the force and the compensation)."""
        n = self._n
        s_x, s_y = state[0:3], state[3:3 + n]
        rate_x, rate_x_dot, rate_y = state[3 + n:6 + n], state[6 + n:9 + n], state[9 + n:]
        d_com = com_shift(self._m, self._K_x, self._D_x, self._k_x, s_x, rate_x, rate_x_dot,
                          force)
        # No F^ in the task's feed-forward: (20)'s J_1 x_g'' misses F^ / m, but the push also
        # drives rho and w_b, and the end effector's whole extra acceleration, J M^-1 [0; F^;
        # 0], is about a tenth of J_1 F^ / m (the arm's joints isolate it: on the helicopter
        # at hover, 50 N along y gives 0.10 m/s^2, F^ / m 0.91). Measured: with J_1 F^ / m
        # the end effector errs 12.1 mm under a 50 N push fed forward, without it 0.92 mm
        # (docs/control.md, "Push rejection").
        # With the wrench compensated the model's x_g'' in (20) gets the estimated force too
        # (observer-corrected accelerations throughout; docs/control.md, "Wrench
        # compensation"); alone, that term made matters worse (the comment above).
        # F^ here is r's force rows (the total external force, unfiltered by the split into
        # the vehicle's and the end effector's wrenches that external_force_estimate is):
        # the same force as compensation() uses, so (20) and the compensation agree.
        accel = tau_hat[3:6] / self._m if self._params.wrench_compensation else np.zeros(3)
        e1, e2 = task_shift(self._K_y, self._k_y, s_y, rate_y, self._rows, accel)
        com, task = shaped_references(com, task, d_com, e1, e2, self._rows)
        self._law.evaluate_into(t, x, com, task, heading, command,
                                diagnostics[:self._paper_size])
        d = self._slices
        diagnostics[d["com_integral_force"]] = -self._k_x * s_x
        diagnostics[d["task_integral_velocity"]] = -self._k_y * s_y
        diagnostics[d["vehicle_force_feedforward"]] = force
        if self._params.wrench_compensation:
            mu_c, tau_c = self._compensation(x, tau_hat)
            command[1:4] += mu_c
            command[4:] += tau_c
            diagnostics[d["compensation_moment"]] = mu_c
            diagnostics[d["compensation_torque"]] = tau_c
        else:
            diagnostics[d["compensation_moment"]] = 0.0
            diagnostics[d["compensation_torque"]] = 0.0
        saturated = np.any(command < self._lower) or np.any(command > self._upper)
        diagnostics[d["integration_held"]] = float(saturated)
        diagnostics[d["singularity_damping"]] = self._singularity.damping_ratio(
            float(diagnostics[d["sigma_min_J3"]][0]))

    def evaluate_into(self, t: float, x: np.ndarray, com: np.ndarray, task: np.ndarray,
                      heading: np.ndarray, command: np.ndarray, diagnostics: np.ndarray,
                      ) -> None:
        """The law with the integrator state, the force and the generalized force of the
        next sample: those left by the latest sample this controller ran (or held at the
        run's start), as the update after the last logged sample computes them (the run's
        log takes its last row so, :mod:`aerial_drake.simulation.run_log`). A run's samples
        read the held state."""
        self._run(t, x, com, task, heading, *self._latest, command, diagnostics)

    def _advance(self, state: np.ndarray, diagnostics: np.ndarray) -> np.ndarray:
        """The integrator state after this sample (class docstring)."""
        n, d = self._n, self._slices
        new = np.zeros_like(state)
        if not self._integrates:  # zero gains: every bound 0, the state stays all zeros
            return new
        s = state[:3 + n]
        if diagnostics[d["integration_held"]][0]:  # the command saturates (_run)
            new[:3 + n] = s
            return new
        error = np.concatenate([diagnostics[d["x_tilde"]],
                                self._integrated_task_error(diagnostics[d["y_tilde"]])])
        stepped = np.clip(s + self._h * error, -self._bound, self._bound)
        new[:3 + n] = stepped
        free = np.abs(stepped) < self._bound  # entries not on their bound
        rate = (stepped - s) / self._h
        new[3 + n:6 + n] = rate[:3]
        new[6 + n:9 + n] = np.where(free[:3], diagnostics[d["x_tilde_dot"]], 0.0)
        new[9 + n:] = rate[3:]
        return new

    def _integrated_task_error(self, y_tilde: np.ndarray) -> np.ndarray:
        """The task error the integral s_y takes in (y~ itself; a subclass may leave out
        directions another loop integrates, as ``paper_force`` the push's)."""
        return y_tilde

    def _sample(self, context: Context, discrete_state) -> None:
        self._step(context, discrete_state, advance=True)

    def hold_sample(self, context: Context) -> None:
        """Run the law at ``context`` and hold its command and diagnostics (the run's start);
        the integrators are not stepped (the periodic update at t = 0 steps them)."""
        self._step(context, context.get_mutable_discrete_state(), advance=False)

    def _step(self, context: Context, discrete_state, *, advance: bool) -> None:
        x, com, task, heading = self._inputs(context)
        force, tau_hat = np.zeros(3), np.zeros(self._tau_port.size())
        if self._params.vehicle_force_feedforward and self._force_port.HasValue(context):
            force = np.array(self._force_port.Eval(context), dtype=float)
        if self._params.wrench_compensation and self._tau_port.HasValue(context):
            tau_hat = np.array(self._tau_port.Eval(context), dtype=float)
        state = np.array(context.get_discrete_state(_INTEGRATOR).value())
        command = discrete_state.get_mutable_value(0)
        diagnostics = discrete_state.get_mutable_value(1)
        self.evaluations += 1
        try:
            self._run(context.get_time(), x, com, task, heading, state, force, tau_hat,
                      command, diagnostics)
        except (AssumptionViolation, FloatingPointError) as err:
            raise at_time(err, context) from None
        if not advance:  # the run's start: evaluate_into reads this run's values, not a
            self._latest = (state, force, tau_hat)  # previous run's of the same diagram
        else:
            new = self._advance(state, diagnostics)
            discrete_state.get_mutable_value(_INTEGRATOR)[:] = new
            self._latest = (new, force, tau_hat)

    def _compensation(self, x: np.ndarray, tau_hat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(mu_c, tau_c) at state ``x`` (:func:`~aerial_drake.control.plus.compensation.
        compensation`, with the plant's CoM Jacobian and attitude there)."""
        plant, context = self._plant, self._plant_context
        plant.SetPositions(context, x[:plant.num_positions()])
        world = plant.world_frame()
        if self._instances:
            J_g = plant.CalcJacobianCenterOfMassTranslationalVelocity(
                context, self._instances, JacobianWrtVariable.kV, world, world)
        else:
            J_g = plant.CalcJacobianCenterOfMassTranslationalVelocity(
                context, JacobianWrtVariable.kV, world, world)
        R_WB = plant.EvalBodyPoseInWorld(context, self._base).rotation().matrix()
        return compensation(tau_hat, J_g, R_WB)


def make_paper_plus(scenario, model: AerialManipulator,
                    limits: tuple[np.ndarray, np.ndarray]) -> PaperPlusController:
    """``paper_plus`` on ``model`` from a scenario's fields (gains, controller.plus,
    controller_period, the assumption limits) and the command ``limits``."""
    return PaperPlusController(
        model, scenario.gains, scenario.controller.plus, limits,
        sigma_min_J3_limit=scenario.sigma_min_J3_limit, f_d_limit=scenario.f_d_limit,
        period=scenario.controller_period, kernel=scenario.controller.kernel)
