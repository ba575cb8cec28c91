"""The one validation pass over a scenario's values, before any model is built.

Every number is checked for its type (a number, not ``true``), finiteness and a stated range;
then the fields are checked against each other (periods against the duration, the estimated
log size against a limit the user can raise). The first problem raises
:class:`ScenarioError` (a ``ValueError``) naming the field, the value, the allowed range
and the fix; :func:`aerial_drake.simulation.scenarios.load_scenario` adds the file's name.
The ranges are listed in docs/reliability.md (keep the two in step).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any, NoReturn

from pydrake.systems.analysis import GetIntegrationSchemes

from aerial_drake.robots.task import POSE_ROW_LABELS, orientation_positions, parse_task

#: Floats per logged sample, an upper bound over the plant variants (time, plant state,
#: commands, diagnostics, references, rotor drive): what the log-size estimate multiplies.
LOG_FLOATS_PER_SAMPLE = 160
#: Default limit of the estimated log size (MB, 10^6 bytes); a scenario's ``max_log_mb`` or
#: ``--max-log-mb`` raises it. The log is held in memory during the run, then compressed.
DEFAULT_MAX_LOG_MB = 1000.0


class ScenarioError(ValueError):
    """A scenario file or value is invalid; the message names the field and the fix, and
    ``field`` is the field's dotted name when one field is to blame (else None)."""

    def __init__(self, message: str, field: str | None = None) -> None:
        super().__init__(message)
        self.field = field


def _error(field: str, message: str) -> ScenarioError:
    return ScenarioError(message, field)


@dataclass(frozen=True)
class Range:
    """An allowed interval of a number, its unit and a hint for fixing a value outside it."""

    low: float
    high: float
    unit: str = ""
    low_open: bool = False
    fix: str = ""

    def contains(self, x: float) -> bool:
        above = x > self.low if self.low_open else x >= self.low
        return above and x <= self.high

    def text(self) -> str:
        unit = f" {self.unit}" if self.unit else ""
        return f"{'>' if self.low_open else '>='} {self.low:g} and <= {self.high:g}{unit}"


def show(value: Any) -> str:
    """A value as the user wrote it: plain floats and lists, no numpy reprs; YAML's words."""
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float) or hasattr(value, "dtype"):
        try:
            x = float(value)
        except (TypeError, ValueError):
            return repr(value)
        if math.isnan(x):
            return ".nan"
        if math.isinf(x):
            return ".inf" if x > 0 else "-.inf"
        return repr(x)
    if isinstance(value, (list, tuple)) or hasattr(value, "tolist"):
        items = value.tolist() if hasattr(value, "tolist") else value
        if isinstance(items, list):
            return "[" + ", ".join(show(v) for v in items) + "]"
    if isinstance(value, str):
        return repr(value)
    return repr(value)


def _fail(field: str, value: Any, rule: str, fix: str = "") -> NoReturn:
    raise _error(field, f"{field} must be {rule}; got {show(value)}"
                 + (f" ({fix})" if fix else ""))


