"""Tests of the controller base (aerial_drake.control.base) with a minimal subclass: the ports
and their sizes, the hold over a period and the update at t = k period, one evaluation per
context when continuous, the diagnostics by name, and the time in a failure's message."""

import re

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource

from aerial_drake.control.base import NONFINITE_STATE, ControllerBase
from aerial_drake.control.interface import check_controller_ports
from aerial_drake.control.law import AssumptionViolation
from aerial_drake.robots.models import make_plant

PERIOD = 0.01


class Clock(ControllerBase):
    """The command's thrust is the time the law was told and the mu's are the first three
    state entries (so a held sample shows when it was taken); ``rate`` is an extra."""

    def __init__(self, model, period=0.0, fail_after=np.inf):
        super().__init__(model.plant, model.task, period=period,
                         diagnostics_layout=(("rate", 1), ("unset", 2)))
        self._n = model.n
        self._fail_after = fail_after

    def calc_command(self, t, x, com, task, heading):
        if t > self._fail_after:
            raise AssumptionViolation("the clock stopped")
        command = np.concatenate([[t], x[:3], np.zeros(self._n)])
        return command, {"rate": 2.0 * t}


@pytest.fixture(scope="module")
def model():
    return make_plant("rigid")


def closed(model, controller, x=None):
    """``controller`` fed a constant state and constant references."""
    builder = DiagramBuilder()
    builder.AddSystem(controller)
    nx = model.plant.num_multibody_states()
    x = np.arange(1.0, nx + 1.0) if x is None else x
    for port, value in (("state", x), ("com_reference", np.zeros(15)),
                        ("task_reference", np.zeros(27)), ("heading_reference", np.zeros(9))):
        source = builder.AddSystem(ConstantVectorSource(value))
        builder.Connect(source.get_output_port(), controller.GetInputPort(port))
    return builder.Build()


def test_ports_and_layout(model):
    dut = Clock(model)
    check_controller_ports(dut, model.plant.num_multibody_states(), model.n,
                           model.task.n_joints)
    assert dut.diagnostics_layout == (("rate", 1), ("unset", 2))
    assert dut.get_command_output_port().size() == 4 + model.n
    assert dut.get_diagnostics_output_port().size() == 3
    assert dut.period == 0.0


def test_sampled_holds_over_a_period_and_updates_at_each_multiple(model):
    dut = Clock(model, period=PERIOD)
    simulator = Simulator(closed(model, dut))
    context = dut.GetMyContextFromRoot(simulator.get_context())
    # Drake runs the update at t_k when the simulation steps past t_k.
    for t_end, sample in ((0.005, 0.0), (0.0099, 0.0), (0.0101, 0.01), (0.0234, 0.02),
                          (0.0301, 0.03)):
        simulator.AdvanceTo(t_end)
        command = dut.get_command_output_port().Eval(context)
        assert command[0] == pytest.approx(sample, abs=1e-12), t_end
        np.testing.assert_array_equal(command[1:4], [1.0, 2.0, 3.0])
        diagnostics = dut.get_diagnostics_output_port().Eval(context)
        assert diagnostics[0] == pytest.approx(2.0 * sample, abs=1e-12)
        assert np.all(np.isnan(diagnostics[1:]))  # declared, not returned: NaN
    assert dut.evaluations == 4  # t = 0, 0.01, 0.02, 0.03


def test_hold_sample_holds_the_law_at_the_context(model):
    dut = Clock(model, period=PERIOD)
    diagram = closed(model, dut)
    root = diagram.CreateDefaultContext()
    root.SetTime(0.042)
    context = dut.GetMyMutableContextFromRoot(root)
    assert not np.any(dut.get_command_output_port().Eval(context))  # nothing held yet
    dut.hold_sample(context)
    assert dut.get_command_output_port().Eval(context)[0] == 0.042
    command, diagnostics = dut.law_at(context)
    np.testing.assert_array_equal(dut.get_command_output_port().Eval(context), command)
    with pytest.raises(RuntimeError, match="continuous"):
        Clock(model).hold_sample(context)


def test_continuous_evaluates_once_per_context_for_both_outputs(model):
    dut = Clock(model)
    diagram = closed(model, dut)
    root = diagram.CreateDefaultContext()
    context = dut.GetMyContextFromRoot(root)
    for _ in range(3):
        dut.get_command_output_port().Eval(context)
        dut.get_diagnostics_output_port().Eval(context)
    assert dut.evaluations == 1
    root.SetTime(0.5)  # a new time: one more evaluation
    assert dut.get_diagnostics_output_port().Eval(context)[0] == 1.0
    assert dut.get_command_output_port().Eval(context)[0] == 0.5
    assert dut.evaluations == 2


def test_evaluate_needs_no_context(model):
    dut = Clock(model)
    x = np.arange(1.0, model.plant.num_multibody_states() + 1.0)
    command, diagnostics = dut.evaluate(x, np.zeros(15), np.zeros(27), np.zeros(9), t=0.25)
    assert command[0] == 0.25 and diagnostics[0] == 0.5 and dut.evaluations == 1


