"""The checks of a ``waypoints:`` section (:func:`waypoints_errors`, what
:meth:`~aerial_drake.trajectories.params.WaypointsParams.errors` returns) and the field
checks the trajectory sections share (:func:`is_finite_number`, :func:`vector_error`).

Each message names the field with its waypoint's index, the value and the fix. The velocities
a waypoint may give (``ee_velocity``, ``ee_angular_velocity``, ``com_velocity``,
``heading_rate``, ``joint_velocities``) must be zero at the first and last waypoint: the
reference holds still before the first and after the last, so a velocity there would jump.
"""

import math
from typing import Any

import numpy as np

from aerial_drake.trajectories.orientation import orientation_errors

__all__ = ["is_finite_number", "vector_error", "waypoints_errors", "COM_RULES",
           "HEADING_RULES", "WAYPOINT_MODES"]

#: How the waypoints kind finds the CoM: rule (33) from the end-effector path, or its own
#: waypoints.
COM_RULES = ("offset", "waypoints")
#: How the waypoints kind finds the heading.
HEADING_RULES = ("constant", "given", "along_path")
#: What happens at an interior waypoint: "stop" (what is not given is at rest) or "through"
#: (what is not given is chosen so the path passes through: :mod:`.through`).
WAYPOINT_MODES = ("stop", "through")


def is_finite_number(x) -> bool:
    return (isinstance(x, (int, float, np.floating, np.integer)) and not isinstance(x, bool)
            and math.isfinite(x))


def vector_error(name: str, value, size: int, meaning: str) -> str | None:
    try:
        length = len(value)
    except TypeError:
        length = None
    if length != size:
        return f"'{name}' must be a list of {size} floats {meaning}, got {value!r}"
    if not all(is_finite_number(x) for x in value):
        return f"'{name}' must hold finite numbers ({meaning}), got {value!r}"
    return None


def waypoints_errors(section: Any, n_joints: int | None, prefix: str) -> list[str]:
    """What is wrong with ``section`` (a WaypointsParams); ``n_joints``: the task's joint
    components (each waypoint's ``joints`` has as many), None: not checked."""
    found: list[str | None] = []
    if section.com not in COM_RULES:
        found.append(f"'{prefix}com' must be one of {COM_RULES}, got {section.com!r}")
    if section.heading not in HEADING_RULES:
        found.append(f"'{prefix}heading' must be one of {HEADING_RULES}, got "
                     f"{section.heading!r}")
    if section.mode not in WAYPOINT_MODES:
        found.append(f"'{prefix}mode' must be one of {WAYPOINT_MODES}, got {section.mode!r}: "
                     "stop (at rest at every waypoint unless a velocity is given) or through "
                     "(passes through the interior waypoints without stopping)")
    if not is_finite_number(section.heading_angle):
        found.append(f"'{prefix}heading_angle' must be a finite angle (rad), got "
                     f"{section.heading_angle!r}")
    points = section.points
    if len(points) < 2:
        found.append(f"'{prefix}points' needs at least two waypoints, got "
                     f"{len(points)}: for a constant reference use kind: hover")
    previous = -math.inf
    for i, w in enumerate(points):
        where = f"{prefix}points[{i}]."
        if not is_finite_number(w.time) or w.time < 0:
            found.append(f"'{where}time' must be a finite time >= 0 (s), got {w.time!r}")
        elif not w.time > previous:
            found.append(f"'{where}time' = {w.time!r} must be later than the waypoint "
                         f"before ({previous!r} s): list waypoints in time order")
        else:
            previous = w.time
        found.append(vector_error(where + "ee_position", w.ee_position, 3, "[x, y, z] in m"))
        found.append(vector_error(where + "ee_rpy", w.ee_rpy, 3, "[a, b, c] in rad"))
        found += orientation_errors(where, w.ee_rpy, w.ee_orientation)
        found += _joint_errors(w, where, n_joints)
        found += _com_and_heading_errors(section, w, where)
        for name in ("ee_velocity", "ee_angular_velocity"):
            value = getattr(w, name)
            if value:
                found.append(vector_error(where + name, value, 3, "World, per s"))
    if points and any(w.joints for w in points) and not all(w.joints for w in points):
        found.append(f"'{prefix}points[*].joints' is set at some waypoints only: give it "
                     "at every waypoint, or at none (joint_targets holds them)")
    for end in (0, len(points) - 1) if points else ():
        found += _moving_end_errors(points[end], f"{prefix}points[{end}].")
    return [e for e in found if e]


