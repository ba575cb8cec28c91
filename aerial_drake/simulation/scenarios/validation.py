"""The one validation pass over a scenario's values, before any model is built:
:func:`validate_scenario` checks each field once, with the one rule of :mod:`.checks` (its
range) or of the module that owns the field (the gains: :meth:`Gains.validate`; the baselines'
parameters; the trajectory: :mod:`.trajectory`).

Every number is checked for its type (a number, not ``true``), finiteness and a stated range;
then the fields are checked against each other (periods against the duration, the estimated
log size against a limit the user can raise). The first problem raises
:class:`~.checks.ScenarioError` (a ``ValueError``) naming the field, the value, the allowed
range and the fix; :func:`~.loading.load_scenario` adds the file's name. The ranges are
listed in docs/reliability.md.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from pydrake.systems.analysis import GetIntegrationSchemes

from aerial_drake.control.gains import GainError
from aerial_drake.robots.task import parse_task
from aerial_drake.simulation.scenarios.checks import (
    ACCURACY,
    AIRSPEED,
    ANGLE_OFFSET,
    BALANCE_GRADE,
    BODY_TORQUE,
    COUNT,
    DELAY,
    DISTURBANCE_TARGETS,
    DRAG,
    DRIVE_GAIN,
    DURATION,
    F_D_LIMIT,
    FORCE,
    HOLD_FRACTION,
    INERTIA,
    JOINT_TARGET,
    LAG,
    LENGTH,
    LOG_PERIOD,
    MAGNITUDE,
    MASS,
    MAX_LOG_MB,
    MAX_STEP,
    MAX_WINDOWS,
    MIN_EDGE_GAP_S,
    OFFSET,
    OLD_TARGETS,
    PERIOD,
    POSITION_LIMIT_MODES,
    POSITION_OFFSET,
    REALTIME,
    RELATIVE,
    ROTOR_SPEED,
    SAMPLE,
    SCALE,
    SEED,
    SIGMA,
    SIGMA_LIMIT,
    SPEED,
    START_TIME,
    STD,
    THRUST,
    TIME,
    TORQUE,
    TRAJECTORY,
    VELOCITY_LIMIT_MODES,
    WINDOW,
    Range,
    RobotFacts,
    ScenarioError,
    _error,
    _fail,
    check_body_names,
    estimated_log_mb,
    flag,
    folder_name,
    is_number,
    number,
    text,
    vector,
)
from aerial_drake.simulation.scenarios.control_checks import check_controller, check_observer
from aerial_drake.simulation.scenarios.fields import find_array
from aerial_drake.simulation.scenarios.gain_check import warn_gain_design
from aerial_drake.simulation.scenarios.robot import robot_description, robot_facts
from aerial_drake.simulation.scenarios.trajectory import check_trajectory
from aerial_drake.simulation.scenarios.world import check_world


def validate_scenario(s: Any) -> None:
    """Check every value of scenario ``s`` (a :class:`.schema.Scenario`) once, in the order of
    its fields; raise ScenarioError naming the field, the value, the allowed range and the
    fix."""
    array = find_array(s)
    if array is not None:  # (a numpy array has no truth value: refused here, by name)
        raise ScenarioError(f"{array} is a numpy array: give a list "
                            "of Python numbers (value.tolist()); run_scenario converts them "
                            "itself", array)
    facts = robot_facts(s)
    check_values(s, facts)
    check_trajectory(s, np.array(facts.joint_nominal))
    check_controller(s, facts.n, facts.mass)
    check_observer(s.observer, s.controller_period)
    check_perturbations(s, facts)
    check_world(s)
    _check_force_sensor(s.force_sensor)
    _check_joint_limits(s.joint_limits, s.plant.time_step)
    warn_gain_design(s, facts.mass)  # a warning, after every error


def _check_joint_limits(limits: Any, time_step: float) -> None:
    """The modes of ``joint_limits``; "enforce" needs a discrete plant (Drake's continuous
    MultibodyPlant does not hold a joint at its limit)."""
    text("joint_limits.positions", limits.positions, POSITION_LIMIT_MODES)
    text("joint_limits.velocities", limits.velocities, VELOCITY_LIMIT_MODES)
    if limits.positions == "enforce" and time_step == 0:
        raise ScenarioError(
            "joint_limits.positions: 'enforce' needs a discrete plant (Drake's discrete "
            "MultibodyPlant holds a joint at its limit; the continuous one, plant.time_step 0, "
            "does not): set plant.time_step (e.g. 0.001), or choose 'stop' or 'report'",
            "joint_limits.positions")


def _check_window_count(s: Any) -> None:
    """At most MAX_WINDOWS windows, the random ones counted (a run's scenario.yaml holds them
    all, and must read back as a scenario file)."""
    count = len(s.disturbances)
    random = s.random_disturbances.count
    total = count + (int(random) if isinstance(random, int) and random > 0 else 0)
    if total > MAX_WINDOWS:
        raise ScenarioError(f"disturbances: {count} windows (and random_disturbances.count = "
                            f"{random}) make {total}, more than a scenario holds "
                            f"({MAX_WINDOWS}): merge adjacent windows, or split the run",
                            "disturbances")


def _check_window_edges(disturbances: list) -> None:
    """Window edges are equal or at least MIN_EDGE_GAP_S apart (round-off otherwise)."""
    edges = sorted((float(t), f"disturbances[{i}].{side}")
                   for i, d in enumerate(disturbances)
                   for side, t in (("start", d.start), ("stop", d.stop)))
    for (a, name_a), (b, name_b) in zip(edges, edges[1:]):
        if 0 < b - a < MIN_EDGE_GAP_S:
            raise ScenarioError(f"{name_a} = {a!r} s and {name_b} = {b!r} s differ by "
                                f"{b - a:.3g} s (round-off?): make them equal or at least "
                                f"{MIN_EDGE_GAP_S:g} s apart", name_b)


def _check_gains(gains: Any, n_task: int, task_rows: tuple[int, ...]) -> None:
    """The gains' one rule set (:meth:`aerial_drake.control.gains.Gains.validate`)."""
    try:
        gains.validate(n_task, "gains", task_rows)
    except GainError as err:
        raise ScenarioError(str(err), err.field) from None


