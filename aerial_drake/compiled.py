"""The decomposition of Section II and the law (10)-(22), compiled with numba (double only).

The reference implementation is the numpy code of :mod:`aerial_drake.decoupling` and
:mod:`aerial_drake.control`, fed by Drake's kinematics; it stays the path for AutoDiffXd
(``Linearize``) and is the oracle the tests hold this module against. This module computes the
same quantities, with the same formulas in the same order, but from its own forward kinematics
(:class:`~aerial_drake.kinematic_tree.KinematicTree`), in compiled loops over small fixed-size
arrays: one evaluation of the law costs tens of microseconds instead of about two milliseconds
of numpy calls on 3- to 13-element arrays. See ``docs/performance.md``.

The only entry points are :class:`CompiledLaw` and :func:`decompose`; the kernels are private.
numba compiles them on first use and caches the machine code next to this file (``cache=True``),
so only the first run after installing pays the compile time (about a minute on a 2-core
machine; a note on stderr says so); later processes load the machine code in under a second.
"""

from __future__ import annotations

import math
import os
import sys

import numpy as np
from numba import njit

from aerial_drake.control import DIAGNOSTICS_SIZE
from aerial_drake.kinematic_tree import FREE, REVOLUTE, KinematicTree
from aerial_drake.reference import (
    COM_REFERENCE_SIZE, HEADING_REFERENCE_SIZE, TASK_REFERENCE_SIZE, unpack_heading_reference,
    unpack_task_reference)

# error_model="numpy": a division by zero gives inf/nan as in the numpy path (and the checks
# of Assumptions 1 and 2 report it) instead of raising ZeroDivisionError mid-law.
_jit = njit(cache=True, nogil=True, error_model="numpy")

#: Status codes of the law kernel.
OK, ASSUMPTION_2, ASSUMPTION_1, NONFINITE = 0, 1, 2, 3


# --- small dense linear algebra (explicit loops: no BLAS/LAPACK, hence no SciPy) -------------

@_jit
def _mm(A, B):
    n, k, m = A.shape[0], A.shape[1], B.shape[1]
    out = np.zeros((n, m))
    for i in range(n):
        for p in range(k):
            a = A[i, p]
            if a != 0.0:
                for j in range(m):
                    out[i, j] += a * B[p, j]
    return out


@_jit
def _mtm(A, B):
    """A^T B."""
    return _mm(A.T, B)


@_jit
def _mv(A, x):
    """A x, two rows at a time: two independent sums in flight instead of one (the same sums,
    in the same order)."""
    n, k = A.shape
    out = np.empty(n)
    for i in range(0, n - 1, 2):
        s0, s1 = 0.0, 0.0
        for p in range(k):
            s0 += A[i, p] * x[p]
            s1 += A[i + 1, p] * x[p]
        out[i], out[i + 1] = s0, s1
    if n % 2:
        s0 = 0.0
        for p in range(k):
            s0 += A[n - 1, p] * x[p]
        out[n - 1] = s0
    return out


@_jit
def _mtv(A, x):
    """A^T x."""
    k, n = A.shape
    out = np.zeros(n)
    for p in range(k):
        a = x[p]
        for i in range(n):
            out[i] += A[p, i] * a
    return out


@_jit
def _dot(a, b):
    s = 0.0
    for i in range(a.shape[0]):
        s += a[i] * b[i]
    return s


@_jit
def _cross(a, b):
    out = np.empty(3)
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]
    return out


@_jit
def _hat(a):
    out = np.zeros((3, 3))
    out[0, 1], out[0, 2] = -a[2], a[1]
    out[1, 0], out[1, 2] = a[2], -a[0]
    out[2, 0], out[2, 1] = -a[1], a[0]
    return out


@_jit
def _vee(S):
    """vee of the skew-symmetric part, as decoupling.vee."""
    out = np.empty(3)
    out[0] = 0.5 * (S[2, 1] - S[1, 2])
    out[1] = 0.5 * (S[0, 2] - S[2, 0])
    out[2] = 0.5 * (S[1, 0] - S[0, 1])
    return out


@_jit
def _lu(A):
    """LU factorisation with partial pivoting: (LU packed, pivot rows)."""
    n = A.shape[0]
    LU = A.copy()
    piv = np.arange(n)
    for k in range(n):
        p = k
        big = abs(LU[k, k])
        for i in range(k + 1, n):
            if abs(LU[i, k]) > big:
                big, p = abs(LU[i, k]), i
        if p != k:
            for j in range(n):
                LU[k, j], LU[p, j] = LU[p, j], LU[k, j]
            piv[k], piv[p] = piv[p], piv[k]
        d = LU[k, k]
        for i in range(k + 1, n):
            LU[i, k] /= d
            f = LU[i, k]
            if f != 0.0:
                for j in range(k + 1, n):
                    LU[i, j] -= f * LU[k, j]
    return LU, piv


@_jit
def _lu_solve(LU, piv, B):
    """A^{-1} B from _lu(A), B of shape (n, m)."""
    n, m = B.shape
    X = np.empty((n, m))
    for i in range(n):
        X[i] = B[piv[i]]
    for i in range(n):
        for k in range(i):
            f = LU[i, k]
            if f != 0.0:
                for j in range(m):
                    X[i, j] -= f * X[k, j]
    for i in range(n - 1, -1, -1):
        for k in range(i + 1, n):
            f = LU[i, k]
            if f != 0.0:
                for j in range(m):
                    X[i, j] -= f * X[k, j]
        d = LU[i, i]
        for j in range(m):
            X[i, j] /= d
    return X


@_jit
def _inv(A):
    LU, piv = _lu(A)
    return _lu_solve(LU, piv, np.eye(A.shape[0]))


@_jit
def _rotate_pair(A, i, j, k, l, c, s):
    g, h = A[i, j], A[k, l]
    A[i, j] = c * g - s * h
    A[k, l] = s * g + c * h


