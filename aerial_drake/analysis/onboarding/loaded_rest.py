"""The closed loop at rest under a constant load, and the limits it must keep there.

A push ``F`` (World, N) on the vehicle is the generalized force ``[0; F; 0]`` in the plant's
velocities ``[w_WB; v_WBo; qdot_arm]`` (the run applies it so, at the vehicle frame's
origin: :func:`aerial_drake.simulation.actuators.free_body_wrench_map`); a wrench at the end
effector is ``J_E^T w``. The equilibrium under either is the zero of (1) at rest under the
paper's law (:func:`aerial_drake.analysis.wrench_deflection.external_force_equilibrium`).
Under the law the CoM settles at ``x_d + F / K_x`` ((10) at rest: ``K_x e_x`` balances the
push) while the task loop holds the end effector (decoupling): the arm absorbs the CoM's
deflection, and so a push is limited by the arm's workspace as much as by the inputs.

At an equilibrium :meth:`RestLoop.limits_at` checks what a run would stop on or clip:
Assumption 1 (``sigma_min(J_3)`` above the scenario's ``sigma_min_J3_limit``), the arm's joint
position limits (a run stops there by default, ``joint_limits.positions: stop``; not with
``report``, and then neither does the check), the joint
efforts, the thrust range and the body torque bounds (the applied command's saturation,
:func:`aerial_drake.control.limits.command_limits`), and Assumption 2 (``|f_d|`` above
``f_d_limit``), and three a run does not stop on: the task loop faster than the vehicle's
(the slowest root of ``-Lambda_z^-1 K_z`` at the loaded posture :data:`TASK_SEPARATION` times
faster than the slowest CoM or attitude root, or no slower than :data:`TASK_SLOWDOWN` of its
rate at the nominal posture where that is slower already), the closed loop's slowest root
there (linearised: :meth:`RestLoop.slowest_root`) keeping :data:`ROOT_KEEP` of its decay
rate at the nominal posture (stable, and not so soft that a run never settles), and the
end effector held within :data:`EE_HOLD_FRACTION` of the workspace radius of its target.

The task-loop limit is what a slow push meets first near a singularity of J_3: Lambda_z
grows along the direction J_3 loses, its task root slows towards 0, and the static
equilibrium goes on, near-singular, with the end effector let go; but a task loop slower
than the vehicle's motion no longer follows it, and a run's transient crosses the
singularity (Assumption 1 stops it). On the test robot of tests/own_robot.py pushed along
+x the root is -1.35 1/s at 1.0 N and -0.51 1/s at 1.1 N against the vehicle's -1.26 1/s;
runs ramped over 16 s survive 1.0 N and stop on Assumption 1 at 1.06 N (docs/robots.md,
"robot check").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from aerial_drake.analysis.onboarding.check_subject import CheckSubject
from aerial_drake.analysis.wrench_deflection import (
    ExternalForce,
    external_force_equilibrium,
    moved_positions,
)
from aerial_drake.control.controller import make_controller
from aerial_drake.control.gain_design import loop_roots
from aerial_drake.control.law import AssumptionViolation, diagnostics_slices
from aerial_drake.control.limits import command_limits
from aerial_drake.dynamics.decoupling import DecoupledDynamics
from aerial_drake.dynamics.equilibrium import kinematic_J3

#: The end effector counts as held while its position is within this fraction of the
#: description's ``workspace_radius`` of its target: near a singularity of J_3 the task's
#: inertia Lambda_z grows and the law lets the end effector go long before sigma_min(J_3)
#: reaches the Assumption-1 limit (a run does not stop on it; the check does).
EE_HOLD_FRACTION = 0.25
#: The task loop's slowest root at a loaded posture must be this many times faster (in real
#: part) than the vehicle's slowest (CoM or attitude) root (module docstring), or, where the
#: gains make it slower than that already at the nominal posture (a light wrist's small K_z),
#: keep this fraction of its nominal rate.
TASK_SEPARATION = 3.0
TASK_SLOWDOWN = 0.5
#: The loaded equilibrium's slowest closed-loop root must keep this fraction of the nominal
#: posture's decay rate: a push can lead the arm to a soft equilibrium (on the UR3e pushed
#: up, near 44 N, a root at -0.04 1/s and the CoM drifting 150 mm sideways) that a run of
#: finite length does not reach, or to an unstable one.
ROOT_KEEP = 0.5
#: What a failed equilibrium solve reports as its binding limit.
NO_EQUILIBRIUM = "no equilibrium (Newton's method did not converge)"


@dataclass(frozen=True)
class RestState:
    """The loop at rest at positions ``q``: the law's command and how much of each limit it
    uses (``usage[name]``: 1 at the limit, above 1 past it)."""

    q: np.ndarray
    command: np.ndarray  # [f, mu (3), tau (n)] (N, N m)
    sigma_min: float  # sigma_min(J_3)
    usage: dict[str, float]  # limit name -> fraction used (module docstring's limits)
    violated: tuple[str, ...]  # each limit violated, named with its value; () when none

    @property
    def ok(self) -> bool:
        return not self.violated

    @property
    def nearest(self) -> tuple[str, float]:
        """The limit most used and its fraction."""
        name = max(self.usage, key=lambda k: self.usage[k])
        return name, self.usage[name]


class RestLoop:
    """The paper's law on the subject's model, held at rest under constant loads."""

    def __init__(self, subject: CheckSubject) -> None:
        self.subject = subject
        model = subject.model
        plant = model.plant
        if plant.num_positions() != plant.num_velocities() + 1:
            raise ValueError("robot check needs a quaternion floating base")
        s = subject.scenario
        self.sigma_limit = float(s.sigma_min_J3_limit)
        self.f_d_limit = float(s.f_d_limit)
        # Thresholds at 0: the law must not stop inside a Newton solve; the limits are
        # checked at the solution (limits_at).
        self.controller = make_controller(model, s.gains, sigma_min_J3_limit=0.0,
                                          f_d_limit=0.0)
        self.lower, self.upper = command_limits(s.actuation, model)
        self.q_lower, self.q_upper = model.arm_position_limits()
        self.joint_names = [j.name() for j in model.arm_joints]
        # A scenario whose runs only report the joint limits (joint_limits.positions: report,
        # as the paper's, whose reference needs joint 6 past its limit) is not held to them.
        self.joint_limits_bind = s.joint_limits.positions != "report"
        self.ee_hold = EE_HOLD_FRACTION * float(model.description.workspace_radius)
        self.dynamics = DecoupledDynamics(plant, model.base_body)
        self.context = plant.CreateDefaultContext()
        self.zero_v = np.zeros(plant.num_velocities())
        g = s.gains
        roots = loop_roots(subject.mass, g.K_x, g.D_x, g.k_R, g.k_w, g.Lambda2_bar)
        self.vehicle_rate = abs(max(roots.slowest_com.real, roots.slowest_attitude.real))
        self._K_z = np.diag(np.asarray(g.K_z, dtype=float))
        self._jacobian: dict = {}  # the last Newton Jacobian, reused along a continuation
        self._f_d_at = diagnostics_slices(model.n)["f_d_norm"].start
        # The nominal posture's slowest closed-loop root and task rate: the references of
        # the stability usage and of the task-loop limit.
        self.nominal_growth = self.slowest_root(subject.q0)
        nominal = self.task_rate(subject.q0)
        self.task_rate_needed = min(TASK_SEPARATION * self.vehicle_rate,
                                    TASK_SLOWDOWN * nominal)
        self.task_rule = (f"{TASK_SEPARATION:g}x the vehicle's slowest root, "
                          f"{-self.vehicle_rate:.3g} 1/s"
                          if self.task_rate_needed < TASK_SLOWDOWN * nominal else
                          f"{TASK_SLOWDOWN:g} of its {-nominal:.3g} 1/s at the nominal posture")

    # --- Loads ---------------------------------------------------------------------------
    def vehicle_push(self, start: np.ndarray, end: np.ndarray) -> ExternalForce:
        """A force on the vehicle (World, N) growing from ``start`` to ``end``."""
        start, end = np.asarray(start, float), np.asarray(end, float)

        def external(dynamics, d, fraction: float) -> np.ndarray:
            G = np.zeros(self.zero_v.size)
            G[3:6] = start + fraction * (end - start)  # [w_WB; v_WBo] rows: the force
            return G
        return external

    def ee_wrench(self, start: np.ndarray, end: np.ndarray) -> ExternalForce:
        """A wrench ``[force; torque]`` (World, N and N m) at the end-effector point, growing
        from ``start`` to ``end``."""
        start, end = np.asarray(start, float), np.asarray(end, float)
        frame = self.subject.model.end_effector_frame

        def external(dynamics, d, fraction: float) -> np.ndarray:
            J6, _ = dynamics.frame_jacobian(d, frame)  # rows [v_E; w_E]
            return J6.T @ (start + fraction * (end - start))
        return external

    # --- Equilibria ----------------------------------------------------------------------
    def equilibrium(self, external: ExternalForce, q_start: np.ndarray
                    ) -> tuple[np.ndarray | None, str]:
        """The rest positions under ``external`` followed from ``q_start`` (the equilibrium
        at the load's start): in 1 step, else 4; ``(None, why)`` when neither converges."""
        why = NO_EQUILIBRIUM
        for steps in (1, 4):
            try:
                q = external_force_equilibrium(
                    self.subject.model, self.subject.scenario.gains, self.subject.references,
                    external, q_start, steps=steps, tolerance=1e-8, max_iterations=25,
                    controller=self.controller, cache=self._jacobian)
            except (RuntimeError, np.linalg.LinAlgError, AssumptionViolation,
                    FloatingPointError) as err:
                why = f"{NO_EQUILIBRIUM}: {str(err).split(':', 1)[0]}" \
                    if isinstance(err, AssumptionViolation) else NO_EQUILIBRIUM
                continue
            if np.all(np.isfinite(q)):
                return q, ""
        return None, why

    def limits_at(self, q: np.ndarray, external: ExternalForce | None = None) -> RestState:
        """The command at rest at ``q`` and how much of every limit of the module docstring
        it uses; the violated ones listed Assumption 1 and the joint limits first (a run
        stops on them; the inputs are clipped). Usage: ``sigma_min_J3_limit / sigma_min``,
        a joint's distance from the middle of its range over the half range, an input over
        its bound on its side, ``f_d_limit / |f_d|``."""
        plant, model = self.subject.model.plant, self.subject.model
        x = np.concatenate([q, self.zero_v])
        out = self.controller.solve(x, *self.subject.references)
        command = np.concatenate([[float(out.f)], out.mu, out.tau])
        plant.SetPositions(self.context, q)
        J3 = kinematic_J3(model, self.context)
        sigma = float(np.linalg.svd(J3, compute_uv=False)[-1])
        usage: dict[str, float] = {}
        violated = []
        usage["Assumption 1"] = self.sigma_limit / sigma if sigma > 0 else np.inf
        if not sigma > self.sigma_limit:
            violated.append(f"Assumption 1: sigma_min(J_3) = {sigma:.3g} at the limit "
                            f"{self.sigma_limit:g}")
        q_arm = q[model.arm_position_indices]
        for name, value, low, high in zip(self.joint_names, q_arm, self.q_lower,
                                          self.q_upper):
            if not self.joint_limits_bind:
                continue
            half = 0.5 * (high - low)
            usage[f"joint '{name}' position"] = (
                abs(value - 0.5 * (high + low)) / half if np.isfinite(half) and half > 0
                else 0.0)
            if not low <= value <= high:
                violated.append(f"joint '{name}' position {value:.3f} rad outside "
                                f"[{low:.3f}, {high:.3f}]")
        f_d = float(out.diagnostics[self._f_d_at])
        usage["Assumption 2"] = self.f_d_limit / f_d if f_d > 0 else np.inf
        if not f_d > self.f_d_limit:
            violated.append(f"Assumption 2: |f_d| = {f_d:.3g} N at the limit "
                            f"{self.f_d_limit:g} N")
        names = ["thrust"] + [f"body torque about b{i + 1}" for i in range(3)] + [
            f"joint '{n}' effort" for n in self.joint_names]
        units = ["N"] + ["N m"] * (3 + len(self.joint_names))
        for name, unit, value, low, high in zip(names, units, command, self.lower,
                                                self.upper):
            bound = high if value >= 0 else low
            usage[name] = value / bound if np.isfinite(bound) and bound != 0 else 0.0
            if name == "thrust":  # its range need not hold 0: the side it is nearest
                usage[name] = max(value / high if np.isfinite(high) and high > 0 else 0.0,
                                  low / value if value > 0 and low > 0 else 0.0)
            if not low <= value <= high:
                bound = high if value > high else low
                violated.append(f"{name} {value:.3g} {unit} past its limit {bound:.3g} {unit}")
        task_rate = self._task_rate(out.Lambda_z)
        need = self.task_rate_needed
        usage["task loop speed"] = need / task_rate if task_rate > 0 else np.inf
        if not task_rate > need:
            violated.append(f"task loop speed: its slowest root, {-task_rate:.3g} 1/s, is "
                            f"slower than {-need:.3g} 1/s ({self.task_rule})")
        ee_error = float(np.linalg.norm(
            model.end_effector_frame.CalcPoseInWorld(self.context).translation()
            - self.subject.hover.p_ed))
        usage["end-effector hold"] = ee_error / self.ee_hold
        if not ee_error <= self.ee_hold:
            violated.append(f"end-effector hold: {1000 * ee_error:.3g} mm from its target, "
                            f"past {1000 * self.ee_hold:.3g} mm")
        # Last, and only where nothing else broke (it costs 2 nv + 1 evaluations of (1)):
        # so a state past another limit has no "closed-loop speed" usage.
        if not violated:
            rate = -self.slowest_root(q, external)  # the slowest root's decay rate
            need = ROOT_KEEP * -self.nominal_growth
            usage["closed-loop speed"] = need / rate if rate > 0 else np.inf
            if not rate > need:
                violated.append(
                    f"closed-loop speed: the slowest root at {-rate:.3g} 1/s, "
                    f"{'unstable' if rate <= 0 else 'slower than'} {ROOT_KEEP:g} of the "
                    f"nominal posture's {self.nominal_growth:.3g} 1/s")
        return RestState(q=q, command=command, sigma_min=sigma, usage=usage,
                         violated=tuple(violated))

    def _task_rate(self, Lambda_z: np.ndarray) -> float:
        """|real part| of the slowest root of -Lambda_z^-1 K_z (1/s)."""
        modes = np.linalg.eigvals(-np.linalg.solve(Lambda_z, self._K_z))
        return float(np.min(np.abs(modes.real)))

    def task_rate(self, q: np.ndarray) -> float:
        """The task loop's slowest rate (1/s) at rest at ``q``."""
        x = np.concatenate([q, self.zero_v])
        return self._task_rate(self.controller.solve(x, *self.subject.references).Lambda_z)

    def slowest_root(self, q: np.ndarray, external: ExternalForce | None = None) -> float:
        """The largest real part (1/s) of the closed loop's roots linearised at rest at ``q``
        under the load ``external`` (its full value): ``[delta; v]' = [v; v_dot]`` with
        ``delta`` the position offset along :func:`~aerial_drake.analysis.wrench_deflection.
        moved_positions`' coordinates (at rest its rate is ``v``), ``v_dot`` from (1) under
        the law's command, by forward differences (continuous feedback, no saturation)."""
        plant = self.subject.model.plant
        nv = self.zero_v.size

        def v_dot(delta: np.ndarray, v: np.ndarray) -> np.ndarray:
            x = np.concatenate([moved_positions(q, delta), v])
            out = self.controller.solve(x, *self.subject.references)
            plant.SetPositionsAndVelocities(self.context, x)
            d = self.dynamics.compute(self.context)
            base = np.concatenate([[0.0, 0.0, float(out.f)], out.mu])
            G = external(self.dynamics, d, 1.0) if external is not None else 0.0
            return np.linalg.solve(d.M, d.J_b.T @ base + d.Q.T @ out.tau + G - d.g
                                   - d.C @ v)  # (1)

        h, zero = 1e-7, np.zeros(nv)
        A = np.zeros((2 * nv, 2 * nv))
        A[:nv, nv:] = np.eye(nv)
        at_rest = v_dot(zero, zero)  # ~0 at an equilibrium; subtracted all the same
        for i, e in enumerate(np.eye(nv)):
            A[nv:, i] = (v_dot(h * e, zero) - at_rest) / h
            A[nv:, nv + i] = (v_dot(zero, h * e) - at_rest) / h
        return float(np.max(np.linalg.eigvals(A).real))

    def com_and_ee(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The system CoM and the end-effector point (World, m) at ``q``."""
        plant, model = self.subject.model.plant, self.subject.model
        plant.SetPositions(self.context, q)
        return (plant.CalcCenterOfMassPositionInWorld(self.context),
                model.end_effector_frame.CalcPoseInWorld(self.context).translation())
