"""x_d planned with margin (the paper's future work, Section V): for a given task reference
y_d and heading, a CoM reference that keeps the arm away from Assumption 1's boundary, from its
joint limits and inside its reach, built offline before the run (docs/control.md, "x_d
planned with margin"; option ``trajectory.com_planning``).

Construction:

1. x_d = x_d^kind + delta(t): the kind's own CoM reference (rule (33) for the paper and
   waypoints kinds) plus a correction delta, a degree-7 B-spline (Drake's BsplineTrajectory)
   on uniform knots every ``knot_period`` continued past both ends of [0, duration], so x_d
   is C^6 and its first four derivatives are the exact rates of the curve flown;
2. every ``sample_period`` t_k, the posture with the task on y_d(t_k) and the vehicle level at
   the reference heading (the quasi-static choice, :mod:`.com_margins`) is a function of the
   system CoM x alone (3 + n equations in 3 + n unknowns: Newton from the sample's last
   posture, Drake's InverseKinematics for the first), and

       f_k(x) = (sigma_0 / smin sigma(J_3))^6 + (d_0 / smin d(q))^6 + (|e(x)| / rho)^6

   where smin(v) = (sum v_i^-6)^(-1/6) is a smooth minimum, sigma(J_3) the singular values of
   J_3 of (17) (Assumption 1), d(q) each arm joint's distance to both its limits as a
   fraction of its range (through a softplus of 0.02, so a joint the task itself drives past
   a limit leaves a finite, flat term), e(x) the end effector's offset from x in the heading
   frame minus the nominal posture's, rho the robot's ``workspace_radius`` (the reach), and
   sigma_0, d_0 the kind's own worst smooth margins over the run: each term is 1 where the
   kind is worst, so the sum over k is a soft maximum over time of the three normalised
   shortfalls, with no weight to tune;
3. the control points, constrained so that delta's derivatives 1-4 vanish at t = 0 (the run
   starts at rest with the kind's rates; x_d(0) itself may move), minimise sum_k
   f_k(x_d(t_k)) plus a small penalty on their 4th differences (which settles those the
   samples barely hold): Newton steps with each sample's gradient and Hessian by central
   differences (2 mm; the Hessian made positive definite), a backtracking line search, from
   delta = 0 (so never worse than the kind's in that sum);
4. the margins of the postures that realise the planned x_d, and of the kind's own, are
   reported (:class:`ComPlanReport`): the exact sigma_min(J_3), not the smooth one.

The knots set the plan's bandwidth: 0.4 s lets x_d follow the paper's agile motion (3 rad/s)
in part; 1-2 s keeps only slow shifts (gentler on the vehicle, less margin at the worst
instant). docs/control.md gives the figures.
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
#: Exponent of the smooth minima and of the soft maximum over time; the softplus scale of
#: the joint distances (fraction of range).
_P = 6.0
_SOFTPLUS = 0.02
#: Finite-difference step on the CoM (m); the least curvature of a sample's model (1/m^2);
#: Newton iterations at most, and their stop (mean decrease of f per sample).
_STEP = 2e-3
_CURVATURE = 1.0
_NEWTON = 6
_STOP = 1e-4
#: Weight of the penalty on the control points' 4th differences (1/m^2).
_SMOOTHING = 1.0


@dataclasses.dataclass(frozen=True)
class ComPlanReport:
    """What the plan achieved: the margins of its postures and of the kind's own x_d (rule
    (33) for the paper kind) at the same times, and how far x_d moved from the kind's."""

    planned: PostureMargins
    kind: PostureMargins
    #: The largest |x_d - x_d^kind| over the samples (m).
    max_shift_m: float
    samples: int

    def as_dict(self) -> dict:
        return {"planned": self.planned.as_dict(), "kind": self.kind.as_dict(),
                "max_shift_m": self.max_shift_m, "samples": self.samples}

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
        """delta and its 1st..4th derivatives at t (5, 3). Outside the plan's span delta
        holds its value at the nearer end and its derivatives are zero, so that the
        corrected x_d stays consistent with its own derivatives there."""
        start, end = self._span
        if start <= t <= end:
            return np.array([rate.value(float(t))[:, 0] for rate in self._rates])
        out = np.zeros((5, 3))
        out[0] = self.delta.value(start if t < start else end)[:, 0]
        return out

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
    kind's own x_d leaves the arm's reach (the plan starts from it)."""
    count = max(int(math.ceil(duration / sample_period - 1e-9)), 2)
    times = np.linspace(0.0, duration, count + 1)
    base = source.sample(times).com[:, 0]
    basis, B_all = _basis(duration, knot_period, times)
    # delta's derivatives 1-4 vanish at t = 0 (Z spans the control points that keep them so):
    # the run starts at rest as with the kind's x_d, whose rates it then has at t = 0; the
    # plan may still move x_d(0), where the start posture is built. (Free, the study base's
    # plan began at x_d'' = 1.8 m/s^2 and its start transient grew from 76 to 117 mm at the
    # end effector.)
    Z = _start_at_kind_rates(basis)
    B = B_all @ Z
    samples = _Samples(source, model, times)
    c = np.zeros((B.shape[1], 3))  # the free coordinates: start at the kind's x_d
    D = np.diff(np.eye(B_all.shape[1]), n=4, axis=0) @ Z
    P = _SMOOTHING * np.kron(D.T @ D, np.eye(3))

    def total(values: np.ndarray, c: np.ndarray) -> float:
        return float(values.sum() + 0.5 * c.reshape(-1) @ P @ c.reshape(-1))

    values = samples.values(base, commit=True)
    objective = total(values, c)
    for _ in range(_NEWTON):
        g, H = samples.derivatives(base + B @ c, values)
        # Newton on the control points: sum_k f_k(B_k c) by each sample's quadratic model.
        A = np.einsum("ki,kj,kab->iajb", B, B, H).reshape(c.size, c.size) + P
        b = np.einsum("ki,ka->ia", B, g).reshape(-1) + P @ c.reshape(-1)
        step = -np.linalg.solve(A, b).reshape(c.shape)
        alpha = 1.0
        while alpha > 1e-3:
            trial = samples.values(base + B @ (c + alpha * step))
            if np.all(np.isfinite(trial)) and total(trial, c + alpha * step) < objective:
                break
            alpha *= 0.5
        else:
            break
        c = c + alpha * step
        values = samples.values(base + B @ c, commit=True)
        improvement, objective = objective - total(values, c), total(values, c)
        if improvement < _STOP * values.size:
            break
    delta = BsplineTrajectory(basis, [row.reshape(3, 1) for row in Z @ c])
    planned = PlannedComReference(source, delta)
    report = ComPlanReport(
        planned=posture_margins(planned, model, times),
        kind=posture_margins(source, model, times),
        max_shift_m=float(np.max(np.linalg.norm(B @ c, axis=1))),
        samples=int(times.size))
    planned.report = report
    return planned


class _Margin:
    """f(x) of the module docstring at one sample, and the posture it solved."""

    def __init__(self, postures: LevelPostures, ref, nominal: np.ndarray, radius: float):
        self.postures, self.ref = postures, ref
        self.nominal, self.radius = nominal, radius
        self.R = postures.targets(ref, np.zeros(3))["R_WB"]
        #: The kind's smallest smooth margins over the run (sigma, joint limits).
        self.scales = (1.0, 1.0)

    def smooth_margins(self, q: np.ndarray) -> tuple[float, float]:
        """The smooth minima of sigma(J_3) and of the joint distances at ``q``."""
        self.postures.model.plant.SetPositions(self.postures.context, q)
        arm = q[self.postures.model.arm_position_indices]
        lower, upper = self.postures.lower, self.postures.upper
        span = np.tile(upper - lower, 2)
        with np.errstate(invalid="ignore"):
            d = np.concatenate([arm - lower, upper - arm]) / span
        # A joint without limits (continuous) is never near one: a full range away.
        d = np.where(np.isfinite(span), d, 1.0)
        return (_smooth_min(self.postures.sigmas()),
                _smooth_min(_SOFTPLUS * np.logaddexp(0.0, d / _SOFTPLUS)))

    def __call__(self, x: np.ndarray, q_guess: np.ndarray) -> tuple[float, np.ndarray | None]:
        reach = self.R.T @ (self.ref.p_ed - x) - self.nominal
        q = self.postures.solve(self.postures.targets(self.ref, x), q_guess, fallback=False)
        if q is None:
            return math.inf, None
        sigma, limit = self.smooth_margins(q)
        if sigma <= 0.0:
            return math.inf, None
        return ((self.scales[0] / sigma) ** _P + (self.scales[1] / limit) ** _P
                + (float(np.linalg.norm(reach)) / self.radius) ** _P), q


class _Samples:
    """f at every sample time, each posture solved from that sample's last accepted one."""

    def __init__(self, source: ReferenceSource, model: AerialManipulator, times: np.ndarray):
        postures = LevelPostures(model)
        nominal = nominal_end_effector_offset(model)
        radius = float(model.description.workspace_radius)
        ref = source.sample(times)
        self.times = times
        self.margins = [_Margin(postures, sample_at(ref, k), nominal, radius)
                        for k in range(times.size)]
        self.q: list[np.ndarray] = []
        q = None
        for k, margin in enumerate(self.margins):  # the kind's postures, tracked in time
            try:
                q = postures.solve(postures.targets(margin.ref, margin.ref.com[0]), q)
            except UnreachablePose as err:
                raise ValueError(f"com_planning: no posture realises the task at t = "
                                 f"{times[k]:.3f} s from the reference's CoM: {err}") from None
            assert q is not None  # solve() with its fallback returns a posture or raises
            self.q.append(q)
        kind = np.array([m.smooth_margins(q) for m, q in zip(self.margins, self.q)])
        for margin in self.margins:  # each margin relative to the kind's worst
            margin.scales = (float(kind[:, 0].min()), float(kind[:, 1].min()))

    def values(self, X: np.ndarray, commit: bool = False) -> np.ndarray:
        """f_k(X[k]) (N); ``commit``: keep the postures as the next starting points."""
        out = np.empty(len(self.margins))
        for k, margin in enumerate(self.margins):
            out[k], q = margin(X[k], self.q[k])
            if not commit:
                continue
            if q is None:
                raise ValueError(f"com_planning: no posture realises the planned CoM at t = "
                                 f"{self.times[k]:.3f} s (a singular one, or none)")
            self.q[k] = q
        return out

    def derivatives(self, X: np.ndarray, values: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
        """Gradients (N, 3) and positive definite Hessians (N, 3, 3) of f_k at X[k], by
        central differences of step _STEP (eigenvalues raised to at least _CURVATURE)."""
        g, H = np.zeros((len(X), 3)), np.zeros((len(X), 3, 3))
        E = _STEP * np.eye(3)
        for k, margin in enumerate(self.margins):
            f = lambda dx: margin(X[k] + dx, self.q[k])[0]  # noqa: E731
            plus, minus = [f(e) for e in E], [f(-e) for e in E]
            if not np.all(np.isfinite(plus + minus)):
                H[k] = _CURVATURE * np.eye(3)  # at the reach's edge: hold still
                continue
            for i in range(3):
                g[k, i] = (plus[i] - minus[i]) / (2 * _STEP)
                H[k, i, i] = (plus[i] - 2 * values[k] + minus[i]) / _STEP ** 2
                for j in range(i):
                    cross = (f(E[i] + E[j]) - f(E[i] - E[j]) - f(E[j] - E[i])
                             + f(-E[i] - E[j])) / (4 * _STEP ** 2)
                    H[k, i, j] = H[k, j, i] = cross if math.isfinite(cross) else 0.0
            w, V = np.linalg.eigh(H[k])
            H[k] = (V * np.maximum(w, _CURVATURE)) @ V.T
        return g, H


def _smooth_min(values: np.ndarray) -> float:
    values = np.asarray(values, dtype=float)
    if np.any(values <= 0.0):
        return 0.0
    scale = float(values.min())
    return scale * float(np.sum((values / scale) ** -_P)) ** (-1.0 / _P)


def _basis(duration: float, knot_period: float, times: np.ndarray
           ) -> tuple[BsplineBasis, np.ndarray]:
    """The degree-7 B-spline basis with knots every about ``knot_period`` over [0, duration],
    and its values at ``times`` (N, number of control points)."""
    intervals = max(int(round(duration / knot_period)), 1)
    h = duration / intervals
    # Uniform knots continued past both ends (not clamped there): the curve on [0, duration]
    # is an inner piece, its end derivatives as tame as its middle's (a clamped spline's
    # blow up at the ends, which few samples hold).
    basis = BsplineBasis(ORDER, (h * np.arange(-(ORDER - 1), intervals + ORDER)).tolist())
    B = np.array([[basis.EvaluateBasisFunctionI(i, float(t))
                   for i in range(basis.num_basis_functions())] for t in times])
    return basis, B


def _start_at_kind_rates(basis: BsplineBasis) -> np.ndarray:
    """An orthonormal basis Z (m, m - 4) of the control points whose curve has zero
    derivatives 1-4 at t = 0."""
    m = basis.num_basis_functions()
    unit = BsplineTrajectory(basis, [row.reshape(m, 1) for row in np.eye(m)])  # value: B(t)
    N = np.array([unit.MakeDerivative(k).value(0.0)[:, 0] for k in range(1, 5)])
    return np.linalg.svd(N)[2][4:].T
