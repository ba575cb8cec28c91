"""The scenario's perturbation sections (issue: studies at scale): model mismatch, a payload,
wind, sensing and random disturbance windows, each a dataclass whose default is *off*, so a
scenario without them runs exactly as before (no system added, no parameter touched).

Every random draw takes its own ``seed`` (numpy's ``default_rng``), so one scenario file, seed
included, reproduces one run exactly. The sections are schema only; what they do lives in
:mod:`aerial_drake.simulation.perturbations`, :mod:`aerial_drake.simulation.wind`,
:mod:`aerial_drake.simulation.sensing` and :mod:`aerial_drake.simulation.disturbances`.
"""

# No "from __future__ import annotations": pydrake's yaml_load_typed needs real type objects.
import math
from dataclasses import dataclass, field
from typing import Any

from aerial_drake.simulation.scenarios.checks import (
    Range,
    ScenarioError,
    _fail,
    flag,
    is_number,
    number,
    text,
    vector,
)

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
TARGETS = ("helicopter", "end_effector")


@dataclass
class ModelMismatch:
    """The simulated plant's inertial parameters set apart from the model's (the controller
    keeps the nominal model): per body, in the plant context's parameters.

    Each body of the simulated plant (World excepted; bodies of zero mass kept at zero) gets
    ``mass * mass_scale * (1 + e_m)``, its rotational inertia about its CoM times
    ``inertia_scale * (1 + e_I)``, and its CoM moved by ``com_offset + d``, where ``e_m``,
    ``e_I`` are uniform in +-``mass_error``, +-``inertia_error`` and ``d`` uniform per axis in
    +-``com_error`` times the body's radius of gyration, drawn from ``default_rng(seed)`` in the
    plant's body order.
    """

    # Scale of every body's mass (1 = the model's).
    mass_scale: float = 1.0
    # Scale of every body's rotational inertia about its CoM.
    inertia_scale: float = 1.0
    # Offset of every body's CoM (m), body axes.
    com_offset: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    # Half-widths of the random relative errors (0.1 = +-10 %); com_error is relative to the
    # body's radius of gyration sqrt(tr(I_cm) / 2m).
    mass_error: float = 0.0
    inertia_error: float = 0.0
    com_error: float = 0.0
    seed: int = 0

    def active(self) -> bool:
        return (self.mass_scale != 1.0 or self.inertia_scale != 1.0 or any(self.com_offset)
                or self.mass_error > 0 or self.inertia_error > 0 or self.com_error > 0)


@dataclass
class Payload:
    """A rigid payload held at the end effector, unknown to the controller: its spatial
    inertia is added to the end-effector body's parameters in the simulated plant."""

    # Mass (kg); 0 = no payload.
    mass: float = 0.0
    # Principal moments about the payload's CoM, end-effector frame E axes (kg m^2).
    inertia: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    # The payload's CoM in the end-effector frame E (m).
    offset: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])

    def active(self) -> bool:
        return self.mass > 0


@dataclass
class Wind:
    """Mean wind plus Dryden turbulence (MIL-F-8785C), as a drag force at the vehicle's CoM
    (:mod:`aerial_drake.simulation.wind` documents the filters)."""

    enabled: bool = False
    # Mean wind (m/s), World axes.
    mean: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    # Turbulence intensities sigma_u, sigma_v, sigma_w (m/s): along the mean wind, across it
    # (horizontal) and vertical; zeros = mean wind only.
    sigma: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    # Scale lengths L_u, L_v, L_w (m).
    length_scale: list[float] = field(default_factory=lambda: [150.0, 150.0, 10.0])
    # Airspeed V of Taylor's frozen field (m/s); NaN = |mean| (at least 1 m/s).
    airspeed: float = math.nan
    # Drag in the vehicle's body axes: F_B = linear * v_r + quadratic * |v_r| v_r per axis,
    # v_r the wind relative to the vehicle (N s/m and N s^2/m^2).
    drag_linear: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    drag_quadratic: list[float] = field(default_factory=lambda: [1.5, 1.5, 3.0])
    # Time step of the turbulence samples (s), linearly interpolated between.
    sample_period: float = 0.01
    seed: int = 0


@dataclass
class Sensing:
    """What the controller measures: the plant's state, delayed and with Gaussian noise per
    sample (:mod:`aerial_drake.simulation.sensing`). Needs a sampled controller."""

    # Delay (s): a multiple of controller_period.
    delay: float = 0.0
    # Standard deviations per sample: base position (m), base attitude (rad, a random small
    # rotation), joint positions (rad), base angular velocity (rad/s), base linear velocity
    # (m/s), joint velocities (rad/s).
    base_position_std: float = 0.0
    base_attitude_std: float = 0.0
    joint_position_std: float = 0.0
    base_angular_velocity_std: float = 0.0
    base_linear_velocity_std: float = 0.0
    joint_velocity_std: float = 0.0
    seed: int = 0

    def noise_stds(self) -> tuple[float, ...]:
        return (self.base_position_std, self.base_attitude_std, self.joint_position_std,
                self.base_angular_velocity_std, self.base_linear_velocity_std,
                self.joint_velocity_std)

    def active(self) -> bool:
        return self.delay > 0 or any(s > 0 for s in self.noise_stds())


