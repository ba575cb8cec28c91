"""Piecewise Hermite polynomials: each segment matches given derivatives at both its ends.

A segment from t_i to t_{i+1} (length T) that matches the values and the first m - 1
derivatives at both ends is the unique polynomial of degree 2m - 1 in tau = (t - t_i) / T.
Neighbouring segments share their end derivatives, so the whole curve is C^(m-1): the
waypoints kind uses m = 5 (degree 9, C^4: the CoM's snap is continuous, as the attitude
feed-forward (13)-(16) needs) with the acceleration, jerk and snap zero at each waypoint
(``mode: stop``) or chosen by :mod:`.through` (``mode: through``), and m = 3 (degree 5, C^2)
for the orientation's rotation vector. Local (a waypoint moves only its two segments), exact
at the waypoints, and with zero end velocities each segment is a monotone blend (no overshoot
between rest points).

Pure numpy; the evaluation is one small matrix product per call. A run evaluates these
curves by the compiled :mod:`.spline_kernel` instead (equal to round-off).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["hermite_segment", "PiecewiseHermite"]


def _basis(tau: float, degree: int, orders: int) -> np.ndarray:
    """B[k, j] = d^k/dtau^k tau^j for k < orders, j <= degree."""
    P, E = _basis_tables(degree, orders)
    return P * tau ** E


_TABLES: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}


def _basis_tables(degree: int, orders: int) -> tuple[np.ndarray, np.ndarray]:
    """The factors j!/(j-k)! and exponents max(j - k, 0) of :func:`_basis`, built once."""
    key = (degree, orders)
    if key not in _TABLES:
        k, j = np.meshgrid(np.arange(orders), np.arange(degree + 1), indexing="ij")
        P = np.vectorize(math.perm)(j, k).astype(float)
        _TABLES[key] = (P, np.maximum(j - k, 0).astype(float))
    return _TABLES[key]


def hermite_segment(duration: float, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """Coefficients c (2m, C) in tau of the polynomial p(tau) = sum_j c_j tau^j whose time
    derivatives 0..m-1 are ``start`` (m, C) at tau = 0 and ``end`` (m, C) at tau = 1 (time
    derivatives: d/dt = (1/duration) d/dtau)."""
    start, end = np.atleast_2d(start).astype(float), np.atleast_2d(end).astype(float)
    m = start.shape[0]
    if end.shape != start.shape:
        raise ValueError(f"start {start.shape} and end {end.shape} differ")
    if not duration > 0:
        raise ValueError(f"a segment needs a positive duration, got {duration!r}")
    degree = 2 * m - 1
    A = np.vstack([_basis(0.0, degree, m), _basis(1.0, degree, m)])
    scale = duration ** np.arange(m)[:, None]  # d^k/dtau^k = T^k d^k/dt^k
    return np.linalg.solve(A, np.vstack([start * scale, end * scale]))


class PiecewiseHermite:
    """Segments of :func:`hermite_segment` between ``knots`` (N + 1 increasing times), each
    with its own coefficients (N, 2m, C); before the first and after the last knot the curve
    holds its end value with zero derivatives (so the ends must be at rest for continuity:
    :meth:`from_waypoints` checks it).

    A segment need not start where the previous one ended (the orientation's rotation vector
    restarts from zero at each waypoint); :meth:`from_waypoints` builds a continuous curve.
    """

    def __init__(self, knots: np.ndarray, coefficients: np.ndarray) -> None:
        self.knots = np.asarray(knots, dtype=float)
        self.coefficients = np.asarray(coefficients, dtype=float)
        if self.knots.ndim != 1 or self.knots.size != self.coefficients.shape[0] + 1:
            raise ValueError("knots must be N + 1 times for N segments")
        if np.any(np.diff(self.knots) <= 0):
            raise ValueError("knots must increase")
        self.degree = self.coefficients.shape[1] - 1
        self.channels = self.coefficients.shape[2]

    @classmethod
    def from_waypoints(cls, knots: np.ndarray, derivatives: np.ndarray) -> "PiecewiseHermite":
        """The C^(m-1) curve through ``derivatives`` (N + 1, m, C): row i holds the value and
        the first m - 1 time derivatives at knot i."""
        knots = np.asarray(knots, dtype=float)
        derivatives = np.asarray(derivatives, dtype=float)
        if np.any(derivatives[0, 1:]) or np.any(derivatives[-1, 1:]):
            raise ValueError("the first and last waypoints must be at rest (the curve holds "
                             "still outside them)")
        coefficients = np.stack([
            hermite_segment(knots[i + 1] - knots[i], derivatives[i], derivatives[i + 1])
            for i in range(knots.size - 1)])
        return cls(knots, coefficients)

    @classmethod
    def through(cls, knots: np.ndarray, derivatives: np.ndarray) -> "PiecewiseHermite":
        """The C^(m-1) curve through ``derivatives`` (N + 1, m, C) at the knots, as
        :meth:`from_waypoints` but with no end at rest required (a sampled curve)."""
        derivatives = np.asarray(derivatives, dtype=float)
        return cls.from_segment_ends(knots, derivatives[:-1], derivatives[1:])

    @classmethod
    def from_segment_ends(cls, knots: np.ndarray, starts: np.ndarray, ends: np.ndarray
                          ) -> "PiecewiseHermite":
        """Segment i matching ``starts[i]`` (m, C) at knot i and ``ends[i]`` at knot i + 1:
        :func:`hermite_segment` for all segments at once."""
        knots = np.asarray(knots, dtype=float)
        starts, ends = np.asarray(starts, dtype=float), np.asarray(ends, dtype=float)
        m = starts.shape[1]
        degree = 2 * m - 1
        A = np.vstack([_basis(0.0, degree, m), _basis(1.0, degree, m)])
        scale = np.diff(knots)[:, None, None] ** np.arange(m)[None, :, None]
        rhs = np.concatenate([starts * scale, ends * scale], axis=1)
        return cls(knots, np.linalg.solve(A, rhs))

    def segment(self, t: float) -> tuple[int, float]:
        """(segment index, tau) at time t; tau clamped to [0, 1] outside the knots."""
        i = int(np.searchsorted(self.knots, t, side="right")) - 1
        i = min(max(i, 0), self.knots.size - 2)
        T = self.knots[i + 1] - self.knots[i]
        return i, min(max((t - self.knots[i]) / T, 0.0), 1.0)

    def evaluate(self, t: float, orders: int) -> np.ndarray:
        """The value and the first ``orders - 1`` time derivatives at t, (orders, C); outside
        the knots the end value and zero derivatives."""
        i, tau = self.segment(t)
        T = self.knots[i + 1] - self.knots[i]
        out = _basis(tau, self.degree, orders) @ self.coefficients[i]
        out /= (T ** np.arange(orders))[:, None]
        if t < self.knots[0] or t > self.knots[-1]:
            out[1:] = 0.0
        return out
