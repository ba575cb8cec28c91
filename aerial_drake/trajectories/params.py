"""The scenario's ``trajectory:`` section: which reference kind flies and its numbers
(:class:`TrajectoryParams`, loadable by ``pydrake.common.yaml.yaml_load_typed``).

Kinds (``kind``; docs/trajectories.md; the registry of kinds, and the one validation of the
section, is :mod:`aerial_drake.trajectories.kinds`):

- ``paper`` (default): the paper's (28)-(33), constants in the top-level fields
  (:mod:`aerial_drake.trajectories.paper`);
- ``hover``: constant CoM, heading and task (:class:`HoverParams`);
- ``waypoints``: end-effector poses (and task joint angles) at given times, interpolated
  smoothly enough for the law (:class:`WaypointsParams`, :mod:`.waypoints`);
- ``python``: a function of the user's, or Drake trajectories (:class:`PythonParams`,
  :mod:`.python_kind`).

"CoM" here is always the whole system's centre of mass (vehicle, arm and payload: x_g of (3),
what x_d tracks), never the vehicle's alone.

``joint_targets`` (the task's joint components' angles) and ``com_offset`` (r_o of (33)) are
shared: the paper and hover kinds and waypoints' ``com: offset`` rule read them.

Do not add ``from __future__ import annotations`` here: Drake's ``yaml_load_typed`` needs the
real (non-string) field types.
"""

import dataclasses
import math
import typing

from aerial_drake.trajectories.orientation import EeOrientation, orientation_errors
from aerial_drake.trajectories.waypoint_checks import (
    COM_RULES,
    HEADING_RULES,
    WAYPOINT_MODES,
    is_finite_number,
    vector_error,
    waypoints_errors,
)

__all__ = ["TrajectoryParams", "HoverParams", "Waypoint", "WaypointsParams",
           "PythonParams", "ComPlanningParams", "COM_RULES", "HEADING_RULES", "WAYPOINT_MODES"]


@dataclasses.dataclass
class HoverParams:
    """``kind: hover``: everything constant (the CoM at rest, the arm holding its task)."""

    # The end effector's position, World [x, y, z] (m).
    ee_position: typing.List[float] = dataclasses.field(
        default_factory=lambda: [0.6, 0.0, 0.8])
    # Its orientation R_ed = R1(a) R2(b) R3(c) = Rx(a) Ry(b) Rz(c), the paper's (29) (not
    # Drake's RollPitchYaw): [a, b, c] (rad). ee_orientation names the convention instead.
    ee_rpy: typing.List[float] = dataclasses.field(default_factory=lambda: [0.0, 0.0, 0.0])
    # The orientation in an explicit convention (one of rpy_paper, rpy_drake, quaternion);
    # empty: ee_rpy.
    ee_orientation: EeOrientation = dataclasses.field(default_factory=EeOrientation)
    # The vehicle's heading phi4, b1d = [cos phi4, sin phi4, 0] (rad).
    heading: float = 0.0
    # The system's CoM (vehicle, arm and payload; x_g of (3)), World [x, y, z] (m); empty:
    # rule (33), ee_position + R3(heading) com_offset.
    com: typing.List[float] = dataclasses.field(default_factory=list)

    def errors(self, n_joints: int | None = None, prefix: str = "hover.") -> list[str]:
        """What is wrong with the section (``n_joints``: unused, the kinds' common
        signature)."""
        found = [vector_error(prefix + "ee_position", self.ee_position, 3, "[x, y, z] in m"),
                 vector_error(prefix + "ee_rpy", self.ee_rpy, 3, "[a, b, c] in rad")]
        found += orientation_errors(prefix, self.ee_rpy, self.ee_orientation)
        if self.com:
            found.append(vector_error(prefix + "com", self.com, 3, "[x, y, z] in m"))
        if not is_finite_number(self.heading):
            found.append(f"'{prefix}heading' must be a finite angle (rad), got "
                         f"{self.heading!r}")
        return [e for e in found if e]


