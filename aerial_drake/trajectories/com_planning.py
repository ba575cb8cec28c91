"""x_d planned with margin (the paper's future work, Section V): for a given task reference
y_d and heading, a CoM reference that keeps the arm away from Assumption 1's boundary, from its
joint limits and inside its reach, built offline before the run (docs/control.md, "x_d
planned with margin"; option ``trajectory.com_planning``).

Construction:

1. every ``sample_period`` over [0, duration], the posture with the task on y_d(t_k) and the
   vehicle level at the reference heading (:mod:`.com_margins`) is a function of the system
   CoM x alone (3 + n equations in 3 + n unknowns); x_k minimises

       f(x) = -log smin(sigma(J_3)) - log smin(d(q)) - log(1 - |e(x)|^2 / rho^2)

   where smin(v) = (sum v_i^-8)^(-1/8) is a smooth minimum, sigma(J_3) the singular values of
   J_3 of (17), d(q) each arm joint's distance to both its limits as a fraction of its range
   (passed through a softplus of 0.02, so a joint the task itself drives past a limit leaves a
   finite, flat term), e(x) the end effector's offset from x in the heading frame minus the
   nominal posture's, and rho the robot's ``workspace_radius``: the three margins Assumption 1,
   the joint limits and the reach, with no weight to tune. Quasi-Newton (BFGS) steps with
   finite-difference gradients, from the previous sample's optimum moved as the kind's own
   x_d moves; every posture by Newton from the last (Drake's InverseKinematics where Newton
   fails);
2. the corrections x_k - x_d^kind(t_k) are fitted by least squares with a degree-7 B-spline
   (Drake's BsplineTrajectory, knots every ``knot_period``, a small penalty on the control
   points' 4th differences), so the planned x_d = x_d^kind + delta(t) is C^6 with its first four
   derivatives exact for the curve flown, and holds no motion faster than the knots (which
   the CoM loop, slower than the task's, could not follow anyway);
3. the margins of the postures that realise the planned x_d, and of the kind's own, are
   reported (:class:`ComPlanReport`).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from pydrake.math import BsplineBasis
from pydrake.trajectories import BsplineTrajectory

from aerial_drake.dynamics.equilibrium import UnreachablePose
from aerial_drake.robots.models import AerialManipulator, nominal_end_effector_offset
from aerial_drake.trajectories.base import ReferenceSource
from aerial_drake.trajectories.com_margins import (
    LevelPostures,
    PostureMargins,
    posture_margins,
    sample_at,
)
from aerial_drake.trajectories.params import ComPlanningParams
from aerial_drake.trajectories.reference import COM_REFERENCE_SIZE

__all__ = ["PlannedComReference", "ComPlanReport", "plan_com", "planned_reference",
           "plan_summary"]

#: B-spline order (degree 7): x_d is C^6, one more than the law's 4 derivatives need.
ORDER = 8
#: Exponent of the smooth minimum, and the softplus scale of the joint distances.
_P = 8.0
_SOFTPLUS = 0.02
#: Finite-difference step on the CoM (m) and the optimiser's stop (m, per step).
_STEP = 1e-6
_STOP = 1e-7
_ITERATIONS = 40
#: Weight of the penalty on the control points' 4th differences (relative to the data's).
_SMOOTHING = 1e-4


@dataclasses.dataclass(frozen=True)
class ComPlanReport:
    """What the plan achieved: the margins of its postures and of the kind's own x_d (rule
    (33) for the paper kind) at the same times, and how far x_d moved from the kind's."""

    planned: PostureMargins
    kind: PostureMargins
    #: The largest |x_d - x_d^kind| over the samples (m), and the fit's largest miss of the
    #: optimised samples (m).
    max_shift_m: float
    max_fit_error_m: float
    samples: int

    def as_dict(self) -> dict:
        return {"planned": self.planned.as_dict(), "kind": self.kind.as_dict(),
                "max_shift_m": self.max_shift_m, "max_fit_error_m": self.max_fit_error_m,
                "samples": self.samples}

    def line(self) -> str:
        """One line for the run's summary (:func:`plan_summary` of :meth:`as_dict`)."""
        return plan_summary(self.as_dict())


def plan_summary(report: dict) -> str:
    """One line of a :class:`ComPlanReport`'s :meth:`~ComPlanReport.as_dict` (metrics.json's
    ``com_planning``): the planned margins, the kind's own in brackets."""
    p, k = report["planned"], report["kind"]
    return (f"x_d planned with margin: min sigma_min(J_3) {p['sigma_min']:.3f} at "
            f"{p['sigma_time_s']:.2f} s (kind's x_d: {k['sigma_min']:.3f}); nearest joint limit "
            f"{100 * p['limit_fraction']:.1f} % of range, joint {p['limit_joint']} at "
            f"{p['limit_time_s']:.2f} s ({100 * k['limit_fraction']:.1f} %); max |q|/limit "
            f"{p['max_limit_ratio']:.3f} ({k['max_limit_ratio']:.3f}); x_d moved up to "
            f"{1e3 * report['max_shift_m']:.0f} mm")


