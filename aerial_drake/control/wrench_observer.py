"""The external wrench observer as a Drake system: :class:`WrenchObserver` runs the
generalized-momentum observer of :mod:`aerial_drake.dynamics.momentum_observer` on the
controller's own rigid model, sampled at the controller's period, and splits its estimate into
the vehicle's and the end effector's wrenches (docs/control.md, "External wrench estimate").

Ports (by name):

- input ``state``: ``[q; v]`` of the rigid model (what the controller measures);
- input ``applied_command``: ``[f, mu (3), tau (n)]`` as it reaches the plant (after lag and
  saturation), read at each sample as the command held over the sample that just ended;
- output ``external_wrench_estimate`` (12): the vehicle's wrench (World axes, at the base
  frame's origin, where the closed loop's ``vehicle_wrench`` input applies it) then the end
  effector's (World axes, at the end-effector frame's origin, as ``end_effector_wrench``),
  each ``[torque; force]``: :data:`~aerial_drake.dynamics.momentum_observer.
  WRENCH_ESTIMATE_LAYOUT`;
- output ``generalized_force_estimate`` (nv): the raw estimate ``r`` of ``tau_ext``;
- output ``external_force_estimate`` (3): the whole external force on the robot (N, World),
  the vehicle's force plus the end effector's (entries 3-5 and 9-11 of
  ``external_wrench_estimate``): the force the CoM's dynamics (9a) see, which ``paper_plus``
  feeds forward into (10) through its input ``vehicle_force_estimate``.

The outputs are held discrete state (no direct feedthrough), so a controller may feed on them
without an algebraic loop. :func:`add_wrench_observer` adds one to a builder;
:func:`add_scenario_observer` as a scenario's ``observer`` section asks, and connects the
external force to the controller's ``vehicle_force_estimate`` input and ``r`` to its
``generalized_force_estimate`` input (paper_plus's).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pydrake.multibody.tree import JacobianWrtVariable
from pydrake.systems.framework import (
    Context,
    DiagramBuilder,
    DiscreteValues,
    LeafSystem,
    OutputPort,
    System,
)

from aerial_drake.dynamics.momentum_observer import (
    WRENCH_ESTIMATE_LAYOUT,
    ObserverSample,
    ObserverState,
    filter_pole,
    start,
    step,
)
from aerial_drake.robots.models import AerialManipulator

#: The observer's output ports, by name.
OBSERVER_OUTPUTS = ("external_wrench_estimate", "generalized_force_estimate",
                    "external_force_estimate")
#: The controller input port the observer's external force feeds (paper_plus's).
FORCE_INPUT = "vehicle_force_estimate"
#: The controller input port the observer's generalized force feeds (paper_plus's).
GENERALIZED_FORCE_INPUT = "generalized_force_estimate"


def _force_parts(wrench_part: slice) -> tuple[slice, slice]:
    """Where the vehicle's and the end effector's forces are in the observer's state: within
    ``wrench_part``, at :data:`WRENCH_ESTIMATE_LAYOUT`'s ``vehicle_force`` and
    ``end_effector_force``."""
    starts, start = {}, wrench_part.start
    for name, size in WRENCH_ESTIMATE_LAYOUT:
        starts[name] = slice(start, start + size)
        start += size
    return starts["vehicle_force"], starts["end_effector_force"]


def observer_layouts(n: int) -> dict[str, tuple[tuple[str, int], ...]]:
    """The (name, size) pairs of the observer's outputs by port name, for ``n`` arm joints
    (the generalized force's first six entries are a World wrench at the base origin)."""
    return {"external_wrench_estimate": WRENCH_ESTIMATE_LAYOUT,
            "generalized_force_estimate": (("vehicle_torque", 3), ("vehicle_force", 3),
                                           ("arm_torque", n))}


class WrenchObserver(LeafSystem):
    """The momentum observer of the external wrench on ``model`` (the controller's rigid
    model: its plant, base body and end-effector frame) with ``bandwidth`` (1/s), updated
    every ``period`` (s), started at the first state it sees (an initialization event)."""

    def __init__(self, model: AerialManipulator, bandwidth: float, period: float):
        super().__init__()
        self._plant = model.plant
        self._context = model.plant.CreateDefaultContext()
        self._base = model.base_body
        self._frame = model.end_effector_frame
        self._nq, self._nv = self._plant.num_positions(), self._plant.num_velocities()
        self._pole = filter_pole(bandwidth, period)
        self.period, self.bandwidth = float(period), float(bandwidth)
        nv = self._nv
        self._state_port = self.DeclareVectorInputPort("state", self._nq + nv)
        self._command_port = self.DeclareVectorInputPort("applied_command", nv - 2)
        self._memory = self.DeclareDiscreteState(ObserverState.size(nv))
        # Started at the first state (p(0)); the first sample ends at t = period. The
        # periodic event has the controller's offset, 0, so that both compute the same event
        # times to the bit (offset period gives period + k period, which can differ from
        # (k + 1) period in the last bit and split an integrator step: the paper law's
        # command then changed at 1e-14 with the observer on); the update at the start time
        # keeps the initialized state (_update).
        self.DeclareInitializationDiscreteUpdateEvent(self._initialize)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._update)
        r_part, wrench_part = ObserverState.parts(nv)
        held = {self.discrete_state_ticket(self._memory)}  # no direct feedthrough
        for name, part in (("external_wrench_estimate", wrench_part),
                           ("generalized_force_estimate", r_part)):
            self.DeclareVectorOutputPort(
                name, part.stop - part.start,
                lambda c, out, part=part: out.SetFromVector(
                    c.get_discrete_state(self._memory).value()[part]), held)
        vehicle, end_effector = _force_parts(wrench_part)
        self.DeclareVectorOutputPort(
            "external_force_estimate", 3,
            lambda c, out: out.SetFromVector(
                c.get_discrete_state(self._memory).value()[vehicle]
                + c.get_discrete_state(self._memory).value()[end_effector]), held)

    def _held(self, context: Context) -> ObserverState:
        vector = context.get_discrete_state(self._memory).get_value()
        return ObserverState(np.array(vector), self._nv)

    def _sample(self, context: Context) -> ObserverSample:
        """The model's terms at the measured state (the model's own context)."""
        x = self._state_port.Eval(context)
        plant, ctx = self._plant, self._context
        plant.SetPositionsAndVelocities(ctx, x)
        world = plant.world_frame()
        return ObserverSample(
            M=plant.CalcMassMatrix(ctx), v=np.array(x[self._nq:]),
            bias=plant.CalcBiasTerm(ctx), g=-plant.CalcGravityGeneralizedForces(ctx),
            R_WB=plant.EvalBodyPoseInWorld(ctx, self._base).rotation().matrix(),
            J_E=plant.CalcJacobianSpatialVelocity(ctx, JacobianWrtVariable.kV, self._frame,
                                                  np.zeros(3), world, world))

    def _initialize(self, context: Context, discrete_state: DiscreteValues) -> None:
        state = ObserverState(np.zeros(ObserverState.size(self._nv)), self._nv)
        start(state, self._sample(context))
        discrete_state.set_value(self._memory, state.vector)

    def _update(self, context: Context, discrete_state: DiscreteValues) -> None:
        state = self._held(context)
        if context.get_time() < 0.5 * self.period:
            return  # the start's sample (runs start at 0): no interval yet, state kept
        step(state, self._sample(context), self._command_port.Eval(context), self.period,
             self._pole)
        discrete_state.set_value(self._memory, state.vector)

    def get_state_input_port(self):
        return self._state_port

    def get_applied_command_input_port(self):
        return self._command_port


