"""The waypoints kind's orientation through a waypoint with a given angular velocity (not rest
to rest): the angular velocity there is the given one, the angular acceleration is zero from
both sides (continuous), and each derivative is the rate of the one below (issue 27)."""

import numpy as np
import pytest

from aerial_drake.trajectories.kinds import reference_of
from aerial_drake.trajectories.params import TrajectoryParams, Waypoint, WaypointsParams

W_GIVEN = [0.3, -0.2, 0.4]  # rad/s, World


@pytest.fixture(scope="module")
def source():
    points = [
        Waypoint(time=0.0, ee_position=[0.6, 0.0, 1.0], ee_rpy=[0.0, 0.0, 0.0]),
        Waypoint(time=1.3, ee_position=[0.7, 0.1, 1.0], ee_rpy=[0.2, -0.3, 0.5],
                 ee_angular_velocity=W_GIVEN, ee_velocity=[0.05, 0.02, 0.0]),
        Waypoint(time=2.9, ee_position=[0.6, 0.2, 1.1], ee_rpy=[-0.1, 0.2, 0.9]),
    ]
    params = TrajectoryParams(kind="waypoints", joint_targets=[0.0],
                              waypoints=WaypointsParams(points=points))
    return reference_of(params, None)


def test_the_given_angular_velocity_is_flown_with_zero_angular_acceleration(source):
    at = source.evaluate(1.3)
    np.testing.assert_allclose(at.w_ed, W_GIVEN, atol=1e-12)
    for t in (1.3 - 1e-9, 1.3, 1.3 + 1e-9):
        np.testing.assert_allclose(source.evaluate(t).dw_ed, 0.0, atol=1e-7)


@pytest.mark.parametrize("t", [1.3 - 2e-3, 1.3 - 1e-4, 1.3 + 1e-4, 1.3 + 2e-3, 0.7, 2.2])
def test_angular_acceleration_is_the_rate_of_angular_velocity_through_the_waypoint(source, t):
    h = 1e-6
    lo, mid, hi = source.evaluate(t - h), source.evaluate(t), source.evaluate(t + h)
    np.testing.assert_allclose((hi.w_ed - lo.w_ed) / (2 * h), mid.dw_ed, atol=1e-6)
    D = hi.R_ed @ lo.R_ed.T  # w from R: vee(D - D^T) / 2 / 2h, small angle
    w = 0.5 * np.array([D[2, 1] - D[1, 2], D[0, 2] - D[2, 0], D[1, 0] - D[0, 1]]) / (2 * h)
    np.testing.assert_allclose(w, mid.w_ed, atol=1e-6)