@_jit
def _min_eigenvalue_sym(S):
    """Smallest eigenvalue of a symmetric matrix (cyclic Jacobi; high relative accuracy)."""
    A = S.copy()
    n = A.shape[0]
    for _ in range(100):
        off = 0.0
        for i in range(n):
            for j in range(i + 1, n):
                off += A[i, j] * A[i, j]  # upper triangle
        scale = 0.0
        for i in range(n):
            scale += A[i, i] * A[i, i]
        if off <= 1e-36 * scale:
            break
        for p in range(n):
            for q in range(p + 1, n):
                apq = A[p, q]
                if apq == 0.0:
                    continue
                theta = (A[q, q] - A[p, p]) / (2.0 * apq)
                t = (1.0 if theta >= 0.0 else -1.0) / (abs(theta) + math.sqrt(theta * theta + 1.0))
                c = 1.0 / math.sqrt(t * t + 1.0)
                s = t * c
                # A <- G^T A G on the upper triangle only (A stays symmetric): the rotation
                # zeroes A[p, q] and mixes the rest of rows and columns p and q.
                A[p, p] -= t * apq
                A[q, q] += t * apq
                A[p, q] = 0.0
                for k in range(p):
                    _rotate_pair(A, k, p, k, q, c, s)
                for k in range(p + 1, q):
                    _rotate_pair(A, p, k, k, q, c, s)
                for k in range(q + 1, n):
                    _rotate_pair(A, p, k, q, k, c, s)
    lowest = A[0, 0]
    for i in range(1, n):
        lowest = min(lowest, A[i, i])
    return lowest


# --- kinematics ------------------------------------------------------------------------------

@_jit
def _quaternion_matrix_into(w, x, y, z, R):
    """Rotation of the (not necessarily unit) quaternion, as Drake's (scaled by 2/|q|^2)."""
    s = 2.0 / (w * w + x * x + y * y + z * z)
    R[0, 0], R[0, 1], R[0, 2] = 1.0 - s * (y * y + z * z), s * (x * y - w * z), s * (x * z + w * y)
    R[1, 0], R[1, 1], R[1, 2] = s * (x * y + w * z), 1.0 - s * (x * x + z * z), s * (y * z - w * x)
    R[2, 0], R[2, 1], R[2, 2] = s * (x * z - w * y), s * (y * z + w * x), 1.0 - s * (x * x + y * y)


@_jit
def _axis_angle_matrix_into(a, angle, R):
    """Rodrigues' formula: rotation by ``angle`` about the unit axis ``a``."""
    c, s = math.cos(angle), math.sin(angle)
    t = 1.0 - c
    R[0, 0], R[0, 1], R[0, 2] = c + t * a[0] * a[0], t * a[0] * a[1] - s * a[2], \
        t * a[0] * a[2] + s * a[1]
    R[1, 0], R[1, 1], R[1, 2] = t * a[1] * a[0] + s * a[2], c + t * a[1] * a[1], \
        t * a[1] * a[2] - s * a[0]
    R[2, 0], R[2, 1], R[2, 2] = t * a[2] * a[0] - s * a[1], t * a[2] * a[1] + s * a[0], \
        c + t * a[2] * a[2]


@_jit
def _mm3_into(A, B, out):
    for i in range(3):
        for j in range(3):
            out[i, j] = A[i, 0] * B[0, j] + A[i, 1] * B[1, j] + A[i, 2] * B[2, j]


@_jit
def _affine_into(p, R, x, out):
    """out = p + R x (3-vectors)."""
    for i in range(3):
        out[i] = p[i] + R[i, 0] * x[0] + R[i, 1] * x[1] + R[i, 2] * x[2]


@_jit
def _kinematics(q, v, parent, joint_type, q_start, v_start, R_PF, p_PF, R_MC, p_MC, axis_F):
    """Body poses in World and body-frame spatial velocity Jacobians ``[w; v]`` about each body
    origin (Drake's ``CalcJacobianSpatialVelocity(kV, B, 0, World, B)``)."""
    nb, nv = parent.shape[0], v.shape[0]
    R_all = np.empty((nb, 3, 3))
    p_all = np.empty((nb, 3))
    axis_W = np.zeros((nb, 3))  # joint axis in World
    origin_W = np.zeros((nb, 3))  # joint frame M's origin in World
    R_WF, R_FM, R_WM = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
    p_WF = np.empty(3)
    for b in range(nb):
        P = parent[b]
        if P < 0:
            R_WF[:, :] = R_PF[b]
            p_WF[:] = p_PF[b]
        else:
            _mm3_into(R_all[P], R_PF[b], R_WF)
            _affine_into(p_all[P], R_all[P], p_PF[b], p_WF)
        i = q_start[b]
        if joint_type[b] == FREE:
            _quaternion_matrix_into(q[i], q[i + 1], q[i + 2], q[i + 3], R_FM)
            _mm3_into(R_WF, R_FM, R_WM)
            _affine_into(p_WF, R_WF, q[i + 4:i + 7], origin_W[b])
        elif joint_type[b] == REVOLUTE:
            _axis_angle_matrix_into(axis_F[b], q[i], R_FM)
            _mm3_into(R_WF, R_FM, R_WM)
            origin_W[b] = p_WF
            a = axis_F[b]
            for r in range(3):
                axis_W[b, r] = R_WF[r, 0] * a[0] + R_WF[r, 1] * a[1] + R_WF[r, 2] * a[2]
        else:
            R_WM[:, :] = R_WF
            origin_W[b] = p_WF
        _mm3_into(R_WM, R_MC[b], R_all[b])
        _affine_into(origin_W[b], R_WM, p_MC[b], p_all[b])

    J = np.zeros((nb, 6, nv))
    for b in range(nb):
        R = R_all[b]
        a = b
        while a >= 0:
            k = v_start[a]
            rx = p_all[b, 0] - origin_W[a, 0]
            ry = p_all[b, 1] - origin_W[a, 1]
            rz = p_all[b, 2] - origin_W[a, 2]
            if joint_type[a] == REVOLUTE:
                wx, wy, wz = axis_W[a, 0], axis_W[a, 1], axis_W[a, 2]
                lx, ly, lz = wy * rz - wz * ry, wz * rx - wx * rz, wx * ry - wy * rx
                for i in range(3):  # R^T [w; w x r]
                    J[b, i, k] = R[0, i] * wx + R[1, i] * wy + R[2, i] * wz
                    J[b, 3 + i, k] = R[0, i] * lx + R[1, i] * ly + R[2, i] * lz
            elif joint_type[a] == FREE:
                # Columns of w_WB (e_j, e_j x r) and of v_WBo (0, e_j), in the body frame.
                for i in range(3):
                    J[b, i, k], J[b, i, k + 1], J[b, i, k + 2] = R[0, i], R[1, i], R[2, i]
                    J[b, 3 + i, k + 3], J[b, 3 + i, k + 4], J[b, 3 + i, k + 5] = \
                        R[0, i], R[1, i], R[2, i]
                    J[b, 3 + i, k] = R[2, i] * ry - R[1, i] * rz  # R^T (e_x x r)
                    J[b, 3 + i, k + 1] = R[0, i] * rz - R[2, i] * rx
                    J[b, 3 + i, k + 2] = R[1, i] * rx - R[0, i] * ry
            a = parent[a]
    return R_all, p_all, J


