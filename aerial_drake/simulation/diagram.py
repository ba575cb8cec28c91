"""The closed loop of Fig. 2 of the paper in Drake's systems framework.

:func:`build_closed_loop` wires the simulated plant and its SceneGraph, the reference generator,
the controller (on its own rigid-body model of the plant, holding its samples), the actuator lag
and saturation, the rotor drive, and two exported disturbance input ports, as one Diagram.
:func:`build_simulation` adds the same systems straight into the simulation's builder, with the
disturbance sources and loggers around them: not nested in a Diagram of their own, because
each level of nesting costs framework work at every integrator stage (the continuous state
is a vector of vectors, and every access goes through each level; about 6 % of a step,
callgrind), while the two diagrams compute the same doubles.

Ports of the closed loop (the Diagram's exported ports, or :meth:`ClosedLoop.input_port` and
:meth:`ClosedLoop.output_port` either way):

- inputs ``vehicle_wrench`` and ``end_effector_wrench``: ``[torque; force]`` in World (6).
- outputs ``plant_state``, ``command`` (what the controller asks for, held between samples),
  ``applied_command`` (what reaches the plant, after lag and saturation), ``diagnostics``,
  ``com_reference``, ``task_reference``, ``heading_reference``, ``query_object`` (for
  visualisers), ``rotor_drive_torque`` (rotors variant only), the wrench observer's
  ``external_wrench_estimate``, ``generalized_force_estimate`` and ``external_force_estimate``
  (``observer.enabled`` only; the last also feeds the controller's ``vehicle_force_estimate``
  input if it has one, paper_plus's), ``contact_wrench`` and ``measured_contact_force``
  (:mod:`aerial_drake.simulation.contact`; with an environment).
"""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from pydrake.multibody.plant import ExternallyAppliedSpatialForceMultiplexer
from pydrake.systems.framework import Diagram, DiagramBuilder, InputPort, OutputPort
from pydrake.systems.primitives import (
    AffineSystem,
    Demultiplexer,
    MatrixGain,
    Saturation,
)

from aerial_drake.control.base import ControllerBase
from aerial_drake.control.controller import DecoupledController
from aerial_drake.control.interface import check_controller_ports
from aerial_drake.control.limits import command_limits
from aerial_drake.control.registry import ControllerFactory, make_controller_system
from aerial_drake.control.registry import controller_factory as scenario_controller_factory
from aerial_drake.control.wrench_observer import add_scenario_observer
from aerial_drake.robots.models import AerialManipulator, add_to_builder
from aerial_drake.simulation.actuators import (
    ActuatorLag,
    PointWrenchApplier,
    free_body_wrench_map,
    lag_time_constant,
    make_base_actuator,
)
from aerial_drake.simulation.contact import add_contact_sensing
from aerial_drake.simulation.disturbances import (
    add_wrench_source,
    bound_end_effector_windows,
    resolve_random_disturbances,
)
from aerial_drake.simulation.loggers import PortLog, log_ports
from aerial_drake.simulation.scenarios import Scenario, ScenarioError
from aerial_drake.simulation.sensing import add_state_sensor
from aerial_drake.simulation.wind import add_wind
from aerial_drake.trajectories.com_planning import planned_reference
from aerial_drake.trajectories.generator import ReferenceGenerator
from aerial_drake.trajectories.kinds import reference_of


