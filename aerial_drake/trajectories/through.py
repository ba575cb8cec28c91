"""Knot derivatives for the waypoints kind's ``mode: through``: the velocity, acceleration,
jerk and snap at each interior waypoint that make the path pass through without stopping.

Positions, CoM, heading, joint angles (:func:`through_derivatives`): the curve between
waypoints stays the degree-9 Hermite of :mod:`.hermite` (value and four derivatives matched
at both ends of each segment, so C^4 whatever the knot derivatives are); only the knot
derivatives change. Of all such C^4 curves through the waypoints' values (and their given
velocities), the one with the least integral of the squared snap, int |x''''|^2 dt
(Mellinger and Kumar's minimum-snap criterion for quadrotors: the snap is what the attitude
feed-forward (13)-(16) differentiates the thrust from). Away from the ends that minimiser is
the interpolating spline of degree 7 (C^6), which the degree-9 segments hold exactly; the
first and last waypoints are fully at rest (the reference holds still outside them).

Why this rather than knot derivatives from a C^2 cubic spline or from finite differences,
fed to the same segments: it is one spline, so between the knots the curve is what the knot
derivatives promise, and it stays closest to a smooth path the waypoints were sampled from.
Measured (docs/trajectories.md, "mode: through": a rest-to-rest planned CoM path, 0.8 m in
10 s, sampled at 8 waypoints, largest distance from the plan): rest at each waypoint
(``mode: stop``) 62 mm, three-point differences 16 mm, a cubic spline's velocity and
acceleration 8.1 mm, least jerk 4.7 mm, least snap 3.4 mm (and the least peak snap). The
price: the solve is global (moving one waypoint moves every segment a little, less with
distance), so a hold (two equal waypoints) is no longer exact: use ``mode: stop`` for that.

Orientation (:func:`knot_rotation_rates`): the angular velocity and acceleration the
per-segment quintics of :mod:`.waypoints` match (C^2 on SO(3) whatever they are), from the
same least-snap curve through the neighbours' rotation vectors in the waypoint's own tangent
space (SO(3) has no global chart for one global spline).

Pure numpy, at build time: one symmetric positive-definite solve (4 unknowns per free knot)
shared by every channel.
"""

from __future__ import annotations

import math

import numpy as np

from aerial_drake.trajectories.so3 import log_so3

__all__ = ["through_derivatives", "knot_rotation_rates", "MINIMISED_ORDER", "KNOT_ORDERS",
           "ROTATION_NEIGHBOURS"]

#: Value and four derivatives at each knot (the Hermite segments' m = 5, C^4).
KNOT_ORDERS = 5
#: The derivative whose squared integral is minimised: 4, the snap (module docstring).
MINIMISED_ORDER = 4
#: Waypoints on each side whose orientations set a waypoint's angular velocity and
#: acceleration (:func:`knot_rotation_rates`).
ROTATION_NEIGHBOURS = 4
#: A second neighbour further than this from the waypoint (rad) is left out: its rotation
#: vector would be near the log's branch cut at pi.
NEIGHBOUR_MAX_ANGLE = math.pi / 2


def _hermite_inverse(m: int) -> np.ndarray:
    """A^-1 (2m, 2m): the degree-(2m - 1) coefficients in tau from [start; end] derivatives
    in tau (the matrix :func:`aerial_drake.trajectories.hermite.hermite_segment` solves)."""
    degree = 2 * m - 1
    rows = []
    for tau in (0.0, 1.0):
        for k in range(m):
            rows.append([math.perm(j, k) * tau ** (j - k) if j >= k else 0.0
                         for j in range(degree + 1)])
    return np.linalg.inv(np.array(rows))


def _gram(degree: int, order: int) -> np.ndarray:
    """Q[i, j] = int_0^1 (d^order tau^i)(d^order tau^j) dtau."""
    Q = np.zeros((degree + 1, degree + 1))
    for i in range(order, degree + 1):
        for j in range(order, degree + 1):
            Q[i, j] = (math.perm(i, order) * math.perm(j, order)
                       / (i + j - 2 * order + 1))
    return Q


def _segment_cost(duration: float, order: int) -> np.ndarray:
    """K (2m, 2m): int over the segment of |d^order x/dt^order|^2 = d^T K d for d = [start;
    end] time derivatives 0..m-1 (d/dt = (1/T) d/dtau, dt = T dtau)."""
    m = KNOT_ORDERS
    scale = np.tile(duration ** np.arange(m), 2)  # time derivatives -> tau derivatives
    B = _hermite_inverse(m) * scale[None, :]
    return duration ** (1 - 2 * order) * B.T @ _gram(2 * m - 1, order) @ B


