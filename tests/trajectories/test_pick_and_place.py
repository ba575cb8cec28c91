"""The shipped pick-and-place (waypoints kind) converges and tracks the end effector to below
1 mm and 1 mrad after the first second; the logged reference (what the figures and Meshcat
draw) is the waypoints reference itself; a too-fast or out-of-reach edit is refused before
simulating, naming the time and the cause (issue 18)."""

import re

import numpy as np
import pytest

from aerial_drake.control.law import diagnostics_slices, task_size_of_diagnostics
from aerial_drake.simulation.feasibility import check_reference
from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import ScenarioError, load_scenario, shipped_scenarios
from aerial_drake.trajectories.kinds import sample_reference


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    scenario = load_scenario("pick_and_place")
    out = tmp_path_factory.mktemp("pp")
    result = run_scenario(scenario, out_dir=out / "pick_and_place", progress=False)
    return scenario, result, np.load(out / "pick_and_place" / "log.npz")


def test_tracks_below_a_millimetre_and_a_milliradian_after_the_first_second(run):
    scenario, result, log = run
    assert scenario.trajectory.kind == "waypoints"
    t, D = log["t"], log["diagnostics"]
    assert t[-1] == pytest.approx(scenario.duration)
    sl = diagnostics_slices(task_size_of_diagnostics(D.shape[1]))
    after = t >= 1.0
    position = D[after, sl["ee_position_error"]][:, 0]
    orientation = D[after, sl["ee_orientation_error"]][:, 0]
    assert position.max() < 1e-3, position.max()
    assert orientation.max() < 1e-3, orientation.max()
    # It did start off the reference (the first second shows convergence).
    assert D[t < 0.1, sl["ee_position_error"]][:, 0].max() > 0.01


def test_the_logged_reference_is_the_waypoints_reference(run):
    scenario, _, log = run
    model = scenario.controller_model()
    ref = sample_reference(scenario.trajectory, log["t"], model.task_joint_nominal())
    com, task, heading = ref.to_vectors()
    assert np.array_equal(log["com_reference"], com)
    assert np.array_equal(log["task_reference"], task)
    # At the place waypoint the logged end-effector reference is the waypoint's position.
    place = scenario.trajectory.waypoints.points[6]
    k = int(np.argmin(np.abs(log["t"] - place.time)))
    assert np.allclose(task[k, :3], place.ee_position, atol=1e-9)


def _edited(tmp_path, old, new):
    text = shipped_scenarios()["pick_and_place"].read_text()
    assert old in text
    path = tmp_path / "edited.yaml"
    path.write_text(text.replace(old, new, 1))
    scenario = load_scenario(path)
    return scenario, scenario.controller_model()


def _time_in(message):
    return float(re.search(r"t = ([0-9.]+) s", message).group(1))


def test_too_fast_for_the_thrust_limit_is_refused_before_simulating(tmp_path):
    # The descent to the pick point in 0.1 s instead of 1.5 s.
    scenario, model = _edited(tmp_path, "time: 3.5,", "time: 2.1,")
    with pytest.raises(ScenarioError) as err:
        check_reference(scenario, model)
    message = str(err.value)
    assert "thrust" in message, message
    assert 2.0 <= _time_in(message) <= 2.1


def test_out_of_reach_is_refused_before_simulating(tmp_path):
    # The CoM rule (33) puts the CoM 3 m from the end effector: beyond the arm's reach.
    scenario, model = _edited(tmp_path, "com_offset: [-0.3, 0.0, 0.6]",
                              "com_offset: [-0.3, 0.0, 3.0]")
    with pytest.raises(ScenarioError) as err:
        check_reference(scenario, model)
    message = str(err.value)
    assert "leaves the arm's workspace" in message and _time_in(message) >= 0.0, message
