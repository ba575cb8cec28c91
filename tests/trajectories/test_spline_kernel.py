"""The compiled evaluation of the waypoints kind equals its numpy evaluation to round-off
(both modes, given velocities, every heading and CoM construction, orientation on SO(3))."""

import numpy as np
import pytest

from aerial_drake.simulation.scenarios import load_scenario
from aerial_drake.trajectories.hermite import PiecewiseHermite
from aerial_drake.trajectories.kinds import reference_of
from aerial_drake.trajectories.params import TrajectoryParams, Waypoint, WaypointsParams
from aerial_drake.trajectories.sampled import _signals
from aerial_drake.trajectories.spline_kernel import pack_spline_reference

# Measured: at most 1.3e-12 of a signal's largest value (pick_and_place, x_d'''' and the
# orientation's rates): the degree-9 segments' coefficients reach hundreds of times the
# change they blend, so either evaluation rounds at about that level.
ROUND_OFF = 5e-12


def _plan(mode: str, com: str, heading: str) -> TrajectoryParams:
    """Four waypoints turning about changing axes, with given velocities at an interior one
    (ee, angular, CoM, heading rate and joint velocities, as the section allows)."""
    rpys = [[0.0, 0.0, 0.0], [0.3, -0.2, 0.6], [-0.2, 0.4, 1.2], [0.1, 0.1, 1.5]]
    points = []
    for k, (t, rpy) in enumerate(zip((0.0, 1.5, 3.2, 4.4), rpys)):
        extra = {}
        if k == 1:
            extra = dict(ee_velocity=[0.05, -0.02, 0.03], ee_angular_velocity=[0.2, -0.1, 0.3],
                         joint_velocities=[0.1])
            if com == "waypoints":
                extra["com_velocity"] = [0.04, 0.01, -0.02]
            if heading == "given":
                extra["heading_rate"] = 0.15
        if com == "waypoints":
            extra["com"] = [0.3 + 0.1 * k, 0.05 * k, 1.9 - 0.02 * k]
        if heading == "given":
            extra["heading"] = 0.2 * k
        points.append(Waypoint(time=t, ee_position=[0.6 + 0.1 * k, 0.1 * np.sin(k), 1.3],
                               ee_rpy=rpy, joints=[0.2 * np.cos(k)], **extra))
    return TrajectoryParams(kind="waypoints", joint_targets=[0.0], waypoints=WaypointsParams(
        points=points, com=com, heading=heading, mode=mode))


def _compare(source, times):
    compiled = source.packed(times)
    numpy = np.empty_like(compiled)
    for k, t in enumerate(times):
        source.fill_interpreted(float(t), numpy[k])
    for name, index in _signals(source.n_joints):
        scale = np.abs(numpy[:, index]).max()
        error = np.abs(compiled[:, index] - numpy[:, index]).max()
        assert error <= ROUND_OFF * scale, (name, error, scale)
    R = compiled[:, 18:27].reshape(-1, 3, 3)
    np.testing.assert_allclose(R @ np.swapaxes(R, 1, 2), np.broadcast_to(np.eye(3), R.shape),
                               atol=1e-14)
    return compiled


@pytest.mark.parametrize("mode", ["stop", "through"])
@pytest.mark.parametrize("com, heading", [("offset", "given"), ("waypoints", "given"),
                                          ("offset", "along_path"), ("offset", "constant")])
def test_compiled_waypoints_equal_numpy_to_round_off(mode, com, heading):
    source = reference_of(_plan(mode, com, heading), None)
    # Before, between, at and after the waypoints (outside them the reference holds still).
    times = np.concatenate([np.linspace(-0.5, 5.0, 1500), [0.0, 1.5, 3.2, 4.4]])
    _compare(source, times)


def test_compiled_pick_and_place_equals_numpy_to_round_off():
    scenario = load_scenario("pick_and_place", validate=False)
    source = reference_of(scenario.trajectory, [0.0])
    compiled = _compare(source, np.linspace(0.0, 15.0, 3001))
    assert np.any(compiled[:, 15 + 15:15 + 18] != 0.0)  # it turns (w_ed)


def test_rule_33_needs_the_heading_angle():
    curve = PiecewiseHermite(np.array([0.0, 1.0]), np.zeros((1, 6, 3)))
    with pytest.raises(ValueError, match="rule \\(33\\) needs the heading angle"):
        pack_spline_reference(0, curve, curve, True, None, np.zeros(3), None, np.zeros(0),
                              curve, np.eye(3)[None], [None])
