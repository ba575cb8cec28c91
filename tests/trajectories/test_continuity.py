"""continuity.knot_jumps: a jump at a knot in any derivative the law reads (here the CoM's snap
and the end effector's acceleration, down to 1e-4 of their size) is found and named with its
knot; a fast but smooth change at a knot is not (issue 28)."""

import dataclasses

import numpy as np

from aerial_drake.trajectories.continuity import knot_jumps
from aerial_drake.trajectories.kinds import reference_of
from aerial_drake.trajectories.params import TrajectoryParams, Waypoint, WaypointsParams

KNOTS = [0.0, 1.0, 2.5, 3.0, 4.5]


def _source():
    points = [Waypoint(time=t, ee_position=[0.6 + 0.1 * t, 0.05 * t * t, 1.0],
                       com=[0.3 + 0.1 * t, 0.05 * t * t, 1.6], ee_rpy=[0.0, 0.05 * t, 0.1 * t])
              for t in KNOTS]
    return reference_of(TrajectoryParams(kind="waypoints", joint_targets=[0.0],
                                         waypoints=WaypointsParams(points=points,
                                                                   com="waypoints",
                                                                   mode="through")), None)


def _patched(change):
    source = _source()

    def sample(times):
        times = np.asarray(times, dtype=float)
        return change(times, source.sample(times))
    return sample


def test_a_smooth_reference_has_no_knot_jump():
    assert knot_jumps(_source().sample, KNOTS) == []


def test_a_small_step_in_the_snap_at_a_knot_is_named():
    def step(times, ref):
        com = ref.com.copy()
        com[:, 4, 1] += 1e-4 * (times >= 2.5)
        return dataclasses.replace(ref, com=com)
    found = knot_jumps(_patched(step), KNOTS)
    assert [(d.time, d.signal) for d in found] == [(2.5, "x_d''''")], found
    assert "x_d'''' jumps at the knot t = 2.500000 s" in found[0].describe()
    assert abs(found[0].size - 1e-4) < 1e-6


def test_a_step_in_the_end_effector_acceleration_is_named():
    def step(times, ref):
        return dataclasses.replace(ref, a_ed=ref.a_ed + 1e-3 * (times >= 1.0)[:, None])
    found = knot_jumps(_patched(step), KNOTS)
    assert [(d.time, d.signal) for d in found] == [(1.0, "a_ed")], found


def test_a_fast_but_smooth_change_at_a_knot_is_not_a_jump():
    def wiggle(times, ref):
        com = ref.com.copy()
        com[:, 4, 0] += np.sin(50.0 * (times - 3.0))  # 50 rad/s through the knot at 3 s
        return dataclasses.replace(ref, com=com)
    assert knot_jumps(_patched(wiggle), KNOTS) == []