def _target(field: str, value: Any) -> None:
    """A disturbance target: one of DISTURBANCE_TARGETS (an earlier name set after loading
    is refused with today's)."""
    if isinstance(value, str) and value in OLD_TARGETS:
        raise _error(field, f"{field}: '{value}' is the earlier name of "
                            f"'{OLD_TARGETS[value]}': write target: {OLD_TARGETS[value]}")
    text(field, value, DISTURBANCE_TARGETS)


def check_values(s: Any, robot: RobotFacts) -> None:
    """Check every field of scenario ``s`` (a :class:`.schema.Scenario`) but the trajectory,
    the controller and the perturbations, for its ``robot``; raise ScenarioError."""
    n = robot.n
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
    _check_gains(s.gains, n, parse_task(robot_description(s.robot).task).rows)
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
    _check_window_count(s)
    for i, d in enumerate(s.disturbances):
        where = f"disturbances[{i}]"
        _target(f"{where}.target", d.target)
        start = number(f"{where}.start", d.start, WINDOW)
        stop = number(f"{where}.stop", d.stop, WINDOW)
        if not stop > start:
            _fail(f"{where}.stop", stop, f"> {where}.start ({start:g} s)",
                  "a window is [start, stop)")
        vector(f"{where}.force", d.force, 3, FORCE)
        vector(f"{where}.torque", d.torque, 3, TORQUE)
    _check_window_edges(s.disturbances)
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


def _seed(name: str, value: Any) -> None:
    if isinstance(value, bool) or not isinstance(value, int) or not SEED.contains(value):
        _fail(name, value, f"an integer {SEED.text()}", SEED.fix)


def _check_force_sensor(sensor: Any) -> None:
    """The wrist force sensor of paper_force (docs/contact.md): a positive cut-off (.inf:
    none), a noise that is a standard deviation, an integer seed."""
    bandwidth = sensor.bandwidth
    if not is_number(bandwidth) or math.isnan(bandwidth) or not bandwidth > 0:
        _fail("force_sensor.bandwidth", bandwidth, "a number > 0 (Hz; .inf: no filter)",
              "a 6-axis wrist sensor's filter is set between 100 Hz and 1 kHz, e.g. 200")
    number("force_sensor.noise_std", sensor.noise_std, Range(0.0, 1e3, "N",
           fix="0: none; an ATI Mini45 resolves 1/16 N, e.g. 0.05"))
    _seed("force_sensor.seed", sensor.seed)


def _interval(name: str, value: Any, allowed: Range) -> None:
    vector(name, value, 2, allowed)
    if value[1] < value[0]:
        _fail(name, value, "[low, high] with low <= high")


def check_perturbations(s: Any, robot: RobotFacts) -> None:
    """Check the perturbation sections of scenario ``s`` for its ``robot``; raise
    ScenarioError naming the field, the value and the fix."""
    _check_mismatch(s, robot)
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
    _target("random_disturbances.target", r.target)
    for name, allowed in (("start", TIME), ("length", TIME), ("force", MAGNITUDE),
                          ("torque", MAGNITUDE)):
        _interval(f"random_disturbances.{name}", getattr(r, name), allowed)
    if r.count and not r.length[0] > 0:
        _fail("random_disturbances.length", r.length, "a low end > 0 s (a window is [start, "
              "stop) with stop > start)")
    _seed("random_disturbances.seed", r.seed)
    number("random_disturbances.arm_hold_fraction", r.arm_hold_fraction, HOLD_FRACTION)


def _check_mismatch(s: Any, robot: RobotFacts) -> None:
    m = s.model_mismatch
    number("model_mismatch.mass_scale", m.mass_scale, SCALE)
    number("model_mismatch.inertia_scale", m.inertia_scale, SCALE)
    vector("model_mismatch.com_offset", m.com_offset, 3, OFFSET)
    for name in ("mass_error", "inertia_error", "com_error"):
        number(f"model_mismatch.{name}", getattr(m, name), RELATIVE)
    _seed("model_mismatch.seed", m.seed)
    check_body_names(m.bodies, robot.body_names(s.plant_variant))
    grade = number("model_mismatch.rotor_balance_grade", m.rotor_balance_grade, BALANCE_GRADE)
    if grade == 0:
        return
    if s.plant_variant not in robot.rotor_variants:
        variants = ", ".join(robot.rotor_variants)
        raise ScenarioError(
            f"model_mismatch.rotor_balance_grade = {grade:g} mm/s is a rotor unbalance, and "
            f"plant_variant '{s.plant_variant}' has no rotor joints: "
            + (f"use a variant with rotors ({variants})" if variants else
               "this robot has no variant with rotors") + " or remove rotor_balance_grade",
            "model_mismatch.rotor_balance_grade")
    if s.rotors.speed == 0:
        raise ScenarioError(
            f"model_mismatch.rotor_balance_grade = {grade:g} mm/s: the unbalance e = G / omega "
            "needs the rotors' speed, and rotors.speed is 0: set rotors.speed or remove "
            "rotor_balance_grade", "model_mismatch.rotor_balance_grade")


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
