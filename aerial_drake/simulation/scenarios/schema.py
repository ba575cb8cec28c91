"""The scenario's schema: one dataclass tree, every field with its unit in a comment above it
(Drake's style), read by :func:`~aerial_drake.simulation.scenarios.loading.load_scenario`
and checked by :mod:`~aerial_drake.simulation.scenarios.validation` (the perturbation
sections are in :mod:`aerial_drake.simulation.scenarios.perturbations`).

A scenario holds every number of a run: Table II's gains, the trajectory constants of
(28)-(33), the initial offset, the actuator limits of Table I, the disturbance windows, the
integrator.
"""


# No "from __future__ import annotations": pydrake's yaml_load_typed needs real type objects.
import math
from dataclasses import dataclass, field

from pydrake.multibody.plant import MultibodyPlantConfig
from pydrake.systems.analysis import SimulatorConfig

from aerial_drake.control.baselines.params import BaselineParams
from aerial_drake.control.force.params import ForceTaskParams
from aerial_drake.control.gains import Gains
from aerial_drake.control.law import F_D_LIMIT, SIGMA_MIN_J3_LIMIT
from aerial_drake.control.plus.params import PlusParams
from aerial_drake.control.registry import LAW_KERNEL_CHOICES, PAPER_CONTROLLER
from aerial_drake.robots.description import DEFAULT_ROBOT, RobotDescription
from aerial_drake.robots.models import AerialManipulator, make_plant
from aerial_drake.simulation.scenarios.checks import (
    DEFAULT_MAX_LOG_MB,
    current_target,
    folder_name,
)
from aerial_drake.simulation.scenarios.perturbations import (
    ModelMismatch,
    Payload,
    RandomDisturbances,
    Sensing,
    Wind,
)
from aerial_drake.simulation.scenarios.robot import robot_description
from aerial_drake.simulation.scenarios.world import Environment, ForceSensor, continuous_plant
from aerial_drake.trajectories.params import TrajectoryParams

__all__ = ["Scenario", "Disturbance", "InitialCondition", "Actuation", "Rotors",
           "ControllerConfig", "JointLimits", "Observer", "ModelMismatch", "Payload", "Wind",
           "Sensing", "RandomDisturbances"]


@dataclass
class Disturbance:
    """A constant external wrench, in World, active for ``start <= t < stop``."""

    # Where it acts: "vehicle" (at the vehicle's frame, its CoM) or "end_effector"; the
    # earlier name "helicopter" reads as "vehicle", with a FutureWarning.
    target: str = "vehicle"
    # Window (s).
    start: float = 0.0
    stop: float = 0.0
    # Force (N), World axes.
    force: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    # Torque (N m), World axes.
    torque: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])

    def __post_init__(self) -> None:
        self.target = current_target(self.target, "Disturbance.target")


@dataclass
class InitialCondition:
    """The start: the configuration that realises the reference at t = 0 (CoM on x_d, base at
    R_d, end effector on its desired pose, the task's joints at their targets), then these
    offsets; velocities zero."""

    # Offset of the base (and so the whole robot) position (m), World axes.
    base_position_offset: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    # Offset of the base attitude, roll-pitch-yaw about World axes (rad).
    base_rpy_offset: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    # Offsets of the arm's joints, one per joint (rad); empty: none.
    arm_offset: list[float] = field(default_factory=list)


@dataclass
class Actuation:
    """What stands between the controller's command and the plant (Section IV)."""

    # 10-90% rise time of the first-order lag on thrust and body torques (s); 0 = no lag.
    lag_rise_time: float = 0.0
    # Saturate the applied inputs at the robot's limits (its description's ``limits``: thrust
    # range, body torque bounds, the arm's effort limits), or at the overrides below.
    saturate: bool = True
    # Overrides of the robot's thrust range (N) and body torque bound, each axis (N m); .nan
    # (the default): the robot description's.
    thrust_min: float = math.nan
    thrust_max: float = math.nan
    body_torque_max: float = math.nan


@dataclass
class Rotors:
    """The spinning rotors of the "rotors" plant variant (docs/models.md, Helicopter with
    rotors)."""

    # Rotor speed, left rotor positive, right negative (rad/s).
    speed: float = 0.0
    # Gain of the drive that holds the speed (N m s/rad); the rotors scenario sets it.
    drive_gain: float = 0.0


@dataclass
class ControllerConfig:
    """Which controller closes the loop (docs/baselines.md); all use the scenario's gains."""

    # "paper" (Section III), "paper_plus" (the paper's law with integral action and the
    # vehicle-force feed-forward, docs/control.md), "paper_force" (paper_plus with a force
    # task, docs/contact.md), "uncoupled", "static_compensation", or a
    # name registered with aerial_drake.control.registry.register_controller.
    type: str = PAPER_CONTROLLER
    # The baselines' own parameters (used by "uncoupled" and "static_compensation").
    baseline: BaselineParams = field(default_factory=BaselineParams)
    # paper_plus's options (used by "paper_plus" and "paper_force"; the defaults are all off).
    plus: PlusParams = field(default_factory=PlusParams)
    # The force task (used by "paper_force"; docs/contact.md).
    force: ForceTaskParams = field(default_factory=ForceTaskParams)
    # The compiled law's kernel (used by "paper" and "paper_plus"; docs/control.md, "The fast
    # kernel"): "exact" (the paper runs' arithmetic, bit for bit) or "fast" (the same law to
    # round-off, about a tenth faster; compiled the first time it is chosen).
    kernel: str = LAW_KERNEL_CHOICES[0]