@dataclasses.dataclass
class Waypoint:
    """One waypoint: where the end effector is at ``time``, and optionally how fast."""

    # Time (s), increasing along the list.
    time: float = 0.0
    # End-effector position, World [x, y, z] (m).
    ee_position: typing.List[float] = dataclasses.field(
        default_factory=lambda: [0.6, 0.0, 0.8])
    # End-effector orientation R_ed = R1(a) R2(b) R3(c) = Rx(a) Ry(b) Rz(c), the paper's (29)
    # (not Drake's RollPitchYaw): [a, b, c] (rad). ee_orientation names the convention instead.
    ee_rpy: typing.List[float] = dataclasses.field(default_factory=lambda: [0.0, 0.0, 0.0])
    # The orientation in an explicit convention (rpy_paper, rpy_drake or quaternion); empty:
    # ee_rpy.
    ee_orientation: EeOrientation = dataclasses.field(default_factory=EeOrientation)
    # The task's joint components' angles (rad); empty: joint_targets (or the nominal).
    joints: typing.List[float] = dataclasses.field(default_factory=list)
    # The system's CoM (x_g of (3)), World [x, y, z] (m): required with ``com: waypoints``,
    # else empty.
    com: typing.List[float] = dataclasses.field(default_factory=list)
    # The heading phi4 (rad): required with ``heading: given``, else .nan.
    heading: float = math.nan
    # Velocity through the waypoint, World (m/s); empty: at rest there (mode: stop), or
    # chosen (mode: through).
    ee_velocity: typing.List[float] = dataclasses.field(default_factory=list)
    # Angular velocity of the end effector through the waypoint, World (rad/s); empty: 0
    # (mode: stop), or chosen (mode: through).
    ee_angular_velocity: typing.List[float] = dataclasses.field(default_factory=list)
    # The CoM's velocity through the waypoint, World (m/s), only with ``com: waypoints``;
    # empty: at rest (mode: stop), or chosen (mode: through).
    com_velocity: typing.List[float] = dataclasses.field(default_factory=list)
    # The heading's rate through the waypoint (rad/s), only with ``heading: given``; .nan:
    # at rest (mode: stop), or chosen (mode: through).
    heading_rate: float = math.nan
    # The task joint components' rates through the waypoint (rad/s), only with ``joints``;
    # empty: at rest (mode: stop), or chosen (mode: through).
    joint_velocities: typing.List[float] = dataclasses.field(default_factory=list)


@dataclasses.dataclass
class WaypointsParams:
    """``kind: waypoints``: end-effector poses at given times (docs/trajectories.md)."""

    points: typing.List[Waypoint] = dataclasses.field(default_factory=list)
    # "offset": the CoM follows the end-effector path at com_offset rotated with the heading
    # (the paper's rule (33)); "waypoints": each waypoint's ``com``.
    com: str = "offset"
    # "constant" (heading_angle), "given" (each waypoint's ``heading``), "along_path" (each
    # waypoint faces the horizontal direction to the next).
    heading: str = "constant"
    # The heading of ``heading: constant`` (rad).
    heading_angle: float = 0.0
    # "stop": at each waypoint every velocity not given is zero, and the acceleration, jerk
    # and snap are zero; "through": at the interior waypoints the velocities not given and
    # every acceleration, jerk and snap are chosen (least snap) so the path passes through
    # without stopping (aerial_drake.trajectories.through; docs/trajectories.md).
    mode: str = "stop"

    def errors(self, n_joints: int | None = None, prefix: str = "waypoints.") -> list[str]:
        """What is wrong with the section; ``n_joints``: the task's joint components (each
        waypoint's ``joints`` has as many), None: not checked
        (:func:`~aerial_drake.trajectories.waypoint_checks.waypoints_errors`)."""
        return waypoints_errors(self, n_joints, prefix)


@dataclasses.dataclass
class PythonParams:
    """``kind: python``: a reference of the user's (docs/trajectories.md)."""

    # "module:name": a function f(t) -> ReferenceSample, or a dict of Drake trajectories
    # (keys com, ee_position, ee_rotation_vector, heading, joints), or a function of no
    # arguments returning either.
    function: str = ""
    # A folder added to the import path first (relative to the scenario file); empty: none.
    path: str = ""

    def errors(self, n_joints: int | None = None, prefix: str = "python.") -> list[str]:
        """What is wrong with the section (``n_joints``: unused, the kinds' common
        signature)."""
        if not isinstance(self.function, str) or self.function.count(":") != 1 or not all(
                part.strip() for part in self.function.split(":")):
            return [f"'{prefix}function' must be 'module:name' (e.g. 'my_paths:inspection'), "
                    f"got {self.function!r}"]
        return []


@dataclasses.dataclass
class ComPlanningParams:
    """``trajectory.com_planning``: replace the kind's CoM reference x_d by one planned
    offline for the arm's margin (:mod:`aerial_drake.trajectories.com_planning`;
    docs/control.md, "x_d planned with margin"). Off: the kind's own x_d, unchanged."""

    enabled: bool = False
    # Period of the postures optimised along the run (s); the plan's cost grows as 1/period.
    sample_period: float = 0.1
    # Knot spacing of the degree-7 B-spline fitted through them (s): the plan keeps no motion
    # faster than about this (the CoM loop could not follow it), and x_d is C^6.
    knot_period: float = 0.4

    def errors(self, prefix: str = "com_planning.") -> list[str]:
        """What is wrong with the section, one message per field naming it and the fix."""
        found = []
        if not isinstance(self.enabled, bool):
            found.append(f"'{prefix}enabled' must be true or false, got {self.enabled!r}")
        for name, low, high in (("sample_period", 0.005, 1.0), ("knot_period", 0.05, 5.0)):
            value = getattr(self, name)
            if not is_finite_number(value) or not low <= value <= high:
                found.append(f"'{prefix}{name}' must be a time in [{low:g}, {high:g}] s, got "
                             f"{value!r}")
        if not found and self.knot_period < 2 * self.sample_period:
            found.append(f"'{prefix}knot_period' = {self.knot_period!r} s must be at least "
                         f"twice '{prefix}sample_period' = {self.sample_period!r} s (each knot "
                         "interval needs samples): raise knot_period or lower sample_period")
        return found