@_jit
def _crm_times_into(s, a, out, col):
    """out[:, col] = crm(s) a for spatial vectors, crm([w; v]) = [[w x, 0], [v x, w x]]."""
    wx, wy, wz, vx, vy, vz = s[0], s[1], s[2], s[3], s[4], s[5]
    out[0, col] = wy * a[2] - wz * a[1]
    out[1, col] = wz * a[0] - wx * a[2]
    out[2, col] = wx * a[1] - wy * a[0]
    out[3, col] = vy * a[2] - vz * a[1] + wy * a[5] - wz * a[4]
    out[4, col] = vz * a[0] - vx * a[2] + wz * a[3] - wx * a[5]
    out[5, col] = vx * a[1] - vy * a[0] + wx * a[4] - wy * a[3]


@_jit
def _jacobian_derivative(Jb, Vb, v, R, J_dot, work):
    """d/dt of one body-frame Jacobian into ``J_dot``, as
    DecoupledDynamics._jacobian_derivatives (the free joint's six velocities first, then 1-DoF
    joints; KinematicTree guarantees both). ``work``: a 6-vector of scratch space."""
    nv = v.shape[0]
    after = work  # sum over later joint columns m > k of J[:, m] v_m
    after[:] = 0.0
    for k in range(nv - 1, 5, -1):
        _crm_times_into(Jb[:, k], after, J_dot, k)
        for r in range(6):
            after[r] += Jb[r, k] * v[k]
    # Free joint's columns: -crm(V) J[:, k], plus R^T (v_WBo x e_j) on the angular ones.
    neg_col = work
    for k in range(6):
        for r in range(6):
            neg_col[r] = -Jb[r, k]
        _crm_times_into(Vb, neg_col, J_dot, k)
    ux, uy, uz = v[3], v[4], v[5]
    for i in range(3):
        J_dot[3 + i, 0] += R[1, i] * uz - R[2, i] * uy  # column j of R^T hat(u): R^T (u x e_j)
        J_dot[3 + i, 1] += R[2, i] * ux - R[0, i] * uz
        J_dot[3 + i, 2] += R[0, i] * uy - R[1, i] * ux


# --- Section II ------------------------------------------------------------------------------

@_jit
def _coriolis_kernel(I, Vb, A):
    """A = crf(V) I + I crm(V) + Hbar (crf(V) = -crm(V)^T), the 6x6 matrix of body b's
    Christoffel-consistent Coriolis term (design notes, section 3), into ``A``."""
    wx, wy, wz, vx, vy, vz = Vb[0], Vb[1], Vb[2], Vb[3], Vb[4], Vb[5]
    # I crm(V) column by column (crm(V) = [[w x, 0], [v x, w x]]); crf(V) I = -(I crm(V))^T
    # as I is symmetric.
    for i in range(6):
        a0, a1, a2, a3, a4, a5 = I[i, 0], I[i, 1], I[i, 2], I[i, 3], I[i, 4], I[i, 5]
        A[i, 0] = a1 * wz - a2 * wy + a4 * vz - a5 * vy
        A[i, 1] = a2 * wx - a0 * wz + a5 * vx - a3 * vz
        A[i, 2] = a0 * wy - a1 * wx + a3 * vy - a4 * vx
        A[i, 3] = a4 * wz - a5 * wy
        A[i, 4] = a5 * wx - a3 * wz
        A[i, 5] = a3 * wy - a4 * wx
    for i in range(6):
        for j in range(i + 1, 6):
            d = A[i, j] - A[j, i]
            A[i, j], A[j, i] = d, -d
        A[i, i] = 0.0
    h0, h1, h2, h3, h4, h5 = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    for k in range(6):
        h0 += I[0, k] * Vb[k]
        h1 += I[1, k] * Vb[k]
        h2 += I[2, k] * Vb[k]
        h3 += I[3, k] * Vb[k]
        h4 += I[4, k] * Vb[k]
        h5 += I[5, k] * Vb[k]
    # Hbar = [[-hat(h_w), -hat(h_v)], [-hat(h_v), 0]]
    A[0, 1] += h2
    A[0, 2] -= h1
    A[1, 0] -= h2
    A[1, 2] += h0
    A[2, 0] += h1
    A[2, 1] -= h0
    for (r0, c0) in ((0, 3), (3, 0)):
        A[r0 + 0, c0 + 1] += h5
        A[r0 + 0, c0 + 2] -= h4
        A[r0 + 1, c0 + 0] -= h5
        A[r0 + 1, c0 + 2] += h3
        A[r0 + 2, c0 + 0] += h4
        A[r0 + 2, c0 + 1] -= h3


