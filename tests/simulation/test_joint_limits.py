"""The arm's joint limits in a run (aerial_drake.simulation.joint_limits and the scenario's
``joint_limits``): the ratios, the first sample past a limit, the modes' checks, and short
runs (0.6 s) whose reference turns the LWR's joint 7 past its +-170 deg limit."""

import copy
import io
import math
from types import SimpleNamespace

import numpy as np
import pytest

from aerial_drake.cli.run import _warn_past_limits
from aerial_drake.simulation import joint_limits as dut
from aerial_drake.simulation.diagram import build_closed_loop
from aerial_drake.simulation.runner import SimulationFailed, run_scenario
from aerial_drake.simulation.scenarios import (
    JointLimits,
    ScenarioError,
    load_scenario,
    shipped_scenarios,
)
from aerial_drake.viz.run_plots import write_run_figures

INF = math.inf
#: A free box beside the robot (7 more positions, 6 more velocities in the plant's state).
BOX = """
environment:
  directives:
  - add_model:
      name: box
      file: package://aerial_drake/environments/box.sdf
      default_free_body_pose:
        box:
          translation: [3.0, 0.0, 0.8]
"""


def limits(lower, upper, velocity):
    n = len(lower)
    return dut.ArmLimits(names=tuple(f"j{i + 1}" for i in range(n)), revolute=(True,) * n,
                         lower=np.array(lower, float), upper=np.array(upper, float),
                         velocity=np.array(velocity, float),
                         q_index=np.arange(n), v_index=n + np.arange(n))


def states(q, v=None):
    q = np.atleast_2d(np.asarray(q, float))
    return np.hstack([q, np.zeros_like(q) if v is None else np.atleast_2d(v)])


# --- The ratios --------------------------------------------------------------------------
def test_position_ratio_is_q_over_the_limit_of_its_side_and_one_at_the_limit():
    lim = limits([-2.0, -1.0, 0.5, -INF, -INF, 1.0], [2.0, 3.0, 2.5, 1.0, INF, INF],
                 [1.0] * 6)
    # Opposite signs: q / upper above 0, q / lower below it.
    r = lim.position_ratios(states([[1.0, -0.5, 1.5, 0.5, 7.0, 2.0],
                                    [-3.0, 3.3, 2.5, -9.0, -7.0, 1.0]]))
    assert r[0, 0] == 0.5 and r[1, 0] == 1.5  # symmetric: |q| / limit
    assert r[0, 1] == 0.5 and r[1, 1] == pytest.approx(1.1)  # -0.5 / -1, 3.3 / 3
    # Limits of one sign: from the middle of the range, 1 at either limit.
    assert r[0, 2] == 0.0 and r[1, 2] == 1.0
    # One finite side straddling 0: q / that limit; the infinite side is never reached.
    assert r[0, 3] == 0.5 and r[1, 3] == 0.0
    # No finite limit: no ratio.
    assert np.isnan(r[:, 4]).all()
    # One-sided, not straddling 0: measured from 1 rad inside the limit.
    assert r[1, 5] == 1.0 and r[0, 5] == 0.0


def test_velocity_ratio_and_the_metrics_entries():
    lim = limits([-1.0, -INF], [1.0, INF], [2.0, INF])
    x = states([[0.5, 100.0], [1.2, -100.0]], [[-3.0, 50.0], [1.0, 0.0]])
    np.testing.assert_array_equal(lim.velocity_ratios(x)[:, 0], [1.5, 0.5])
    assert np.isnan(lim.velocity_ratios(x)[:, 1]).all()
    metrics = dut.limit_metrics(x, lim)
    assert metrics["joint_limits"]["j1"] == {
        "position_ratio": 1.2, "velocity_ratio": 1.5, "lower_rad": -1.0, "upper_rad": 1.0,
        "velocity_limit_rad_s": 2.0}
    assert metrics["joint_limits"]["j2"]["position_ratio"] is None
    assert metrics["joint_limits"]["j2"]["velocity_ratio"] is None
    assert metrics["joint_limits_exceeded"] == ["j1"]
    assert dut.exceeded_summary(metrics) == "j1 position 1.20 velocity 1.50"
    inside = dut.limit_metrics(states([[0.5, 0.0]]), lim)
    assert inside["joint_limits_exceeded"] == [] and dut.exceeded_summary(inside) is None