@dataclass
class ClosedLoop:
    """The closed loop's systems and its ports by name.

    ``diagram`` is the closed loop as a Diagram of its own (:func:`build_closed_loop`), or None
    where its systems were added straight into a larger builder (:func:`build_simulation`).
    """

    diagram: Diagram | None
    simulated_plant: AerialManipulator  # the simulated plant
    controller_model: AerialManipulator  # the controller's own rigid model
    controller: DecoupledController  # or any system of aerial_drake.control.interface
    reference: ReferenceGenerator
    lag: ActuatorLag | None
    n_arm: int
    inputs: dict[str, InputPort] = field(default_factory=dict)
    outputs: dict[str, OutputPort] = field(default_factory=dict)
    # The scenario's StateSensor between the plant and the controller (None without sensing).
    sensor: Any = None
    # The scenario as simulated, windows drawn and bounded (build_simulation; else None).
    scenario: Scenario | None = None

    def input_port(self, name: str) -> InputPort:
        """The closed loop's input port ``name`` (``vehicle_wrench``, ...). The earlier name
        ``helicopter_wrench`` still answers, with a FutureWarning naming today's."""
        return _port(self.inputs, _current_port_name(name), "input")

    def output_port(self, name: str) -> OutputPort:
        """The closed loop's output port ``name`` (``plant_state``, ``command``, ...)."""
        return _port(self.outputs, name, "output")

    def has_output_port(self, name: str) -> bool:
        return name in self.outputs


#: Port names of earlier releases -> today's (the vehicle is not always a helicopter).
OLD_PORT_NAMES = {"helicopter_wrench": "vehicle_wrench"}


def _current_port_name(name: str) -> str:
    if name in OLD_PORT_NAMES:
        warnings.warn(f"the closed loop's port {name!r} is now {OLD_PORT_NAMES[name]!r}; "
                      f"ask for {OLD_PORT_NAMES[name]!r} (the old name will be removed)",
                      FutureWarning, stacklevel=3)
        return OLD_PORT_NAMES[name]
    return name


def _port(ports: dict, name: str, kind: str):
    try:
        return ports[name]
    except KeyError:
        raise KeyError(f"the closed loop has no {kind} port {name!r}; it has "
                       f"{sorted(ports)}") from None


