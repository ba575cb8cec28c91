"""The run's shared logger (aerial_drake.simulation.loggers): each port's part of the one log
equals, to the bit and at the same times, what a logger of its own records; a port of no
entries logs zero rows (a run's log through it: tests/simulation/test_runner.py)."""

import numpy as np
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import (
    ConstantVectorSource,
    LogVectorOutput,
    Sine,
)

from aerial_drake.simulation.loggers import PortLog, log_ports


def test_each_port_logs_as_its_own_logger_would():
    builder = DiagramBuilder()
    sines = builder.AddSystem(Sine(amplitudes=[1.0, 2.0, 3.0], frequencies=[1.0, 3.0, 7.0],
                                   phases=[0.1, 0.2, 0.3]))
    constant = builder.AddSystem(ConstantVectorSource(np.array([4.0, -5.0])))
    empty = builder.AddSystem(ConstantVectorSource(np.zeros(0)))
    ports = {"sines": sines.get_output_port(0), "empty": empty.get_output_port(),
             "constant": constant.get_output_port()}
    own = {name: LogVectorOutput(port, builder, 0.01) for name, port in ports.items()}
    shared = log_ports(builder, ports, 0.01)
    assert all(isinstance(part, PortLog) for part in shared.values())
    diagram = builder.Build()
    simulator = Simulator(diagram)
    simulator.AdvanceTo(0.255)
    context = simulator.get_context()
    for name in ports:
        mine, theirs = shared[name].FindLog(context), own[name].FindLog(context)
        assert mine.num_samples() == theirs.num_samples() == 26
        np.testing.assert_array_equal(mine.sample_times(), theirs.sample_times())
        assert mine.data().shape == theirs.data().shape
        np.testing.assert_array_equal(mine.data(), theirs.data())
    assert shared["empty"].FindLog(context).data().shape == (0, 26)
    assert np.ptp(shared["sines"].FindLog(context).data()) > 1.0  # a moving signal


def test_no_ports_no_logger():
    builder = DiagramBuilder()
    assert log_ports(builder, {}, 0.01) == {}
    assert builder.GetSystems() == []