def test_monitor_finds_the_first_sample_past_a_stopping_limit_and_names_it():
    lim = limits([-1.0, -2.0], [1.0, 2.0], [5.0, 0.5])
    x = states([[0.0, 0.0], [0.5, -1.0], [0.9, -2.5], [1.1, 0.0]],
               [[0, 0], [0, 0.6], [0, 0], [0, 0]])
    assert dut.LimitMonitor(lim, "report", "report").first_crossing(x) is None
    assert dut.LimitMonitor(lim, "stop", "report").first_crossing(x) == 2
    assert dut.LimitMonitor(lim, "report", "stop").first_crossing(x) == 1
    assert dut.LimitMonitor(lim, "stop", "stop").first_crossing(x) == 1
    monitor = dut.LimitMonitor(lim, "stop", "report")
    assert not monitor.past(x[1]) and monitor.past(x[2])
    message = monitor.message(12.34567, x[2])
    assert message.startswith("t = 12.3457 s: joint limit: j2 at -143.2 deg (-2.5000 rad) is "
                              "past its lower limit -114.6 deg (-2.0000 rad)")
    assert "joint_limits.positions" in message
    velocity = dut.LimitMonitor(lim, "report", "stop").message(1.0, x[1])
    assert velocity.startswith("t = 1.0000 s: joint limit: j2 moves at")
    assert "velocity limit" in velocity and "joint_limits.velocities" in velocity
    # The log is cut at the crossing, unless something else (a non-finite sample) came first.
    arrays = {"t": np.arange(4.0), "plant_state": x}
    cut, t, text = monitor.cut(arrays)
    assert t == 2.0 and len(cut["t"]) == 3 and text.startswith("t = 2.0000 s: joint limit")
    assert monitor.cut(arrays, before=1) is None


# --- The scenario field ------------------------------------------------------------------
def test_modes_are_checked_and_enforce_needs_a_discrete_plant():
    assert load_scenario("orbit").joint_limits.positions == "stop"  # the default
    assert load_scenario("orbit").joint_limits.velocities == "report"
    for name in ("nominal", "disturbed"):  # the paper's motion, limits reported
        assert (load_scenario(name).joint_limits.positions,
                load_scenario(name).joint_limits.velocities) == ("report", "report")
    with pytest.raises(ScenarioError, match="joint_limits.positions: 'hold' is not one of "
                                            "stop, enforce, report"):
        load_scenario("orbit", overrides={"joint_limits.positions": "hold"})
    with pytest.raises(ScenarioError, match="joint_limits.velocities: 'enforce' is not one "
                                            "of stop, report"):
        load_scenario("orbit", overrides={"joint_limits.velocities": "enforce"})
    with pytest.raises(ScenarioError, match=r"'enforce' needs a discrete plant.*set "
                                            r"plant.time_step \(e.g. 0.001\)") as err:
        load_scenario("orbit", overrides={"joint_limits.positions": "enforce"})
    assert err.value.field == "joint_limits.positions"
    load_scenario("orbit", overrides={"joint_limits.positions": "enforce",
                                      "plant.time_step": 0.001})


# --- Runs past a limit -------------------------------------------------------------------
LIMIT_7 = math.radians(170.0)


def wrist_turn(**overrides):
    """pick_and_place's start, then the end effector yawing -3.1 rad (rest to rest in two
    steps, 0.5 s) while the vehicle keeps its heading: joint 7 (the wrist's vertical axis)
    turns to +3.1 rad, past its 170 deg (2.967 rad) limit at about 0.44 s."""
    scenario = load_scenario("pick_and_place", overrides={
        "duration": 0.6, "initial.base_position_offset": [0.0, 0.0, 0.0],
        "initial.base_rpy_offset": [0.0, 0.0, 0.0], **overrides})
    start = scenario.trajectory.waypoints.points[0]
    points = []
    for time, yaw in ((0.0, 0.0), (0.25, -1.55), (0.5, -3.1)):
        point = copy.deepcopy(start)
        point.time, point.ee_rpy = time, [0.0, 0.0, yaw]
        points.append(point)
    scenario.trajectory.waypoints.points = points
    return scenario


def q7(result):
    return result.log["plant_state"][:, 7 + 6]


def test_report_lets_the_joint_pass_and_reports_it(tmp_path):
    result = run_scenario(wrist_turn(**{"joint_limits.positions": "report"}), progress=False,
                          out_dir=tmp_path)
    assert result.completed and q7(result).max() > LIMIT_7 + math.radians(5)
    entry = result.metrics["joint_limits"]["lwr_joint_7"]
    assert entry["position_ratio"] == pytest.approx(q7(result).max() / LIMIT_7)
    assert entry["upper_rad"] == pytest.approx(LIMIT_7)
    assert "lwr_joint_7" in result.metrics["joint_limits_exceeded"]
    # The run's figures include its joints against their limits.
    assert tmp_path / "joint_limits.png" in write_run_figures(tmp_path)


