"""The compiled evaluation of a reference made of piecewise polynomials: the waypoints kind
(:mod:`.waypoints`) and the python kind sampled onto splines (:mod:`.sampled`).

One numba kernel, :func:`fill_spline_reference`, writes the packed [com, task, heading]
vector (:mod:`.reference`) at a time from one float array and one integer array built once
by :func:`pack_spline_reference`. The pieces, each optional where the kinds differ:

- curves (:class:`~aerial_drake.trajectories.hermite.PiecewiseHermite`: knots and
  coefficients in tau per segment): the end-effector position, the heading (the angle phi4,
  or b1d's three components), the CoM (x_d; else rule (33), x_d = p_ed + R3(phi4) r_o), the
  task's joint components (else constant targets), and the orientation's rotation vector r;
- per orientation segment its base R_i, with R = R_i exp(hat(r)) (:mod:`.so3`), and, for a
  segment turning about a fixed axis u, the terms of Rodrigues' formula on that axis.

The arithmetic is the numpy code's (:meth:`PiecewiseHermite.evaluate`,
:func:`.heading.heading_and_offset`, :func:`.so3.exp_so3`, :func:`.so3.rotation_vector_rates`)
in compiled loops: equal to round-off (a polynomial by Horner's rule rather than by powers),
the tests hold it to 1e-12 relative. At 1 kHz the numpy evaluation cost about 35 us a call,
this about 1 us.
"""

from __future__ import annotations

import math
import os
import sys

import numba
import numpy as np

from aerial_drake.trajectories.hermite import PiecewiseHermite
from aerial_drake.trajectories.so3 import (
    _A_RATE_SERIES,
    _A_RATE_THRESHOLD,
    _A_SERIES,
    _A_THRESHOLD,
    _B_RATE_SERIES,
    _B_RATE_THRESHOLD,
    _B_SERIES,
    _B_THRESHOLD,
    _SINC_SERIES,
    _SINC_THRESHOLD,
)

__all__ = ["pack_spline_reference", "fill_spline_reference", "compile_spline_reference",
           "POSITION", "HEADING", "COM", "JOINTS", "ROTATION"]

#: The curves, in the order of their entries in the integer array.
POSITION, HEADING, COM, JOINTS, ROTATION = range(5)
_CURVES = 5
# The integer array: n_j, the com / heading / joint modes, the offsets of r_o, the joint
# targets, the orientation bases and their axis terms in the float array, then per curve
# (knots' offset, segments, degree, channels, coefficients' offset).
_HEADER = 8
_PER_CURVE = 5
#: Per orientation segment: a flag (1: about a fixed axis), u, R_i u, R_i hat(u), R_i hat(u)^2.
_AXIS_ENTRIES = 25


def pack_spline_reference(n_joints: int, position: PiecewiseHermite,
                          heading: PiecewiseHermite, heading_is_b1d: bool,
                          com: PiecewiseHermite | None, com_offset: np.ndarray,
                          joints: PiecewiseHermite | None, joint_targets: np.ndarray,
                          rotation: PiecewiseHermite, bases: np.ndarray,
                          axis_terms: list) -> tuple[np.ndarray, np.ndarray]:
    """The (float, integer) arrays :func:`fill_spline_reference` reads.

    ``heading``: phi4 (1 channel, b1d = [cos phi4, sin phi4, 0]) or, ``heading_is_b1d``,
    b1d itself (3 channels); ``com`` None: rule (33) with ``com_offset`` (then the position
    and phi4 need 4 derivatives); ``joints`` None: ``joint_targets``; ``rotation``: r per
    segment, whose ``bases`` (segments, 3, 3) are R_i; ``axis_terms``: per segment None or
    (u, R_i u, R_i hat(u), R_i hat(u)^2) for a segment turning about the fixed axis u.
    """
    if com is None and heading_is_b1d:
        raise ValueError("rule (33) needs the heading angle phi4, not b1d")
    chunks: list[np.ndarray] = []
    size = 0

    def put(values) -> int:
        nonlocal size
        values = np.ascontiguousarray(values, dtype=float).reshape(-1)
        chunks.append(values)
        size += values.size
        return size - values.size

    layout = np.zeros(_HEADER + _PER_CURVE * _CURVES, dtype=np.int64)
    layout[0] = int(n_joints)
    layout[1] = 0 if com is None else 1
    layout[2] = 1 if heading_is_b1d else 0
    layout[3] = 0 if joints is None else 1
    layout[4] = put(np.asarray(com_offset, dtype=float).reshape(3))
    layout[5] = put(np.asarray(joint_targets, dtype=float).reshape(int(n_joints)))
    bases = np.asarray(bases, dtype=float)
    if bases.shape != (rotation.coefficients.shape[0], 3, 3):
        raise ValueError(f"one base per orientation segment, got {bases.shape}")
    layout[6] = put(bases)
    axis = np.zeros((len(axis_terms), _AXIS_ENTRIES))
    for i, terms in enumerate(axis_terms):
        if terms is not None:
            axis[i, 0] = 1.0
            axis[i, 1:] = np.concatenate([np.reshape(x, -1) for x in terms])
    layout[7] = put(axis)
    for which, curve in ((POSITION, position), (HEADING, heading), (COM, com),
                         (JOINTS, joints), (ROTATION, rotation)):
        if curve is None:
            continue
        at = _HEADER + _PER_CURVE * which
        layout[at] = put(curve.knots)
        layout[at + 1] = curve.coefficients.shape[0]
        layout[at + 2] = curve.degree
        layout[at + 3] = curve.channels
        layout[at + 4] = put(curve.coefficients)
    return np.concatenate(chunks), layout


