"""The python kind sampled once onto splines, evaluated by the compiled kernel
(:mod:`.spline_kernel`): :func:`sample_onto_splines`.

The user's function (or dict of Drake trajectories) gives the reference and every derivative
the law reads. A run calls it once per knot instead of once per controller sample: at knots
:data:`SAMPLE_PERIOD` apart over [0, duration] it is sampled, and each signal is joined by the
Hermite segments of the order the law needs, matching at both knots every derivative given:

- x_d (the system's CoM) to the 4th: degree 9, C^4 (the attitude feed-forward (13)-(16));
- p_ed to the 2nd, q_jd to the 2nd and b1d to the 2nd: degree 5, C^2 ((17)-(20), (13));
- R_ed with w_ed and dw_ed: R_i exp(hat(r(t))) on each segment, r a quintic in R_i's tangent
  space matching both ends' angular velocity and acceleration (as the waypoints kind's
  orientation, :mod:`.waypoints`): C^2 on SO(3).

The error bound is checked at load, against the function itself: at a third of every
segment (:data:`CHECK_AT`: not the middle, where the leading interpolation error of every
odd derivative vanishes by symmetry), each signal's spline must be within :data:`TOLERANCE`
times the larger of 1 and the signal's largest magnitude over the knots (in the signal's
units: m, m/s, ..., rad/s^2). A segment that is not is halved (its midpoint becomes a knot),
down to :data:`REFINEMENTS` halvings; past that the reference is refused with a ValueError
naming ``python.function``, the signal, the time, the error and the tolerance. A derivative
that is not the rate of the one below it, or that jumps, shows up there too: the spline,
which matches the given derivatives at the knots, cannot follow the function in between.

Outside [0, duration] the sampled reference holds its end value with zero derivatives.
"""

from __future__ import annotations

import numpy as np

from aerial_drake.trajectories.base import ReferenceSource
from aerial_drake.trajectories.hermite import PiecewiseHermite
from aerial_drake.trajectories.reference import (
    COM_REFERENCE_SIZE,
    TaskReferenceLayout,
    task_reference_size,
)
from aerial_drake.trajectories.so3 import (
    INVERSE_MAX_ANGLE,
    ROTATION_TOLERANCE,
    _coef_a,
    _coef_a_rate,
    _coef_b,
    _coef_b_rate,
    _coef_c,
    log_so3,
)
from aerial_drake.trajectories.spline_kernel import (
    compile_spline_reference,
    fill_spline_reference,
    pack_spline_reference,
)

__all__ = ["SampledReference", "sample_onto_splines", "SAMPLE_PERIOD", "REFINEMENTS",
           "TOLERANCE"]

#: Knot spacing of the task's and the heading's quintics before any refinement (s), at most:
#: one call of the user's function per 20 controller samples at 1 kHz (none when the
#: load-time check sampled there already, :meth:`.python_kind._UserReference.packed`), and
#: one more per segment for the check.
SAMPLE_PERIOD = 0.02
#: The CoM's degree-9 segments span this many of those knots (0.1 s): its 4th derivative
#: from a segment of length T carries the samples' rounding times about 1/T^4 (1e-4 of the
#: signal at T = 5 ms, 1e-8 at 0.1 s), while its interpolation error falls as T^6.
COM_STRIDE = 5
COM_SAMPLE_PERIOD = SAMPLE_PERIOD * COM_STRIDE
#: Where in each segment (tau) the splines are checked against the function: not at the
#: middle, where the leading interpolation error of every odd derivative vanishes by symmetry.
CHECK_AT = 1.0 / 3.0
#: Halvings of a segment whose spline misses the function: the task's 20 ms down to 2.5 ms.
REFINEMENTS = 3
#: The largest error allowed, relative to max(1, the signal's largest magnitude).
TOLERANCE = 1e-6


