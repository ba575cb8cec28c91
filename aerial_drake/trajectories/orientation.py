"""The end effector's desired orientation R_ed as a user writes it, in one of three explicit
conventions (``ee_orientation:`` of a hover section or a waypoint; docs/trajectories.md):

- ``rpy_paper: [a, b, c]``: R_ed = R1(a) R2(b) R3(c) = Rx(a) Ry(b) Rz(c), the paper's (29)
  (the same as the older field ``ee_rpy``, which stays and means this);
- ``rpy_drake: [roll, pitch, yaw]``: Drake's ``RollPitchYaw``, R_ed = Rz(yaw) Ry(pitch)
  Rx(roll): the same three numbers give another rotation unless two of them are zero;
- ``quaternion: [w, x, y, z]``: a unit quaternion, scalar first (Drake's ``Quaternion``
  order; normalised if within :data:`QUATERNION_NORM_TOLERANCE` of 1).

Do not add ``from __future__ import annotations`` here: Drake's ``yaml_load_typed`` needs the
real (non-string) field types of :class:`EeOrientation`.
"""

import dataclasses
import math
import typing

import numpy as np

__all__ = ["EeOrientation", "ORIENTATION_CONVENTIONS", "QUATERNION_NORM_TOLERANCE",
           "paper_angles_rotation", "drake_rpy_rotation", "quaternion_rotation",
           "orientation_errors", "end_effector_rotation"]

#: The conventions ``ee_orientation`` may name, one at a time.
ORIENTATION_CONVENTIONS = ("rpy_paper", "rpy_drake", "quaternion")
#: A quaternion whose norm is further than this from 1 is refused (a typo, not rounding).
QUATERNION_NORM_TOLERANCE = 1e-3


@dataclasses.dataclass
class EeOrientation:
    """``ee_orientation:``: set exactly one field (module docstring); all empty: ``ee_rpy``."""

    # R1(a) R2(b) R3(c) = Rx(a) Ry(b) Rz(c) of (29): [a, b, c] (rad).
    rpy_paper: typing.List[float] = dataclasses.field(default_factory=list)
    # Drake's RollPitchYaw, Rz(yaw) Ry(pitch) Rx(roll): [roll, pitch, yaw] (rad).
    rpy_drake: typing.List[float] = dataclasses.field(default_factory=list)
    # A unit quaternion [w, x, y, z], scalar first.
    quaternion: typing.List[float] = dataclasses.field(default_factory=list)


def _rx(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _ry(b: float) -> np.ndarray:
    c, s = math.cos(b), math.sin(b)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rz(c_: float) -> np.ndarray:
    c, s = math.cos(c_), math.sin(c_)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def paper_angles_rotation(angles) -> np.ndarray:
    """R = R1(a) R2(b) R3(c) (RotX, RotY, RotZ) of (29) for ``angles`` = [a, b, c] (rad)."""
    a, b, c = (float(x) for x in angles)
    return _rx(a) @ _ry(b) @ _rz(c)


def drake_rpy_rotation(rpy) -> np.ndarray:
    """Drake's ``RollPitchYaw([r, p, y]).ToRotationMatrix()``: Rz(y) Ry(p) Rx(r)."""
    r, p, y = (float(x) for x in rpy)
    return _rz(y) @ _ry(p) @ _rx(r)


def quaternion_rotation(quaternion) -> np.ndarray:
    """The rotation of the quaternion [w, x, y, z] (normalised first)."""
    w, x, y, z = np.asarray(quaternion, dtype=float) / np.linalg.norm(quaternion)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _given(orientation: EeOrientation) -> list[str]:
    return [name for name in ORIENTATION_CONVENTIONS if getattr(orientation, name)]


def _finite(values) -> bool:
    return all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
               for x in values)


def orientation_errors(prefix: str, ee_rpy, orientation: EeOrientation) -> list[str]:
    """What is wrong with ``ee_orientation`` (``prefix``: e.g. "waypoints.points[2].") beside
    ``ee_rpy``: several conventions at once, or with a non-zero ``ee_rpy``, is ambiguous."""
    given = _given(orientation)
    where = prefix + "ee_orientation"
    if not given:
        return []
    if len(given) > 1:
        return [f"'{where}' gives {' and '.join(given)}: give one convention only"]
    name = given[0]
    value = getattr(orientation, name)
    found = []
    if ee_rpy and _finite(ee_rpy) and any(ee_rpy):
        found.append(f"'{prefix}ee_rpy' = {list(ee_rpy)!r} and '{where}' are both given: "
                     "remove ee_rpy (it means ee_orientation: {rpy_paper: ...})")
    size = 4 if name == "quaternion" else 3
    meaning = "[w, x, y, z], scalar first" if size == 4 else "in rad"
    if len(value) != size or not _finite(value):
        found.append(f"'{where}.{name}' must be {size} finite numbers ({meaning}), got "
                     f"{value!r}")
    elif name == "quaternion":
        norm = float(np.linalg.norm(value))
        if abs(norm - 1.0) > QUATERNION_NORM_TOLERANCE:
            found.append(f"'{where}.quaternion' = {value!r} has norm {norm:.6g}: give a unit "
                         "quaternion [w, x, y, z] (scalar first)")
    return found


def end_effector_rotation(ee_rpy, orientation: EeOrientation) -> np.ndarray:
    """R_ed from ``ee_orientation`` if it gives one, else from ``ee_rpy`` (the paper's (29));
    both already checked (:func:`orientation_errors`)."""
    given = _given(orientation)
    if not given:
        return paper_angles_rotation(ee_rpy)
    value = getattr(orientation, given[0])
    return {"rpy_paper": paper_angles_rotation, "rpy_drake": drake_rpy_rotation,
            "quaternion": quaternion_rotation}[given[0]](value)