def is_number(value: Any) -> bool:
    """An int or float, not a bool (``true`` is not a duration)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def number(field: str, value: Any, allowed: Range) -> float:
    """Check one number against ``allowed``; returns it as a float."""
    if not is_number(value):
        _fail(field, value, f"a number {allowed.text()}", allowed.fix)
    if not math.isfinite(value) or not allowed.contains(value):
        _fail(field, value, f"finite, {allowed.text()}", allowed.fix)
    return float(value)


def vector(field: str, value: Any, size: int | None, allowed: Range) -> None:
    """Check a list of ``size`` numbers, each within ``allowed``."""
    if not isinstance(value, (list, tuple)) or (size is not None and len(value) != size):
        count = f"{size} numbers" if size is not None else "numbers"
        _fail(field, value, f"a list of {count}, each {allowed.text()}", allowed.fix)
    for i, v in enumerate(value):
        if not is_number(v) or not math.isfinite(v) or not allowed.contains(v):
            _fail(f"{field}[{i}]", v, f"finite, {allowed.text()}", allowed.fix)


def flag(field: str, value: Any) -> None:
    if not isinstance(value, bool):
        _fail(field, value, "true or false")


def text(field: str, value: Any, choices: tuple[str, ...] | None = None) -> None:
    if not isinstance(value, str):
        _fail(field, value, "text")
    if choices is not None and value not in choices:
        raise _error(field, f"{field}: {show(value)} is not one of "
                                 f"{', '.join(choices)}")


# --- The ranges (docs/reliability.md lists them) ------------------------------------------
DAY = 86400.0
DURATION = Range(0.0, DAY, "s", low_open=True, fix="the paper's runs are 15 s")
PERIOD = Range(1e-5, 0.1, "s", fix="the paper samples at 1e-3 s (1 kHz)")
LOG_PERIOD = Range(1e-5, DAY, "s", fix="1e-3 s logs every controller sample")
MAX_STEP = Range(1e-6, 0.1, "s", fix="the shipped scenarios use 1e-3 s")
ACCURACY = Range(0.0, 1.0, low_open=True, fix="the shipped scenarios use 1e-6")
REALTIME = Range(0.0, 1000.0, fix="0 runs as fast as possible, 1 paces at real time")
START_TIME = Range(0.0, 0.0, "s", fix="runs start at t = 0 (the reference's origin); "
                   "remove simulator.start_time")
GAIN = Range(0.0, 1e6, low_open=True, fix="Table II's gains are 0.36 to 800; "
             "Proposition 1 needs every gain > 0")
POSITION_OFFSET = Range(-1.0, 1.0, "m", fix="the shipped scenarios use 0.05 m")
ANGLE_OFFSET = Range(-math.pi, math.pi, "rad", fix="the shipped scenarios use 0.05 rad")
LAG = Range(0.0, 10.0, "s", fix="the paper's lag has a 0.1 s rise time; 0 = no lag")
THRUST = Range(0.0, 1e5, "N", fix="Table I: thrust in [0, 980.6] N")
BODY_TORQUE = Range(0.0, 1e5, "N m", low_open=True, fix="Table I: 200 N m")
ROTOR_SPEED = Range(-1e4, 1e4, "rad/s", fix="Table I: 26 pi = 81.68 rad/s")
DRIVE_GAIN = Range(0.0, 1e5, "N m s/rad", fix="the disturbed scenario uses 50")
WINDOW = Range(0.0, DAY, "s", fix="a disturbance window lies in [0, 86400] s")
FORCE = Range(-1e5, 1e5, "N", fix="the paper's disturbances are 40-50 N")
TORQUE = Range(-1e5, 1e5, "N m", fix="the paper's disturbance torque is 20 N m")
SIGMA_LIMIT = Range(0.0, 1e3, low_open=True, fix="the default is 1e-3")
F_D_LIMIT = Range(0.0, 1e4, "N", low_open=True, fix="the default is 1 N")
MAX_LOG_MB = Range(0.0, 1e6, "MB", low_open=True, fix="the default is 1000 MB")
TRAJECTORY = {
    "center": (3, Range(-1e3, 1e3, "m")),
    "basic_amplitude": (None, Range(0.0, 100.0, "m", fix="the paper's is 0.5 m")),
    "basic_frequency": (None, Range(0.0, 100.0, "rad/s", fix="the paper's is 0.5 rad/s")),
    "basic_climb_rate": (None, Range(-100.0, 100.0, "m/s", fix="the paper's is 0.045 m/s")),
    "agile_amplitude": (None, Range(0.0, 10.0, "m", fix="the paper's is 0.1 m")),
    "agile_frequency": (None, Range(0.0, 100.0, "rad/s", fix="the paper's is 3 rad/s")),
    "orientation_amplitudes": (3, Range(0.0, math.pi, "rad", fix="the paper's are 0.5 rad")),
    "orientation_frequency": (None, Range(0.0, 100.0, "rad/s", fix="the paper's is 3 rad/s")),
    "heading_initial": (None, Range(-1e3, 1e3, "rad")),
    "heading_rate": (None, Range(-100.0, 100.0, "rad/s", fix="the paper's is 0.5 rad/s")),
    "com_offset": (3, Range(-10.0, 10.0, "m", fix="the paper's is [-0.3, 0, 0.6] m")),
}
#: Characters a run folder's name keeps; any other run of characters becomes "_".
_UNSAFE = re.compile(r"[^A-Za-z0-9._-]+")


def folder_name(name: str) -> str:
    """The run folder's name for scenario ``name``: letters, digits, '.', '_' and '-' only,
    no leading dot, so it never leaves the output folder ('../../x' gives 'x'). Empty if
    nothing is left."""
    return _UNSAFE.sub("_", name).strip("._-")


def estimated_log_mb(duration: float, log_period: float) -> float:
    """Estimated size (MB) of a run's log in memory: samples times floats per sample."""
    samples = math.floor(duration / log_period) + 1
    return samples * LOG_FLOATS_PER_SAMPLE * 8 / 1e6


JOINT_TARGET = Range(-2 * math.pi, 2 * math.pi, "rad")