@numba.njit(cache=True)
def _curve(data, layout, which, t, orders, out):
    """Curve ``which``'s value and first ``orders - 1`` derivatives at t into out[:orders]
    (as :meth:`PiecewiseHermite.evaluate`: the end value, zero derivatives outside the
    knots); returns the segment index."""
    at = _HEADER + _PER_CURVE * which
    knots, n, degree, channels, coefficients = (layout[at], layout[at + 1], layout[at + 2],
                                                layout[at + 3], layout[at + 4])
    lo, hi = 0, n + 1  # searchsorted(knots, t, side="right")
    while lo < hi:
        mid = (lo + hi) // 2
        if data[knots + mid] <= t:
            lo = mid + 1
        else:
            hi = mid
    i = min(max(lo - 1, 0), n - 1)
    t0 = data[knots + i]
    T = data[knots + i + 1] - t0
    tau = min(max((t - t0) / T, 0.0), 1.0)
    outside = t < data[knots] or t > data[knots + n]
    row = coefficients + i * (degree + 1) * channels
    for k in range(orders):
        scale = T ** k
        for c in range(channels):
            value = 0.0
            if k == 0 or not outside:
                for j in range(degree, k - 1, -1):  # Horner on d^k/dtau^k sum_j c_j tau^j
                    factor = 1.0
                    for m in range(j - k + 1, j + 1):
                        factor *= m
                    value = value * tau + factor * data[row + j * channels + c]
                value /= scale
            out[k, c] = value
    return i


@numba.njit(cache=True)
def _horner(series, t2):
    value = 0.0
    for k in range(len(series) - 1, -1, -1):
        value = value * t2 + series[k]
    return value


@numba.njit(cache=True)
def _so3_coefficients(t):
    """sin t / t, a, b, a'(t)/t, b'(t)/t of :mod:`.so3` (its series and thresholds)."""
    t2 = t * t
    sinc = _horner(_SINC_SERIES, t2) if t < _SINC_THRESHOLD else math.sin(t) / t
    if t < _A_THRESHOLD:
        a = _horner(_A_SERIES, t2)
    else:
        s = math.sin(0.5 * t) / t
        a = 2.0 * s * s
    b = _horner(_B_SERIES, t2) if t < _B_THRESHOLD else (t - math.sin(t)) / t ** 3
    if t < _A_RATE_THRESHOLD:
        a_rate = _horner(_A_RATE_SERIES, t2)
    else:
        s = math.sin(0.5 * t)
        a_rate = (t * math.sin(t) - 4.0 * s * s) / t ** 4
    if t < _B_RATE_THRESHOLD:
        b_rate = _horner(_B_RATE_SERIES, t2)
    else:
        b_rate = (3.0 * math.sin(t) - 2.0 * t - t * math.cos(t)) / t ** 5
    return sinc, a, b, a_rate, b_rate


