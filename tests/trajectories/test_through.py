"""mode: through's knot derivatives: the least-snap curve (no change of a free knot derivative
lowers the integral of the squared snap, computed here by quadrature, independently of the
solve), given velocities kept, the ends at rest, the same curve whatever the time unit; the
orientation's rates those of the same curve through the rotation angle about a fixed axis
(issue 28)."""

import numpy as np
import pytest

from aerial_drake.trajectories.hermite import PiecewiseHermite
from aerial_drake.trajectories.so3 import exp_so3
from aerial_drake.trajectories.through import knot_rotation_rates, through_derivatives

KNOTS = np.array([0.0, 0.8, 2.0, 2.7, 4.1, 5.0])
VALUES = np.array([[0.0, 1.0], [0.3, 1.2], [0.2, 0.9], [0.6, 1.1], [0.5, 1.4], [0.9, 1.0]])


def _snap_cost(knots, derivatives):
    """int |x''''|^2 dt by 8-point Gauss-Legendre on each segment (exact: degree 10)."""
    curve = PiecewiseHermite.from_waypoints(knots, derivatives)
    nodes, weights = np.polynomial.legendre.leggauss(8)
    total = 0.0
    for a, b in zip(knots[:-1], knots[1:]):
        for x, w in zip(nodes, weights):
            snap = curve.evaluate(a + (b - a) * (x + 1) / 2, 5)[4]
            total += w * (b - a) / 2 * float(snap @ snap)
    return total


def test_no_change_of_a_free_knot_derivative_lowers_the_snap_integral():
    d = through_derivatives(KNOTS, VALUES)
    best = _snap_cost(KNOTS, d)
    for i in range(1, KNOTS.size - 1):
        for k in range(1, 5):
            for step in (1e-2, -1e-2):
                changed = d.copy()
                changed[i, k, 0] += step * 10.0 ** (k - 1)
                assert _snap_cost(KNOTS, changed) > best, (i, k, step)


def test_the_ends_rest_and_the_values_and_given_velocities_are_kept_exactly():
    velocities = np.full(VALUES.shape, np.nan)
    velocities[2] = [0.4, -0.1]
    d = through_derivatives(KNOTS, VALUES, velocities)
    np.testing.assert_array_equal(d[:, 0], VALUES)
    np.testing.assert_array_equal(d[2, 1], [0.4, -0.1])
    assert not d[[0, -1], 1:].any()
    free = through_derivatives(KNOTS, VALUES)
    assert np.abs(free[2, 1] - d[2, 1]).max() > 0.05  # the given velocity changed something
    # ...and the rest is still the least snap with that velocity held.
    best = _snap_cost(KNOTS, d)
    for k in (2, 3, 4):
        changed = d.copy()
        changed[2, k] += 1e-2 * 10.0 ** (k - 1)
        assert _snap_cost(KNOTS, changed) > best


@pytest.mark.parametrize("scale", [1e-2, 1e3])
def test_the_same_curve_in_any_time_unit(scale):
    d = through_derivatives(KNOTS, VALUES)
    scaled = through_derivatives(KNOTS * scale, VALUES)
    powers = scale ** -np.arange(5)
    np.testing.assert_allclose(scaled, d * powers[None, :, None], rtol=1e-8,
                               atol=1e-12 * np.abs(d).max())


def test_rotation_rates_about_a_fixed_axis_are_the_angle_curves():
    axis = np.array([1.0, 2.0, -0.5]) / np.linalg.norm([1.0, 2.0, -0.5])
    R0 = exp_so3(np.array([0.3, -0.2, 0.9]))
    angles = np.array([0.0, 0.12, 0.35, 0.5, 0.62, 0.7])  # all within pi/2 of each other
    rotations = [exp_so3(axis * a) @ R0 for a in angles]  # World axis: w = theta' axis
    omega, alpha = knot_rotation_rates(KNOTS, rotations, [None] * KNOTS.size)
    theta = through_derivatives(KNOTS, angles)
    np.testing.assert_allclose(omega, theta[:, 1, 0][:, None] * axis, atol=1e-10)
    np.testing.assert_allclose(alpha, theta[:, 2, 0][:, None] * axis, atol=1e-10)
    assert np.abs(omega[1:-1]).max() > 0.05
    # A given angular velocity is kept; the acceleration then changes.
    given = [None] * KNOTS.size
    given[3] = np.array([0.0, 0.3, 0.0])
    omega_given, alpha_given = knot_rotation_rates(KNOTS, rotations, given)
    np.testing.assert_allclose(omega_given[3], given[3], atol=1e-12)
    assert np.abs(alpha_given[3] - alpha[3]).max() > 1e-3
