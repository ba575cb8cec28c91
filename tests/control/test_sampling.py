"""The sampled controller (period > 0): the law runs in a periodic discrete update and its
command and diagnostics are held in the controller's state; the runner's log still gives each
sample's diagnostics at its own time."""

import re

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource

from aerial_drake.control.controller import make_controller
from aerial_drake.control.law import AssumptionViolation, diagnostics_slices
from aerial_drake.robots.models import make_plant
from aerial_drake.simulation.runner import SimulationFailed, reference_configuration, run_scenario
from aerial_drake.simulation.scenarios import load_scenario
from aerial_drake.trajectories.generator import ReferenceGenerator

PERIOD = 1e-3
N_TASK = 7  # the paper's task: end-effector pose and q3


@pytest.fixture(scope="module")
def scenario():
    return load_scenario("nominal", overrides={"duration": 0.3})


def controller_with_sources(scenario, x, *, zero=False, **limits):
    """The sampled controller fed a constant state and the scenario's reference generator."""
    model = make_plant("rigid")
    builder = DiagramBuilder()
    controller = builder.AddSystem(make_controller(model, scenario.gains, period=PERIOD,
                                                   zero=zero, **limits))
    reference = builder.AddSystem(ReferenceGenerator(scenario.trajectory))
    state = builder.AddSystem(ConstantVectorSource(x))
    builder.Connect(state.get_output_port(), controller.get_state_input_port())
    for port in ("com_reference", "task_reference", "heading_reference"):
        builder.Connect(reference.GetOutputPort(port), controller.GetInputPort(port))
    return builder.Build(), controller, reference


def at_reference(scenario):
    model = make_plant("rigid")
    q = reference_configuration(scenario, model)
    v = np.full(model.plant.num_velocities(), 0.05)
    return np.concatenate([q, v])


def test_update_holds_the_law_of_its_sample(scenario):
    """Between samples the outputs are the last sample's law, which the update at t_k computes
    from the inputs at t_k; before any sample they are zero (or what hold_sample set)."""
    x = at_reference(scenario)
    diagram, controller, reference = controller_with_sources(scenario, x)
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    ctrl_context = controller.GetMyContextFromRoot(context)
    ref_context = reference.CreateDefaultContext()
    assert not np.any(controller.get_command_output_port().Eval(ctrl_context))

    def law_at(t):
        ref_context.SetTime(t)
        refs = [reference.GetOutputPort(p).Eval(ref_context).copy()
                for p in ("com_reference", "task_reference", "heading_reference")]
        return controller.evaluate(x, *refs)

    for t_end, k in ((0.0105, 10), (0.0139, 13), (14 * PERIOD, 13)):
        simulator.AdvanceTo(t_end)
        command, diagnostics = law_at(k * PERIOD)  # Drake's sample times: k * period
        np.testing.assert_array_equal(
            controller.get_command_output_port().Eval(ctrl_context), command)
        np.testing.assert_array_equal(
            controller.get_diagnostics_output_port().Eval(ctrl_context), diagnostics)
        assert np.any(command != law_at(t_end)[0])  # a different time gives another command


def test_hold_sample_sets_the_outputs_at_the_context(scenario):
    x = at_reference(scenario)
    diagram, controller, reference = controller_with_sources(scenario, x)
    context = diagram.CreateDefaultContext()
    context.SetTime(0.25)
    ctrl_context = controller.GetMyMutableContextFromRoot(context)
    controller.hold_sample(ctrl_context)
    command, diagnostics = controller.law_at(ctrl_context)
    np.testing.assert_array_equal(controller.get_command_output_port().Eval(ctrl_context),
                                  command)
    np.testing.assert_array_equal(controller.get_diagnostics_output_port().Eval(ctrl_context),
                                  diagnostics)


def test_sampled_law_failure_names_the_time(scenario):
    diagram, _, _ = controller_with_sources(scenario, at_reference(scenario),
                                            sigma_min_J3_limit=100.0)
    with pytest.raises(AssumptionViolation, match=r"t = 0\.0000 s: Assumption 1"):
        Simulator(diagram).AdvanceTo(0.0005)