class SampledReference(ReferenceSource):
    """A reference held as splines (module docstring); :attr:`knots` their times,
    :attr:`max_relative_error` the worst error found at the check points (relative to each
    signal's scale, as :data:`TOLERANCE`)."""

    kind = "python"

    def __init__(self, n_joints: int, knots: np.ndarray, data: np.ndarray,
                 layout: np.ndarray, max_relative_error: float) -> None:
        super().__init__(n_joints)
        self.knots = knots
        self.max_relative_error = max_relative_error
        self._data, self._layout = data, layout

    def fill(self, t: float, out: np.ndarray) -> None:
        fill_spline_reference(self._data, self._layout, float(t), out)


def _signals(n_joints: int) -> list[tuple[str, np.ndarray]]:
    """(name, indices into the packed vector) of every signal the law reads."""
    at = TaskReferenceLayout.of(n_joints)
    task = COM_REFERENCE_SIZE
    heading = task + task_reference_size(n_joints)
    names = ["x_d", "x_d'", "x_d''", "x_d'''", "x_d''''"]
    out = [(name, np.arange(3 * k, 3 * k + 3)) for k, name in enumerate(names)]
    for name, part in (("p_ed", at.p), ("R_ed", at.R), ("q_jd", at.q), ("v_ed", at.v),
                       ("w_ed", at.w), ("q_jd'", at.q_dot), ("a_ed", at.a), ("dw_ed", at.dw),
                       ("q_jd''", at.q_ddot)):
        if part.stop > part.start:
            out.append((name, np.arange(task + part.start, task + part.stop)))
    out += [(name, np.arange(heading + 3 * k, heading + 3 * k + 3))
            for k, name in enumerate(("b1d", "b1d'", "b1d''"))]
    return out


def _hats(v: np.ndarray) -> np.ndarray:
    """hat(v) of each row of ``v`` (N, 3): (N, 3, 3)."""
    out = np.zeros(v.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2], out[..., 1, 2] = -v[..., 2], v[..., 1], -v[..., 0]
    out[..., 1, 0], out[..., 2, 0], out[..., 2, 1] = v[..., 2], -v[..., 1], v[..., 0]
    return out


def _coefficients(function, t: np.ndarray) -> np.ndarray:
    return np.array([function(float(x)) for x in t])


def _log_rotations(R: np.ndarray, knots: np.ndarray, label: str) -> np.ndarray:
    """log_so3 of each of ``R`` (N, 3, 3), relative rotations over the segments: the usual
    case (turns under 90 deg) at once, any other (or a matrix that is not a rotation, for
    the message) by :func:`.so3.log_so3` itself."""
    s = 0.5 * np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0],
                        R[:, 1, 0] - R[:, 0, 1]], axis=1)
    sin_t = np.linalg.norm(s, axis=1)
    cos_t = 0.5 * (np.trace(R, axis1=1, axis2=2) - 1.0)
    t = np.arctan2(sin_t, cos_t)
    out = s * np.where(sin_t > 0.0, t / np.where(sin_t > 0.0, sin_t, 1.0), 0.0)[:, None]
    orthogonality = np.abs(np.swapaxes(R, 1, 2) @ R - np.eye(3)).max(axis=(1, 2))
    odd = (cos_t < 0.0) | (orthogonality > ROTATION_TOLERANCE) | (
        np.abs(np.linalg.det(R) - 1.0) > ROTATION_TOLERANCE) | ~np.isfinite(sin_t)
    for i in np.flatnonzero(odd):
        try:
            out[i] = log_so3(R[i])
        except ValueError as err:
            raise ValueError(f"Invalid python: 'python.function' {label!r}: R_ed at t = "
                             f"{knots[i]:.4f} to {knots[i + 1]:.4f} s: {err}") from None
    return out