def test_failures_name_the_time(model):
    sampled = Clock(model, period=PERIOD, fail_after=0.015)
    simulator = Simulator(closed(model, sampled))
    with pytest.raises(AssumptionViolation, match=r"^t = 0\.0200 s: the clock stopped$"):
        simulator.AdvanceTo(0.05)
    continuous = Clock(model, fail_after=-1.0)
    context = continuous.GetMyContextFromRoot(closed(model, continuous).CreateDefaultContext())
    with pytest.raises(AssumptionViolation, match=r"^t = 0\.0000 s: the clock stopped$"):
        continuous.get_command_output_port().Eval(context)
    x = np.full(model.plant.num_multibody_states(), np.nan)
    nan_state = Clock(model, period=PERIOD)
    with pytest.raises(FloatingPointError, match=r"^t = 0\.0000 s: " + re.escape(NONFINITE_STATE)):
        Simulator(closed(model, nan_state, x)).AdvanceTo(0.0)


def test_bad_layouts_and_entries_are_refused(model):
    with pytest.raises(ValueError, match="period must be >= 0"):
        Clock(model, period=-1.0)

    class Repeated(Clock):
        def __init__(self, model):
            ControllerBase.__init__(self, model.plant, model.task,
                                    diagnostics_layout=(("a", 1), ("a", 2)))

    with pytest.raises(ValueError, match="repeated"):
        Repeated(model)

    class Unknown(Clock):
        def calc_command(self, t, x, com, task, heading):
            return super().calc_command(t, x, com, task, heading)[0], {"speed": 1.0}

    x = np.zeros(model.plant.num_multibody_states())
    with pytest.raises(KeyError, match="no diagnostics entry 'speed'"):
        Unknown(model).evaluate(x, np.zeros(15), np.zeros(27), np.zeros(9))

    class Short(Clock):
        def calc_command(self, t, x, com, task, heading):
            return np.zeros(4)

    with pytest.raises(ValueError, match=r"Short.calc_command returned a command of shape "
                                         r"\(4,\); it must be \[f, mu \(3\), tau \(n\)\], 11"):
        Short(model).evaluate(x, np.zeros(15), np.zeros(27), np.zeros(9))

    class Nothing(ControllerBase):
        pass

    nothing = Nothing(model.plant, model.task)
    assert nothing.diagnostics_layout == () and nothing.get_diagnostics_output_port().size() == 0
    with pytest.raises(NotImplementedError, match="Nothing must implement calc_command"):
        nothing.evaluate(x, np.zeros(15), np.zeros(27), np.zeros(9))


class Recorder(ControllerBase):
    """Zeros, recording the references each sample was given (copies)."""

    def __init__(self, model, period):
        super().__init__(model.plant, model.task, period=period)
        self._n = model.n
        self.seen = []

    def calc_command(self, t, x, com, task, heading):
        self.seen.append((t, np.concatenate([com, task, heading])))
        return np.zeros(4 + self._n)


def _references_seen(model, source, read_from_source):
    """The references a sampled controller fed by a ReferenceGenerator of ``source`` sees
    over a few samples, read from its ports or (``read_from_source``) from the source."""
    from aerial_drake.trajectories.generator import ReferenceGenerator

    builder = DiagramBuilder()
    dut = builder.AddSystem(Recorder(model, PERIOD))
    reference = builder.AddSystem(ReferenceGenerator(source))
    for port in ("com_reference", "task_reference", "heading_reference"):
        builder.Connect(reference.GetOutputPort(port), dut.GetInputPort(port))
    x = np.zeros(model.plant.num_multibody_states())
    x[0] = 1.0
    state = builder.AddSystem(ConstantVectorSource(x))
    builder.Connect(state.get_output_port(), dut.get_state_input_port())
    if read_from_source:
        dut.read_references_from(source)
    simulator = Simulator(builder.Build())
    simulator.AdvanceTo(7.5 * PERIOD)
    return dut.seen


def test_references_read_from_their_source_equal_the_ports_to_the_bit(model):
    from aerial_drake.trajectories.kinds import reference_of
    from aerial_drake.trajectories.params import TrajectoryParams

    source = reference_of(TrajectoryParams(), model.task_joint_nominal())
    by_ports = _references_seen(model, source, False)
    by_source = _references_seen(model, source, True)
    assert len(by_ports) == len(by_source) == 8  # t = 0, ..., 7 PERIOD
    for (t1, r1), (t2, r2) in zip(by_ports, by_source):
        assert t1 == t2
        np.testing.assert_array_equal(r1, r2)
    # The references move (so the comparison holds them at each sample, not a constant).
    assert not np.array_equal(by_source[1][1], by_source[-1][1])


def test_read_references_from_refuses_a_source_of_another_size_and_none_restores(model):
    from aerial_drake.trajectories.kinds import reference_of
    from aerial_drake.trajectories.params import TrajectoryParams

    dut = Recorder(model, PERIOD)
    source = reference_of(TrajectoryParams(), model.task_joint_nominal())
    source.size += 1  # as a source for a task of another shape
    with pytest.raises(ValueError, match=r"read_references_from: .* reference ports take"):
        dut.read_references_from(source)
    source.size -= 1
    dut.read_references_from(source)
    assert dut._reference is not None
    dut.read_references_from(None)
    assert dut._reference is None