@dataclasses.dataclass
class TrajectoryParams:
    """The ``trajectory:`` section: the kind and its numbers; the top-level constants are the
    paper kind's (28)-(33) (defaults: the paper's values).

    Loadable by ``pydrake.common.yaml.yaml_load_typed`` (a misspelt key is an error).
    Checked by :func:`aerial_drake.trajectories.kinds.validate_trajectory` (the kind and its
    section; :func:`~aerial_drake.trajectories.kinds.reference_of` calls it once per build).
    """

    # The reference kind: one of aerial_drake.trajectories.kinds.KINDS (docs/trajectories.md).
    kind: str = "paper"
    # Centre of the basic motion, World [x, y, z] (m).
    center: typing.List[float] = dataclasses.field(default_factory=lambda: [0.6, 0.0, 1.3])
    # Amplitude A_b of the basic motion (m).
    basic_amplitude: float = 0.5
    # Angular frequency w_b of the basic motion (rad/s).
    basic_frequency: float = 0.5
    # Climb rate c of the basic motion's z term, scaled by A_b (1/s): z gains A_b c t.
    basic_climb_rate: float = 0.045
    # Amplitude A_a of the agile motion (m).
    agile_amplitude: float = 0.1
    # Angular frequency w_a of the agile motion (rad/s).
    agile_frequency: float = 3.0
    # Amplitudes [a1, a2, a3] of the orientation angles phi1, phi2, phi3 of (31) (rad).
    orientation_amplitudes: typing.List[float] = dataclasses.field(
        default_factory=lambda: [0.5, 0.5, 0.5]
    )
    # Angular frequency w_o of the orientation angles (rad/s).
    orientation_frequency: float = 3.0
    # Desired angles of the task's joint components, in task order (rad): [q3d] for the
    # paper's task (30). Empty: each at the robot's nominal posture.
    joint_targets: typing.List[float] = dataclasses.field(default_factory=list)
    # Initial helicopter heading phi4_0 (rad).
    heading_initial: float = 0.0
    # Heading rate w_h, phi4 = phi4_0 + w_h t (rad/s); either sign.
    heading_rate: float = 0.5
    # Offset r_o from x_c to the desired CoM (the system's), rotated by R3(phi4), [x, y, z] (m).
    com_offset: typing.List[float] = dataclasses.field(default_factory=lambda: [-0.3, 0.0, 0.6])

    # The other kinds' sections (read only by their kind).
    hover: HoverParams = dataclasses.field(default_factory=HoverParams)
    waypoints: WaypointsParams = dataclasses.field(default_factory=WaypointsParams)
    python: PythonParams = dataclasses.field(default_factory=PythonParams)
    # The CoM reference planned for the arm's margin instead of the kind's (default off).
    com_planning: ComPlanningParams = dataclasses.field(default_factory=ComPlanningParams)

    def errors(self) -> list[str]:
        """What is wrong with the fields every kind shares and the paper kind's (the kind's
        name and its own section: :func:`aerial_drake.trajectories.kinds.validate_trajectory`),
        one message per field naming it and the fix."""
        errors = []
        for name, meaning in (
            ("center", "[x, y, z] in m"),
            ("orientation_amplitudes", "[a1, a2, a3] in rad"),
            ("com_offset", "[x, y, z] in m"),
        ):
            value = getattr(self, name)
            try:
                length = len(value)
            except TypeError:
                length = None
            if length != 3:
                errors.append(
                    f"'{name}' must be a list of 3 floats {meaning}, got {value!r}: "
                    "give exactly three entries"
                )
                continue
            if not all(is_finite_number(x) for x in value):
                errors.append(f"'{name}' must hold finite numbers, got {value!r}")
            elif name == "orientation_amplitudes" and any(x < 0 for x in value):
                errors.append(
                    f"'{name}' must be >= 0, got {value!r}: flip the sign through the "
                    "angle's phase instead (an amplitude is a magnitude)"
                )
        for name in (
            "basic_amplitude",
            "basic_frequency",
            "basic_climb_rate",
            "agile_amplitude",
            "agile_frequency",
            "orientation_frequency",
            "heading_initial",
            "heading_rate",
        ):
            value = getattr(self, name)
            if not is_finite_number(value):
                errors.append(f"'{name}' must be a finite float, got {value!r}")
            elif name.endswith(("_amplitude", "_frequency")) and value < 0:
                errors.append(f"'{name}' must be >= 0, got {value!r}: use its magnitude")
        targets = self.joint_targets
        if not isinstance(targets, (list, tuple)) or not all(
                is_finite_number(x) for x in targets):
            errors.append(f"'joint_targets' must hold finite angles (rad), got "
                          f"{self.joint_targets!r}")
        errors += self.com_planning.errors()
        given = {"waypoints": self.waypoints.com == "waypoints", "hover": bool(self.hover.com)}
        if self.com_planning.enabled is True and given.get(self.kind, False):
            errors.append(f"'com_planning.enabled' is true but the {self.kind} section gives the "
                          "CoM, which the plan would replace: remove the section's com (or set "
                          "waypoints.com: offset), or set com_planning.enabled: false")
        return errors