def through_derivatives(knots: np.ndarray, values: np.ndarray,
                        velocities: np.ndarray | None = None,
                        order: int = MINIMISED_ORDER,
                        at_rest: tuple[bool, bool] = (True, True)) -> np.ndarray:
    """Knot derivatives (N + 1, 5, C) for
    :meth:`~aerial_drake.trajectories.hermite.PiecewiseHermite.from_waypoints`: the values
    (N + 1, C), at the first and last knot zero derivatives, at each interior knot the given
    velocity (a row of ``velocities`` (N + 1, C) that is not NaN; None: none given) and
    every other derivative chosen to minimise int |d^order x / dt^order|^2 (module
    docstring). ``at_rest``: whether the first and the last knot are at rest (False: their
    derivatives are chosen too, a natural end; :func:`knot_rotation_rates`' windows)."""
    knots = np.asarray(knots, dtype=float)
    values = np.asarray(values, dtype=float).reshape(knots.size, -1)
    n, channels, m = knots.size, values.shape[1], KNOT_ORDERS
    out = np.zeros((n, m, channels))
    out[:, 0] = values
    fixed = np.zeros((n, m), dtype=bool)
    fixed[:, 0] = True
    fixed[0, 1:], fixed[-1, 1:] = at_rest  # at rest: the reference holds still outside
    if velocities is not None:
        velocities = np.asarray(velocities, dtype=float).reshape(n, channels)
        given = ~np.isnan(velocities).any(axis=1)
        given[0] &= not at_rest[0]  # an end at rest stays so whatever is given there
        given[-1] &= not at_rest[1]
        fixed[given, 1] = True
        out[given, 1] = velocities[given]
    if fixed.all():
        return out
    # Time in units of the mean segment: the solve's scale is then near 1 whatever the
    # waypoints' spacing (derivative k scales by unit^k).
    unit = float(knots[-1] - knots[0]) / (n - 1)
    powers = unit ** np.arange(m)
    durations = np.diff(knots) / unit
    H = np.zeros((n * m, n * m))
    for i, T in enumerate(durations):
        block = slice(i * m, (i + 2) * m)
        H[block, block] += _segment_cost(float(T), order)
    z = (out * powers[None, :, None]).reshape(n * m, channels)
    free = ~fixed.reshape(-1)
    z[free] = np.linalg.solve(H[np.ix_(free, free)], -H[np.ix_(free, ~free)] @ z[~free])
    return z.reshape(n, m, channels) / powers[None, :, None]


def knot_rotation_rates(knots: np.ndarray, rotations: list[np.ndarray],
                        given: list[np.ndarray | None]) -> tuple[np.ndarray, np.ndarray]:
    """World angular velocities and accelerations (N + 1, 3) at the waypoints of
    ``rotations`` for ``mode: through``: zero at the first and last; at an interior waypoint
    i, those at t_i of the least-snap curve (:func:`through_derivatives`) through the
    rotation vectors r_j = log(R_i^T R_j) of up to :data:`ROTATION_NEIGHBOURS` waypoints j
    on each side (r_i = 0), at rest where the window reaches the first or last waypoint and
    free (natural) where it stops short. Each waypoint has its own chart, the tangent space
    at R_i: SO(3) has no global one for a global spline, and R_i's is exact for a rotation
    about a fixed axis (then the rates are the angle's spline's). A waypoint's ``given``
    angular velocity (World; None: not given) is kept and only the acceleration chosen. At
    r = 0 the rotation vector's rates are the body angular velocity and acceleration
    (J_r(0) = I, dJ_r/dt r' = 0)."""
    n = len(rotations)
    omega, alpha = np.zeros((n, 3)), np.zeros((n, 3))
    for i in range(1, n - 1):
        R_i = rotations[i]
        window = [i]
        for step in (-1, 1):  # outwards while the log stays away from its cut at pi
            j = i + step
            while 0 <= j < n and abs(j - i) <= ROTATION_NEIGHBOURS:
                if abs(j - i) > 1 and np.linalg.norm(
                        log_so3(R_i.T @ rotations[j])) > NEIGHBOUR_MAX_ANGLE:
                    break
                window.append(j)
                j += step
        window.sort()
        vectors = np.array([log_so3(R_i.T @ rotations[j]) for j in window])
        rates = np.full((len(window), 3), np.nan)
        here = window.index(i)
        if given[i] is not None:
            rates[here] = R_i.T @ np.asarray(given[i], dtype=float)
        # Fewer than 4 waypoints with a free end: minimise the jerk instead (the snap's null
        # space, cubics, would not be pinned by 3 values).
        order = MINIMISED_ORDER if len(window) >= 4 else MINIMISED_ORDER - 1
        d = through_derivatives(knots[window], vectors, rates, order,
                                (window[0] == 0, window[-1] == n - 1))
        omega[i], alpha[i] = R_i @ d[here, 1], R_i @ d[here, 2]
    return omega, alpha