@dataclass
class Observer:
    """The external wrench observer (docs/control.md, "External wrench estimate"): a
    generalized-momentum observer on the controller's model, sampled at controller_period.
    Off by default: no system is added and the run is unchanged."""

    # Add it to the run and log its estimate (log.npz's ``external_wrench_estimate``).
    enabled: bool = False
    # Its bandwidth K_O (1/s): the estimate follows a step of the external force as
    # 1 - exp(-K_O t).
    bandwidth: float = 20.0


@dataclass
class JointLimits:
    """What the arm's joint limits (its model files') do in a run (docs/reliability.md)."""

    # "stop": the run fails at the first logged sample past a position limit, naming the
    # joint; "enforce": the plant holds the joint at its limit (Drake's discrete plant only:
    # set plant.time_step); "report": nothing stops (metrics.json reports the ratios).
    positions: str = "stop"
    # "stop" or "report" for the joint speed limits (|v| <= v_max).
    velocities: str = "report"


@dataclass
class Scenario:
    """One run of the closed loop."""

    # A short name (used for output folders).
    name: str = "unnamed"
    description: str = ""
    # The robot: a shipped robot's name (helicopter_lwr, ...) or the path of a robot
    # description file (*.robot.yaml; relative to the scenario file). docs/robots.md.
    robot: str = DEFAULT_ROBOT
    # Simulated plant: "rigid" (the robot's own models, the controller's) or one of the
    # robot's variants (the paper's robot: "rotors", with spinning rotor bodies).
    plant_variant: str = "rigid"
    # Simulated time (s).
    duration: float = 15.0
    # Controller sample period (s); 0 wires continuous feedback (for analysis).
    controller_period: float = 1e-3
    # Logging period (s).
    log_period: float = 1e-3
    # Drake's simulator settings (integration scheme, accuracy, step).
    simulator: SimulatorConfig = field(default_factory=SimulatorConfig)
    # Table II's gains (units per entry in aerial_drake.control.gains.Gains).
    gains: Gains = field(default_factory=Gains)
    # The reference: its kind and constants (aerial_drake.trajectories.params).
    trajectory: TrajectoryParams = field(default_factory=TrajectoryParams)
    initial: InitialCondition = field(default_factory=InitialCondition)
    actuation: Actuation = field(default_factory=Actuation)
    rotors: Rotors = field(default_factory=Rotors)
    # Constant wrench windows (N, N m, s).
    disturbances: list[Disturbance] = field(default_factory=list)
    # Thresholds of the Assumption 1 (sigma_min(J_3)) and 2 (|f_d|, N) checks.
    sigma_min_J3_limit: float = SIGMA_MIN_J3_LIMIT
    f_d_limit: float = F_D_LIMIT
    # The controller (default: the paper's).
    controller: ControllerConfig = field(default_factory=ControllerConfig)
    # The external wrench observer (default: off).
    observer: Observer = field(default_factory=Observer)

    # Refuse a run whose estimated log (held in memory) exceeds this (MB; docs/reliability.md).
    max_log_mb: float = DEFAULT_MAX_LOG_MB

    # Perturbations (docs/studies.md), all off by default: the simulated plant's inertial
    # parameters apart from the controller's model, a payload unknown to the controller, wind,
    # noisy and delayed measurements, random disturbance windows.
    model_mismatch: ModelMismatch = field(default_factory=ModelMismatch)
    payload: Payload = field(default_factory=Payload)
    wind: Wind = field(default_factory=Wind)
    sensing: Sensing = field(default_factory=Sensing)
    random_disturbances: RandomDisturbances = field(default_factory=RandomDisturbances)

    # The world (docs/world.md): Drake's MultibodyPlantConfig of the simulated plant (default:
    # continuous, time_step 0) and the environment's model directives (default: none).
    plant: MultibodyPlantConfig = field(default_factory=continuous_plant)
    environment: Environment = field(default_factory=Environment)
    # The wrist force sensor of paper_force's force task (docs/contact.md).
    force_sensor: ForceSensor = field(default_factory=ForceSensor)
    # What the arm's joint limits do: stop the run (default), enforce, or report only.
    joint_limits: JointLimits = field(default_factory=JointLimits)

    def validate(self) -> "Scenario":
        """Check every value (:func:`.validation.validate_scenario`: type, finiteness, range,
        consistency); raise ScenarioError naming the field, the value, the allowed range and
        the fix. Returns self."""
        from aerial_drake.simulation.scenarios.validation import validate_scenario

        validate_scenario(self)
        return self

    def robot_description(self) -> RobotDescription:
        """The robot this scenario flies (ScenarioError naming ``robot`` if it is invalid)."""
        return robot_description(self.robot)

    def controller_model(self, floating_base: str = "quaternion") -> AerialManipulator:
        """A fresh finalized plant of the robot's rigid model (the controller's)."""
        return make_plant(floating_base=floating_base, robot=self.robot_description())

    @property
    def folder_name(self) -> str:
        """The run folder's name: the name with unsafe characters replaced (never a path)."""
        return folder_name(self.name)