def add_wrench_observer(builder: DiagramBuilder, model: AerialManipulator, bandwidth: float,
                        period: float, state: OutputPort, applied_command: OutputPort,
                        name: str = "wrench_observer") -> WrenchObserver:
    """Add a :class:`WrenchObserver` on ``model`` to ``builder``, its inputs connected to
    ``state`` (the model's ``[q; v]``) and ``applied_command``; returns it."""
    observer = builder.AddSystem(WrenchObserver(model, bandwidth, period))
    observer.set_name(name)
    builder.Connect(state, observer.get_state_input_port())
    builder.Connect(applied_command, observer.get_applied_command_input_port())
    return observer


def add_scenario_observer(builder: DiagramBuilder, scenario: Any, model: AerialManipulator,
                          state: OutputPort, applied_command: OutputPort,
                          controller: System | None = None) -> dict[str, OutputPort]:
    """The observer of ``scenario``'s ``observer`` section (a
    :class:`~aerial_drake.simulation.scenarios.Scenario`; not imported here: the simulation
    layer is above this one), at its ``controller_period``: its outputs by name, or none when
    the section does not enable it (nothing is added).

    When ``controller`` (a system in ``builder``) has an input port ``vehicle_force_estimate``
    (paper_plus's), the observer's ``external_force_estimate`` is connected to it: the
    vehicle's and the end effector's forces, as both move the CoM (9a); paper_plus reads it
    only with ``controller.plus.vehicle_force_feedforward`` (docs/control.md, "Push
    rejection"); likewise ``generalized_force_estimate`` to the input of that name, read with
    ``controller.plus.wrench_compensation`` ("Wrench compensation"). Both sides hold their
    values between samples, so this closes no algebraic loop: the controller's sample at t_k
    reads the estimate the observer's update at t_k-1 left (the momentum change over t_k-2 ..
    t_k-1, filtered)."""
    config = scenario.observer
    if not config.enabled:
        return {}
    observer = add_wrench_observer(builder, model, config.bandwidth, scenario.controller_period,
                                   state, applied_command)
    outputs = {name: observer.GetOutputPort(name) for name in OBSERVER_OUTPUTS}
    if controller is not None and controller.HasInputPort(FORCE_INPUT):
        builder.Connect(outputs["external_force_estimate"], controller.GetInputPort(FORCE_INPUT))
    if controller is not None and controller.HasInputPort(GENERALIZED_FORCE_INPUT):
        builder.Connect(outputs["generalized_force_estimate"],
                        controller.GetInputPort(GENERALIZED_FORCE_INPUT))
    return outputs