@_jit
def _body_sums(q, v, parent, joint_type, q_start, v_start, R_PF, p_PF, R_MC, p_MC, axis_F,
               inertia, mass, com_B, reflected):
    """The sums over bodies of Section II: M, the Christoffel-consistent C, the CoM, its
    Jacobian J_g and J_g_dot, with the kinematics they come from."""
    nb, nv = parent.shape[0], v.shape[0]
    R_all, p_all, J = _kinematics(q, v, parent, joint_type, q_start, v_start, R_PF, p_PF,
                                  R_MC, p_MC, axis_F)
    m = 0.0
    base = -1
    for b in range(nb):
        m += mass[b]
        if joint_type[b] == FREE:
            base = b

    M = np.zeros((nv, nv))
    C = np.zeros((nv, nv))
    J_g = np.zeros((3, nv))
    J_g_dot = np.zeros((3, nv))
    p_WG = np.zeros(3)
    J_dot_all = np.zeros((nb, 6, nv))
    cols = np.empty(nv, dtype=np.int64)
    Vb = np.empty(6)
    work = np.empty(6)
    A = np.empty((6, 6))
    # Body b's nonzero Jacobian columns (its ancestors' velocities) gathered side by side, and
    # the products of its mass and Coriolis terms over them, so that the inner loops run over
    # contiguous memory.
    Jc = np.empty((6, nv))
    Jdc = np.empty((6, nv))
    IJ = np.empty((6, nv))
    inner = np.empty((6, nv))
    row_m = np.empty(nv)
    row_c = np.empty(nv)
    for b in range(nb):
        Jb, J_dot = J[b], J_dot_all[b]
        for r in range(6):
            s = 0.0
            for k in range(nv):
                s += Jb[r, k] * v[k]
            Vb[r] = s
        _jacobian_derivative(Jb, Vb, v, R_all[b], J_dot, work)
        if mass[b] == 0.0:
            continue
        nc = 0
        a = b
        while a >= 0:
            width = 6 if joint_type[a] == FREE else (1 if joint_type[a] == REVOLUTE else 0)
            for j in range(width):
                cols[nc] = v_start[a] + j
                nc += 1
            a = parent[a]
        for r in range(6):
            for c in range(nc):
                Jc[r, c] = Jb[r, cols[c]]
                Jdc[r, c] = J_dot[r, cols[c]]
        # M += J^T I J, C += J^T (I J_dot + 1/2 A J) (design notes, section 3).
        I = inertia[b]
        _coriolis_kernel(I, Vb, A)
        for i in range(6):
            IJ[i, :nc] = 0.0
            inner[i, :nc] = 0.0
            for j in range(6):
                f, h = I[i, j], 0.5 * A[i, j]
                for c in range(nc):
                    IJ[i, c] += f * Jc[j, c]
                    inner[i, c] += f * Jdc[j, c] + h * Jc[j, c]
        for ci in range(nc):
            row_m[:nc] = 0.0
            row_c[:nc] = 0.0
            for r in range(6):
                f = Jc[r, ci]
                for c in range(nc):
                    row_c[c] += f * inner[r, c]
                for c in range(ci, nc):  # M is symmetric: each pair of columns once
                    row_m[c] += f * IJ[r, c]
            i = cols[ci]
            for c in range(nc):
                C[i, cols[c]] += row_c[c]
            M[i, i] += row_m[ci]
            for c in range(ci + 1, nc):
                M[i, cols[c]] += row_m[c]
                M[cols[c], i] += row_m[c]
        # CoM Jacobian: sum m_i/m R_i P_i J_i, with P_i J_i = J_v - c x J_w, and its
        # derivative sum m_i/m (R_i hat(w_i) P_i J_i + R_i P_i J_dot_i).
        frac = mass[b] / m
        Rb = R_all[b]
        wx, wy, wz = Vb[0], Vb[1], Vb[2]
        cx, cy, cz = com_B[b, 0], com_B[b, 1], com_B[b, 2]
        for c in range(nc):
            k = cols[c]
            ax, ay, az = Jc[0, c], Jc[1, c], Jc[2, c]
            px = Jc[3, c] - (cy * az - cz * ay)
            py = Jc[4, c] - (cz * ax - cx * az)
            pz = Jc[5, c] - (cx * ay - cy * ax)
            ax, ay, az = Jdc[0, c], Jdc[1, c], Jdc[2, c]
            dx = Jdc[3, c] - (cy * az - cz * ay) + (wy * pz - wz * py)
            dy = Jdc[4, c] - (cz * ax - cx * az) + (wz * px - wx * pz)
            dz = Jdc[5, c] - (cx * ay - cy * ax) + (wx * py - wy * px)
            for r in range(3):
                J_g[r, k] += frac * (Rb[r, 0] * px + Rb[r, 1] * py + Rb[r, 2] * pz)
                J_g_dot[r, k] += frac * (Rb[r, 0] * dx + Rb[r, 1] * dy + Rb[r, 2] * dz)
        for r in range(3):
            p_WG[r] += frac * (p_all[b, r] + Rb[r, 0] * cx + Rb[r, 1] * cy + Rb[r, 2] * cz)
    for k in range(nv):
        M[k, k] += reflected[k]
    return m, base, R_all, p_all, J, J_dot_all, M, C, J_g, J_g_dot, p_WG


@_jit
def _z_times_into(G, X, identity, out):
    """out = Z X for the closed-form null-space base Z = [0, -A_q^T, E_n] with A_q = G[:, 6:]
    (design notes, section 2): G = J_g gives Z, G = J_g_dot and ``identity`` False Z_dot.
    Z's four nonzeros a row, written out."""
    for r in range(out.shape[0]):
        g0, g1, g2 = G[0, 6 + r], G[1, 6 + r], G[2, 6 + r]
        for c in range(X.shape[1]):
            s = -g0 * X[3, c] - g1 * X[4, c] - g2 * X[5, c]
            out[r, c] = s + X[6 + r, c] if identity else s


