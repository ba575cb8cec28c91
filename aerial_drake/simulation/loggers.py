"""The run's loggers: every logged port through one Drake logger (:func:`log_ports`).

A ``VectorLogSink`` per port costs a periodic publish event per port at every sample: the
simulator finds, orders and dispatches each, and each logger's input is evaluated apart. One
logger on a ``Multiplexer`` of the ports logs the same doubles at the same times with one
event (about 2 % of a paper run's step on this machine, docs/performance.md). Each port's
part of that log is read back through a :class:`PortLog`, which answers ``FindLog`` as a
port's own ``VectorLogSink`` would.
"""

from __future__ import annotations

import numpy as np
from pydrake.systems.framework import Context, DiagramBuilder, OutputPort
from pydrake.systems.primitives import LogVectorOutput, Multiplexer, VectorLogSink

__all__ = ["PortLog", "log_ports"]


class _RowsOfLog:
    """A port's rows of the shared log, as a ``VectorLog`` gives them (the methods the run's
    log reads): ``sample_times()``, ``data()`` (one column per sample), ``num_samples()``."""

    def __init__(self, log, rows: slice):
        self._log, self._rows = log, rows

    def sample_times(self) -> np.ndarray:
        return self._log.sample_times()

    def data(self) -> np.ndarray:
        return self._log.data()[self._rows]

    def num_samples(self) -> int:
        return self._log.num_samples()


class PortLog:
    """One logged port's part of the shared logger (:func:`log_ports`): ``FindLog(context)``
    gives its samples as the port's own ``VectorLogSink.FindLog`` would (the same doubles,
    the same times)."""

    def __init__(self, logger: VectorLogSink, rows: slice):
        self.logger = logger  # the shared logger (a system of the diagram)
        self.rows = rows  # this port's entries in each logged sample

    def FindLog(self, context: Context) -> _RowsOfLog:  # noqa: N802 (Drake's name)
        return _RowsOfLog(self.logger.FindLog(context), self.rows)


def log_ports(builder: DiagramBuilder, ports: dict[str, OutputPort], period: float,
              ) -> dict[str, PortLog]:
    """Log ``ports`` (name -> vector output port) every ``period`` s with one logger on a
    ``Multiplexer`` of them; returns each port's :class:`PortLog` by name (empty for none)."""
    if not ports:
        return {}
    # A port of no entries (a controller without diagnostics) has an empty part and no input.
    wired = [port for port in ports.values() if port.size() > 0]
    mux = builder.AddSystem(Multiplexer([port.size() for port in wired]))
    mux.set_name("logged_ports")
    for i, port in enumerate(wired):
        builder.Connect(port, mux.get_input_port(i))
    logger = LogVectorOutput(mux.get_output_port(), builder, period)
    logger.set_name("log")
    parts, at = {}, 0
    for name, port in ports.items():
        parts[name] = PortLog(logger, slice(at, at + port.size()))
        at += port.size()
    return parts
