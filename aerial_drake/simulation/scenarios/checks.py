"""The scenario's rule toolkit: :class:`ScenarioError`, the checks of one value (a number in
a :class:`Range`, a list of numbers, a flag, a choice of text) and every field's allowed range,
each written once. :mod:`.validation` applies them, field by field, in one pass. The ranges
are listed in docs/reliability.md (keep the two in step).
"""

from __future__ import annotations

import math
import re
import warnings
from dataclasses import dataclass
from typing import Any, NoReturn

from aerial_drake.control.gains import show

__all__ = ["ScenarioError", "Range", "RobotFacts", "show", "number", "vector", "flag", "text",
           "is_number", "folder_name", "estimated_log_mb", "current_target",
           "check_body_names"]

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
POSITION_OFFSET = Range(-1.0, 1.0, "m", fix="the shipped scenarios use 0.05 m")
ANGLE_OFFSET = Range(-math.pi, math.pi, "rad", fix="the shipped scenarios use 0.05 rad")
LAG = Range(0.0, 10.0, "s", fix="the paper's lag has a 0.1 s rise time; 0 = no lag")
BANDWIDTH = Range(0.0, 1e4, "1/s", low_open=True,
                  fix="20 1/s settles a step to 2 % in 0.2 s (docs/control.md)")
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
JOINT_TARGET = Range(-2 * math.pi, 2 * math.pi, "rad")
#: Where a disturbance window acts; OLD_TARGETS: earlier names, read with a FutureWarning.
DISTURBANCE_TARGETS = ("vehicle", "end_effector")
OLD_TARGETS = {"helicopter": "vehicle"}
#: What an arm joint's limit does (the scenario's ``joint_limits``, docs/reliability.md).
POSITION_LIMIT_MODES = ("stop", "enforce", "report")
VELOCITY_LIMIT_MODES = ("stop", "report")
# The perturbation sections (scenarios.perturbations).
RELATIVE = Range(0.0, 0.9, fix="0.1 is a +-10 % error; 0 turns it off")
SCALE = Range(0.1, 10.0, fix="1 keeps the model's value")
MASS = Range(0.0, 1e3, "kg", fix="a payload of up to 1 kg is the robustness study's")
INERTIA = Range(0.0, 1e3, "kg m^2", fix="a 1 kg, 0.1 m cube has 1.7e-3 kg m^2")
OFFSET = Range(-2.0, 2.0, "m", fix="offsets of a few centimetres")
SPEED = Range(-100.0, 100.0, "m/s", fix="a strong breeze is 10 m/s")
SIGMA = Range(0.0, 50.0, "m/s", fix="MIL-F-8785C's moderate turbulence at low altitude is "
              "about 1.5 m/s (W20 = 15 m/s)")
LENGTH = Range(0.1, 1e4, "m", fix="MIL-F-8785C at 10 m altitude: L_w = 10 m, L_u = L_v = 150 m")
AIRSPEED = Range(0.1, 100.0, "m/s", fix="the mean wind speed, at least 1 m/s in hover")
DRAG = Range(0.0, 1e4, fix="a 3 m helicopter fuselage: linear 0, quadratic 1-3 N s^2/m^2")
SAMPLE = Range(1e-4, 1.0, "s", fix="0.01 s resolves turbulence well above the loop's bandwidth")
STD = Range(0.0, 1.0, fix="0 turns the channel's noise off")
DELAY = Range(0.0, 1.0, "s", fix="a multiple of controller_period; 0 = no delay")
SEED = Range(0, 2 ** 32 - 1, fix="any integer >= 0")
TIME = Range(0.0, 86400.0, "s", fix="a window inside the run")
MAGNITUDE = Range(0.0, 1e5, fix="the paper's windows are 40-50 N, 20 N m")
COUNT = Range(0, 100, fix="0 turns the random windows off")
BALANCE_GRADE = Range(0.0, 4000.0, "mm/s", fix="ISO 21940-11's grades run from G0.4 to G4000; "
                      "G6.3 suits rotors of this kind; 0 turns the unbalance off")
HOLD_FRACTION = Range(0.0, 1.0, fix="0.8 keeps each joint within 80 % of its torque limit; "
                      "0 turns the bound off")
#: The most disturbance windows a scenario holds (its own and random_disturbances.count): more
#: would make the run's scenario.yaml larger than a scenario file may be (reading.py).
MAX_WINDOWS = 1000
#: Two window edges closer than this but not equal (round-off, e.g. 0.1 + 0.2 and 0.3) cannot
#: both be breaks of the wrench schedule (Drake's PiecewisePolynomial needs distinct times).
MIN_EDGE_GAP_S = 1e-9
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


def check_body_names(names: Any, available: list[str] | tuple[str, ...],
                     field: str = "model_mismatch.bodies") -> list[str]:
    """The bodies ``names`` asks for (empty: all of ``available``, the robot's bodies with
    mass); raise ScenarioError naming ``field``, the value and the bodies there are."""
    if not isinstance(names, (list, tuple)) or not all(isinstance(n, str) for n in names):
        _fail(field, names, "a list of body names (empty: every body with mass)")
    unknown = [n for n in names if n not in available]
    if unknown:
        raise _error(field, f"{field}: {show(unknown[0])} is not a body with mass of the "
                            f"plant; its bodies with mass are {', '.join(available)}")
    return list(names) if names else list(available)


def folder_name(name: str) -> str:
    """The run folder's name for scenario ``name``: letters, digits, '.', '_' and '-' only,
    no leading dot, so it never leaves the output folder ('../../x' gives 'x'). Empty if
    nothing is left."""
    return _UNSAFE.sub("_", name).strip("._-")


def estimated_log_mb(duration: float, log_period: float) -> float:
    """Estimated size (MB) of a run's log in memory: samples times floats per sample."""
    samples = math.floor(duration / log_period) + 1
    return samples * LOG_FLOATS_PER_SAMPLE * 8 / 1e6



@dataclass(frozen=True)
class RobotFacts:
    """What the checks need to know of the scenario's robot (built from its description)."""

    n: int  # arm joints = task rows
    n_task_joints: int  # joint components of the task
    variants: tuple[str, ...]
    rotor_variants: tuple[str, ...]  # the variants with rotor joints
    thrust: tuple[float, float]  # the robot's thrust range (N)
    joint_nominal: tuple[float, ...] = ()  # the task's joint components at the nominal posture
    mass: float = 0.0  # the robot's total mass (kg), the controller model's
    #: Names of the robot's bodies with mass, per plant variant (model_mismatch.bodies).
    bodies: tuple[tuple[str, tuple[str, ...]], ...] = ()

    def body_names(self, variant: str) -> tuple[str, ...]:
        """The names of the robot's bodies with mass in plant ``variant`` (none if unknown)."""
        return dict(self.bodies).get(variant, ())


def current_target(value: Any, where: str) -> Any:
    """A disturbance ``target`` with an earlier name (``helicopter``) read as today's
    (``vehicle``), saying so with a FutureWarning (shown by default, once per ``where``) that
    names ``where`` and the fix; any other value unchanged (the validation pass checks it)."""
    if isinstance(value, str) and value in OLD_TARGETS:
        new = OLD_TARGETS[value]
        warnings.warn(f"{where}: '{value}' is deprecated and reads as '{new}' (the same "
                      f"frame, renamed for any vehicle): write '{new}'", FutureWarning,
                      stacklevel=3)
        return new
    return value