@dataclass
class RandomDisturbances:
    """Random disturbance windows, drawn from ``default_rng(seed)`` before the run (the drawn
    windows replace this section's effect in the run's scenario.yaml: ``disturbances`` holds
    them, ``count`` and ``redirect`` are reset).

    ``redirect``: each of the scenario's own windows keeps its timing and magnitudes, its force
    and its torque each turned along a direction uniform on the sphere. Then ``count`` new
    windows on ``target``: start uniform in ``start``, length uniform in ``length``, force and
    torque magnitudes uniform in their ranges, each along its own uniform direction.
    """

    # Turn the scenario's own windows to random directions.
    redirect: bool = False
    # New windows.
    count: int = 0
    target: str = "helicopter"
    # Ranges [low, high] (s, s, N, N m).
    start: list[float] = field(default_factory=lambda: [0.0, 0.0])
    length: list[float] = field(default_factory=lambda: [1.0, 1.0])
    force: list[float] = field(default_factory=lambda: [0.0, 0.0])
    torque: list[float] = field(default_factory=lambda: [0.0, 0.0])
    seed: int = 0


def _seed(name: str, value: Any) -> None:
    if isinstance(value, bool) or not isinstance(value, int) or not SEED.contains(value):
        _fail(name, value, f"an integer {SEED.text()}", SEED.fix)


def _interval(name: str, value: Any, allowed: Range) -> None:
    vector(name, value, 2, allowed)
    if value[1] < value[0]:
        _fail(name, value, "[low, high] with low <= high")


def check_perturbations(s: Any) -> None:
    """Check the perturbation sections of scenario ``s``; raise ScenarioError naming the
    field, the value and the fix."""
    m = s.model_mismatch
    number("model_mismatch.mass_scale", m.mass_scale, SCALE)
    number("model_mismatch.inertia_scale", m.inertia_scale, SCALE)
    vector("model_mismatch.com_offset", m.com_offset, 3, OFFSET)
    for name in ("mass_error", "inertia_error", "com_error"):
        number(f"model_mismatch.{name}", getattr(m, name), RELATIVE)
    _seed("model_mismatch.seed", m.seed)
    p = s.payload
    number("payload.mass", p.mass, MASS)
    vector("payload.inertia", p.inertia, 3, INERTIA)
    a, b, c = p.inertia
    if not (a + b >= c and b + c >= a and a + c >= b):
        _fail("payload.inertia", p.inertia, "principal moments that meet the triangle "
              "inequality (each <= the sum of the other two)", "e.g. [1e-3, 1e-3, 1e-3]")
    vector("payload.offset", p.offset, 3, OFFSET)
    _check_wind(s.wind)
    _check_sensing(s.sensing, s.controller_period)
    r = s.random_disturbances
    flag("random_disturbances.redirect", r.redirect)
    number("random_disturbances.count", r.count, COUNT)
    text("random_disturbances.target", r.target, TARGETS)
    for name, allowed in (("start", TIME), ("length", TIME), ("force", MAGNITUDE),
                          ("torque", MAGNITUDE)):
        _interval(f"random_disturbances.{name}", getattr(r, name), allowed)
    if r.count and not r.length[0] > 0:
        _fail("random_disturbances.length", r.length, "a low end > 0 s (a window is [start, "
              "stop) with stop > start)")
    _seed("random_disturbances.seed", r.seed)


def _check_wind(w: Any) -> None:
    flag("wind.enabled", w.enabled)
    vector("wind.mean", w.mean, 3, SPEED)
    vector("wind.sigma", w.sigma, 3, SIGMA)
    vector("wind.length_scale", w.length_scale, 3, LENGTH)
    if not (is_number(w.airspeed) and math.isnan(w.airspeed)):
        number("wind.airspeed", w.airspeed, AIRSPEED)
    vector("wind.drag_linear", w.drag_linear, 3, DRAG)
    vector("wind.drag_quadratic", w.drag_quadratic, 3, DRAG)
    number("wind.sample_period", w.sample_period, SAMPLE)
    _seed("wind.seed", w.seed)


def _check_sensing(n: Any, controller_period: float) -> None:
    delay = number("sensing.delay", n.delay, DELAY)
    for name in ("base_position_std", "base_attitude_std", "joint_position_std",
                 "base_angular_velocity_std", "base_linear_velocity_std",
                 "joint_velocity_std"):
        number(f"sensing.{name}", getattr(n, name), STD)
    _seed("sensing.seed", n.seed)
    if not n.active():
        return
    if controller_period == 0:
        raise ScenarioError("sensing: noise and delay are per controller sample; "
                            "controller_period is 0 (continuous feedback): set "
                            "controller_period (e.g. 0.001) or remove the sensing section",
                            "sensing")
    steps = delay / controller_period
    if abs(steps - round(steps)) > 1e-6:
        _fail("sensing.delay", delay, f"a multiple of controller_period "
              f"({controller_period:g} s)", f"e.g. {round(steps) * controller_period:g}")