@numba.njit(cache=True)
def _orientation(data, layout, t, task, W, DW):
    """R_ed (row-major at task[3:12]), w_ed and dw_ed (at W, DW) of R_i exp(hat(r(t)))."""
    r = np.empty((3, 3))
    i = _curve(data, layout, ROTATION, t, 3, r)
    base = layout[6] + 9 * i
    axis = layout[7] + _AXIS_ENTRIES * i
    if data[axis] != 0.0:  # about the fixed axis u: R = R_i (I + sin th K + (1 - cos th) K^2)
        th = np.empty(3)
        for k in range(3):
            th[k] = r[k, 0] * data[axis + 1] + r[k, 1] * data[axis + 2] + r[k, 2] * data[axis + 3]
        s, c1 = math.sin(th[0]), 1.0 - math.cos(th[0])
        for e in range(9):
            task[3 + e] = data[base + e] + s * data[axis + 7 + e] + c1 * data[axis + 16 + e]
        for e in range(3):
            task[W + e] = th[1] * data[axis + 4 + e]
            task[DW + e] = th[2] * data[axis + 4 + e]
        return
    x, y, z = r[0, 0], r[0, 1], r[0, 2]
    sinc, a, b, a_rate, b_rate = _so3_coefficients(math.sqrt(x * x + y * y + z * z))
    K = np.empty((3, 3))  # hat(r) and hat(r')
    Kd = np.empty((3, 3))
    _hat(r[0], K)
    _hat(r[1], Kd)
    rate = x * r[1, 0] + y * r[1, 1] + z * r[1, 2]
    # exp(hat(r)) = I + sinc K + a K^2, J_r = I - a K + b K^2 and its rate (so3.py).
    E = np.empty((3, 3))
    J = np.empty((3, 3))
    J_dot = np.empty((3, 3))
    for m in range(3):
        for n in range(3):
            K2 = K[m, 0] * K[0, n] + K[m, 1] * K[1, n] + K[m, 2] * K[2, n]
            KKd = (K[m, 0] * Kd[0, n] + K[m, 1] * Kd[1, n] + K[m, 2] * Kd[2, n]
                   + Kd[m, 0] * K[0, n] + Kd[m, 1] * K[1, n] + Kd[m, 2] * K[2, n])
            eye = 1.0 if m == n else 0.0
            E[m, n] = eye + sinc * K[m, n] + a * K2
            J[m, n] = eye - a * K[m, n] + b * K2
            J_dot[m, n] = (-a_rate * rate * K[m, n] - a * Kd[m, n] + b_rate * rate * K2
                           + b * KKd)
    omega = np.empty(3)
    domega = np.empty(3)
    for m in range(3):
        omega[m] = J[m, 0] * r[1, 0] + J[m, 1] * r[1, 1] + J[m, 2] * r[1, 2]
        domega[m] = (J[m, 0] * r[2, 0] + J[m, 1] * r[2, 1] + J[m, 2] * r[2, 2]
                     + J_dot[m, 0] * r[1, 0] + J_dot[m, 1] * r[1, 1] + J_dot[m, 2] * r[1, 2])
    R = np.empty((3, 3))
    for m in range(3):
        for n in range(3):
            R[m, n] = (data[base + 3 * m] * E[0, n] + data[base + 3 * m + 1] * E[1, n]
                       + data[base + 3 * m + 2] * E[2, n])
            task[3 + 3 * m + n] = R[m, n]
    for m in range(3):  # World: w = R omega, dw = R domega
        task[W + m] = R[m, 0] * omega[0] + R[m, 1] * omega[1] + R[m, 2] * omega[2]
        task[DW + m] = R[m, 0] * domega[0] + R[m, 1] * domega[1] + R[m, 2] * domega[2]


@numba.njit(cache=True)
def _hat(v, out):
    out[0, 0], out[0, 1], out[0, 2] = 0.0, -v[2], v[1]
    out[1, 0], out[1, 1], out[1, 2] = v[2], 0.0, -v[0]
    out[2, 0], out[2, 1], out[2, 2] = -v[1], v[0], 0.0


