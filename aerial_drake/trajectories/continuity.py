"""Is a sampled reference as smooth as the law needs? Jumps and inconsistent derivatives.

The law reads x_d up to its 4th derivative (the snap feeds the attitude feed-forward through
f_d_ddot, (10)-(16)), the task's p_ed, R_ed (as w_ed, dw_ed) and q_jd up to the 2nd (17)-(20),
and b1d up to the 2nd (13). A reference whose derivative jumps (a spline of too low a degree,
a wrapped angle, a user's piecewise function) or whose given derivative is not the rate of the
signal below it would feed the law a wrong feed-forward without any error. Two tests, on
samples a period ``h`` apart (:func:`find_discontinuity`):

- **jump**: the change of a signal over one interval is far larger than over its neighbours
  (a smooth signal changes by about the same over adjacent intervals, so a ratio above
  :data:`JUMP_RATIO` marks a candidate); the interval is then bisected
  :data:`BISECTIONS` times on fresh samples: a true jump keeps its size down to microseconds,
  a fast but smooth change shrinks with the interval and is let through;
- **mismatch**: a central difference of the lower signal against the given derivative, with
  the tolerance the difference's own truncation error allows (a sixth of the derivative's
  second difference, times :data:`MISMATCH_RATIO`), re-checked at h / 16 where it fails.

The samples come from any reference kind (e.g. a
:class:`~aerial_drake.trajectories.base.ReferenceSource`'s ``sample``), so the test serves
every one.

Where the knots are known (the waypoints kind's), :func:`knot_jumps` checks them directly:
each signal's one-sided limits at each knot, extrapolated from samples just before and just
after it, must agree (a jump stays as the samples close in, a continuous change vanishes).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from aerial_drake.trajectories.reference import ReferenceSample

#: A change this many times the neighbouring intervals' is a jump candidate (a smooth signal's
#: ratio stays near 1: at a turning point the interval holding it changes least).
JUMP_RATIO = 4.0
#: Halvings of a candidate interval: 10 ms / 2^12 = 2.4 us, where a smooth change has shrunk
#: 4096-fold and a jump has not.
BISECTIONS = 12
#: The central difference's error is h^2/6 |d''| = |second difference of d| / 6: allow 6x that.
MISMATCH_RATIO = 1.0
#: Changes below this fraction of a signal's largest value are rounding, not jumps.
RELATIVE_FLOOR = 1e-6
#: The one-sided limits of :func:`knot_jumps` from samples this far and twice as far from a
#: knot (s), then again at a tenth of it.
KNOT_STEP = 1e-4
#: Limits that differ by less than this times (1 + the signal's size) agree: the linear
#: extrapolation's error is about step^2 |s''|, 1e-8 |s''| at KNOT_STEP.
KNOT_TOLERANCE = 1e-7

#: The chains of signals, lowest first: each entry's derivative is the next one.
CHAINS: tuple[tuple[str, ...], ...] = (
    ("x_d", "x_d'", "x_d''", "x_d'''", "x_d''''"),
    ("p_ed", "v_ed", "a_ed"),
    ("R_ed", "w_ed", "dw_ed"),
    ("q_jd", "q_jd'", "q_jd''"),
    ("b1d", "b1d'", "b1d''"),
)


@dataclass(frozen=True)
class Discontinuity:
    """Where a sampled reference fails the law's smoothness, and how."""

    time: float  # s
    signal: str  # e.g. "x_d''''"
    kind: str  # "jump", "knot", "mismatch" or "non-finite"
    size: float  # the jump, or the difference from the finite difference
    expected: float  # the neighbours' change, or the tolerance

    def describe(self) -> str:
        if self.kind == "non-finite":
            return f"{self.signal} is not finite at t = {self.time:.6f} s"
        if self.kind == "jump":
            return (f"{self.signal} jumps at t = {self.time:.6f} s: it changes by "
                    f"{self.size:.3g} within microseconds, while it changes by about "
                    f"{self.expected:.3g} over each neighbouring sample interval")
        if self.kind == "knot":
            return (f"{self.signal} jumps at the knot t = {self.time:.6f} s: its limits from "
                    f"before and after differ by {self.size:.3g} (tolerance "
                    f"{self.expected:.3g})")
        return (f"{self.signal} at t = {self.time:.6f} s is not the rate of the signal below "
                f"it: it differs by {self.size:.3g} from a finite difference of that signal "
                f"(tolerance {self.expected:.3g})")