def input_limits(scenario: Scenario, model: AerialManipulator,
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper limits of the applied ``[f, mu, tau]``: the robot's thrust range and
    body torque bounds (its description, or the scenario's ``actuation`` overrides) and the
    arm's effort limits; infinite where the scenario does not saturate."""
    return command_limits(scenario.actuation, model)


def _actuation_port(builder: DiagramBuilder, sim: AerialManipulator, actuators, name: str
                    ) -> InputPort:
    """Where a vector of torques for ``actuators`` (in that order) enters the plant: their
    model instance's actuation port when they are exactly its actuators in order (no system
    in between), else a MatrixGain into the whole plant's actuation port (summed by Drake
    with the per-instance ports)."""
    plant = sim.plant
    instance = actuators[0].model_instance()
    own = [plant.get_joint_actuator(i) for i in plant.GetJointActuatorIndices(instance)]
    if [a.index() for a in own] == [a.index() for a in actuators]:
        return plant.get_actuation_input_port(instance)
    whole = plant.get_actuation_input_port()
    if builder.IsConnectedOrExported(whole):
        raise NotImplementedError(
            f"the {name} actuators share model instances with others in an order that needs "
            "a second connection to the plant's actuation port; put them in a model of their "
            "own")
    place = np.zeros((plant.num_actuated_dofs(), len(actuators)))
    for k, actuator in enumerate(actuators):
        place[actuator.input_start(), k] = 1.0
    gain = builder.AddSystem(MatrixGain(place))
    gain.set_name(f"{name}_actuation")
    builder.Connect(gain.get_output_port(), whole)
    return gain.get_input_port()


def connect_actuation(builder: DiagramBuilder, sim: AerialManipulator, base_command: OutputPort,
                      joint_command: OutputPort) -> OutputPort:
    """Wire ``[f, mu]`` (``base_command``, 4) and ``tau`` (``joint_command``) to the plant:
    the thrust and body torques as a body wrench at the vehicle frame (2) through Drake's
    ``Propeller``, the joint torques to the arm's actuators. Returns the base wrench's
    spatial-force output port, for the caller to connect to the plant (alone or multiplexed).

    MultibodyPlant silently clips actuation at the joints' effort limits, even in continuous
    mode; saturation is ours to model and log (diagram's ``Saturation``, only if the scenario
    asks), so the simulated plant's own clip is lifted. The limits stay on the controller's
    model, where ``input_limits`` reads them.
    """
    for actuator in sim.arm_actuators:
        actuator.set_effort_limit(np.inf)
    base_actuator = builder.AddSystem(make_base_actuator(sim.base_body))
    base_actuator.set_name("base_actuator")
    builder.Connect(base_command, base_actuator.get_command_input_port())
    builder.Connect(sim.plant.get_body_poses_output_port(),
                    base_actuator.get_body_poses_input_port())
    builder.Connect(joint_command, _actuation_port(builder, sim, sim.arm_actuators, "arm"))
    return base_actuator.get_spatial_forces_output_port()


def _add_command_path(
        builder: DiagramBuilder, scenario: Scenario, model: AerialManipulator,
        command: OutputPort) -> tuple[OutputPort, OutputPort, OutputPort,
                                      ActuatorLag | None]:
    """From the held command ``[f, mu, tau]`` to what reaches the plant: the actuator lag on
    ``[f, mu]`` (Section IV), then the saturation at ``input_limits``.

    Returns the base (4) and joint (n) command ports that drive the actuation, the applied
    command port (``[f, mu, tau]`` after lag and saturation) and the lag (None without).
    Each system here adds framework work to every integrator stage, so there are few: one lag
    system that passes the joint torques through, one saturation on the whole vector.
    """
    n = len(model.arm_joints)
    lag = None
    if scenario.actuation.lag_rise_time > 0:
        lag = builder.AddSystem(ActuatorLag(  # [f, mu] lagged, the joint torques passed
            lag_time_constant(scenario.actuation.lag_rise_time), 4, n))
        lag.set_name("actuator_lag")
        builder.Connect(command, lag.get_input_port())
        command = lag.get_output_port()
    if scenario.actuation.saturate:
        saturation = builder.AddSystem(Saturation(*input_limits(scenario, model)))
        saturation.set_name("saturation")
        builder.Connect(command, saturation.get_input_port())
        command = saturation.get_output_port()
    split = builder.AddSystem(Demultiplexer([4, n]))
    split.set_name("split_command")
    builder.Connect(command, split.get_input_port())
    return split.get_output_port(0), split.get_output_port(1), command, lag


def build_closed_loop(scenario: Scenario, *, name: str = "closed_loop",
                      controller_factory: ControllerFactory | None = None) -> ClosedLoop:
    """The closed loop of ``scenario`` as one Diagram with exported disturbance inputs.

    ``controller_factory`` (``factory(scenario, model) -> system``,
    :mod:`aerial_drake.control.registry`; e.g. its ``zero_controller``, the benchmarks'
    baseline) overrides the scenario's ``controller.type``.
    """
    builder = DiagramBuilder()
    loop = add_closed_loop(builder, scenario, controller_factory=controller_factory)
    for port_name, port in loop.inputs.items():
        builder.ExportInput(port, port_name)
    for port_name, port in loop.outputs.items():
        builder.ExportOutput(port, port_name)
    diagram = builder.Build()
    diagram.set_name(name)
    return dataclasses.replace(
        loop, diagram=diagram,
        inputs={k: diagram.GetInputPort(k) for k in loop.inputs},
        outputs={k: diagram.GetOutputPort(k) for k in loop.outputs})


def add_closed_loop(builder: DiagramBuilder, scenario: Scenario, *,
                    controller_factory: ControllerFactory | None = None) -> ClosedLoop:
    """Add the systems of the closed loop of ``scenario`` to ``builder`` (its disturbance
    inputs left to connect); the returned :class:`ClosedLoop` names its ports."""
    inputs, outputs = {}, {}
    robot = scenario.robot_description()
    # The scenario's plant config (default continuous) and environment (docs/world.md).
    sim = add_to_builder(builder, scenario.plant_variant, robot=robot,
                         plant_config=scenario.plant,
                         environment=scenario.environment.model_directives(),
                         environment_packages=scenario.environment.packages)
    plant = sim.plant
    plant.set_name("plant")
    model = scenario.controller_model()
    n = model.n

    # The run's reference, built once (its x_d planned here if trajectory.com_planning is on):
    # the checks, the start posture, the logs and Meshcat read this object (reference.source).
    # A python kind's function is sampled once onto compiled splines here (for_run).
    source = reference_of(scenario.trajectory, model.task_joint_nominal())
    try:
        source = source.for_run(scenario.duration)
    except ValueError as err:
        raise ScenarioError(f"trajectory: {err}", "trajectory.python.function") from None
    source = planned_reference(source, scenario.trajectory.com_planning, model,
                               scenario.duration)
    reference = builder.AddSystem(ReferenceGenerator(source))
    reference.set_name("reference")
    # Sampling: the paper's controller runs at 1 kHz and holds its command between samples
    # (its own discrete state); period 0 means continuous feedback.
    # The controller: the scenario's ``controller.type`` (default the paper's), or the
    # caller's factory (aerial_drake.control.registry).
    factory = controller_factory or scenario_controller_factory(scenario)
    system = make_controller_system(factory, scenario, model, source)
    assert model.task is not None
    check_controller_ports(system, model.plant.num_multibody_states(), n, model.task.n_joints)
    controller = builder.AddSystem(system)
    controller.set_name("controller")
    for port in ("com_reference", "task_reference", "heading_reference"):
        builder.Connect(reference.GetOutputPort(port), controller.GetInputPort(port))
        outputs[port] = reference.GetOutputPort(port)
    if isinstance(controller, ControllerBase):
        # The generator outputs source.fill at the context's time: the controller evaluates it
        # itself, the same doubles without three port evaluations (docs/performance.md).
        controller.read_references_from(source)

    state_out = plant.get_state_output_port()
    model_state = state_out
    nx = sim.plant.num_multibody_states()
    if not np.array_equal(sim.rigid_state_indices, np.arange(nx)):
        # The variant's state without its rotors' coordinates is the rigid model's.
        selector = builder.AddSystem(MatrixGain(np.eye(nx)[sim.rigid_state_indices]))
        selector.set_name("model_state")
        builder.Connect(state_out, selector.get_input_port())
        model_state = selector.get_output_port()
    # What the controller measures: the state itself, or delayed and noisy (sensing).
    measured, sensor = add_state_sensor(builder, scenario.sensing, model,
                                        scenario.controller_period, scenario.duration,
                                        model_state)
    builder.Connect(measured, controller.GetInputPort("state"))

    command = controller.GetOutputPort("command")
    outputs["command"] = command
    outputs["diagnostics"] = controller.GetOutputPort("diagnostics")

    base_cmd, joint_cmd, applied, lag = _add_command_path(builder, scenario, model, command)
    outputs["applied_command"] = applied
    # The observer (observer.enabled) feeds paper_plus's vehicle_force_estimate input.
    outputs.update(add_scenario_observer(builder, scenario, model, measured, applied,
                                         controller))

    # (2): thrust along body z and body torques, at the helicopter frame; joint torques.
    base_forces = connect_actuation(builder, sim, base_cmd, joint_cmd)
    # Disturbances: at the vehicle frame (generalized force), at the end-effector point.
    to_generalized = builder.AddSystem(MatrixGain(free_body_wrench_map(plant.num_velocities())))
    to_generalized.set_name("vehicle_wrench_to_generalized_force")
    builder.Connect(to_generalized.get_output_port(),
                    plant.get_applied_generalized_force_input_port())
    ee_wrench = builder.AddSystem(PointWrenchApplier(
        sim.end_effector_body, sim.end_effector_frame.GetFixedPoseInBodyFrame().translation(),
        plant.num_bodies()))
    ee_wrench.set_name("end_effector_wrench")
    forces = builder.AddSystem(ExternallyAppliedSpatialForceMultiplexer(2))
    forces.set_name("spatial_forces")
    builder.Connect(base_forces, forces.get_input_port(0))
    builder.Connect(ee_wrench.get_output_port(), forces.get_input_port(1))
    builder.Connect(forces.get_output_port(), plant.get_applied_spatial_force_input_port())
    inputs["vehicle_wrench"] = to_generalized.get_input_port()
    inputs["end_effector_wrench"] = ee_wrench.get_input_port()

    if sim.rotor_joints:
        outputs["rotor_drive_torque"] = _add_rotor_drive(builder, sim, scenario)

    outputs["plant_state"] = state_out
    assert sim.scene_graph is not None  # add_to_builder registers the plant with one
    outputs["query_object"] = sim.scene_graph.get_query_output_port()
    outputs.update(add_contact_sensing(builder, scenario, sim, controller))  # docs/contact.md
    return ClosedLoop(diagram=None, simulated_plant=sim, controller_model=model,
                      controller=controller, reference=reference, lag=lag, n_arm=n,
                      inputs=inputs, outputs=outputs, sensor=sensor)


def _add_rotor_drive(builder: DiagramBuilder, sim: AerialManipulator, scenario: Scenario,
                     ) -> OutputPort:
    """Holds the rotors at +-speed with a damping drive, torque ``gain (speed - w)`` per rotor;
    returns the drive's torque output.

    A Drake ``AffineSystem`` on the plant's state, ``y = D x + y0`` with ``D = -gain`` at the
    rotors' velocities and ``y0 = gain speed``: no state of its own (unlike a PidController).
    """
    plant = sim.plant
    nq = plant.num_positions()
    k = len(sim.rotor_joints)
    gain = scenario.rotors.drive_gain
    speeds = scenario.rotors.speed * np.array(sim.rotor_directions)
    D = np.zeros((k, plant.num_multibody_states()))
    for i, joint in enumerate(sim.rotor_joints):
        D[i, nq + joint.velocity_start()] = -gain
    drive = builder.AddSystem(AffineSystem(D=D, y0=gain * speeds))
    drive.set_name("rotor_drive")
    builder.Connect(plant.get_state_output_port(), drive.get_input_port())
    builder.Connect(drive.get_output_port(),
                    _actuation_port(builder, sim, sim.rotor_actuators, "rotor"))
    return drive.get_output_port()


#: The closed loop's outputs logged at every sample. The references are not among them: they
#: are functions of time alone, recomputed after the run from the sample times by the same
#: compiled code (the run's ``ReferenceGenerator.source``, equal to the last bit), so nothing
#: evaluates them in the loop but the controller.
LOGGED_PORTS = ("plant_state", "command", "applied_command", "diagnostics", "rotor_drive_torque",
                "external_wrench_estimate", "generalized_force_estimate", "contact_wrench",
                "measured_contact_force")


def build_simulation(scenario: Scenario, *, builder: DiagramBuilder | None = None,
                     controller_factory: ControllerFactory | None = None,
                     ) -> tuple[DiagramBuilder, ClosedLoop, dict[str, PortLog]]:
    """Add the closed loop's systems (:func:`add_closed_loop`, not nested in a Diagram of
    their own), the scenario's disturbance sources and loggers to ``builder``.

    Returns the builder (not yet built, so callers can add a visualiser), the closed loop
    (``diagram`` None; its ports by name) and each logged port's log by port name (a
    :class:`~aerial_drake.simulation.loggers.PortLog`: ``FindLog(context)`` as a logger's).
    """
    builder = builder or DiagramBuilder()
    scenario = resolve_random_disturbances(scenario)
    loop = add_closed_loop(builder, scenario, controller_factory=controller_factory)
    sim = loop.simulated_plant
    scenario = bound_end_effector_windows(scenario, loop.controller_model, loop.reference.source)
    loop.scenario = scenario
    for target, port in (("vehicle", "vehicle_wrench"),
                         ("end_effector", "end_effector_wrench")):
        wrench = add_wrench_source(builder, scenario.disturbances, target).get_output_port()
        if target == "vehicle":  # the wind's drag acts beside the windows (wind.py)
            wrench = add_wind(builder, scenario.wind, scenario.duration, sim.plant,
                              sim.base_body, wrench)
        builder.Connect(wrench, loop.input_port(port))
    # One logger for all (simulation.loggers: one publish event per sample, not one per port).
    loggers = log_ports(builder, {port: loop.output_port(port) for port in LOGGED_PORTS
                                  if loop.has_output_port(port)}, scenario.log_period)
    return builder, loop, loggers