@numba.njit(cache=True)
def fill_spline_reference(data, layout, t, out):
    """The packed [com (15), task (24 + 3 n_j), heading (9)] at time t into ``out``, from
    the arrays of :func:`pack_spline_reference`."""
    nj, com_curve, heading_is_b1d, joint_curve = layout[0], layout[1], layout[2], layout[3]
    W, QD, A, DW, QDD = 15 + nj, 18 + nj, 18 + 2 * nj, 21 + 2 * nj, 24 + 2 * nj
    task_end = 15 + 24 + 3 * nj
    task = out[15:task_end]
    P = np.empty((5, 3))
    _curve(data, layout, POSITION, t, 3 if com_curve else 5, P)
    h = np.empty((5, 3))
    if heading_is_b1d:
        _curve(data, layout, HEADING, t, 3, h)
        for k in range(3):
            for c in range(3):
                out[task_end + 3 * k + c] = h[k, c]
    else:
        # d^k/dt^k exp(i phi4) = f_k exp(i phi4) (heading.unit_phasor_derivatives).
        _curve(data, layout, HEADING, t, 5, h)
        d1, d2, d3, d4 = h[1, 0], h[2, 0], h[3, 0], h[4, 0]
        fr = (1.0, 0.0, -d1 ** 2, -3 * d1 * d2, -4 * d1 * d3 - 3 * d2 ** 2 + d1 ** 4)
        fi = (0.0, d1, d2, d3 - d1 ** 3, d4 - 6 * d1 ** 2 * d2)
        c, s = math.cos(h[0, 0]), math.sin(h[0, 0])
        rx, ry, rz = data[layout[4]], data[layout[4] + 1], data[layout[4] + 2]
        for k in range(5):
            re, im = fr[k] * c - fi[k] * s, fr[k] * s + fi[k] * c
            if k < 3:
                out[task_end + 3 * k] = re
                out[task_end + 3 * k + 1] = im
                out[task_end + 3 * k + 2] = 0.0
            if not com_curve:  # (33) x_d = p_ed + R3(phi4) r_o: the xy part turned
                out[3 * k] = P[k, 0] + (re * rx - im * ry)
                out[3 * k + 1] = P[k, 1] + (re * ry + im * rx)
                out[3 * k + 2] = P[k, 2] + (rz if k == 0 else 0.0)
    if com_curve:
        X = np.empty((5, 3))
        _curve(data, layout, COM, t, 5, X)
        for k in range(5):
            for c in range(3):
                out[3 * k + c] = X[k, c]
    for c in range(3):
        task[c] = P[0, c]
        task[12 + nj + c] = P[1, c]
        task[A + c] = P[2, c]
    _orientation(data, layout, t, task, W, DW)
    if joint_curve:
        q = np.empty((3, nj))
        _curve(data, layout, JOINTS, t, 3, q)
        for e in range(nj):
            task[12 + e], task[QD + e], task[QDD + e] = q[0, e], q[1, e], q[2, e]
    else:
        for e in range(nj):
            task[12 + e], task[QD + e], task[QDD + e] = data[layout[5] + e], 0.0, 0.0


def compile_spline_reference() -> None:
    """Compile the kernel into numba's cache, or load it, for the argument types a run
    passes; with a note on stderr when it compiles (the first waypoints or python reference
    after installing: a few seconds). Called where such a reference is built, not by
    ``simulation.runner.compile_kernels``, so the paper kind's first run does not pay it."""
    if not fill_spline_reference.signatures and _cache_is_cold():
        print("aerial_drake: compiling the reference kernel with numba (first waypoints or "
              "python reference after installing; a few seconds, cached afterwards) ...",
              file=sys.stderr, flush=True)
    vector = numba.types.Array(numba.types.float64, 1, "C")
    fill_spline_reference.compile(
        (vector, numba.types.Array(numba.types.int64, 1, "C"), numba.types.float64, vector))


def _cache_is_cold() -> bool:
    try:
        # numba's internals (untyped), as control.compiled.law_cache_is_cold.
        index = fill_spline_reference._cache._cache_file._index_path  # type: ignore[attr-defined]
        return not os.path.exists(index)
    except AttributeError:  # numba internals moved: no note
        return False
