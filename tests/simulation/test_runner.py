"""Tests of aerial_drake.simulation.runner's simulation loop: where it pauses, that pausing
changes no number, progress lines, a diverging plant, and the references it logs."""

import io
import json
import re

import numpy as np
import pytest
from pydrake.systems.analysis import ApplySimulatorConfig, Simulator

from aerial_drake.control.registry import zero_controller
from aerial_drake.simulation import runner as dut
from aerial_drake.simulation.diagram import build_simulation
from aerial_drake.simulation.scenarios import load_scenario
from aerial_drake.trajectories.generator import ReferenceGenerator

DURATION = 2.5


def short_nominal():
    return load_scenario("nominal", overrides={"duration": DURATION})


@pytest.fixture(scope="module")
def zero_run():
    """The nominal diagram with the zero controller (cheap: no control law), 2.5 s."""
    stream = io.StringIO()
    result = dut.run_scenario(short_nominal(), stream=stream, controller_factory=zero_controller)
    return result, stream.getvalue()


def test_a_completed_run_has_no_failure_cause(zero_run):
    result, _ = zero_run
    assert result.completed and result.metrics["failure_cause"] is None


def test_pause_times_are_multiples_of_the_period_then_the_end():
    assert dut.pause_times(2.5, 1e-3) == [1000 * 1e-3, 2000 * 1e-3, 2.5]
    assert dut.pause_times(3.0, 1e-3) == [1.0, 2.0, 3.0]
    # A period that does not divide a second: pauses stay on the period's multiples.
    assert dut.pause_times(2.0, 0.3) == [3 * 0.3, 6 * 0.3, 2.0]
    assert dut.pause_times(0.5, 1e-3) == [0.5]


def test_pauses_fall_on_logged_samples(zero_run):
    result, _ = zero_run
    times = set(result.log["t"].tolist())
    assert all(t in times for t in dut.pause_times(DURATION, 1e-3))


def test_pausing_changes_no_number(zero_run):
    """The same diagram advanced in one AdvanceTo call logs the same doubles."""
    scenario = short_nominal()
    builder, loop, loggers = build_simulation(scenario, controller_factory=zero_controller)
    simulator = Simulator(builder.Build())
    ApplySimulatorConfig(scenario.simulator, simulator)
    context = simulator.get_mutable_context()
    dut.set_initial_state(scenario, loop,
                          loop.simulated_plant.plant.GetMyMutableContextFromRoot(context))
    simulator.Initialize()
    simulator.AdvanceTo(DURATION)
    result, _ = zero_run
    for port in ("plant_state", "command", "applied_command"):
        np.testing.assert_array_equal(loggers[port].FindLog(context).data().T, result.log[port],
                                      err_msg=port)


def test_progress_line_about_every_simulated_second(zero_run):
    _, text = zero_run
    lines = text.splitlines()
    assert [line.split()[2] for line in lines] == ["1.00", "2.00", "2.50"]
    assert all("real-time factor" in line for line in lines)


def test_logged_references_are_the_generators_outputs(zero_run):
    """The references are computed after the run from the logged times; they must be what the
    generator's ports (which the controller reads) give at those times, to the last bit."""
    result, _ = zero_run
    generator = ReferenceGenerator(short_nominal().trajectory)
    context = generator.CreateDefaultContext()
    for k in range(0, len(result.log["t"]), 97):
        context.SetTime(result.log["t"][k])
        for port in ("com_reference", "task_reference", "heading_reference"):
            np.testing.assert_array_equal(generator.GetOutputPort(port).Eval(context),
                                          result.log[port][k], err_msg=port)


def test_diverging_plant_stops_with_the_time_of_the_first_non_finite_sample(
        monkeypatch, tmp_path):
    """A non-finite state stops the run; the log ends at the first non-finite sample (here the
    initial one: an arm joint's rate is NaN), whatever raised later."""
    set_initial_state = dut.set_initial_state

    def nan_rate(scenario, loop, plant_context):
        set_initial_state(scenario, loop, plant_context)
        loop.simulated_plant.arm_joints[3].set_angular_rate(plant_context, float("nan"))

    monkeypatch.setattr(dut, "set_initial_state", nan_rate)
    with pytest.raises(dut.SimulationFailed,
                       match=r"t = 0\.0000 s: the plant state became non-finite \(diverged\)"):
        dut.run_scenario(short_nominal(), out_dir=tmp_path, progress=False,
                         controller_factory=zero_controller)
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert metrics["completed"] is False and "diverged" in metrics["failure"]
    assert metrics["failure_cause"]["cause"] == "divergence"
    assert metrics["simulated_time_s"] == 0.0
    log = np.load(tmp_path / "log.npz")
    assert log["t"].tolist() == [0.0]
    assert {len(log[k]) for k in log.files if k != "layout"} == {1}


def test_a_nan_command_stops_the_run_with_time_signal_and_cause(monkeypatch, tmp_path):
    """A NaN reaching the loop (here the law's command, from its 300th sample on) stops the
    run with the time, the first non-finite signal and a likely cause; the logs up to then
    are kept and metrics.json stays strict JSON (Drake's own message was "Spatial force
    applied on body helicopter contains NaN", with neither)."""
    from aerial_drake.control.controller import _DecoupledControllerBase

    evaluate_into = _DecoupledControllerBase.evaluate_into

    def poisoned(self, t, x, com, task, heading, command, diagnostics):
        evaluate_into(self, t, x, com, task, heading, command, diagnostics)
        if self.evaluations > 300:
            command[0] = float("nan")

    monkeypatch.setattr(_DecoupledControllerBase, "evaluate_into", poisoned)
    with pytest.raises(dut.SimulationFailed) as info:
        dut.run_scenario(short_nominal(), out_dir=tmp_path, progress=False)
    message = str(info.value)
    assert re.search(r"t = 0\.\d+ s: the control law's command became non-finite \(first "
                     r"non-finite signal: 'command'\).*likely cause: ", message), message
    metrics = json.loads((tmp_path / "metrics.json").read_text(),
                         parse_constant=lambda c: pytest.fail(f"{c} in metrics.json"))
    assert metrics["completed"] is False and metrics["failure"] in message
    log = np.load(tmp_path / "log.npz")
    assert 0.25 < log["t"][-1] < 0.31 and np.all(np.isfinite(log["plant_state"]))