class PlannedComReference(ReferenceSource):
    """``source`` with its CoM reference replaced by x_d^kind + ``delta`` (a
    BsplineTrajectory with 3 rows, over [0, duration]); task and heading unchanged."""

    def __init__(self, source: ReferenceSource, delta: BsplineTrajectory,
                 report: ComPlanReport | None = None) -> None:
        super().__init__(source.n_joints)
        self.kind = source.kind
        self.source = source
        self.delta = delta
        self._rates = [delta] + [delta.MakeDerivative(k) for k in range(1, 5)]
        self._span = (delta.start_time(), delta.end_time())
        self.report = report

    def correction(self, t: float) -> np.ndarray:
        """delta and its 1st..4th derivatives at t (5, 3); t clamped to the plan's span."""
        t = min(max(float(t), self._span[0]), self._span[1])
        return np.array([rate.value(t)[:, 0] for rate in self._rates])

    def fill(self, t: float, out: np.ndarray) -> None:
        self.source.fill(t, out)
        out[:COM_REFERENCE_SIZE] += self.correction(t).reshape(-1)

    def packed(self, times: np.ndarray) -> np.ndarray:
        out = self.source.packed(times)
        for i, t in enumerate(np.asarray(times, dtype=float)):
            out[i, :COM_REFERENCE_SIZE] += self.correction(float(t)).reshape(-1)
        return out


def planned_reference(source: ReferenceSource, params: ComPlanningParams,
                      model: AerialManipulator, duration: float) -> ReferenceSource:
    """``source`` itself if ``params.enabled`` is False (bit for bit the kind's reference),
    else :func:`plan_com` of it over [0, ``duration``]."""
    if not params.enabled:
        return source
    return plan_com(source, model, duration, sample_period=params.sample_period,
                    knot_period=params.knot_period)


def plan_com(source: ReferenceSource, model: AerialManipulator, duration: float, *,
             sample_period: float = 0.1, knot_period: float = 0.4) -> PlannedComReference:
    """The reference ``source`` with x_d planned for the arm's margin over [0, ``duration``]
    (module docstring), with its :class:`ComPlanReport`. ValueError naming the time where the
    task leaves the arm's reach."""
    count = max(int(math.ceil(duration / sample_period - 1e-9)), 2)
    times = np.linspace(0.0, duration, count + 1)
    optimum = _optimise_samples(source, model, times)
    base = source.sample(times).com[:, 0]
    delta = _fit(times, optimum - base, duration, knot_period)
    planned = PlannedComReference(source, delta)
    fitted = planned.sample(times).com[:, 0]
    report = ComPlanReport(
        planned=posture_margins(planned, model, times),
        kind=posture_margins(source, model, times),
        max_shift_m=float(np.max(np.linalg.norm(fitted - base, axis=1))),
        max_fit_error_m=float(np.max(np.linalg.norm(fitted - optimum, axis=1))),
        samples=int(times.size))
    planned.report = report
    return planned


class _Margin:
    """f(x) of the module docstring at one sample, and the posture it last solved."""

    def __init__(self, postures: LevelPostures, ref, nominal: np.ndarray, radius: float):
        self.postures, self.ref = postures, ref
        self.nominal, self.radius = nominal, radius
        self.R = postures.targets(ref, np.zeros(3))["R_WB"]

    def __call__(self, x: np.ndarray, q_guess: np.ndarray) -> tuple[float, np.ndarray | None]:
        reach = self.R.T @ (self.ref.p_ed - x) - self.nominal
        r2 = float(reach @ reach) / self.radius ** 2
        if r2 >= 1.0:
            return math.inf, None
        q = self.postures.solve(self.postures.targets(self.ref, x), q_guess, fallback=False)
        if q is None:
            return math.inf, None
        d = np.concatenate([q[self.postures.model.arm_position_indices] - self.postures.lower,
                            self.postures.upper - q[self.postures.model.arm_position_indices]])
        d = d / np.tile(self.postures.upper - self.postures.lower, 2)
        d = _SOFTPLUS * np.logaddexp(0.0, d / _SOFTPLUS)
        return (-math.log(_smooth_min(self.postures.sigmas())) - math.log(_smooth_min(d))
                - math.log1p(-r2)), q


def _smooth_min(values: np.ndarray) -> float:
    values = np.asarray(values, dtype=float)
    if np.any(values <= 0.0):
        return 0.0
    scale = float(values.min())
    return scale * float(np.sum((values / scale) ** -_P)) ** (-1.0 / _P)