def signals(ref: ReferenceSample) -> dict[str, np.ndarray]:
    """Every signal of :data:`CHAINS` from a time-sampled reference, (N, size) each."""
    n = ref.p_ed.shape[0]
    out = {name: ref.com[:, k] for k, name in enumerate(CHAINS[0])}
    out.update({"p_ed": ref.p_ed, "v_ed": ref.v_ed, "a_ed": ref.a_ed,
                "R_ed": ref.R_ed.reshape(n, 9), "w_ed": ref.w_ed, "dw_ed": ref.dw_ed,
                "q_jd": ref.q_jd.reshape(n, -1), "q_jd'": ref.q_jd_dot.reshape(n, -1),
                "q_jd''": ref.q_jd_ddot.reshape(n, -1)})
    out.update({name: ref.b1d[:, k] for k, name in enumerate(CHAINS[4])})
    return out


def rotation_rate(R_before: np.ndarray, R_after: np.ndarray, dt: float) -> np.ndarray:
    """The constant World angular velocity w (N, 3) that turns ``R_before`` into ``R_after``
    (N, 3, 3) in ``dt``: R_after = exp(hat(w) dt) R_before (d/dt R_ed = hat(w_ed) R_ed)."""
    D = R_after @ np.swapaxes(R_before, -1, -2)
    s = 0.5 * np.stack([D[:, 2, 1] - D[:, 1, 2], D[:, 0, 2] - D[:, 2, 0],
                        D[:, 1, 0] - D[:, 0, 1]], axis=-1)  # sin(angle) axis
    sin = np.linalg.norm(s, axis=-1)
    angle = np.arctan2(sin, 0.5 * (np.trace(D, axis1=-2, axis2=-1) - 1.0))
    scale = np.where(sin > 1e-12, angle / np.maximum(sin, 1e-300), 1.0)
    return s * scale[:, None] / dt


def _central_difference(name: str, values: np.ndarray, h: float) -> np.ndarray:
    """d/dt of signal ``name`` at the interior samples, from its neighbours 2 h apart."""
    if name == "R_ed":
        R = values.reshape(-1, 3, 3)
        return rotation_rate(R[:-2], R[2:], 2.0 * h)
    return (values[2:] - values[:-2]) / (2.0 * h)


def find_discontinuity(sample: Callable[[np.ndarray], ReferenceSample], times: np.ndarray,
                       ) -> Discontinuity | None:
    """The earliest place where the reference ``sample(times) -> ReferenceSample`` fails the
    law's smoothness (module docstring), or None. ``times``: evenly spaced, at least 4."""
    h = float(times[1] - times[0])
    values = signals(sample(times))
    bad = _non_finite(values)
    if bad:
        k, name = bad
        return Discontinuity(float(times[k]), name, "non-finite", float("nan"), float("nan"))
    found: list[Discontinuity] = []
    for name, v in values.items():
        found += _confirmed_jumps(sample, name, v, times)
    if found:
        return min(found, key=lambda d: d.time)
    for chain in CHAINS:
        for lower, higher in zip(chain, chain[1:]):
            found += _confirmed_mismatches(sample, lower, higher, values, times, h)
    return min(found, key=lambda d: d.time) if found else None


def _non_finite(values: dict[str, np.ndarray]) -> tuple[int, str] | None:
    """(sample index, signal) of the earliest non-finite value, or None."""
    bad = [(int(np.argmax(~np.all(np.isfinite(v), axis=1))), name)
           for name, v in values.items() if v.size and not np.all(np.isfinite(v))]
    return min(bad) if bad else None


def _confirmed_jumps(sample: Callable[[np.ndarray], ReferenceSample], name: str,
                     v: np.ndarray, times: np.ndarray) -> list[Discontinuity]:
    if v.shape[1] == 0 or v.shape[0] < 3:
        return []
    change = np.linalg.norm(np.diff(v, axis=0), axis=1)
    before = np.concatenate([[0.0], change[:-1]])
    after = np.concatenate([change[1:], [0.0]])
    neighbours = np.maximum(before, after)
    floor = RELATIVE_FLOOR * float(np.abs(v).max())
    out = []
    for k in np.flatnonzero(change > JUMP_RATIO * neighbours + floor):
        time = _bisect_jump(sample, name, times[k], times[k + 1], v[k], v[k + 1])
        if time is not None:
            out.append(Discontinuity(time[0], name, "jump", time[1], float(neighbours[k])))
            break  # the earliest of this signal is enough
    return out