@_jit
def _times_zt_into(X, G, identity, out):
    """out = X Z^T, Z as in _z_times_into."""
    for i in range(X.shape[0]):
        x0, x1, x2 = X[i, 3], X[i, 4], X[i, 5]
        for r in range(out.shape[1]):
            s = -x0 * G[0, 6 + r] - x1 * G[1, 6 + r] - x2 * G[2, 6 + r]
            out[i, r] = s + X[i, 6 + r] if identity else s


@_jit
def _transformation(v, R, M, C, J_g, J_g_dot):
    """T of (3), its derivative, N of (4) and N_dot, and T^-1."""
    nv = v.shape[0]
    n = nv - 6
    J_bw = np.zeros((3, nv))
    J_bw_dot = np.zeros((3, nv))
    # J_bw = [R^T, 0, 0], J_bw_dot = [-hat(R^T w) R^T, 0, 0] (w = v[:3] in World).
    wx = R[0, 0] * v[0] + R[1, 0] * v[1] + R[2, 0] * v[2]
    wy = R[0, 1] * v[0] + R[1, 1] * v[1] + R[2, 1] * v[2]
    wz = R[0, 2] * v[0] + R[1, 2] * v[1] + R[2, 2] * v[2]
    for j in range(3):
        J_bw[0, j], J_bw[1, j], J_bw[2, j] = R[j, 0], R[j, 1], R[j, 2]
        J_bw_dot[0, j] = -(wy * R[j, 2] - wz * R[j, 1])
        J_bw_dot[1, j] = -(wz * R[j, 0] - wx * R[j, 2])
        J_bw_dot[2, j] = -(wx * R[j, 1] - wy * R[j, 0])

    ZM = np.empty((n, nv))
    ZdM = np.empty((n, nv))
    ZMd = np.empty((n, nv))
    ZMZ = np.empty((n, n))
    _z_times_into(J_g, M, True, ZM)
    _times_zt_into(ZM, J_g, True, ZMZ)
    LU, piv = _lu(ZMZ)
    N = _lu_solve(LU, piv, ZM)  # (4)
    _z_times_into(J_g_dot, M, False, ZdM)
    _z_times_into(J_g, C + C.T, True, ZMd)  # Z M_dot, M_dot = C + C^T
    # d/dt (Z M Z^T) = Z_dot M Z^T + Z M_dot Z^T + Z M Z_dot^T
    a, b, c = np.empty((n, n)), np.empty((n, n)), np.empty((n, n))
    _times_zt_into(ZdM, J_g, True, a)
    _times_zt_into(ZMd, J_g, True, b)
    _times_zt_into(ZM, J_g_dot, False, c)
    rhs = ZdM + ZMd
    for i in range(n):
        for k in range(n):
            f = (a[i, k] + b[i, k]) + c[i, k]
            if f != 0.0:
                for j in range(nv):
                    rhs[i, j] -= f * N[k, j]
    N_dot = _lu_solve(LU, piv, rhs)

    T = np.empty((nv, nv))  # (3)
    T_dot = np.empty((nv, nv))
    T[:3], T[3:6], T[6:] = J_g, J_bw, N
    T_dot[:3], T_dot[3:6], T_dot[6:] = J_g_dot, J_bw_dot, N_dot
    return N, N_dot, T, T_dot, _inv(T)


@_jit
def _lambda_gamma(M, C, T_inv, T_dot):
    """Lambda = T^-T M T^-1 (5) and Gamma = T^-T (C - M T^-1 T_dot) T^-1 (6), formed (for
    :func:`decompose`; the law only applies them to vectors)."""
    X = C - _mm(M, _mm(T_inv, T_dot))
    return _mtm(T_inv, _mm(M, T_inv)), _mtm(T_inv, _mm(X, T_inv))


@_jit
def _lambda_times(M, T_inv, y):
    """Lambda y = T^-T (M (T^-1 y)) (5): the law applies Lambda and Gamma to vectors only, so
    it never forms them (13x13 products) but multiplies through."""
    return _mtv(T_inv, _mv(M, _mv(T_inv, y)))


@_jit
def _lambda_gamma_times(M, C, T_inv, T_dot, a, b):
    """Lambda a + Gamma b = T^-T (M T^-1 (a - T_dot u) + C u), u = T^-1 b (5)-(6)."""
    u = _mv(T_inv, b)
    return _mtv(T_inv, _mv(M, _mv(T_inv, a - _mv(T_dot, u))) + _mv(C, u))


@_jit
def _gamma_t_times(M, C, T_inv, T_dot, y):
    """Gamma^T y = T^-T (C^T u - T_dot^T T^-T (M u)), u = T^-1 y (6)."""
    u = _mv(T_inv, y)
    return _mtv(T_inv, _mtv(C, u) - _mtv(T_dot, _mtv(T_inv, _mv(M, u))))


@_jit
def _jt_dot_times(J_y_dot, Jt, T_dot, T_inv, y):
    """Jt_dot y for Jt_dot = (J_y_dot - Jt T_dot) T^-1, the derivative of Jt = J_y T^-1
    (d/dt T^-1 = -T^-1 T_dot T^-1)."""
    u = _mv(T_inv, y)
    return _mv(J_y_dot, u) - _mv(Jt, _mv(T_dot, u))


@_jit
def _embed(nv, first, a):
    """The nv-vector that is ``a`` at ``first:first + len(a)`` and zero elsewhere."""
    out = np.zeros(nv)
    out[first:first + a.shape[0]] = a
    return out


