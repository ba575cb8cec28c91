"""The controller base: the ports, sample-and-hold and caching every controller shares.

A controller subclasses :class:`ControllerBase` and implements one method,
:meth:`ControllerBase_.calc_command`, from (time, measured state, references) to the command
``[f, mu (3), tau (n)]``; it may also declare named extra diagnostics (``diagnostics_layout``)
and return their values by name. The base owns everything else:

- the input ports ``state`` (``nq + nv`` of the controller's model plant), ``com_reference``
  (15), ``task_reference`` (24 + 3 n_j) and ``heading_reference`` (9), sized from the model and
  its task (:mod:`aerial_drake.control.interface`);
- the output ports ``command`` (4 + n) and ``diagnostics`` (the sum of the layout's sizes; a
  controller without extras has a size-0 port, which Drake accepts and logs as zero rows);
- ``period`` > 0: a periodic discrete update at t = k period writes the command and the
  diagnostics into two discrete state groups that the outputs read (Drake's state output
  ports): a sample-and-hold, set at the initial state by :meth:`hold_sample`;
- ``period`` 0: one evaluation per context (a cache entry) feeds both outputs;
- :meth:`evaluate` (no context needed), :attr:`evaluations`, and the time of the context
  prefixed to an :class:`~aerial_drake.control.law.AssumptionViolation` or FloatingPointError.

``ControllerBase_`` is a template over the scalar type (float, AutoDiffXd) for controllers
that convert (Drake's ``TemplateSystem``, as :mod:`aerial_drake.control.controller`);
``ControllerBase`` is its float instantiation, what a controller of one's own subclasses.
A fast controller overrides :meth:`ControllerBase_.evaluate_into` to write straight into the
held state (the paper controller's compiled law does).
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np
from pydrake.autodiffutils import AutoDiffXd
from pydrake.common.cpp_template import TemplateClass
from pydrake.common.value import AbstractValue
from pydrake.multibody.plant import MultibodyPlant_
from pydrake.systems.framework import Context_, LeafSystem_, ValueProducer

from aerial_drake.control.law import AssumptionViolation, diagnostics_slices
from aerial_drake.robots.task import TaskLayout
from aerial_drake.trajectories.reference import (
    COM_REFERENCE_SIZE,
    HEADING_REFERENCE_SIZE,
    task_reference_size,
)

NONFINITE_STATE = ("the plant state is not finite (the simulation diverged before the "
                   "controller could act)")

#: The discrete state groups of a sampled controller (declared in this order).
_COMMAND, _DIAGNOSTICS = 0, 1

DiagnosticsLayout = tuple[tuple[str, int], ...]


def at_time(err: Exception, context: Any) -> Exception:
    """``err`` again, its message prefixed by the context's time."""
    return type(err)(f"t = {context.get_time():.4f} s: {err}")