def test_zero_controller_holds_zeros_and_samples_its_inputs(scenario):
    diagram, controller, _ = controller_with_sources(scenario, at_reference(scenario),
                                                     zero=True)
    simulator = Simulator(diagram)
    simulator.AdvanceTo(0.01)
    ctrl_context = controller.GetMyContextFromRoot(simulator.get_context())
    command = controller.get_command_output_port().Eval(ctrl_context)
    assert command.size == 11 and not np.any(command)
    assert controller.diagnostics_layout == ()  # no diagnostics: a size-0 port
    assert controller.get_diagnostics_output_port().size() == 0
    # It read its inputs (the reference is generated, as for the real controller) at each
    # sample before t = 0.01 s: 0, 1, ..., 9 ms.
    assert controller.evaluations == 10


def test_negative_period_is_refused(scenario):
    with pytest.raises(ValueError, match="period must be >= 0"):
        make_controller(make_plant("rigid"), scenario.gains, period=-1e-3)


@pytest.fixture(scope="module")
def short_run(scenario):
    return run_scenario(scenario, progress=False)


def test_logged_diagnostics_are_those_of_their_own_sample(short_run):
    """The runner's re-alignment: row k is the law at the logged state and references of row
    k, the last row included (to the last bit: the same compiled law on the same numbers)."""
    log = short_run.log
    ctrl = make_controller(make_plant("rigid"), short_run.scenario.gains, period=PERIOD)
    n = len(log["t"])
    assert n == 301 and log["t"][-1] == pytest.approx(0.3)
    for k in (0, 1, 2, 150, n - 2, n - 1):
        refs = [log[p][k] for p in ("com_reference", "task_reference", "heading_reference")]
        np.testing.assert_array_equal(ctrl.evaluate(log["plant_state"][k], *refs)[1],
                                      log["diagnostics"][k], err_msg=f"row {k}")


def test_logged_command_is_the_previous_samples(short_run):
    """The command logged at t_k is the one held over [t_k-1, t_k): the law of row k-1."""
    log = short_run.log
    ctrl = make_controller(make_plant("rigid"), short_run.scenario.gains, period=PERIOD)
    for k in (1, 2, 150, len(log["t"]) - 1):
        refs = [log[p][k - 1] for p in ("com_reference", "task_reference", "heading_reference")]
        np.testing.assert_array_equal(ctrl.evaluate(log["plant_state"][k - 1], *refs)[0],
                                      log["command"][k], err_msg=f"row {k}")


def test_failed_sample_is_not_logged(tmp_path, monkeypatch):
    """An assumption violated at a sample stops the run there; the log ends one sample before
    (that sample's diagnostics were never computed). sigma_min(J_3) starts at 0.203 and first
    drops below 0.2 at about 0.135 s; a start posture that violates the limit is refused
    before simulating (tests/simulation/test_closed_loop.py), and so would the reference
    (its check's margin is 3 x the limit): that check is bypassed to reach the in-run stop."""
    monkeypatch.setattr("aerial_drake.simulation.runner.check_reference", lambda *a: None)
    limit = 0.2
    scenario = load_scenario("nominal", overrides={"duration": 0.2,
                                                   "sigma_min_J3_limit": limit})
    with pytest.raises(SimulationFailed, match=r"t = 0\.1\d+ s: Assumption 1") as failure:
        run_scenario(scenario, out_dir=tmp_path, progress=False)
    t_failed = float(re.search(r"t = (\d+\.\d+) s", str(failure.value)).group(1))
    log = np.load(tmp_path / "log.npz")
    assert len(log["t"]) == len(log["diagnostics"]) == round(t_failed / PERIOD)
    assert log["t"][-1] == pytest.approx(t_failed - PERIOD, abs=1e-9)
    sigma = log["diagnostics"][:, diagnostics_slices(N_TASK)["sigma_min_J3"]]
    assert np.all(sigma > limit)