def _optimise_samples(source: ReferenceSource, model: AerialManipulator,
                      times: np.ndarray) -> np.ndarray:
    """x_k, the minimiser of f at each sample time (N, 3)."""
    postures = LevelPostures(model)
    nominal = nominal_end_effector_offset(model)
    radius = float(model.description.workspace_radius)
    ref = source.sample(times)
    out = np.empty((times.size, 3))
    q: np.ndarray | None = None
    x = ref.com[0, 0].copy()
    for k, t in enumerate(times):
        sample = sample_at(ref, k)
        if k > 0:
            x = x + ref.com[k, 0] - ref.com[k - 1, 0]  # follow the kind's own x_d
        margin = _Margin(postures, sample, nominal, radius)
        value, q_new = margin(x, q) if q is not None else (math.inf, None)
        if q_new is None:  # no posture near the last: from the kind's x_d, by IK
            x = ref.com[k, 0].copy()
            try:
                q = postures.solve(postures.targets(sample, x), q)
            except UnreachablePose as err:
                raise ValueError(f"com_planning: no posture realises the task at t = "
                                 f"{t:.3f} s from the reference's CoM: {err}") from None
            value, q_new = margin(x, q)
        if q_new is None or not math.isfinite(value):
            raise ValueError(f"com_planning: the reference's posture at t = {t:.3f} s is "
                             "outside the arm's reach (workspace_radius) or singular: the "
                             "plan needs a feasible start at every sample")
        x, q = _bfgs(margin, x, q_new, value)
        out[k] = x
    return out


def _bfgs(f: _Margin, x: np.ndarray, q: np.ndarray, value: float
          ) -> tuple[np.ndarray, np.ndarray]:
    """Minimise f from x (posture q, f(x) = value): BFGS with forward-difference gradients
    and a backtracking (Armijo) line search; stops when a step is below _STOP."""
    H = np.eye(3) * 1e-3  # inverse Hessian guess: steps of millimetres first
    g = _gradient(f, x, q, value)
    for _ in range(_ITERATIONS):
        step = -H @ g
        alpha, accepted = 1.0, None
        while alpha > 1e-6:
            trial, q_trial = f(x + alpha * step, q)
            if q_trial is not None and trial <= value + 1e-4 * alpha * float(g @ step):
                accepted = (x + alpha * step, q_trial, trial)
                break
            alpha *= 0.5
        if accepted is None:
            break
        x_new, q, value = accepted
        g_new = _gradient(f, x_new, q, value)
        s, y = x_new - x, g_new - g
        x, g = x_new, g_new
        if float(s @ y) > 1e-16:
            rho = 1.0 / float(s @ y)
            V = np.eye(3) - rho * np.outer(s, y)
            H = V @ H @ V.T + rho * np.outer(s, s)
        if np.linalg.norm(s) < _STOP:
            break
    return x, q


def _gradient(f: _Margin, x: np.ndarray, q: np.ndarray, value: float) -> np.ndarray:
    g = np.empty(3)
    for i in range(3):
        e = np.zeros(3)
        e[i] = _STEP
        forward, _ = f(x + e, q)
        if math.isfinite(forward):
            g[i] = (forward - value) / _STEP
        else:  # at the reach's edge: the backward difference
            backward, _ = f(x - e, q)
            g[i] = (value - backward) / _STEP
    return g


def _fit(times: np.ndarray, values: np.ndarray, duration: float, knot_period: float
         ) -> BsplineTrajectory:
    """The degree-7 B-spline through ``values`` (N, 3) at ``times`` by least squares, knots
    every about ``knot_period`` over [0, duration], with a small penalty on the control
    points' 4th differences (which also settles control points the samples do not fix)."""
    intervals = max(int(round(duration / knot_period)), 1)
    h = duration / intervals
    # Uniform knots continued past both ends (not clamped there): the curve on [0, duration]
    # is an inner piece, its end derivatives as tame as its middle's (a clamped spline's
    # blow up at the ends, where few samples hold its last control points).
    knots = h * np.arange(-(ORDER - 1), intervals + ORDER)
    basis = BsplineBasis(ORDER, knots.tolist())
    m = basis.num_basis_functions()
    B = np.array([[basis.EvaluateBasisFunctionI(i, float(t)) for i in range(m)]
                  for t in times])
    D = np.diff(np.eye(m), n=4, axis=0)
    A = B.T @ B + _SMOOTHING * np.trace(B.T @ B) / m * (D.T @ D)
    control = np.linalg.solve(A, B.T @ values)
    return BsplineTrajectory(basis, [c.reshape(3, 1) for c in control])