def _joint_errors(w: Any, where: str, n_joints: int | None) -> list[str | None]:
    found: list[str | None] = []
    if w.joints and n_joints is not None:
        found.append(vector_error(where + "joints", w.joints, n_joints,
                                  "one angle per joint component of the task (rad)"))
    elif w.joints and not all(is_finite_number(x) for x in w.joints):
        found.append(f"'{where}joints' must hold finite angles (rad), got {w.joints!r}")
    if w.joint_velocities and not w.joints:
        found.append(f"'{where}joint_velocities' is set but '{where}joints' is not: give the "
                     "waypoint's joint angles too, or remove joint_velocities")
    elif w.joint_velocities:
        size = n_joints if n_joints is not None else len(w.joints)
        found.append(vector_error(where + "joint_velocities", w.joint_velocities, size,
                                  "one rate per joint component of the task (rad/s)"))
    return found


def _com_and_heading_errors(section: Any, w: Any, where: str) -> list[str | None]:
    found: list[str | None] = []
    if section.com == "waypoints":
        found.append(vector_error(where + "com", w.com, 3, "[x, y, z] in m (com: "
                                  "waypoints needs it at every waypoint)"))
        if w.com_velocity:
            found.append(vector_error(where + "com_velocity", w.com_velocity, 3,
                                      "World [vx, vy, vz] in m/s"))
    else:
        for name in ("com", "com_velocity"):
            if getattr(w, name):
                found.append(f"'{where}{name}' is set but the CoM follows rule (33) (com: "
                             "offset): set com: waypoints, or remove it")
    given = section.heading == "given"
    if given and not is_finite_number(w.heading):
        found.append(f"'{where}heading' must be a finite angle (rad) with heading: "
                     f"given, got {w.heading!r}")
    elif not given and not _unset(w.heading):
        found.append(f"'{where}heading' is set but heading is "
                     f"'{section.heading}': set heading: given, or remove it")
    if given and not _unset(w.heading_rate) and not is_finite_number(w.heading_rate):
        found.append(f"'{where}heading_rate' must be a finite rate (rad/s), got "
                     f"{w.heading_rate!r}: give a number, or remove it")
    elif not given and not _unset(w.heading_rate):
        found.append(f"'{where}heading_rate' = {w.heading_rate!r} is set but heading is "
                     f"'{section.heading}': set heading: given (with each waypoint's "
                     "heading), or remove it")
    return found


def _unset(x) -> bool:
    """A float field's "not given" (its default NaN)."""
    return isinstance(x, float) and math.isnan(x)


def _moving_end_errors(w: Any, where: str) -> list[str]:
    """Velocities given at the first or last waypoint that are not zero."""
    found = []
    for name in ("ee_velocity", "ee_angular_velocity", "com_velocity", "joint_velocities"):
        value = getattr(w, name)
        if value and all(is_finite_number(x) for x in value) and any(value):
            found.append(f"'{where}{name}' = {value!r} must be zero: the reference holds "
                         "still before the first and after the last waypoint, so a velocity "
                         "there would jump: remove it (only an interior waypoint is passed moving)")
    rate = w.heading_rate
    if is_finite_number(rate) and rate != 0.0:
        found.append(f"'{where}heading_rate' = {rate!r} must be zero: the reference holds "
                     "still before the first and after the last waypoint, so a rate there "
                     "would jump: remove it (only an interior waypoint is passed moving)")
    return found