@_jit
def _decompose(q, v, parent, joint_type, q_start, v_start, R_PF, p_PF, R_MC, p_MC, axis_F,
               inertia, mass, com_B, reflected, gravity_W):
    """Every quantity of :class:`aerial_drake.decoupling.Decomposition`, with the same
    formulas (see that module)."""
    m, base, R_all, p_all, J, J_dot_all, M, C, J_g, J_g_dot, p_WG = _body_sums(
        q, v, parent, joint_type, q_start, v_start, R_PF, p_PF, R_MC, p_MC, axis_F, inertia,
        mass, com_B, reflected)
    R = R_all[base]
    g = -m * _mtv(J_g, gravity_W)  # -(gravity generalized force)
    N, N_dot, T, T_dot, T_inv = _transformation(v, R, M, C, J_g, J_g_dot)
    Lambda, Gamma = _lambda_gamma(M, C, T_inv, T_dot)
    xi = _mv(T, v)
    return (m, R, p_all, R_all, J, J_dot_all, M, C, g, J_g, J_g_dot, p_WG, N, N_dot, T, T_dot,
            T_inv, Lambda, Gamma, xi)


# --- Section III -----------------------------------------------------------------------------

@_jit
def _unit_vector_derivatives(a, a_dot, a_ddot):
    """As control.unit_vector_derivatives."""
    n = math.sqrt(_dot(a, a))
    b = a / n
    ad_b = _dot(a_dot, b)
    b_dot = (a_dot - b * ad_b) / n
    b_ddot = (a_ddot - b_dot * ad_b - b * (_dot(a_ddot, b) + _dot(a_dot, b_dot))) / n \
        - b_dot * ad_b / n
    return b, b_dot, b_ddot


@_jit
def _desired_attitude(f_d, f_d_dot, f_d_ddot, b1, b1_dot, b1_ddot):
    """As control.desired_attitude: R_d of (12)-(13) and its first two derivatives."""
    b3, b3_dot, b3_ddot = _unit_vector_derivatives(f_d, f_d_dot, f_d_ddot)  # (12)
    c = _cross(b3, b1)
    c_dot = _cross(b3_dot, b1) + _cross(b3, b1_dot)
    c_ddot = _cross(b3_ddot, b1) + 2.0 * _cross(b3_dot, b1_dot) + _cross(b3, b1_ddot)
    b2, b2_dot, b2_ddot = _unit_vector_derivatives(c, c_dot, c_ddot)
    R_d = np.empty((3, 3))  # (13)
    R_d_dot = np.empty((3, 3))
    R_d_ddot = np.empty((3, 3))
    R_d[:, 0] = _cross(b2, b3)
    R_d_dot[:, 0] = _cross(b2_dot, b3) + _cross(b2, b3_dot)
    R_d_ddot[:, 0] = _cross(b2_ddot, b3) + 2.0 * _cross(b2_dot, b3_dot) + _cross(b2, b3_ddot)
    R_d[:, 1], R_d_dot[:, 1], R_d_ddot[:, 1] = b2, b2_dot, b2_ddot
    R_d[:, 2], R_d_dot[:, 2], R_d_ddot[:, 2] = b3, b3_dot, b3_ddot
    return R_d, R_d_dot, R_d_ddot


@_jit
def _rotation_angle(R):
    c = 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0)
    return math.acos(min(max(c, -1.0), 1.0))


@_jit
def _norm(a):
    return math.sqrt(_dot(a, a))