def _define(T):
    class Impl(LeafSystem_[T]):
        """The ports, hold and cache of a controller (module docstring).

        Args:
            plant: the controller's model (a MultibodyPlant of this scalar type): the
                ``state`` port has its ``nq + nv``; the command has ``nv - 6`` joint torques.
            task: the task on ``plant``: ``task_reference``'s size comes from its joints.
            period: the sampling period (s); 0 for continuous feedback.
            diagnostics_layout: the named extra diagnostics, (name, size) pairs in the
                ``diagnostics`` port's order; empty for none.
            converter: Drake's SystemScalarConverter (scalar-converting controllers only).
        """

        def __init__(self, plant: MultibodyPlant_[T], task: TaskLayout, *,
                     period: float = 0.0, diagnostics_layout: DiagnosticsLayout = (),
                     converter=None):
            if converter is None:
                LeafSystem_[T].__init__(self)
            else:
                LeafSystem_[T].__init__(self, converter)
            if not period >= 0.0:
                raise ValueError(
                    f"period must be >= 0 (s; 0 = continuous feedback), got {period}")
            self.diagnostics_layout: DiagnosticsLayout = tuple(
                (str(name), int(size)) for name, size in diagnostics_layout)
            self._slices = _slices(self.diagnostics_layout)
            self._period = float(period)
            self._scalar = float if T is float else object
            self.evaluations = 0  # number of control law evaluations (tests, metrics.json)
            # (fill, buffer, com, task, heading) when the references are read from their
            # source rather than the ports (read_references_from); None: from the ports.
            self._reference: Any = None
            n_arm = plant.num_velocities() - 6
            self._sizes = (4 + n_arm, sum(size for _, size in self.diagnostics_layout))
            self._ports = tuple(self.DeclareVectorInputPort(name, size) for name, size in (
                ("state", plant.num_positions() + plant.num_velocities()),
                ("com_reference", COM_REFERENCE_SIZE),
                ("task_reference", task_reference_size(task.n_joints)),
                ("heading_reference", HEADING_REFERENCE_SIZE)))
            if self._period > 0.0:
                # Groups _COMMAND and _DIAGNOSTICS, in that order.
                held = [self.DeclareDiscreteState(size) for size in self._sizes]
                self.DeclarePeriodicDiscreteUpdateEvent(self._period, 0.0, self._sample)
                for name, index in zip(("command", "diagnostics"), held):
                    self.DeclareStateOutputPort(name, index)
                return
            self._solution = self.DeclareCacheEntry(
                description="control law solution", value_producer=ValueProducer(
                    allocate=AbstractValue.Make(object()).Clone, calc=self._calc_solution),
                prerequisites_of_calc={self.all_input_ports_ticket(), self.time_ticket()})
            for name, i in (("command", 0), ("diagnostics", 1)):
                self.DeclareVectorOutputPort(
                    name, self._sizes[i],
                    lambda c, out, i=i: out.SetFromVector(self._solution.Eval(c)[i]),
                    prerequisites_of_calc={self._solution.ticket()})

        # --- What a subclass implements ---------------------------------------------------
        def calc_command(self, t: float, x: np.ndarray, com: np.ndarray, task: np.ndarray,
                         heading: np.ndarray) -> Any:
            """The command ``[f, mu (3), tau (n)]`` at time ``t``, measured state ``x`` and
            the packed references (:mod:`aerial_drake.trajectories.reference`); or
            ``(command, {name: value})`` with entries of :attr:`diagnostics_layout` (those
            left out are NaN). May raise AssumptionViolation (the run stops, naming the
            time)."""
            raise NotImplementedError(f"{type(self).__name__} must implement calc_command")

        def evaluate_into(self, t: float, x: np.ndarray, com: np.ndarray, task: np.ndarray,
                          heading: np.ndarray, command: np.ndarray, diagnostics: np.ndarray,
                          ) -> None:
            """Write the law's command and diagnostics into ``command`` and ``diagnostics``
            (views of the held state when sampled): :meth:`calc_command` on a finite state,
            its extras placed by name. Override it for a faster path (no copies), or for a
            scalar type other than float (the paper controller does both)."""
            if not np.all(np.isfinite(x)):
                raise FloatingPointError(NONFINITE_STATE)
            result = self.calc_command(t, x, com, task, heading)
            extras: Mapping[str, Any] = {}
            if isinstance(result, tuple):
                result, extras = result
            if np.shape(result) != command.shape:
                raise ValueError(f"{type(self).__name__}.calc_command returned a command of "
                                 f"shape {np.shape(result)}; it must be [f, mu (3), tau (n)], "
                                 f"{command.size} entries")
            command[:] = result
            diagnostics[:] = np.nan
            for name, value in extras.items():
                if name not in self._slices:
                    raise KeyError(f"{type(self).__name__}: no diagnostics entry '{name}'; "
                                   f"its diagnostics_layout has "
                                   f"{[n for n, _ in self.diagnostics_layout]}")
                diagnostics[self._slices[name]] = value

        # --- The machinery ----------------------------------------------------------------
        @property
        def period(self) -> float:
            """The sampling period (s); 0 for continuous feedback."""
            return self._period

        def evaluate(self, x: np.ndarray, com: np.ndarray, task: np.ndarray,
                     heading: np.ndarray, t: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
            """``(command, diagnostics)`` at state ``x``, the packed references and time
            ``t``, as the outputs give them (no context needed)."""
            command = np.empty(self._sizes[0], dtype=self._scalar)
            diagnostics = np.empty(self._sizes[1], dtype=self._scalar)
            self.evaluations += 1
            self.evaluate_into(t, x, com, task, heading, command, diagnostics)
            return command, diagnostics

        def law_at(self, context: Context_[T]) -> tuple[np.ndarray, np.ndarray]:
            """``(command, diagnostics)`` at this system's ``context``: its inputs and time,
            as the outputs (continuous) or the next sample (sampled) would give them.

            Raises:
                AssumptionViolation, FloatingPointError: naming the context's time.
            """
            x, com, task, heading = self._inputs(context)
            try:
                return self.evaluate(x, com, task, heading, t=context.get_time())
            except (AssumptionViolation, FloatingPointError) as err:
                raise at_time(err, context) from None

        def hold_sample(self, context: Context_[T]) -> None:
            """Sampled controller: run the law at ``context`` and hold its result, as the
            periodic update does (e.g. at the initial state, so the hold starts at the first
            command)."""
            if self._period <= 0.0:
                raise RuntimeError("hold_sample: this controller is continuous (period 0); "
                                   "it holds nothing")
            self._sample(context, context.get_mutable_discrete_state())

        def read_references_from(self, source: Any) -> None:
            """Evaluate ``source`` (a :class:`~aerial_drake.trajectories.base.ReferenceSource`)
            at the context's time in place of the three reference input ports, or read the
            ports again (``source`` None).

            Only for a controller whose reference ports are fed by a
            :class:`~aerial_drake.trajectories.generator.ReferenceGenerator` of this very
            source, as :func:`aerial_drake.simulation.diagram.add_closed_loop` wires it: the
            generator's output is ``source.fill`` at the context's time, so the law sees the
            same doubles, without the generator's Python callback and three input
            evaluations at every sample (about a tenth of the closed loop's overhead over the
            plant, docs/performance.md). The ports stay connected for other readers. The
            three arrays the law then receives are views of one buffer, refilled at each
            evaluation: a controller that keeps a reference across samples copies it.
            """
            if source is None:
                self._reference = None
                return
            if self._scalar is not float:
                raise NotImplementedError("read_references_from: double controllers only")
            sizes = [port.size() for port in self._ports[1:]]
            if source.size != sum(sizes):
                raise ValueError(f"read_references_from: the source's packed reference has "
                                 f"{source.size} entries; the controller's reference ports "
                                 f"take {sizes} ({sum(sizes)}): a source for another task")
            buffer = np.zeros(source.size)
            com, task = buffer[:sizes[0]], buffer[sizes[0]:sizes[0] + sizes[1]]
            self._reference = (source.fill, buffer, com, task, buffer[sizes[0] + sizes[1]:])

        def get_state_input_port(self):
            return self._ports[0]

        def get_command_output_port(self):
            return self.GetOutputPort("command")

        def get_diagnostics_output_port(self):
            return self.GetOutputPort("diagnostics")

        def _inputs(self, context: Context_[T]
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
            """The state and the three references at ``context`` (the references from their
            source, :meth:`read_references_from`, or from the ports)."""
            state, com, task, heading = self._ports
            if self._reference is not None:
                fill, buffer, com_value, task_value, heading_value = self._reference
                fill(context.get_time(), buffer)  # the generator's output, to the bit
                return state.Eval(context), com_value, task_value, heading_value
            return (state.Eval(context), com.Eval(context), task.Eval(context),
                    heading.Eval(context))

        def _sample(self, context: Context_[T], discrete_state) -> None:
            # The law writes straight into the update's state (numpy views of Drake's
            # vectors): no copies. On a failure the update is abandoned, so a partial write
            # never reaches the context.
            self.evaluations += 1
            try:
                self.evaluate_into(context.get_time(), *self._inputs(context),
                                   discrete_state.get_mutable_value(_COMMAND),
                                   discrete_state.get_mutable_value(_DIAGNOSTICS))
            except (AssumptionViolation, FloatingPointError) as err:
                raise at_time(err, context) from None

        def _calc_solution(self, context: Context_[T], value: AbstractValue) -> None:
            value.set_value(self.law_at(context))

    Impl.__name__ = Impl.__qualname__ = f"ControllerBase_[{T.__name__}]"
    return Impl


def _slices(layout: DiagnosticsLayout) -> dict[str, slice]:
    """Name -> slice of each entry of ``layout`` (:func:`aerial_drake.control.law.
    diagnostics_slices`); a repeated name or a negative size is refused."""
    names = [name for name, _ in layout]
    for name, size in layout:
        if names.count(name) > 1 or size < 0:
            raise ValueError(f"diagnostics_layout: entry ({name!r}, {size}) is repeated or "
                             "has a negative size; give each entry its own name and a size "
                             ">= 0")
    return diagnostics_slices(list(layout))


#: The base for scalar type ``T`` (float or AutoDiffXd): ``ControllerBase_[T]``.
ControllerBase_ = TemplateClass("ControllerBase_")
for _T in (float, AutoDiffXd):
    ControllerBase_.add_instantiation(_T, _define(_T))

#: The base of a (double) controller: subclass it and implement ``calc_command``.
ControllerBase = ControllerBase_[float]

__all__ = ["ControllerBase", "ControllerBase_", "NONFINITE_STATE", "at_time"]