@dataclass(frozen=True)
class RobotFacts:
    """What the checks need to know of the scenario's robot (built from its description)."""

    n: int  # arm joints = task rows
    n_task_joints: int  # joint components of the task
    variants: tuple[str, ...]
    rotor_variants: tuple[str, ...]  # the variants with rotor joints
    thrust: tuple[float, float]  # the robot's thrust range (N)
    joint_nominal: tuple[float, ...] = ()  # the task's joint components at the nominal posture


def check_values(s: Any, robot: RobotFacts, targets: tuple[str, ...]) -> None:
    """Check every field of scenario ``s`` (a :class:`Scenario`) for its ``robot``; raise
    ScenarioError."""
    n = robot.n
    gain_sizes = {"K_x": 3, "D_x": 3, "Lambda2_bar": 3, "K_y": n, "K_z": n}
    plant_variants = robot.variants
    text("name", s.name)
    if not folder_name(s.name):
        _fail("name", s.name, "a name with at least one letter or digit (it names the run "
              "folder)", "e.g. name: my_test")
    text("description", s.description)
    text("plant_variant", s.plant_variant, plant_variants)
    duration = number("duration", s.duration, DURATION)
    if not is_number(s.controller_period) or not (
            s.controller_period == 0 or PERIOD.contains(s.controller_period)):
        _fail("controller_period", s.controller_period,
              f"0 (continuous feedback) or {PERIOD.text()}", PERIOD.fix)
    if s.controller_period > duration:
        _fail("controller_period", s.controller_period, f"<= duration ({duration:g} s)")
    log_period = number("log_period", s.log_period, LOG_PERIOD)
    if log_period > duration:
        _fail("log_period", log_period, f"<= duration ({duration:g} s)",
              "the log needs at least two samples")
    _check_simulator(s.simulator)
    _check_gains(s.gains, gain_sizes)
    # The description is loaded (and its task parsed) by robot_facts before this runs.
    _check_orientation_gains(s.gains.K_y, parse_task(s.robot_description().task).rows)
    for name, (size, allowed) in TRAJECTORY.items():
        value = getattr(s.trajectory, name)
        if size is None:
            number(f"trajectory.{name}", value, allowed)
        else:
            vector(f"trajectory.{name}", value, size, allowed)
    targets_given = s.trajectory.joint_targets
    if targets_given:
        vector("trajectory.joint_targets", targets_given, robot.n_task_joints, JOINT_TARGET)
    vector("initial.base_position_offset", s.initial.base_position_offset, 3, POSITION_OFFSET)
    vector("initial.base_rpy_offset", s.initial.base_rpy_offset, 3, ANGLE_OFFSET)
    if s.initial.arm_offset:
        vector("initial.arm_offset", s.initial.arm_offset, n, ANGLE_OFFSET)
    _check_actuation(s.actuation, robot.thrust)
    number("rotors.speed", s.rotors.speed, ROTOR_SPEED)
    number("rotors.drive_gain", s.rotors.drive_gain, DRIVE_GAIN)
    spinning = s.plant_variant in robot.rotor_variants
    if spinning and not s.rotors.drive_gain > 0:
        _fail("rotors.drive_gain", s.rotors.drive_gain,
              f"> 0 (N m s/rad) for the '{s.plant_variant}' plant, which has rotor joints",
              DRIVE_GAIN.fix)
    if not spinning and s.rotors.speed != 0:
        raise _error("rotors.speed", f"rotors.speed is set but plant_variant "
                                     f"'{s.plant_variant}' has no rotor joints: use a "
                                     f"variant with rotors ({', '.join(robot.rotor_variants)})"
                                     " or remove rotors.speed" if robot.rotor_variants else
                     f"rotors.speed is set but plant_variant '{s.plant_variant}' has no rotor "
                     "joints (nor does any variant of this robot): remove rotors.speed")
    if not isinstance(s.disturbances, list):
        _fail("disturbances", s.disturbances, "a list of disturbance windows")
    for i, d in enumerate(s.disturbances):
        where = f"disturbances[{i}]"
        text(f"{where}.target", d.target, targets)
        start = number(f"{where}.start", d.start, WINDOW)
        stop = number(f"{where}.stop", d.stop, WINDOW)
        if not stop > start:
            _fail(f"{where}.stop", stop, f"> {where}.start ({start:g} s)",
                  "a window is [start, stop)")
        vector(f"{where}.force", d.force, 3, FORCE)
        vector(f"{where}.torque", d.torque, 3, TORQUE)
    number("sigma_min_J3_limit", s.sigma_min_J3_limit, SIGMA_LIMIT)
    number("f_d_limit", s.f_d_limit, F_D_LIMIT)
    limit = number("max_log_mb", s.max_log_mb, MAX_LOG_MB)
    log_mb = estimated_log_mb(duration, log_period)
    if log_mb > limit:
        raise _error(
            "log_period", f"duration / log_period = {duration:g} / {log_period:g} s gives an "
            f"estimated log of {log_mb:.0f} MB, above the limit max_log_mb = {limit:g} MB: "
            "raise log_period or shorten duration, or raise the limit (max_log_mb in the "
            "scenario, --max-log-mb on the command line)")


