"""``kind: waypoints``: end-effector poses (and task joint angles) at given times, made smooth
enough for the law (docs/trajectories.md).

Constructions (``mode: stop``, the default: all local, a waypoint changes only its two
segments):

- end-effector position, CoM waypoints, heading angle and joint components: piecewise
  degree-9 Hermite polynomials (:mod:`.hermite`), matching at each waypoint the value, the
  given velocity (``ee_velocity``, ``com_velocity``, ``heading_rate``, ``joint_velocities``;
  zero if not given: rest to rest) and zero acceleration, jerk and snap. So every one is C^4
  (the law needs x_d in C^4 for the attitude feed-forward (13)-(16), the task in C^2 (17)-(20)).
- the system's CoM (x_g of (3)) with ``com: offset``: the paper's rule (33),
  x_d = p_ed + R3(phi4) r_o, the end effector's path at the fixed offset r_o
  (``trajectory.com_offset``) rotated with the heading: C^4 because both terms are.
- orientation: on each segment R(t) = R_i exp(hat(r(t))) with r(t) a quintic in the tangent
  space at R_i (:mod:`.so3`) from r = 0 to log(R_i^T R_{i+1}), matching the waypoints' angular
  velocities (zero: rest) and angular accelerations (zero) at both ends. The angular velocity
  w = R J_r(r) r' and acceleration are continuous across waypoints (C^2 on SO(3)), unlike
  slerp's, whose angular velocity jumps at each waypoint.
- heading: ``constant`` (heading_angle), ``given`` (each waypoint's, interpolated as numbers:
  write 3.3 rather than -2.98 to turn the short way from 3.0), or ``along_path`` (each waypoint
  faces the horizontal direction to the next one, the last keeps the one before; a waypoint
  less than 1 cm from the next horizontally keeps the previous heading), then unwrapped.

``mode: through``: the same segments, but at the interior waypoints every velocity not given,
and every acceleration, jerk and snap, is chosen so the path passes through without stopping
(:mod:`.through`: the least-snap C^4 curve through the waypoints; for the orientation the
angular velocity and acceleration of that curve through the neighbours' rotation vectors).
Still C^4 and C^2 on SO(3), exactly: continuity does not depend on the knot derivatives' values,
only on both segments at a knot sharing them. A constant heading stays constant.

Before the first waypoint and after the last the reference holds still (so their velocities
must be zero, which :class:`~aerial_drake.trajectories.params.WaypointsParams` checks).

Evaluated by the compiled :mod:`.spline_kernel` (about 1 us a call, against 35 us for the
numpy code, which stays as :meth:`WaypointsReference.fill_interpreted`: the tests' oracle,
equal to round-off).
"""

from __future__ import annotations

import math

import numpy as np

from aerial_drake.trajectories.base import ReferenceSource
from aerial_drake.trajectories.heading import heading_and_offset
from aerial_drake.trajectories.hermite import PiecewiseHermite, hermite_segment
from aerial_drake.trajectories.orientation import end_effector_rotation, paper_angles_rotation
from aerial_drake.trajectories.params import WaypointsParams
from aerial_drake.trajectories.reference import (
    COM_REFERENCE_SIZE,
    TaskReferenceLayout,
    task_reference_size,
)
from aerial_drake.trajectories.so3 import (
    exp_so3,
    hat,
    log_so3,
    rotation_vector_acceleration,
    rotation_vector_rates,
    rotation_vector_velocity,
)
from aerial_drake.trajectories.spline_kernel import (
    compile_spline_reference,
    fill_spline_reference,
    pack_spline_reference,
)
from aerial_drake.trajectories.through import knot_rotation_rates, through_derivatives

__all__ = ["WaypointsReference", "paper_angles_rotation", "MAX_SEGMENT_ROTATION"]

#: The largest rotation between two waypoints (rad): near pi the shortest way is ambiguous.
MAX_SEGMENT_ROTATION = math.pi - 0.05
#: Horizontal distances below this do not set a heading (``heading: along_path``) (m).
ALONG_PATH_MIN_DISTANCE = 0.01
_C4 = 5  # value and four derivatives
_C2 = 3  # value and two derivatives


def _rest_to_rest(values: np.ndarray, velocities: np.ndarray | None = None) -> np.ndarray:
    """Waypoint derivatives (N, 5, C) for :meth:`PiecewiseHermite.from_waypoints`: the
    values, the velocities (zero if None), zero acceleration, jerk and snap."""
    values = np.asarray(values, dtype=float).reshape(len(values), -1)
    out = np.zeros((values.shape[0], _C4, values.shape[1]))
    out[:, 0] = values
    if velocities is not None:
        out[:, 1] = velocities
    return out


