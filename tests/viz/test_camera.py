"""The camera of a run's Meshcat view (:mod:`aerial_drake.viz.camera`): the robot stays in
view over the whole run."""

import dataclasses

import numpy as np
import pytest

from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import load_scenario, shipped_scenarios
from aerial_drake.trajectories import kinds
from aerial_drake.trajectories.kinds import reference_of
from aerial_drake.trajectories.params import HoverParams, TrajectoryParams
from aerial_drake.viz import camera as dut
from aerial_drake.viz.meshcat_view import MeshcatView


@pytest.mark.parametrize("name", sorted(shipped_scenarios()))
def test_camera_keeps_the_robot_in_view(name):
    """Over the whole run, the robot's envelope (end-effector path, skids and rotor rims about
    the CoM path) stays inside a 4:3 window, and fills most of it."""
    scenario = load_scenario(name)
    camera, target = dut.camera_for(scenario)
    xy = dut.view_coordinates(camera, target, dut.robot_envelope(scenario))
    fill = max(np.abs(xy[:, 0]).max() / (4 / 3), np.abs(xy[:, 1]).max())
    assert 0.8 < fill <= dut.CAMERA_FILL + 1e-6
    # The start is in view too (the envelope holds t = 0).
    start = reference_of(scenario.trajectory).evaluate(0.0).com[0]
    assert np.all(np.abs(dut.view_coordinates(camera, target, [start])) < 0.9)
    # view_coordinates itself: the target is the centre, a point up the screen has y > 0.
    np.testing.assert_allclose(dut.view_coordinates(camera, target, [target]), [[0, 0]],
                               atol=1e-12)
    assert dut.view_coordinates(camera, target, [target + [0, 0, 0.5]])[0, 1] > 0


def test_the_camera_frames_the_reference_it_is_given():
    """With a reference handed in (the run's), the envelope is that reference's path, not one
    rebuilt from the scenario."""
    scenario = load_scenario("nominal")
    elsewhere = TrajectoryParams(kind="hover", hover=HoverParams(ee_position=[5.0, 6.0, 7.0]))
    points = dut.robot_envelope(scenario, reference_of(elsewhere, [0.0]))
    assert np.any(np.all(points == [5.0, 6.0, 7.0], axis=1))
    assert not np.any(np.all(dut.robot_envelope(scenario) == [5.0, 6.0, 7.0], axis=1))


def test_a_watched_run_builds_its_reference_once(monkeypatch):
    """The Meshcat view (camera and overlay) draws the run's own reference: a watched run
    builds no more references than the scenario's load-time check and the run's one."""
    scenario = load_scenario("nominal", overrides={"duration": 0.1})
    builds = []
    entry = kinds.REFERENCE_KINDS["paper"]
    monkeypatch.setitem(kinds.REFERENCE_KINDS, "paper", dataclasses.replace(
        entry, build=lambda params, targets: builds.append(1) or entry.build(params, targets)))
    view = MeshcatView(scenario, port=0, live=False)
    run_scenario(scenario, progress=False, configure=view.configure)
    view.finish()
    assert len(builds) == 2  # Scenario.validate's check, then the run's
