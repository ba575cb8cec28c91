"""Scenario files: one dataclass tree, loaded with Drake's ``yaml_load_typed``; the shipped
YAML files live in this package's folder.

A scenario YAML holds every number of a run: Table II's gains, the trajectory constants of
(28)-(33), the initial offset, the actuator limits of Table I, the disturbance windows, the
integrator. A misspelt key or a wrong type is an error that names the field; values are then
checked by :meth:`Scenario.validate` before anything is simulated.
"""


# No "from __future__ import annotations": pydrake's yaml_load_typed needs real type objects.
import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from pydrake.common.yaml import yaml_dump, yaml_load_typed
from pydrake.multibody.plant import MultibodyPlantConfig
from pydrake.systems.analysis import SimulatorConfig

from aerial_drake.control.baselines.params import BaselineParams
from aerial_drake.control.law import F_D_LIMIT, SIGMA_MIN_J3_LIMIT, Gains
from aerial_drake.drake_compat import SimulatorFieldError, translate_simulator_section
from aerial_drake.robots.description import (
    DEFAULT_ROBOT,
    RobotDescription,
    RobotDescriptionError,
    load_robot_description,
    shipped_robots,
)
from aerial_drake.robots.models import AerialManipulator, make_plant
from aerial_drake.simulation.controllers import PAPER_CONTROLLER, controller_types
from aerial_drake.simulation.scenarios.checks import (
    DEFAULT_MAX_LOG_MB,
    RobotFacts,
    ScenarioError,
    check_values,
    folder_name,
    show,
)
from aerial_drake.simulation.scenarios.perturbations import (
    ModelMismatch,
    Payload,
    RandomDisturbances,
    Sensing,
    Wind,
    check_perturbations,
)
from aerial_drake.simulation.scenarios.reading import read_scenario_file
from aerial_drake.simulation.scenarios.trajectory import check_trajectory, resolve_python_path
from aerial_drake.simulation.scenarios.world import (
    Environment,
    check_world,
    continuous_plant,
    find_bad_world_field,
    resolve_environment,
)
from aerial_drake.trajectories.params import TrajectoryParams

DISTURBANCE_TARGETS = ("helicopter", "end_effector")


@dataclass
class Disturbance:
    """A constant external wrench, in World, active for ``start <= t < stop``."""

    # Where it acts: "helicopter" (at the helicopter's frame, its CoM) or "end_effector".
    target: str = "helicopter"
    # Window (s).
    start: float = 0.0
    stop: float = 0.0
    # Force (N), World axes.
    force: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    # Torque (N m), World axes.
    torque: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])


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

    # "paper" (Section III), "uncoupled", "static_compensation", or a name registered with
    # aerial_drake.simulation.controllers.register_controller.
    type: str = PAPER_CONTROLLER
    # The baselines' own parameters (used by "uncoupled" and "static_compensation").
    baseline: BaselineParams = field(default_factory=BaselineParams)


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
    gains: Gains = field(default_factory=Gains)
    trajectory: TrajectoryParams = field(default_factory=TrajectoryParams)
    initial: InitialCondition = field(default_factory=InitialCondition)
    actuation: Actuation = field(default_factory=Actuation)
    rotors: Rotors = field(default_factory=Rotors)
    disturbances: list[Disturbance] = field(default_factory=list)
    # Thresholds of the Assumption 1 (sigma_min(J_3)) and 2 (|f_d|, N) checks.
    sigma_min_J3_limit: float = SIGMA_MIN_J3_LIMIT
    f_d_limit: float = F_D_LIMIT
    # The controller (default: the paper's).
    controller: ControllerConfig = field(default_factory=ControllerConfig)

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

    def validate(self) -> "Scenario":
        """Check every value (type, finiteness, range, consistency: :mod:`.checks`); raise
        ScenarioError naming the field, the value, the allowed range and the fix. Returns
        self."""
        facts = robot_facts(self)
        check_values(self, facts, DISTURBANCE_TARGETS)
        check_trajectory(self, np.array(facts.joint_nominal))
        self._validate_controller()
        check_perturbations(self)
        check_world(self)
        return self

    def robot_description(self) -> RobotDescription:
        """The robot this scenario flies (ScenarioError naming ``robot`` if it is invalid)."""
        return robot_description(self.robot)

    def controller_model(self, floating_base: str = "quaternion") -> AerialManipulator:
        """A fresh finalized plant of the robot's rigid model (the controller's)."""
        return make_plant(floating_base=floating_base, robot=self.robot_description())

    def _validate_controller(self) -> None:
        if self.controller.type not in controller_types():
            raise ScenarioError(f"controller.type: '{self.controller.type}' is not one of "
                                f"{controller_types()}", "controller.type")
        try:
            self.controller.baseline.validate()
        except ValueError as err:
            # The baseline's message starts with the field's dotted name.
            raise ScenarioError(str(err), str(err).split(" ", 1)[0]) from None

    @property
    def folder_name(self) -> str:
        """The run folder's name: the name with unsafe characters replaced (never a path)."""
        return folder_name(self.name)


