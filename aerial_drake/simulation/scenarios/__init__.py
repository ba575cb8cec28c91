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
from pydrake.common.yaml import yaml_dump, yaml_load_data, yaml_load_typed
from pydrake.systems.analysis import SimulatorConfig

from aerial_drake.control.law import F_D_LIMIT, SIGMA_MIN_J3_LIMIT, Gains
from aerial_drake.drake_compat import SimulatorFieldError, translate_simulator_section
from aerial_drake.robots.models import PLANT_VARIANTS
from aerial_drake.trajectories.paper import TrajectoryParams

DISTURBANCE_TARGETS = ("helicopter", "end_effector")


class ScenarioError(ValueError):
    """A scenario file or value is invalid; the message names the field and the fix."""


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
    R_d, end effector on its desired pose, q3 = q3d), then these offsets; velocities zero."""

    # Offset of the base (and so the whole robot) position (m), World axes.
    base_position_offset: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    # Offset of the base attitude, roll-pitch-yaw about World axes (rad).
    base_rpy_offset: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    # Offsets of the seven arm joints (rad).
    arm_offset: list[float] = field(default_factory=lambda: [0.0] * 7)


@dataclass
class Actuation:
    """What stands between the controller's command and the plant (Section IV)."""

    # 10-90% rise time of the first-order lag on thrust and body torques (s); 0 = no lag.
    lag_rise_time: float = 0.0
    # Saturate the applied inputs at the limits below and the arm's effort limits (model file).
    saturate: bool = True
    # Thrust range (N), Table I: [0, 980.6]. No default: the scenario must say.
    thrust_min: float = 0.0
    thrust_max: float = math.nan
    # Body torque bound, each axis (N m), Table I: 200.
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
class Scenario:
    """One run of the closed loop."""

    # A short name (used for output folders).
    name: str = "unnamed"
    description: str = ""
    # Simulated plant: "rigid" (the nominal rigid body) or "rotors" (spinning rotor bodies).
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

    def validate(self) -> "Scenario":
        """Check values; raise ScenarioError naming the field and the fix. Returns self."""
        if self.plant_variant not in PLANT_VARIANTS:
            raise ScenarioError(f"plant_variant: '{self.plant_variant}' is not one of "
                                f"{PLANT_VARIANTS}")
        for name in ("duration", "log_period"):
            if not getattr(self, name) > 0:
                raise ScenarioError(f"{name} must be > 0 (s); got {getattr(self, name)}")
        if not self.controller_period >= 0:
            raise ScenarioError("controller_period must be >= 0 (s; 0 = continuous feedback)")
        try:
            self.gains.validate()
        except ValueError as err:
            raise ScenarioError(str(err)) from None
        try:
            self.trajectory.validate()
        except ValueError as err:
            raise ScenarioError(f"trajectory: {err}") from None
        _check_vector("initial.base_position_offset", self.initial.base_position_offset, 3)
        _check_vector("initial.base_rpy_offset", self.initial.base_rpy_offset, 3)
        _check_vector("initial.arm_offset", self.initial.arm_offset, 7)
        a = self.actuation
        if not a.lag_rise_time >= 0:
            raise ScenarioError("actuation.lag_rise_time must be >= 0 (s)")
        if a.saturate and not a.thrust_max > a.thrust_min:
            raise ScenarioError("actuation.thrust_max must be set and exceed "
                                f"actuation.thrust_min (N); got {a.thrust_max}")
        if a.saturate and not a.body_torque_max > 0:
            raise ScenarioError("actuation.body_torque_max must be set and > 0 (N m); got "
                                f"{a.body_torque_max}")
        for name in ("sigma_min_J3_limit", "f_d_limit"):
            if not getattr(self, name) > 0:
                raise ScenarioError(f"{name} must be > 0, or the check of the paper's "
                                    f"assumption can never fire; got {getattr(self, name)}")
        if self.plant_variant == "rotors" and not self.rotors.drive_gain > 0:
            raise ScenarioError(f"rotors.drive_gain must be > 0 (N m s/rad); got "
                                f"{self.rotors.drive_gain}")
        if self.plant_variant == "rigid" and self.rotors.speed != 0:
            raise ScenarioError("rotors.speed is set but plant_variant is 'rigid', which has no "
                                "rotor bodies: use plant_variant: rotors or remove rotors.speed")
        for i, d in enumerate(self.disturbances):
            where = f"disturbances[{i}]"
            if d.target not in DISTURBANCE_TARGETS:
                raise ScenarioError(f"{where}.target: '{d.target}' is not one of "
                                    f"{DISTURBANCE_TARGETS}")
            if not 0 <= d.start < d.stop:
                raise ScenarioError(f"{where}: need 0 <= start < stop; got [{d.start}, {d.stop}]")
            _check_vector(f"{where}.force", d.force, 3)
            _check_vector(f"{where}.torque", d.torque, 3)
        return self


def _check_vector(name: str, value, size: int) -> None:
    arr = np.asarray(value, dtype=float)
    if arr.shape != (size,) or not np.all(np.isfinite(arr)):
        raise ScenarioError(f"{name} must be a list of {size} finite numbers; got {value!r}")


def _find_bad_field(data, schema, prefix: str = "") -> str | None:
    """The dotted name of the first value in ``data`` that does not fit ``schema``'s type
    (Drake's loader says what failed to convert, not where)."""
    if not isinstance(data, dict) or not dataclasses.is_dataclass(schema):
        return None
    types = {f.name: f.type for f in dataclasses.fields(schema)}
    for key, value in data.items():
        name = f"{prefix}{key}"
        kind = types.get(key)
        if kind is None:
            return name
        if dataclasses.is_dataclass(kind):
            found = _find_bad_field(value, kind, name + ".")
            if found:
                return found
            continue
        item = getattr(kind, "__args__", (None,))[0]
        values = value if isinstance(value, list) else [value]
        for v in values:
            target = item if isinstance(value, list) and item is not None else kind
            if target is float and not isinstance(v, (int, float)):
                return f"{name} (expected a number, got {v!r})"
            if target is str and not isinstance(v, str):
                return f"{name} (expected text, got {v!r})"
            if target is bool and not isinstance(v, bool):
                return f"{name} (expected true or false, got {v!r})"
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

    ``overrides`` replaces top-level fields after loading (e.g. ``{"duration": 2.0}``).
    """
    path = Path(name_or_path)
    if not path.suffix:
        shipped = shipped_scenarios()
        if str(name_or_path) not in shipped:
            raise ScenarioError(f"no scenario named '{name_or_path}'; shipped scenarios: "
                                f"{sorted(shipped)}, or give a path to a .yaml file")
        path = shipped[str(name_or_path)]
    if not path.is_file():
        raise ScenarioError(f"scenario file not found: {path}")
    data = None
    try:
        text = path.read_text()
        data = yaml_load_data(text)
        # A field only some Drake releases have: checked and removed in one place.
        if isinstance(data, dict) and translate_simulator_section(data.get("simulator"),
                                                                  "simulator"):
            text = yaml_dump(data)
        scenario = yaml_load_typed(schema=Scenario, data=text)
    except SimulatorFieldError as err:
        raise ScenarioError(f"{path}: {err}") from None
    except (RuntimeError, ValueError, TypeError) as err:
        where = _find_bad_field(data, Scenario)
        raise ScenarioError(f"{path}: {where + ': ' if where else ''}{err}") from None
    if overrides:
        scenario = dataclasses.replace(scenario, **overrides)
    return scenario.validate()
