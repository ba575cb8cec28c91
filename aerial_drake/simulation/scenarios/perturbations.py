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
    # Where they act: "vehicle" (its frame, at its CoM) or "end_effector".
    target: str = "vehicle"
    # Ranges [low, high] (s, s, N, N m).
    start: list[float] = field(default_factory=lambda: [0.0, 0.0])
    length: list[float] = field(default_factory=lambda: [1.0, 1.0])
    force: list[float] = field(default_factory=lambda: [0.0, 0.0])
    torque: list[float] = field(default_factory=lambda: [0.0, 0.0])
    seed: int = 0

    def __post_init__(self) -> None:
        self.target = current_target(self.target, "RandomDisturbances.target")
