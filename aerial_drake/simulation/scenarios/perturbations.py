"""The scenario's perturbation sections (issue: studies at scale): model mismatch, a payload,
wind, sensing and random disturbance windows, each a dataclass whose default is *off*, so a
scenario without them runs exactly as before (no system added, no parameter touched).

Every random draw takes its own ``seed`` (numpy's ``default_rng``), so one scenario file, seed
included, reproduces one run exactly. The sections are schema only (their checks are in
:mod:`.validation`); what they do lives in :mod:`aerial_drake.simulation.perturbations`,
:mod:`aerial_drake.simulation.wind`, :mod:`aerial_drake.simulation.sensing` and
:mod:`aerial_drake.simulation.disturbances`.
"""

# No "from __future__ import annotations": pydrake's yaml_load_typed needs real type objects.
import math
from dataclasses import dataclass, field

from aerial_drake.simulation.scenarios.checks import current_target


@dataclass
class ModelMismatch:
    """The simulated plant's inertial parameters set apart from the model's (the controller
    keeps the nominal model): per body, in the plant context's parameters.

    Each body named in ``bodies`` (empty: every body of the simulated plant with mass, World
    and the environment's excepted) gets ``mass * mass_scale * (1 + e_m)``, its rotational
    inertia about its CoM times ``inertia_scale * (1 + e_I)``, and its CoM moved by
    ``com_offset + d``, where ``e_m``, ``e_I`` are uniform in +-``mass_error``,
    +-``inertia_error`` and ``d`` uniform per axis in +-``com_error`` times the body's radius
    of gyration, drawn from ``default_rng(seed)`` for every body with mass in the plant's
    body order (named or not, so a body's draw does not depend on which others are named).

    Rotor bodies (the children of the plant variant's rotor joints) keep their CoM: a
    spinning body's CoM off its axis is an unbalance, a force ``m e omega^2`` turning with the
    rotor. ``com_error: 0.1`` on helicopter_lwr's 1.3 kg rotors (radius of gyration 305 mm)
    moved them up to 30 mm per axis: at 81.7 rad/s about 200 N (up to 390 N) turning at
    13 Hz, where a balanced rotor of that size is off by less than 0.1 mm (< 1 N). They keep
    their mass and inertia errors (their ``d`` is drawn, not applied). A rotor's unbalance is
    asked for by ``rotor_balance_grade`` instead: ISO 21940-11's balance grade G (mm/s), its
    CoM moved by the permissible specific unbalance ``e = G / omega`` (``omega`` =
    ``|rotors.speed|``) perpendicular to its spin axis, at a phase uniform in [0, 2 pi) drawn
    from a stream of its own (``default_rng([seed, 1])``: the other draws are unchanged). It
    needs a plant variant with rotor joints spinning (a scenario without is refused).
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
    # The bodies (names) whose mass, inertia and CoM are wrong; empty = every body with mass.
    bodies: list[str] = field(default_factory=list)
    # ISO 21940-11 balance grade G of the rotors (mm/s; G6.3 is a typical rotor's); 0 = off.
    rotor_balance_grade: float = 0.0

    def body_errors(self) -> bool:
        """Whether the bodies' mass, inertia or CoM are changed (the unbalance aside)."""
        return (self.mass_scale != 1.0 or self.inertia_scale != 1.0 or any(self.com_offset)
                or self.mass_error > 0 or self.inertia_error > 0 or self.com_error > 0)

    def active(self) -> bool:
        return self.body_errors() or self.rotor_balance_grade > 0


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
    them as they acted, bounded, ``count`` and ``redirect`` are reset, ``arm_hold_fraction``
    kept: its windows are within it, so bounding them again changes nothing).

    ``redirect``: each of the scenario's own windows keeps its timing and magnitudes, its force
    and its torque each turned along a direction uniform on the sphere. Then ``count`` new
    windows on ``target``: start uniform in ``start``, length uniform in ``length``, force and
    torque magnitudes uniform in their ranges, each along its own uniform direction.

    ``arm_hold_fraction`` (0 = off) bounds every window on the end effector (the scenario's
    own, redirected or not, and the new ones) by what the arm can hold: its force and torque
    scaled down by one factor ``s <= 1`` so that at the reference postures along the window
    (its edges and every 0.05 s between) ``|tau_g,i + s (J^T w)_i| <= arm_hold_fraction *
    tau_max,i`` for every arm joint ``i``
    (:func:`aerial_drake.simulation.disturbances.bound_end_effector_windows`).
    """

    # Turn the scenario's own windows to random directions.
    redirect: bool = False
    # New windows.
    count: int = 0
    # Where they act: "vehicle" (its frame, at its CoM) or "end_effector".
    target: str = "vehicle"
    # Ranges [low, high] (s, s, N, N m).
    start: list[float] = field(default_factory=lambda: [0.0, 0.0])
    length: list[float] = field(default_factory=lambda: [1.0, 1.0])
    force: list[float] = field(default_factory=lambda: [0.0, 0.0])
    torque: list[float] = field(default_factory=lambda: [0.0, 0.0])
    seed: int = 0
    # The share of each arm joint's torque limit that gravity and an end-effector window may
    # take together (0 = no bound; 1 = the limit itself).
    arm_hold_fraction: float = 0.0

    def __post_init__(self) -> None:
        self.target = current_target(self.target, "RandomDisturbances.target")