def robot_description(robot: str) -> RobotDescription:
    """The description named by a scenario's ``robot`` field (a shipped name or an absolute
    path, as :func:`load_scenario` leaves it), read once per file version."""
    if not isinstance(robot, str) or not robot.strip():
        raise ScenarioError(f"robot: {robot!r} is not a shipped robot's name "
                            f"({', '.join(shipped_robots())}) or a robot description file's "
                            "path", "robot")
    path = shipped_robots().get(robot, Path(robot))
    try:
        stamp = path.stat().st_mtime_ns
    except OSError:
        stamp = -1
    key = (str(path), stamp)
    if key not in _DESCRIPTIONS:
        try:
            _DESCRIPTIONS[key] = load_robot_description(robot)
        except RobotDescriptionError as err:
            raise ScenarioError(f"robot: {err}", "robot" if err.field in (None, "robot")
                                else f"robot: {err.field}") from None
    return _DESCRIPTIONS[key]


_DESCRIPTIONS: dict[tuple[str, int], RobotDescription] = {}
_FACTS: dict[tuple[str, str], RobotFacts] = {}


def robot_facts(scenario: Scenario) -> RobotFacts:
    """Sizes and options of the scenario's robot, for the value checks (the robot's plant is
    built, and its description checked, once per description)."""
    description = robot_description(scenario.robot)
    key = (str(description.source), repr(description))
    if key not in _FACTS:
        try:
            model = make_plant(robot=description)
            rotor_variants = tuple(v.name for v in description.variants if v.rotor_joints)
            for variant in description.variant_names()[1:]:
                make_plant(variant, robot=description)  # its checks, before any run
        except RobotDescriptionError as err:
            raise ScenarioError(f"robot: {err}", f"robot: {err.field}") from None
        assert model.task is not None
        _FACTS[key] = RobotFacts(n=model.n, n_task_joints=model.task.n_joints,
                                 variants=description.variant_names(),
                                 rotor_variants=rotor_variants,
                                 thrust=model.thrust_limits(),
                                 joint_nominal=tuple(model.task_joint_nominal()))
    return _FACTS[key]


def _find_bad_field(data, schema, prefix: str = "") -> str | None:
    """The dotted name of the first value in ``data`` that does not fit ``schema``'s type
    (Drake's loader says what failed to convert, not where), with what was expected."""
    if not isinstance(data, dict) or not dataclasses.is_dataclass(schema):
        return None
    types = {f.name: f.type for f in dataclasses.fields(schema)}
    for key, value in data.items():
        name = f"{prefix}{key}"
        kind = types.get(key)
        if kind is None:
            return f"{name} (not a field of {prefix.rstrip('.') or 'the scenario'}; fields: " \
                   f"{', '.join(types)})"
        if dataclasses.is_dataclass(kind) or kind is SimulatorConfig:
            if not isinstance(value, dict):
                what = "an empty section" if value is None else f"got {show(value)}"
                return f"{name} (expected a section of fields, {what}: give its fields, " \
                       "or remove the line to keep the defaults)"
            if dataclasses.is_dataclass(kind):
                found = _find_bad_field(value, kind, name + ".")
                if found:
                    return found
            continue
        args = getattr(kind, "__args__", None)
        if args:  # a list
            if not isinstance(value, list):
                return f"{name} (expected a list, got {show(value)})"
            item = args[0]
            for i, v in enumerate(value):
                if dataclasses.is_dataclass(item):
                    if not isinstance(v, dict):
                        return f"{name}[{i}] (expected a section of fields, got {show(v)})"
                    found = _find_bad_field(v, item, f"{name}[{i}].")
                    if found:
                        return found
                elif _mismatch(item, v):
                    return f"{name}[{i}] ({_mismatch(item, v)})"
            continue
        if _mismatch(kind, value):
            return f"{name} ({_mismatch(kind, value)})"
    return None


def _mismatch(kind, v) -> str | None:
    if kind is float and (isinstance(v, bool) or not isinstance(v, (int, float))):
        if isinstance(v, str):  # YAML 1.1 reads 1e3 as text; Drake converts it
            try:
                float(v)
                return None
            except ValueError:
                pass
        return f"expected a number, got {show(v)}"
    if kind is str and not isinstance(v, str):
        return f"expected text, got {show(v)}"
    if kind is bool and not isinstance(v, bool):
        return f"expected true or false, got {show(v)}"
    return None


def scenario_directory() -> Path:
    """The folder holding the scenario YAML files shipped with the package (beside this
    module, installed or in a checkout)."""
    return Path(__file__).resolve().parent


def shipped_scenarios() -> dict[str, Path]:
    """Name -> path of the scenario files shipped with the package."""
    return {p.stem: p for p in sorted(scenario_directory().glob("*.yaml"))}