def _check_simulator(sim: Any) -> None:
    schemes = tuple(GetIntegrationSchemes())
    text("simulator.integration_scheme", sim.integration_scheme, schemes)
    number("simulator.max_step_size", sim.max_step_size, MAX_STEP)
    number("simulator.accuracy", sim.accuracy, ACCURACY)
    flag("simulator.use_error_control", sim.use_error_control)
    number("simulator.start_time", sim.start_time, START_TIME)
    number("simulator.target_realtime_rate", sim.target_realtime_rate, REALTIME)


def _check_gains(g: Any, sizes: dict[str, int]) -> None:
    for name, size in sizes.items():
        value = getattr(g, name)
        if not isinstance(value, (list, tuple)) or len(value) != size:
            _fail(f"gains.{name}", value, f"a list of {size} diagonal entries",
                  "set it in the scenario YAML")
        for i, v in enumerate(value):
            if not is_number(v) or not math.isfinite(v) or not GAIN.contains(v):
                raise _error(
                    f"gains.{name}", f"gains.{name} = {show(value)} is not positive definite "
                    f"with bounded entries: entry {i} must be finite, {GAIN.text()}; got "
                    f"{show(v)} ({GAIN.fix})")
    for name in ("k_R", "k_w", "lyapunov_gamma1", "lyapunov_gamma2"):
        number(f"gains.{name}", getattr(g, name), GAIN)


def _check_orientation_gains(K_y: list[float], rows: tuple[int, ...]) -> None:
    """Refuse unequal K_y entries on the orientation rows (docs/control.md, "The orientation
    error and K_y").

    The orientation error e = vee(skew(R_E R_ed^T)) has the rate w_E - w_ed + w_ed x e +
    O(|e|^2), while the law's task velocity error is w_E - w_ed (17): the error vector turns
    with w_ed, so (23d) holds for e only in norm, and only with equal gains k:
    d/dt |e|^2 / 2 = -k |e|^2 + e . z~ as (23d) has it, since e . (w_ed x e) = 0. With unequal
    gains the derivative of (24)'s y~^T K_y K_z y~ keeps e^T K_y K_z (w_ed x e), a term the
    proof of Proposition 1 does not cancel."""
    at = orientation_positions(rows)
    values = [K_y[k] for k in at]
    if values and max(values) != min(values):
        labels = ", ".join(POSE_ROW_LABELS[rows[k]] for k in at)
        raise _error(
            "gains.K_y",
            f"gains.K_y = {show(K_y)}: its orientation entries (task rows "
            f"{', '.join(str(k + 1) for k in at)}: {labels}) are unequal, {show(values)}. "
            "The orientation error vee(skew(R_E R_ed^T)) changes at w_E - w_ed + w_ed x e, "
            "not at the velocity error w_E - w_ed the law drives, so the error turns with "
            "the reference's angular velocity: with equal gains its norm still decays as "
            "(23d) says, with unequal ones (23d) fails and the Lyapunov derivative of "
            "(24)-(26) keeps an uncancelled term (measured: 1.7 % of the decaying term with "
            "[4, 8, 16]). Make the orientation entries equal (e.g. all "
            f"{show(float(values[0]))}; docs/control.md)")


def _check_actuation(a: Any, robot_thrust: tuple[float, float]) -> None:
    """The actuation section; its thrust and torque bounds are optional overrides (.nan, the
    default: the robot description's limits)."""
    number("actuation.lag_rise_time", a.lag_rise_time, LAG)
    flag("actuation.saturate", a.saturate)
    low, high = robot_thrust
    for name in ("thrust_min", "thrust_max", "body_torque_max"):
        value = getattr(a, name)
        if not is_number(value):
            _fail(f"actuation.{name}", value, "a number, or .nan for the robot's limit")
        if math.isnan(value):
            continue
        number(f"actuation.{name}", value, BODY_TORQUE if name == "body_torque_max" else THRUST)
        if name == "thrust_min":
            low = value
        elif name == "thrust_max":
            high = value
    if not low < high:
        _fail("actuation.thrust_max", high, f"> the thrust minimum ({low:g} N)", THRUST.fix)