@_jit
def _law(x, nq, com, task, heading, parent, joint_type, q_start, v_start, R_PF, p_PF, R_MC,
         p_MC, axis_F, inertia, mass, com_B, reflected, ee_body, R_BE, p_BE, q3_q, q3_v, gains,
         limits, command, diagnostics):
    """The law (10)-(22) at state ``x``, as control.compute_control; writes ``command``
    ``[f, mu, tau]`` and ``diagnostics`` (control.DIAGNOSTICS_LAYOUT). Returns
    ``(status, f_d_norm, sigma_min)``; on a status other than OK the outputs are incomplete."""
    for i in range(x.shape[0]):
        if not math.isfinite(x[i]):
            return NONFINITE, 0.0, 0.0
    q, v = x[:nq], x[nq:]
    nv = v.shape[0]
    n = nv - 6
    m, base, R_all, p_all, Jall, J_dot_all, M, C, J_g, J_g_dot, p_WG = _body_sums(
        q, v, parent, joint_type, q_start, v_start, R_PF, p_PF, R_MC, p_MC, axis_F, inertia,
        mass, com_B, reflected)
    R = R_all[base]
    N, N_dot, T, T_dot, T_inv = _transformation(v, R, M, C, J_g, J_g_dot)
    xi = _mv(T, v)
    K_x, D_x, k_R, k_w = gains[0:3], gains[3:6], gains[6], gains[7]
    L2, L2_inv = gains[8:11], gains[11:14]
    K_y, K_z = gains[14:14 + n], gains[14 + n:14 + 2 * n]
    gamma1, gamma2, gravity = gains[14 + 2 * n], gains[15 + 2 * n], gains[16 + 2 * n]
    xg_dot, w_b, rho = xi[:3], xi[3:6], xi[6:]
    x_d, xd1, xd2, xd3, xd4 = com[0:3], com[3:6], com[6:9], com[9:12], com[12:15]
    Re3 = R[:, 2].copy()
    ge3 = np.zeros(3)
    ge3[2] = gravity

    # CoM control (10)-(11).
    x_t = p_WG - x_d
    x_t_dot = xg_dot - xd1
    f_d = m * (xd2 + ge3) - K_x * x_t - D_x * x_t_dot  # (10)
    f_d_norm = _norm(f_d)
    if not f_d_norm > limits[1]:
        return ASSUMPTION_2, f_d_norm, 0.0
    u1 = _dot(f_d, Re3)  # (11)
    xg_dd = u1 * Re3 / m - ge3  # (9a), for the attitude feed-forward
    x_t_dd = xg_dd - xd2
    f_d_dot = m * xd3 - K_x * x_t_dot - D_x * x_t_dd
    e3 = np.zeros(3)
    e3[2] = 1.0
    Re3_dot = _mv(R, _cross(w_b, e3))
    u1_dot = _dot(f_d_dot, Re3) + _dot(f_d, Re3_dot)
    xg_ddd = (u1_dot * Re3 + u1 * Re3_dot) / m
    f_d_ddot = m * xd4 - K_x * x_t_dd - D_x * (xg_ddd - xd3)

    # Attitude control (12)-(16).
    R_d, R_d_dot, R_d_ddot = _desired_attitude(f_d, f_d_dot, f_d_ddot, heading[0:3],
                                               heading[3:6], heading[6:9])
    Omega_d = _vee(_mtm(R_d, R_d_dot))
    Omega_d_dot = _vee(_mtm(R_d_dot, R_d_dot) + _mtm(R_d, R_d_ddot))
    RtRd = _mtm(R, R_d)
    w_d = _mv(RtRd, Omega_d)
    w_d_dot = -_cross(w_b, w_d) + _mv(RtRd, Omega_d_dot)
    RdtR = _mtm(R_d, R)
    e_R = _vee(RdtR)  # (14)
    w_t = w_b - w_d  # (15)
    w_b_dot = w_d_dot - L2_inv * (k_R * e_R + k_w * w_t)
    # u2 = Lambda22 w_b_dot + Gamma22 w_b (16), and Gamma23 rho of (8) with it.
    u2_rho = _lambda_gamma_times(M, C, T_inv, T_dot, _embed(nv, 3, w_b_dot),
                                 _embed(nv, 3, xi[3:]))[3:6]

    # Task kinematics: the end-effector frame E on body ee_body, and q3.
    Ri, pi = R_all[ee_body], p_all[ee_body]
    Ji, Ji_dot = Jall[ee_body], J_dot_all[ee_body]
    w_i = _mv(Ji[:3], v)
    Pp = np.zeros((3, 6))
    Pp[:, :3] = -_hat(p_BE)
    Pp[:, 3:] = np.eye(3)
    top, top_dot = _mm(Pp, Ji), _mm(Pp, Ji_dot)
    Jw, Jw_dot = Ji[:3].copy(), Ji_dot[:3].copy()
    Rw = _mm(Ri, _hat(w_i))
    J_y = np.zeros((n, nv))
    J_y_dot = np.zeros((n, nv))
    J_y[0:3], J_y[3:6] = _mm(Ri, top), _mm(Ri, Jw)
    J_y_dot[0:3] = _mm(Rw, top) + _mm(Ri, top_dot)
    J_y_dot[3:6] = _mm(Rw, Jw) + _mm(Ri, Jw_dot)
    J_y[6, q3_v] = 1.0
    R_WE = _mm(Ri, R_BE)
    p_WE = pi + _mv(Ri, p_BE)

    # Task control (17)-(20).
    Jt = _mm(J_y, T_inv)
    J3 = Jt[:, 6:].copy()
    sigma_min = math.sqrt(max(_min_eigenvalue_sym(_mtm(J3, J3)), 0.0))
    if not sigma_min > limits[0]:
        return ASSUMPTION_1, f_d_norm, sigma_min
    R_ed = task[3:12].copy().reshape((3, 3))
    R_err = _mm(R_WE, R_ed.T)
    y_t = np.empty(n)
    y_t[:3] = p_WE - task[0:3]
    y_t[3:6] = _vee(R_err)
    y_t[6] = x[q3_q] - task[12]
    y_d_dot = np.concatenate((task[13:19], task[19:20]))
    y_d_ddot = np.concatenate((task[20:26], task[26:27]))
    y_t_dot = _mv(Jt, xi) - y_d_dot  # (17)
    z = _mv(J3, rho)
    x12 = _embed(nv, 0, xi[:6])  # [xg_dot; w_b; 0]
    z_d = y_d_dot - _mv(Jt, x12) - K_y * y_t  # J1 xg_dot + J2 w_b = Jt [xg_dot; w_b; 0]
    z_t = z - z_d  # (18)
    a12 = np.zeros(nv)  # [xg_dd; w_b_dot; 0]
    a12[:3], a12[3:6] = xg_dd, w_b_dot
    z_d_dot = (y_d_ddot - _mv(Jt, a12) - _jt_dot_times(J_y_dot, Jt, T_dot, T_inv, x12)
               - K_y * y_t_dot)  # (20)
    # (19): Lambda_z = J3^-T Lambda33 J3^-1, Gamma_z = J3^-T (Gamma33 - Lambda33 J3^-1 J3_dot)
    # J3^-1, applied to vectors.
    J3_inv = _inv(J3)
    s_d = _embed(nv, 6, _mv(J3_inv, z_d))  # [0; 0; J3^-1 z_d]
    J3_dot_s = _jt_dot_times(J_y_dot, Jt, T_dot, T_inv, s_d)
    # Lambda_z z_d_dot + Gamma_z z_d
    #   = J3^-T (Lambda33 J3^-1 (z_d_dot - J3_dot s) + Gamma33 s), s = J3^-1 z_d.
    zz = _mtv(J3_inv, _lambda_gamma_times(M, C, T_inv, T_dot,
                                          _embed(nv, 6, _mv(J3_inv, z_d_dot - J3_dot_s)),
                                          s_d)[6:])
    u3 = _mtv(J3, zz - K_z * z_t)

    # Input mapping (8), (22).
    u_prime = np.concatenate((u1 * Re3, u2_rho,
                              -_gamma_t_times(M, C, T_inv, T_dot, _embed(nv, 3, w_b))[6:] + u3))
    F = _mtv(T, u_prime)  # (22)
    mu = _mtv(R, F[:3])
    force_b = _mtv(R, F[3:6])
    command[0] = force_b[2]
    command[1:4] = mu
    command[4:] = F[6:]

    # Diagnostics (24)-(25), in DIAGNOSTICS_LAYOUT order.
    Lambda_z_zt = _mtv(J3_inv, _lambda_times(M, T_inv, _embed(nv, 6, _mv(J3_inv, z_t)))[6:])
    V_task = 0.5 * _dot(z_t, Lambda_z_zt) + _dot(y_t, K_y * K_z * y_t)  # (24)
    V1 = (0.5 * m * _dot(x_t_dot, x_t_dot) + 0.5 * _dot(x_t, K_x * x_t)
          + gamma1 * _dot(x_t, x_t_dot) + 0.5 * _dot(w_t, L2 * w_t)
          + 0.5 * k_R * (3.0 - RdtR[0, 0] - RdtR[1, 1] - RdtR[2, 2])
          + gamma2 * _dot(e_R, w_t))  # (25)
    k = 0
    for block in (x_t, x_t_dot, e_R, w_t, y_t, z_t):
        diagnostics[k:k + block.shape[0]] = block
        k += block.shape[0]
    scalars = (sigma_min, f_d_norm, V1, V_task, V1 + V_task, _norm(x_t),
               _rotation_angle(RdtR), _norm(y_t[:3]), _rotation_angle(R_err),
               force_b[0], force_b[1])
    for s in scalars:
        diagnostics[k] = s
        k += 1
    return OK, f_d_norm, sigma_min