def load_scenario(name_or_path: str | Path, *, overrides: dict | None = None) -> Scenario:
    """Load a shipped scenario by name (``"nominal"``) or a YAML file by path, and validate it.

    ``overrides`` replaces top-level fields after loading (e.g. ``{"duration": 2.0}``); an
    unknown key or a value of the wrong type is a ScenarioError naming it. Every error names
    the file.
    """
    if not isinstance(name_or_path, (str, Path)):
        raise ScenarioError(f"scenario: expected a shipped scenario's name or a path to a "
                            f"YAML file, got {type(name_or_path).__name__} {name_or_path!r}")
    path = Path(name_or_path)
    if not path.suffix:  # a shipped name first; else a path (e.g. a folder given by mistake)
        shipped = shipped_scenarios()
        if str(name_or_path) in shipped:
            path = shipped[str(name_or_path)]
        elif not path.exists():
            raise ScenarioError(f"no scenario named '{name_or_path}'; shipped scenarios: "
                                f"{', '.join(sorted(shipped))}, or give a path to a .yaml file")
    text, data = read_scenario_file(path)
    if _translate_old_fields(data):
        text = yaml_dump(data)
    try:
        # A field only some Drake releases have: checked and removed in one place.
        if translate_simulator_section(data.get("simulator"), "simulator"):
            text = yaml_dump(data)
        bad = _find_bad_field(data, Scenario) or find_bad_world_field(data)
        if bad:
            raise ScenarioError(f"{path}: {bad}", bad.split(" ")[0])
        scenario = yaml_load_typed(schema=Scenario, data=text)
    except SimulatorFieldError as err:
        raise ScenarioError(f"{path}: {err}", "simulator") from None
    except (RuntimeError, ValueError, TypeError, AssertionError) as err:
        if isinstance(err, ScenarioError):
            raise
        where = _find_bad_field(data, Scenario)
        raise ScenarioError(f"{path}: {where + ': ' if where else ''}{err or type(err).__name__}",
                            where.split(" ")[0] if where else None) from None
    if overrides:
        scenario = apply_overrides(scenario, overrides)
    scenario = resolve_python_path(_resolve_robot(scenario, path), path)
    scenario = dataclasses.replace(scenario, environment=resolve_environment(
        scenario.environment, path.resolve().parent))
    try:
        return scenario.validate()
    except ScenarioError as err:
        raise ScenarioError(f"{path}: {err}", err.field) from None


def _translate_old_fields(data: dict) -> bool:
    """Fields of earlier releases, read as today's (run folders written before the robot
    description keep loading): ``trajectory.q3_desired: x`` is ``joint_targets: [x]``.
    Returns whether ``data`` changed."""
    trajectory = data.get("trajectory")
    if isinstance(trajectory, dict) and "q3_desired" in trajectory:
        if "joint_targets" in trajectory:
            raise ScenarioError("trajectory: q3_desired and joint_targets are both set: keep "
                                "joint_targets (q3_desired is its earlier name)",
                                "trajectory.q3_desired")
        trajectory["joint_targets"] = [trajectory.pop("q3_desired")]
        return True
    return False


def _resolve_robot(scenario: Scenario, path: Path) -> Scenario:
    """``robot`` as a shipped name or an absolute path (a relative path starts at the
    scenario file's folder), so the scenario written into a run folder finds it again."""
    if scenario.robot in shipped_robots() or not isinstance(scenario.robot, str):
        return scenario
    robot = Path(scenario.robot).expanduser()
    if not robot.is_absolute():
        robot = (path.resolve().parent / robot).resolve()
    return dataclasses.replace(scenario, robot=str(robot))


def apply_overrides(scenario: Scenario, overrides: dict) -> Scenario:
    """A copy of ``scenario`` with top-level fields replaced, each checked for its name and
    type (ScenarioError naming ``overrides['key']``); values are checked by validate()."""
    if not isinstance(overrides, dict):
        raise ScenarioError(f"overrides: expected a dict of field -> value, got "
                            f"{type(overrides).__name__}")
    kinds = {f.name: f.type for f in dataclasses.fields(Scenario)}
    changes = {}
    for key, value in overrides.items():
        where = f"overrides[{key!r}]"
        if key not in kinds:
            raise ScenarioError(f"{where}: not a field of the scenario; fields: "
                                f"{', '.join(kinds)}", str(key))
        kind = kinds[key]
        if kind is float:
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ScenarioError(f"{where}: expected a number, got {show(value)}", key)
            value = float(value)
        elif kind in (str, bool) and not isinstance(value, kind):
            raise ScenarioError(f"{where}: expected {kind.__name__}, got {show(value)}", key)
        elif getattr(kind, "__args__", None):
            if not isinstance(value, list):
                raise ScenarioError(f"{where}: expected a list, got {show(value)}", key)
        elif isinstance(kind, type) and kind not in (str, bool) and not isinstance(value, kind):
            raise ScenarioError(f"{where}: expected a {kind.__name__}, got "
                                f"{type(value).__name__}", key)
        changes[key] = value
    return dataclasses.replace(scenario, **changes)