class WaypointsReference(ReferenceSource):
    """The reference through :class:`~aerial_drake.trajectories.params.WaypointsParams`
    (module docstring). ``joint_targets``: the task's joint angles where the waypoints give
    none; ``com_offset``: r_o of (33) for ``com: offset``. ``params`` already checked
    (:func:`aerial_drake.trajectories.kinds.reference_of` does)."""

    kind = "waypoints"

    def __init__(self, params: WaypointsParams, joint_targets: np.ndarray,
                 com_offset: np.ndarray) -> None:
        points = params.points
        super().__init__(len(joint_targets))
        self.times = np.array([w.time for w in points], dtype=float)
        self.mode = params.mode
        positions = np.array([w.ee_position for w in points], dtype=float)
        if self.mode == "stop":  # today's construction, number for number
            velocities = np.array([w.ee_velocity or [0.0, 0.0, 0.0] for w in points],
                                  dtype=float)
            self._position = PiecewiseHermite.from_waypoints(
                self.times, _rest_to_rest(positions, velocities))
        else:
            self._position = self._curve(positions, [w.ee_velocity for w in points])
        headings = self._headings(params, positions)
        if params.heading == "given":
            rates = [[] if math.isnan(w.heading_rate) else [w.heading_rate] for w in points]
            self._heading = self._curve(headings, rates)
        elif params.heading == "along_path" and self.mode == "through":
            self._heading = self._curve(headings, [[] for _ in points])
        else:
            self._heading = PiecewiseHermite.from_waypoints(self.times, _rest_to_rest(headings))
        self._com = None
        if params.com == "waypoints":
            self._com = self._curve(np.array([w.com for w in points], dtype=float),
                                    [w.com_velocity for w in points])
        self._com_offset = np.asarray(com_offset, dtype=float)
        self._joints = None
        self._joint_targets = np.asarray(joint_targets, dtype=float)
        if points[0].joints:
            self._joints = self._curve(np.array([w.joints for w in points], dtype=float),
                                       [w.joint_velocities for w in points])
        self._bases, self._orientation = self._orientation_segments(points)
        self._at = TaskReferenceLayout.of(self.n_joints)
        self._task_end = COM_REFERENCE_SIZE + task_reference_size(self.n_joints)
        compile_spline_reference()  # here, not at the first fill inside a run
        self._data, self._layout = pack_spline_reference(
            self.n_joints, self._position, self._heading, False, self._com, self._com_offset,
            self._joints, self._joint_targets, self._orientation, self._bases,
            self._axis_terms)

    def _curve(self, values: np.ndarray, given: list) -> PiecewiseHermite:
        """The C^4 curve through ``values`` (N, C) with each waypoint's given velocity (an
        empty entry: not given): at rest where not given (``mode: stop``), or passing
        through (``mode: through``, :func:`.through.through_derivatives`)."""
        values = np.asarray(values, dtype=float).reshape(len(given), -1)
        if self.mode == "stop":
            rates = np.array([v if len(v) else np.zeros(values.shape[1]) for v in given],
                             dtype=float)
            return PiecewiseHermite.from_waypoints(self.times, _rest_to_rest(values, rates))
        rates = np.array([v if len(v) else np.full(values.shape[1], np.nan) for v in given],
                         dtype=float)
        return PiecewiseHermite.from_waypoints(
            self.times, through_derivatives(self.times, values, rates))

    @staticmethod
    def _headings(params: WaypointsParams, positions: np.ndarray) -> np.ndarray:
        n = positions.shape[0]
        if params.heading == "constant":
            return np.full(n, float(params.heading_angle))
        if params.heading == "given":
            return np.array([w.heading for w in params.points], dtype=float)
        headings = np.full(n, math.nan)
        for i in range(n - 1):
            d = positions[i + 1, :2] - positions[i, :2]
            if np.linalg.norm(d) >= ALONG_PATH_MIN_DISTANCE:
                headings[i] = math.atan2(d[1], d[0])
        known = headings[~np.isnan(headings)]
        previous = float(known[0]) if known.size else float(params.heading_angle)
        for i in range(n):  # a short step (and the last waypoint) keeps the heading before
            if math.isnan(headings[i]):
                headings[i] = previous
            previous = headings[i]
        return np.unwrap(headings)

    def _orientation_segments(self, points) -> tuple[np.ndarray, PiecewiseHermite]:
        """Per segment: its base R_i and the quintic r(tau) (module docstring)."""
        rotations = [end_effector_rotation(w.ee_rpy, w.ee_orientation) for w in points]
        omegas = [np.asarray(w.ee_angular_velocity or [0.0, 0.0, 0.0], dtype=float)
                  for w in points]
        zero = np.zeros(3)
        alphas = [zero] * len(points)  # World angular accelerations at the waypoints
        if self.mode == "through":
            given = [w.ee_angular_velocity or None for w in points]
            omega_array, alpha_array = knot_rotation_rates(self.times, rotations, given)
            omegas, alphas = list(omega_array), list(alpha_array)
        coefficients = []
        fixed_axis: list[bool] = []
        for i in range(len(points) - 1):
            r_end = log_so3(rotations[i].T @ rotations[i + 1])
            angle = float(np.linalg.norm(r_end))
            if angle > MAX_SEGMENT_ROTATION:
                raise ValueError(
                    f"Invalid waypoints: the end effector turns by {math.degrees(angle):.1f} "
                    f"deg between points[{i}] and points[{i + 1}] (t = {points[i].time:g} and "
                    f"{points[i + 1].time:g} s), above {math.degrees(MAX_SEGMENT_ROTATION):.0f}"
                    " deg where the shortest way is ambiguous: insert a waypoint between them")
            # Body angular velocities: R^T w (the rotation vector lives in R_i's tangent space).
            start_rate = rotations[i].T @ omegas[i]
            start_acceleration = zero if self.mode == "stop" else rotation_vector_acceleration(
                zero, start_rate, rotations[i].T @ alphas[i])
            end_rate = rotation_vector_velocity(r_end, rotations[i + 1].T @ omegas[i + 1])
            end_domega = zero if self.mode == "stop" else rotations[i + 1].T @ alphas[i + 1]
            end_acceleration = rotation_vector_acceleration(r_end, end_rate, end_domega)
            # A segment at rest at both ends turns about the fixed axis of r_end (every
            # coefficient of its r(tau) is parallel to r_end): then J_r(r) r' = r' and
            # R = R_i exp(hat(r)) is Rodrigues' formula on that axis, done in fill() without
            # the general rates (the same numbers, about a tenth of the cost).
            fixed_axis.append(not np.any(omegas[i]) and not np.any(omegas[i + 1])
                              and not np.any(alphas[i]) and not np.any(alphas[i + 1]))
            coefficients.append(hermite_segment(
                points[i + 1].time - points[i].time,
                np.array([zero, start_rate, start_acceleration]),
                np.array([r_end, end_rate, end_acceleration])))
        # Per fixed-axis segment: u, R_i u, R_i hat(u), R_i hat(u)^2 (u = 0 for a segment
        # that does not turn); the angle is theta = u . r.
        self._axis_terms: list[tuple[np.ndarray, ...] | None] = []
        for i, fixed in enumerate(fixed_axis):
            if not fixed:
                self._axis_terms.append(None)
                continue
            r_end = coefficients[i].sum(axis=0)  # r(tau = 1)
            norm = float(np.linalg.norm(r_end))
            u = r_end / norm if norm > 0.0 else np.zeros(3)
            K = hat(u)
            R_i = rotations[i]
            self._axis_terms.append((u, R_i @ u, R_i @ K, R_i @ K @ K))
        return np.array(rotations[:-1]), PiecewiseHermite(self.times, np.array(coefficients))

    def fill(self, t: float, out: np.ndarray) -> None:
        fill_spline_reference(self._data, self._layout, float(t), out)

    def fill_interpreted(self, t: float, out: np.ndarray) -> None:
        """:meth:`fill` in numpy (the compiled kernel's oracle in the tests; equal to
        round-off)."""
        P = self._position.evaluate(t, _C4)
        phi = self._heading.evaluate(t, _C4)[:, 0]
        heading, offset = heading_and_offset(phi, self._com_offset)
        com = self._com.evaluate(t, _C4) if self._com is not None else P + offset
        out[:COM_REFERENCE_SIZE] = com.reshape(-1)
        task = out[COM_REFERENCE_SIZE:self._task_end]
        at = self._at
        task[at.p], task[at.v], task[at.a] = P[0], P[1], P[2]
        i, _ = self._orientation.segment(t)
        r = self._orientation.evaluate(t, _C2)
        terms = self._axis_terms[i]
        if terms is not None:  # about a fixed axis u: R = R_i (I + sin th K + (1 - cos th) K^2)
            u, Ru, RK, RK2 = terms
            theta, theta_dot, theta_ddot = r @ u
            R = self._bases[i] + math.sin(theta) * RK + (1.0 - math.cos(theta)) * RK2
            task[at.R] = R.reshape(-1)
            task[at.w], task[at.dw] = theta_dot * Ru, theta_ddot * Ru  # R u = R_i u
        else:
            R = self._bases[i] @ exp_so3(r[0])
            omega, domega = rotation_vector_rates(r[0], r[1], r[2])
            task[at.R] = R.reshape(-1)
            task[at.w], task[at.dw] = R @ omega, R @ domega  # World: w = R omega, R domega
        if self._joints is not None:
            q = self._joints.evaluate(t, _C2)
            task[at.q], task[at.q_dot], task[at.q_ddot] = q[0], q[1], q[2]
        else:
            task[at.q], task[at.q_dot], task[at.q_ddot] = self._joint_targets, 0.0, 0.0
        out[self._task_end:] = heading.reshape(-1)