def _orientation(knots: np.ndarray, R: np.ndarray, w: np.ndarray, dw: np.ndarray,
                 label: str) -> PiecewiseHermite:
    """The rotation vector's quintic per segment (module docstring), in R_i's tangent space:
    from r = 0 with the body rates R_i^T w_i and R_i^T dw_i (hat(w) w = 0), to
    r_end = log(R_i^T R_(i+1)) with r' = J_r(r)^-1 omega, r'' = J_r^-1 (domega - J_r' r')
    (:mod:`.so3`, for all segments at once)."""
    Rt = np.swapaxes(R, 1, 2)
    r_end = _log_rotations(Rt[:-1] @ R[1:], knots, label)
    angle = np.linalg.norm(r_end, axis=1)
    if np.any(angle >= INVERSE_MAX_ANGLE):
        i = int(np.argmax(angle))
        raise ValueError(f"Invalid python: 'python.function' {label!r}: R_ed turns by "
                         f"{angle[i]:.3f} rad between t = {knots[i]:.4f} and "
                         f"{knots[i + 1]:.4f} s: is it continuous?")
    K = _hats(r_end)
    K2 = K @ K
    J_inv = np.eye(3) + 0.5 * K + _coefficients(_coef_c, angle)[:, None, None] * K2
    omega = (Rt[1:] @ w[1:, :, None])[..., 0]
    domega = (Rt[1:] @ dw[1:, :, None])[..., 0]
    end_rate = (J_inv @ omega[..., None])[..., 0]
    Kd = _hats(end_rate)
    rate = np.sum(r_end * end_rate, axis=1)[:, None, None]
    J_dot = (-_coefficients(_coef_a_rate, angle)[:, None, None] * rate * K
             - _coefficients(_coef_a, angle)[:, None, None] * Kd
             + _coefficients(_coef_b_rate, angle)[:, None, None] * rate * K2
             + _coefficients(_coef_b, angle)[:, None, None] * (K @ Kd + Kd @ K))
    end_acceleration = (J_inv @ (domega - (J_dot @ end_rate[..., None])[..., 0])[..., None]
                        )[..., 0]
    starts = np.stack([np.zeros_like(r_end), (Rt[:-1] @ w[:-1, :, None])[..., 0],
                       (Rt[:-1] @ dw[:-1, :, None])[..., 0]], axis=1)
    ends = np.stack([r_end, end_rate, end_acceleration], axis=1)
    return PiecewiseHermite.from_segment_ends(knots, starts, ends)


def _task_splines(x_d: PiecewiseHermite, knots: np.ndarray, values: np.ndarray,
                  n_joints: int, label: str) -> tuple[np.ndarray, np.ndarray]:
    """The kernel's arrays: the CoM's curve ``x_d``, and splines through the packed samples
    ``values`` (N, size) at ``knots`` for every other signal."""
    at = TaskReferenceLayout.of(n_joints)
    part = values[:, COM_REFERENCE_SIZE:COM_REFERENCE_SIZE + task_reference_size(n_joints)]
    heading = values[:, COM_REFERENCE_SIZE + task_reference_size(n_joints):]

    def rows(*slices):  # (N, orders, channels) from task slices
        return np.stack([part[:, s] for s in slices], axis=1)

    position = PiecewiseHermite.through(knots, rows(at.p, at.v, at.a))
    b1d = PiecewiseHermite.through(knots, heading.reshape(-1, 3, 3))
    joints = (PiecewiseHermite.through(knots, rows(at.q, at.q_dot, at.q_ddot))
              if n_joints else None)
    R = part[:, at.R].reshape(-1, 3, 3)
    rotation = _orientation(knots, R, part[:, at.w], part[:, at.dw], label)
    return pack_spline_reference(n_joints, position, b1d, True, x_d, np.zeros(3), joints,
                                 np.zeros(n_joints), rotation, R[:-1],
                                 [None] * (knots.size - 1))


def _com_spline(knots: np.ndarray, values: np.ndarray) -> PiecewiseHermite:
    return PiecewiseHermite.through(knots, values[:, :COM_REFERENCE_SIZE].reshape(-1, 5, 3))