def _bisect_jump(sample: Callable[[np.ndarray], ReferenceSample], name: str, a: float,
                 b: float, va: np.ndarray, vb: np.ndarray) -> tuple[float, float] | None:
    """(time, size) of a jump of ``name`` inside [a, b], or None if the change shrinks with
    the interval (smooth)."""
    first = float(np.linalg.norm(vb - va))
    for _ in range(BISECTIONS):
        mid = 0.5 * (a + b)
        vm = signals(sample(np.array([mid])))[name][0]
        if np.linalg.norm(vm - va) >= np.linalg.norm(vb - vm):
            b, vb = mid, vm
        else:
            a, va = mid, vm
    last = float(np.linalg.norm(vb - va))
    return (0.5 * (a + b), last) if last > 0.25 * first else None


def _confirmed_mismatches(sample: Callable[[np.ndarray], ReferenceSample], lower: str,
                          higher: str, values: dict[str, np.ndarray], times: np.ndarray,
                          h: float) -> list[Discontinuity]:
    s, d = values[lower], values[higher]
    if s.shape[1] == 0 or s.shape[0] < 3:
        return []
    error, tolerance = _mismatch(lower, s, d, h)
    for k in np.flatnonzero(error > tolerance):
        t = float(times[k + 1])
        fine = signals(sample(np.array([t - h / 16, t, t + h / 16])))
        error_fine, _ = _mismatch(lower, fine[lower], fine[higher], h / 16)
        if error_fine[0] > 0.5 * error[k]:
            return [Discontinuity(t, higher, "mismatch", float(error[k]),
                                  float(tolerance[k]))]
    return []


def _mismatch(lower: str, s: np.ndarray, d: np.ndarray, h: float) -> tuple[Any, Any]:
    """|central difference of s - d| at the interior samples, and its tolerance."""
    error = np.linalg.norm(_central_difference(lower, s, h) - d[1:-1], axis=1)
    second = np.linalg.norm(d[2:] - 2.0 * d[1:-1] + d[:-2], axis=1)
    # Rounding of the difference itself: ~1e-16 |s| / h; 1e-9 leaves room.
    floor = RELATIVE_FLOOR * float(np.abs(d).max()) + 1e-9 * float(np.abs(s).max()) / h
    return error, MISMATCH_RATIO * second + floor


def knot_jumps(sample: Callable[[np.ndarray], ReferenceSample], knots: np.ndarray,
               step: float = KNOT_STEP) -> list[Discontinuity]:
    """Every signal of :data:`CHAINS` (x_d to its 4th derivative, the task to its 2nd, b1d
    to its 2nd) whose one-sided limits at a knot differ, earliest first: each limit
    extrapolated linearly from the samples at ``step`` and 2 ``step`` on its side,
    2 s(t -+ h) - s(t -+ 2h). A difference above :data:`KNOT_TOLERANCE` (1 + |s|) that
    stays above half its size at step / 10 is a jump (a continuous signal's shrinks about
    100-fold, the extrapolation's error being O(h^2))."""
    found = []
    for t in np.asarray(knots, dtype=float):
        gaps = []
        for h in (step, step / 10):
            values = signals(sample(t + h * np.array([-2.0, -1.0, 1.0, 2.0])))
            gaps.append({name: (float(np.linalg.norm((2 * v[2] - v[3]) - (2 * v[1] - v[0]))),
                                float(np.abs(v).max(initial=0.0)))
                         for name, v in values.items() if v.shape[1]})
        for name, (gap, size) in gaps[0].items():
            if gap > KNOT_TOLERANCE * (1.0 + size) and gaps[1][name][0] > 0.5 * gap:
                found.append(Discontinuity(float(t), name, "knot", gaps[1][name][0],
                                           KNOT_TOLERANCE * (1.0 + size)))
    return found