def test_a_run_folders_limits_index_its_log_as_the_run_did(tmp_path):
    """The plant rebuilt from a scenario (rotor joints; a free box in the environment) puts
    the arm's coordinates where the simulated plant of its run had them."""
    boxed = tmp_path / "boxed.yaml"
    boxed.write_text(shipped_scenarios()["orbit"].read_text() + BOX)
    for scenario in (load_scenario("disturbed"), load_scenario(boxed)):
        loop = build_closed_loop(scenario)
        expected = dut.ArmLimits.of(loop.simulated_plant)
        rebuilt = dut.scenario_arm_limits(scenario)
        assert rebuilt.names == expected.names
        for name in ("q_index", "v_index", "lower", "upper", "velocity"):
            np.testing.assert_array_equal(getattr(rebuilt, name), getattr(expected, name))


@pytest.mark.parametrize("time_step", [0.0, 0.001])
def test_stop_ends_the_run_at_the_crossing_naming_the_joint(time_step):
    """The continuous plant lets the joint pass, the discrete one holds it with a compliant
    constraint (a little past): both stop at the first sample past the limit."""
    with pytest.raises(SimulationFailed, match=r"t = 0\.4\d{3} s: joint limit: lwr_joint_7 at "
                                               r"170\.0 deg .* upper limit 170\.0 deg") as err:
        run_scenario(wrist_turn(**{"plant.time_step": time_step}), progress=False)
    result = err.value.result
    assert not result.completed and result.failure.startswith(
        f"t = {result.log['t'][-1]:.4f} s: joint limit: lwr_joint_7")
    # The log and the metrics end at the first sample past the limit.
    assert q7(result)[-1] > LIMIT_7 and np.all(q7(result)[:-1] <= LIMIT_7)
    assert result.metrics["simulated_time_s"] == result.log["t"][-1]


def test_enforce_holds_the_joint_at_its_limit_on_a_discrete_plant():
    result = run_scenario(wrist_turn(**{"joint_limits.positions": "enforce",
                                        "plant.time_step": 0.001}), progress=False)
    assert result.completed and result.log["t"][-1] == pytest.approx(0.6)
    # Drake's discrete plant holds it there (a compliant constraint: within 1e-5 rad).
    assert q7(result).max() == pytest.approx(LIMIT_7, abs=1e-5)
    assert np.abs(q7(result)[-100:] - LIMIT_7).max() < 1e-3  # and keeps it there


def test_velocities_stop_names_the_speed():
    with pytest.raises(SimulationFailed, match=r"joint limit: lwr_joint_7 moves at .* past its "
                                               r"velocity limit 184\.0 deg/s"):
        run_scenario(wrist_turn(**{"joint_limits.positions": "report",
                                   "joint_limits.velocities": "stop"}), progress=False)


def test_the_runner_stops_early_at_a_pause_past_a_limit():
    """A 2.5 s run past the limit at 0.44 s stops at the pause of 1 s, not at its end (the
    log is then cut at the crossing)."""
    stopped_at = []
    original = dut.LimitMonitor.past

    def past(self, x):
        stopped_at.append(original(self, x))
        return stopped_at[-1]

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(dut.LimitMonitor, "past", past)
        with pytest.raises(SimulationFailed, match="t = 0.4"):
            run_scenario(wrist_turn(duration=2.5), progress=False)
    assert stopped_at == [True]  # the first pause (1 s) was past; no other was reached


def test_the_command_line_warns_in_one_line_of_limits_it_only_reports():
    metrics = dut.limit_metrics(states([[1.2, 0.0]], [[3.0, 0.0]]),
                                limits([-1.0, -1.0], [1.0, 1.0], [2.0, 2.0]))
    for modes, expected in ((("report", "report"), "j1 position 1.20 velocity 1.50"),
                            (("stop", "report"), "j1 velocity 1.50"),
                            (("enforce", "stop"), None)):
        stream = io.StringIO()
        result = SimpleNamespace(scenario=SimpleNamespace(joint_limits=JointLimits(*modes)),
                                 metrics=metrics)
        _warn_past_limits(result, stream)
        if expected is None:
            assert stream.getvalue() == ""
        else:
            assert stream.getvalue().count("\n") == 1
            assert stream.getvalue().startswith("warning: past the arm's joint limits")
            assert stream.getvalue().rstrip().endswith(expected)