def _refine(source: ReferenceSource, knots: np.ndarray, values: np.ndarray, evaluate,
            signals: list, scales: dict, period: float, degree: int, label: str
            ) -> tuple[np.ndarray, np.ndarray, float]:
    """Knots (and the samples there) at which ``evaluate(knots, values, times)`` (the
    spline's packed values at ``times``) is within :data:`TOLERANCE` of ``source`` on
    ``signals``, halving the segments that are not; and the worst relative error."""
    todo = np.arange(knots.size - 1)
    worst = 0.0
    for level in range(REFINEMENTS + 1):
        checks = knots[todo] + CHECK_AT * (knots[todo + 1] - knots[todo])
        exact = source.packed(checks)
        approx = evaluate(knots, values, checks)
        # Per check point and signal, the error relative to the signal's scale.
        errors = np.stack([np.max(np.abs(approx[:, index] - exact[:, index]), axis=1)
                           / scales[name] for name, index in signals], axis=1)
        failing = np.max(errors, axis=1) > TOLERANCE
        if not np.all(failing):  # these segments stay: their error is the final one's
            worst = max(worst, float(np.max(errors[~failing])))
        if not np.any(failing):
            return knots, values, worst
        if level == REFINEMENTS:
            k, j = np.unravel_index(int(np.argmax(errors)), errors.shape)
            name = signals[j][0]
            raise ValueError(
                f"Invalid python: 'python.function' {label!r}: sampled onto splines (degree "
                f"{degree}, knots down to {1e3 * period / 2 ** level:.3g} ms apart), {name} "
                f"is off the function by {errors[k, j] * scales[name]:.3g} at t = "
                f"{checks[k]:.4f} s, above the tolerance {TOLERANCE * scales[name]:.3g} "
                f"({TOLERANCE:g} times the larger of 1 and the signal's largest magnitude): "
                "the function "
                "changes faster than that, or a derivative is not the rate of the one below "
                "it. Give a smoother reference or consistent derivatives")
        bad = todo[failing]
        mids = 0.5 * (knots[bad] + knots[bad + 1])
        new = np.concatenate([knots, mids])
        order = np.argsort(new, kind="stable")
        knots, values = new[order], np.concatenate([values, source.packed(mids)])[order]
        j = np.searchsorted(knots, mids)
        todo = np.unique(np.concatenate([j - 1, j]))
    raise AssertionError("unreachable")


def sample_onto_splines(source: ReferenceSource, duration: float, label: str
                        ) -> SampledReference:
    """``source`` (a user's reference) sampled over [0, ``duration``] onto splines and checked
    against it (module docstring). ``label``: ``python.function``, for the messages."""
    compile_spline_reference()
    n_joints, size = source.n_joints, source.size
    com_count = max(int(np.ceil(duration / COM_SAMPLE_PERIOD - 1e-9)), 1)
    count = com_count * COM_STRIDE  # the CoM's knots are every COM_STRIDE-th of the others
    knots = np.linspace(0.0, float(duration), count + 1)
    values = source.packed(knots)
    signals = _signals(n_joints)
    scales = {name: max(1.0, float(np.max(np.abs(values[:, index]))))
              for name, index in signals}

    def com_values(com_knots, com_samples, times):  # only the CoM's entries are compared
        out = np.zeros((times.size, size))
        curve = _com_spline(com_knots, com_samples)
        for k, t in enumerate(times):
            out[k, :COM_REFERENCE_SIZE] = curve.evaluate(float(t), 5).reshape(-1)
        return out

    com_knots, com_samples, com_error = _refine(
        source, knots[::COM_STRIDE], values[::COM_STRIDE], com_values,
        [s for s in signals if s[0].startswith("x_d")], scales, COM_SAMPLE_PERIOD, 9, label)
    x_d = _com_spline(com_knots, com_samples)

    built: dict = {}  # the last splines built, by their knots (the final ones are kept)

    def task_splines(task_knots, task_samples):
        if built.get("knots") is not task_knots:
            built.update(knots=task_knots, arrays=_task_splines(
                x_d, task_knots, task_samples, n_joints, label))
        return built["arrays"]

    def task_values(task_knots, task_samples, times):
        data, layout = task_splines(task_knots, task_samples)
        out = np.empty((times.size, size))
        for k, t in enumerate(times):
            fill_spline_reference(data, layout, float(t), out[k])
        return out

    knots, values, task_error = _refine(
        source, knots, values, task_values,
        [s for s in signals if not s[0].startswith("x_d")], scales, SAMPLE_PERIOD, 5, label)
    data, layout = task_splines(knots, values)
    return SampledReference(n_joints, knots, data, layout, max(com_error, task_error))