# --- Python entry points ---------------------------------------------------------------------

def _tree_args(tree: KinematicTree) -> tuple:
    """The tree's arrays in the order the kernels take them (gravity apart: only
    :func:`_decompose` takes it; the law has g among its gains)."""
    return (tree.parent, tree.joint_type, tree.q_start, tree.v_start, tree.R_PF, tree.p_PF,
            tree.R_MC, tree.p_MC, tree.axis_F, tree.spatial_inertia, tree.mass, tree.com_B,
            tree.reflected_inertia)


_DECOMPOSITION_FIELDS = ("m", "R", "p_all", "R_all", "body_J", "body_J_dot", "M", "C", "g",
                         "J_g", "J_g_dot", "p_WG", "N", "N_dot", "T", "T_dot", "T_inv",
                         "Lambda", "Gamma", "xi")


def decompose(tree: KinematicTree, q: np.ndarray, v: np.ndarray) -> dict[str, np.ndarray]:
    """The compiled decomposition at ``(q, v)`` by field name (as in
    :class:`aerial_drake.decoupling.Decomposition`; ``p_all``/``R_all``/``body_J``/
    ``body_J_dot`` are per body of ``tree``). For tests and benchmarks."""
    values = _decompose(np.ascontiguousarray(q, dtype=float),
                        np.ascontiguousarray(v, dtype=float), *_tree_args(tree),
                        tree.gravity_W)
    return dict(zip(_DECOMPOSITION_FIELDS, values))


def pack_gains(K, gravity: float) -> np.ndarray:
    """The gains of a :class:`aerial_drake.control.GainMatrices` and gravity in the order
    ``_law`` reads them."""
    return np.concatenate([K.K_x, K.D_x, [K.k_R, K.k_w], K.Lambda2_bar, K.Lambda2_bar_inv,
                           K.K_y, K.K_z, [K.gamma1, K.gamma2, gravity]]).astype(float)


class CompiledLaw:
    """The law (10)-(22) on ``tree``, compiled: ``law(x, com, task, heading, command,
    diagnostics)`` fills the two output arrays and returns ``(status, f_d_norm, sigma_min)``
    (status :data:`OK`, :data:`ASSUMPTION_1` or :data:`ASSUMPTION_2`).

    Args:
        tree: the controller model's tree (:meth:`KinematicTree.from_plant`).
        num_positions: size of q in the state ``x = [q; v]``.
        end_effector: ``(index of the body in tree, R_BE, p_BE)`` of the task frame E.
        q3_position_index, q3_velocity_index: the task's joint coordinate q3.
        gains: packed by :func:`pack_gains`.
        sigma_min_J3_limit, f_d_limit: the Assumption 1 and 2 thresholds.
    """

    def __init__(self, tree: KinematicTree, num_positions: int,
                 end_effector: tuple[int, np.ndarray, np.ndarray], q3_position_index: int,
                 q3_velocity_index: int, gains: np.ndarray, sigma_min_J3_limit: float,
                 f_d_limit: float):
        body, R_BE, p_BE = end_effector
        self._args = _tree_args(tree) + (
            int(body), np.ascontiguousarray(R_BE, dtype=float),
            np.ascontiguousarray(p_BE, dtype=float), int(q3_position_index),
            int(q3_velocity_index), np.ascontiguousarray(gains, dtype=float),
            np.array([sigma_min_J3_limit, f_d_limit], dtype=float))
        self._nq = int(num_positions)
        self._compile(tree)

    def _compile(self, tree: KinematicTree) -> None:
        """Compile (or load from numba's cache) now, at construction, rather than in the
        middle of the first simulation step: one evaluation at rest, outputs discarded."""
        if _law.signatures:
            return
        try:
            cold = not os.path.exists(_law._cache._cache_file._index_path)
        except AttributeError:  # numba internals moved; the note is only a courtesy
            cold = False
        if cold:
            print("aerial_drake: compiling the control law with numba (first use after "
                  "installing; about a minute, cached afterwards) ...", file=sys.stderr,
                  flush=True)
        nv = tree.reflected_inertia.size
        x = np.zeros(self._nq + nv)
        x[0] = 1.0  # unit quaternion, all else zero
        com, task = np.zeros(COM_REFERENCE_SIZE), np.zeros(TASK_REFERENCE_SIZE)
        heading = np.zeros(HEADING_REFERENCE_SIZE)
        unpack_task_reference(task).R_ed[:] = np.eye(3)  # views into the vectors
        unpack_heading_reference(heading)[0, 0] = 1.0  # b1d = e_x
        self(x, com, task, heading, np.empty(4 + nv - 6), np.empty(DIAGNOSTICS_SIZE))

    def __call__(self, x: np.ndarray, com: np.ndarray, task: np.ndarray, heading: np.ndarray,
                 command: np.ndarray, diagnostics: np.ndarray) -> tuple[int, float, float]:
        return _law(x, self._nq, com, task, heading, *self._args, command, diagnostics)
