"""The compiled decomposition of Section II and the law (10)-(22): the kernels.

:func:`_decompose` computes every quantity of
:class:`~aerial_drake.dynamics.decoupling.Decomposition` and :func:`_law` the law of
:func:`aerial_drake.control.law.compute_control`, with the same formulas in the same order as
the numpy code; :func:`_tracking` the tracking errors of a batch of states
(:mod:`aerial_drake.simulation.tracking`) with :func:`_law`'s statements for them, so equal
to its diagnostics to the bit (and in this file for the same cache reason as below: it must
recompile whenever Section II or the law's kinematics change);
:mod:`aerial_drake.control.compiled.law` holds the Python entry points.

Why this module is longer than the others (some 1000 lines): Section II and the law are one
compile unit. The law's workspace nests Section II's (:func:`_law_buffers` lays out
:func:`_section2_buffers` first, and :func:`_workspace_size` sizes both), :func:`_section2` is
inlined into both :func:`_decompose` and :func:`_law`, and the law reads Section II's buffers
by name throughout. numba's ``cache=True`` keys each kernel's cached machine code on its own
file only: a kernel compiled with callees from another file keeps their old code after they
change until its own file changes. The helpers split out (:mod:`.views`, :mod:`.linalg`,
:mod:`.kinematics`) are small and stable; keeping Section II and the law in one file keeps
the two that change together under one cache stamp. (After editing one of those helper
modules, delete this package's ``__pycache__`` or touch this file so the law recompiles.)
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from aerial_drake.control.compiled.kinematics import (
    _column6,
    _jacobian_derivative,
    _kinematics,
    _row6,
    _unpack_tree,
)
from aerial_drake.control.compiled.linalg import (
    _copy,
    _cross_at,
    _cross_into,
    _dot,
    _hat_into,
    _inv_into,
    _min_eigenvalue_sym,
    _mm_into,
    _mtm_into,
    _mtv_into,
    _mv_into,
    _norm,
    _solve_into,
    _vee_into,
    _zero,
)
from aerial_drake.control.compiled.views import _forceinline, _inline, _jit, _mat, _mats, _vec
from aerial_drake.dynamics.kinematic_tree import FREE

#: Status codes of the law kernel.
OK, ASSUMPTION_2, ASSUMPTION_1, NONFINITE = 0, 1, 2, 3


#: Section II's quantities and scratch space (see :func:`_section2_buffers`).
_SectionII = namedtuple("_SectionII", "R_all p_all axis_W origin_W frames J J_dot sums M C M_dot "
                                      "J_g J_g_dot p_WG V A products T T_dot T_inv T_LU Z ZZ")


@_forceinline
def _section2_buffers(work, at, nb, nv):
    """Section II's buffers in ``work`` from offset ``at``, and the offset after them."""
    n = nv - 6
    R_all, at = _mats(work, at, nb, 3, 3)
    p_all, at = _mat(work, at, nb, 3)
    axis_W, at = _mat(work, at, nb, 3)  # joint axis in World
    origin_W, at = _mat(work, at, nb, 3)  # joint frame M's origin in World
    frames, at = _mats(work, at, 4, 3, 3)  # R_WF, R_FM, R_WM and (row 0 of the last) p_WF
    # The body Jacobians and their derivatives are written at each body's Jacobian columns
    # only: zero elsewhere from the workspace's allocation, as the tree fixes those columns.
    J, at = _mats(work, at, nb, 6, nv)
    J_dot, at = _mats(work, at, nb, 6, nv)
    # The body sums, side by side so that they are zeroed at once.
    sums, at = _vec(work, at, 2 * nv * nv + 6 * nv + 3)
    M, k = _mat(sums, 0, nv, nv)
    C, k = _mat(sums, k, nv, nv)
    J_g, k = _mat(sums, k, 3, nv)
    J_g_dot, k = _mat(sums, k, 3, nv)
    p_WG, k = _vec(sums, k, 3)
    M_dot, at = _mat(work, at, nv, nv)
    V, at = _mat(work, at, 2, 6)  # a body's spatial velocity and a 6-vector of scratch
    A, at = _mat(work, at, 6, 6)
    # I J and the Coriolis product I J_dot + A J / 2 of a body, and a row of J^T I J
    products, at = _mats(work, at, 3, 6, nv)
    T, at = _mat(work, at, nv, nv)
    T_dot, at = _mat(work, at, nv, nv)
    T_inv, at = _mat(work, at, nv, nv)
    T_LU, at = _mat(work, at, nv, nv)
    Z, at = _mats(work, at, 3, n, nv)  # Z M, Z_dot M, Z M_dot
    ZZ, at = _mats(work, at, 5, n, n)  # Z M Z^T, its factorisation and three products
    return (_SectionII(R_all, p_all, axis_W, origin_W, frames, J, J_dot, sums, M, C, M_dot, J_g,
                       J_g_dot, p_WG, V, A, products, T, T_dot, T_inv, T_LU, Z, ZZ),
            at)



# --- Section II ------------------------------------------------------------------------------

@_inline
def _times_crm_into(Y, V, P):
    """P = Y crm(V), crm(V) = [[w x, 0], [v x, w x]] for the spatial velocity V = [w; v]:
    row i is [y_w x w + y_v x v, y_v x w] for Y's row i = [y_w, y_v]."""
    wx, wy, wz, vx, vy, vz = V[0], V[1], V[2], V[3], V[4], V[5]
    for i in range(6):
        a0, a1, a2, a3, a4, a5 = Y[i, 0], Y[i, 1], Y[i, 2], Y[i, 3], Y[i, 4], Y[i, 5]
        P[i, 0] = a1 * wz - a2 * wy + a4 * vz - a5 * vy
        P[i, 1] = a2 * wx - a0 * wz + a5 * vx - a3 * vz
        P[i, 2] = a0 * wy - a1 * wx + a3 * vy - a4 * vx
        P[i, 3] = a4 * wz - a5 * wy
        P[i, 4] = a5 * wx - a3 * wz
        P[i, 5] = a3 * wy - a4 * wx


@_inline
def _add_hbar(A, Y, V, scale):
    """A += scale Hbar(h), h = Y V, Hbar(h) = [[-hat(h_w), -hat(h_v)], [-hat(h_v), 0]]
    (``scale`` 1 or a power of two: h scaled exactly)."""
    h0, h1, h2, h3, h4, h5 = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    for k in range(6):
        h0 += Y[0, k] * V[k]
        h1 += Y[1, k] * V[k]
        h2 += Y[2, k] * V[k]
        h3 += Y[3, k] * V[k]
        h4 += Y[4, k] * V[k]
        h5 += Y[5, k] * V[k]
    if scale != 1.0:
        h0, h1, h2, h3, h4, h5 = (scale * h0, scale * h1, scale * h2, scale * h3, scale * h4,
                                  scale * h5)
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
def _coriolis_kernel(I, Vb, A):
    """A = crf(V) I + I crm(V) + Hbar (crf(V) = -crm(V)^T), the 6x6 matrix of body b's
    Christoffel-consistent Coriolis term (docs/control.md, Coordinates), into ``A``."""
    # I crm(V) (crm(V) = [[w x, 0], [v x, w x]]); crf(V) I = -(I crm(V))^T as I is symmetric.
    _times_crm_into(I, Vb, A)
    for i in range(6):
        for j in range(i + 1, 6):
            d = A[i, j] - A[j, i]
            A[i, j], A[j, i] = d, -d
        A[i, i] = 0.0
    _add_hbar(A, I, Vb, 1.0)  # Hbar of h = I V


@_jit
def _body_sums(v, tree, s):
    """The sums over bodies of Section II: M, the Christoffel-consistent C, the CoM, its
    Jacobian J_g and J_g_dot (into ``s``), and the body Jacobians' derivatives. Returns the
    total mass and the base body's index."""
    nb, nv = tree.parent.shape[0], v.shape[0]
    mass = tree.mass
    m = 0.0
    base = -1
    for b in range(nb):
        m += mass[b]
        if tree.joint_type[b] == FREE:
            base = b

    M, C, J_g, J_g_dot, p_WG = s.M, s.C, s.J_g, s.J_g_dot, s.p_WG
    s.sums[:] = 0.0
    Vb, work, A = s.V[0], s.V[1], s.A
    # The products of body b's mass and Coriolis terms with its Jacobian, over the columns up to
    # its last nonzero one (the others are zero): the loops over columns run over contiguous
    # memory, and add zero where a column is not the body's.
    IJ, inner, row_m = s.products[0], s.products[1], s.products[2, 0]
    for b in range(nb):
        Jb, J_dot = s.J[b], s.J_dot[b]
        width = tree.width[b]
        _mv_into(Jb, v[:width], Vb)  # (the columns from width on are zero)
        nc = tree.num_cols[b]
        cols = tree.cols[b, :nc]
        _jacobian_derivative(Jb, Vb, v, s.R_all[b], cols, J_dot, work)
        if mass[b] == 0.0:
            continue
        # M += J^T I J, C += J^T (I J_dot + 1/2 A J) (docs/control.md, Coordinates).
        I = tree.inertia[b]
        _coriolis_kernel(I, Vb, A)
        for i in range(6):
            f0, f1, f2, f3, f4, f5 = _row6(I, i)
            h0, h1, h2, h3, h4, h5 = 0.5 * A[i, 0], 0.5 * A[i, 1], 0.5 * A[i, 2], \
                0.5 * A[i, 3], 0.5 * A[i, 4], 0.5 * A[i, 5]
            for c in range(width):
                IJ[i, c] = (f0 * Jb[0, c] + f1 * Jb[1, c] + f2 * Jb[2, c] + f3 * Jb[3, c]
                            + f4 * Jb[4, c] + f5 * Jb[5, c])
                inner[i, c] = ((f0 * J_dot[0, c] + h0 * Jb[0, c])
                               + (f1 * J_dot[1, c] + h1 * Jb[1, c])
                               + (f2 * J_dot[2, c] + h2 * Jb[2, c])
                               + (f3 * J_dot[3, c] + h3 * Jb[3, c])
                               + (f4 * J_dot[4, c] + h4 * Jb[4, c])
                               + (f5 * J_dot[5, c] + h5 * Jb[5, c]))
        for ci in range(nc):
            i = cols[ci]
            w0, w1, w2, w3, w4, w5 = _column6(Jb, i)
            for c in range(width):
                C[i, c] += (w0 * inner[0, c] + w1 * inner[1, c] + w2 * inner[2, c]
                            + w3 * inner[3, c] + w4 * inner[4, c] + w5 * inner[5, c])
            # M is symmetric: each pair of columns once, as (ci, c) for c >= ci, into M[i, j]
            # (M[j, i] follows after the sum).
            for c in range(tree.span[b, ci, 0], tree.span[b, ci, 1]):
                row_m[c] = (w0 * IJ[0, c] + w1 * IJ[1, c] + w2 * IJ[2, c] + w3 * IJ[3, c]
                            + w4 * IJ[4, c] + w5 * IJ[5, c])
            for c in range(ci, nc):
                M[i, cols[c]] += row_m[cols[c]]
        # CoM Jacobian: sum m_i/m R_i P_i J_i, with P_i J_i = J_v - c x J_w, and its
        # derivative sum m_i/m (R_i hat(w_i) P_i J_i + R_i P_i J_dot_i) (zero where a column is
        # not the body's).
        frac = mass[b] / m
        Rb = s.R_all[b]
        wx, wy, wz = Vb[0], Vb[1], Vb[2]
        cx, cy, cz = tree.com_B[b, 0], tree.com_B[b, 1], tree.com_B[b, 2]
        for k in range(width):
            ax, ay, az = Jb[0, k], Jb[1, k], Jb[2, k]
            px = Jb[3, k] - (cy * az - cz * ay)
            py = Jb[4, k] - (cz * ax - cx * az)
            pz = Jb[5, k] - (cx * ay - cy * ax)
            ax, ay, az = J_dot[0, k], J_dot[1, k], J_dot[2, k]
            dx = J_dot[3, k] - (cy * az - cz * ay) + (wy * pz - wz * py)
            dy = J_dot[4, k] - (cz * ax - cx * az) + (wz * px - wx * pz)
            dz = J_dot[5, k] - (cx * ay - cy * ax) + (wx * py - wy * px)
            J_g[0, k] += frac * (Rb[0, 0] * px + Rb[0, 1] * py + Rb[0, 2] * pz)
            J_g[1, k] += frac * (Rb[1, 0] * px + Rb[1, 1] * py + Rb[1, 2] * pz)
            J_g[2, k] += frac * (Rb[2, 0] * px + Rb[2, 1] * py + Rb[2, 2] * pz)
            J_g_dot[0, k] += frac * (Rb[0, 0] * dx + Rb[0, 1] * dy + Rb[0, 2] * dz)
            J_g_dot[1, k] += frac * (Rb[1, 0] * dx + Rb[1, 1] * dy + Rb[1, 2] * dz)
            J_g_dot[2, k] += frac * (Rb[2, 0] * dx + Rb[2, 1] * dy + Rb[2, 2] * dz)
        for r in range(3):
            p_WG[r] += frac * (s.p_all[b, r] + Rb[r, 0] * cx + Rb[r, 1] * cy + Rb[r, 2] * cz)
    # Each pair's sum is in one of M[i, j], M[j, i] (the same for all bodies: the order of two
    # joints in a body's columns is the tree's), the other is zero.
    for i in range(nv):
        for j in range(i + 1, nv):
            M[i, j] = M[j, i] = M[i, j] + M[j, i]
        M[i, i] += tree.reflected[i]
    return m, base


@_jit
def _z_times_into(G, X, identity, out):
    """out = Z X for the closed-form null-space base Z = [0, -A_q^T, E_n] with A_q = G[:, 6:]
    (the paper's (3)-(4), Section II): G = J_g gives Z, G = J_g_dot and ``identity`` False Z_dot.
    Z's four nonzeros a row, written out."""
    for r in range(out.shape[0]):
        g0, g1, g2 = G[0, 6 + r], G[1, 6 + r], G[2, 6 + r]
        for c in range(X.shape[1]):
            t = -g0 * X[3, c] - g1 * X[4, c] - g2 * X[5, c]
            out[r, c] = t + X[6 + r, c] if identity else t


@_jit
def _times_zt_into(X, G, identity, out):
    """out = X Z^T, Z as in _z_times_into."""
    for i in range(X.shape[0]):
        x0, x1, x2 = X[i, 3], X[i, 4], X[i, 5]
        for r in range(out.shape[1]):
            t = -x0 * G[0, 6 + r] - x1 * G[1, 6 + r] - x2 * G[2, 6 + r]
            out[i, r] = t + X[i, 6 + r] if identity else t


@_inline
def _base_rows_into(v, R, J_bw, J_bw_dot):
    """T's rows of the base's body angular velocity (3): J_bw = [R^T, 0, 0] and
    J_bw_dot = [-hat(R^T w) R^T, 0, 0] (w = v[:3] in World)."""
    nv = J_bw.shape[1]
    for i in range(3):
        for j in range(3, nv):
            J_bw[i, j], J_bw_dot[i, j] = 0.0, 0.0
    wx = R[0, 0] * v[0] + R[1, 0] * v[1] + R[2, 0] * v[2]
    wy = R[0, 1] * v[0] + R[1, 1] * v[1] + R[2, 1] * v[2]
    wz = R[0, 2] * v[0] + R[1, 2] * v[1] + R[2, 2] * v[2]
    for j in range(3):
        J_bw[0, j], J_bw[1, j], J_bw[2, j] = R[j, 0], R[j, 1], R[j, 2]
        J_bw_dot[0, j] = -(wy * R[j, 2] - wz * R[j, 1])
        J_bw_dot[1, j] = -(wz * R[j, 0] - wx * R[j, 2])
        J_bw_dot[2, j] = -(wx * R[j, 1] - wy * R[j, 0])


@_jit
def _transformation(v, R, s):
    """T of (3) with N of (4) as its last rows, its derivative (N_dot last), and T^-1, into
    ``s.T``, ``s.T_dot``, ``s.T_inv``."""
    T, T_dot, J_g, J_g_dot = s.T, s.T_dot, s.J_g, s.J_g_dot
    _copy(J_g, T[:3])
    _copy(J_g_dot, T_dot[:3])
    # J_bw = [R^T, 0, 0], J_bw_dot = [-hat(R^T w) R^T, 0, 0] (w = v[:3] in World).
    _base_rows_into(v, R, T[3:6], T_dot[3:6])

    ZM, ZdM, ZMd = s.Z[0], s.Z[1], s.Z[2]
    ZMZ, LU, a, b, c = s.ZZ[0], s.ZZ[1], s.ZZ[2], s.ZZ[3], s.ZZ[4]
    N, N_dot = T[6:], T_dot[6:]
    _z_times_into(J_g, s.M, True, ZM)
    _times_zt_into(ZM, J_g, True, ZMZ)
    _copy(ZMZ, LU)
    _copy(ZM, N)
    _solve_into(LU, N)  # (4)
    _z_times_into(J_g_dot, s.M, False, ZdM)
    M_dot = s.M_dot
    for i in range(M_dot.shape[0]):
        for j in range(M_dot.shape[1]):
            M_dot[i, j] = s.C[i, j] + s.C[j, i]
    _z_times_into(J_g, M_dot, True, ZMd)
    # d/dt (Z M Z^T) = Z_dot M Z^T + Z M_dot Z^T + Z M Z_dot^T
    _times_zt_into(ZdM, J_g, True, a)
    _times_zt_into(ZMd, J_g, True, b)
    _times_zt_into(ZM, J_g_dot, False, c)
    n = N.shape[0]
    for i in range(n):
        for j in range(N.shape[1]):
            N_dot[i, j] = ZdM[i, j] + ZMd[i, j]
        for k in range(n):
            f = (a[i, k] + b[i, k]) + c[i, k]
            if f != 0.0:
                for j in range(N.shape[1]):
                    N_dot[i, j] -= f * N[k, j]
    _copy(ZMZ, LU)
    _solve_into(LU, N_dot)
    _inv_into(T, s.T_LU, s.T_inv)


@_inline
def _section2(q, v, tree, s):
    """Kinematics, the body sums and the transformation (3)-(4) at ``(q, v)``, into ``s``.
    Returns the total mass and the base body's index."""
    _kinematics(q, tree, s)
    m, base = _body_sums(v, tree, s)
    _transformation(v, s.R_all[base], s)
    return m, base


@_jit
def _decompose(q, v, model, index, gravity_W, work):
    """Every quantity of :class:`aerial_drake.dynamics.decoupling.Decomposition`, with the same
    formulas (see that module); ``work`` sized by :func:`_section2_buffers`."""
    tree, _, _ = _unpack_tree(model, index)
    s, end = _section2_buffers(work, 0, tree.parent.shape[0], v.shape[0])
    if end > work.shape[0]:
        raise ValueError("workspace too small")
    m, base = _section2(q, v, tree, s)
    g = np.empty(v.shape[0])
    _mtv_into(s.J_g, gravity_W, g)
    g *= -m  # -(gravity generalized force)
    # Lambda = T^-T M T^-1 (5) and Gamma = T^-T (C - M T^-1 T_dot) T^-1 (6).
    nv = v.shape[0]
    X, Y = np.empty((nv, nv)), np.empty((nv, nv))
    _mm_into(s.T_inv, s.T_dot, X)
    _mm_into(s.M, X, Y)
    X[:, :] = s.C - Y
    Lambda, Gamma = np.empty((nv, nv)), np.empty((nv, nv))
    _mm_into(s.M, s.T_inv, Y)
    _mtm_into(s.T_inv, Y, Lambda)
    _mm_into(X, s.T_inv, Y)
    _mtm_into(s.T_inv, Y, Gamma)
    xi = np.empty(nv)
    _mv_into(s.T, v, xi)
    # Copies: the views into work must not outlive the call (see _view).
    return (m, s.R_all[base].copy(), s.p_all.copy(), s.R_all.copy(), s.J.copy(),
            s.J_dot.copy(), s.M.copy(), s.C.copy(), g, s.J_g.copy(), s.J_g_dot.copy(),
            s.p_WG.copy(), s.T[6:].copy(), s.T_dot[6:].copy(), s.T.copy(), s.T_dot.copy(),
            s.T_inv.copy(), Lambda, Gamma, xi)

# --- Section III -----------------------------------------------------------------------------
# Lambda, Gamma and T^-1 meet only vectors here, most of them zero outside one block (e.g.
# [0; w_b_dot; 0]), and only a block of each result is used: each product runs over the
# columns of T^-1 that the nonzero entries meet (the same sums, without the zero terms).

@_jit
def _lambda_gamma_times(M, C, T_inv, a, first, u, T_dot_u, out, out_first, work):
    """Lambda a + Gamma b = T^-T (M T^-1 (a - T_dot u) + C u), u = T^-1 b (5)-(6), for ``a``
    zero outside ``first:first + len(a)``, given ``u`` and ``T_dot u``: its entries from
    ``out_first`` into ``out``. ``work``: three nv-vectors of scratch."""
    r, t, y = work[0], work[1], work[2]
    for i in range(r.shape[0]):
        r[i] = (a[i - first] if first <= i < first + a.shape[0] else 0.0) - T_dot_u[i]
    _mv_into(T_inv, r, t)
    _mv_into(M, t, y)
    _mv_into(C, u, r)
    for i in range(y.shape[0]):
        y[i] += r[i]
    _mtv_into(T_inv, y, out, out_first)


@_jit
def _gamma_t_times(M, C, T_inv, T_dot, u, out, out_first, work):
    """Gamma^T y = T^-T (C^T u - T_dot^T T^-T (M u)), u = T^-1 y (6), given ``u``: its entries
    from ``out_first`` into ``out``. ``work``: three nv-vectors of scratch."""
    r, t, y = work[0], work[1], work[2]
    _mv_into(M, u, r)
    _mtv_into(T_inv, r, t)
    _mtv_into(T_dot, t, r)
    _mtv_into(C, u, y)
    for i in range(y.shape[0]):
        y[i] -= r[i]
    _mtv_into(T_inv, y, out, out_first)


@_jit
def _jt_dot_times(J_y_dot, Jt, u, T_dot_u, out, work):
    """Jt_dot y = J_y_dot u - Jt (T_dot u), u = T^-1 y, for Jt_dot = (J_y_dot - Jt T_dot) T^-1,
    the derivative of Jt = J_y T^-1 (d/dt T^-1 = -T^-1 T_dot T^-1), given ``u`` and
    ``T_dot u``. ``work``: a task vector of scratch."""
    _mv_into(Jt, T_dot_u, work)
    _mv_into(J_y_dot, u, out)
    for i in range(out.shape[0]):
        out[i] -= work[i]


@_jit
def _unit_vector_derivatives(a, a_dot, a_ddot, b, b_dot, b_ddot):
    """As control.unit_vector_derivatives: b = a / |a| and its first two derivatives."""
    n = _norm(a)
    for i in range(3):
        b[i] = a[i] / n
    ad_b = _dot(a_dot, b)
    for i in range(3):
        b_dot[i] = (a_dot[i] - b[i] * ad_b) / n
    e = _dot(a_ddot, b) + _dot(a_dot, b_dot)
    for i in range(3):
        b_ddot[i] = (a_ddot[i] - b_dot[i] * ad_b - b[i] * e) / n - b_dot[i] * ad_b / n


@_jit
def _cross_derivatives(a, a_dot, a_ddot, b, b_dot, b_ddot, c, c_dot, c_ddot):
    """c = a x b and its first two derivatives (product rule)."""
    for i in range(3):
        c[i] = _cross_at(a, b, i)
        c_dot[i] = _cross_at(a_dot, b, i) + _cross_at(a, b_dot, i)
        c_ddot[i] = (_cross_at(a_ddot, b, i) + 2.0 * _cross_at(a_dot, b_dot, i)
                     + _cross_at(a, b_ddot, i))


@_jit
def _desired_attitude(f_d, heading, R_d, work):
    """As control.desired_attitude: R_d of (12)-(13) and its first two derivatives (``R_d[k]``,
    from f_d and its derivatives ``f_d[k]`` and the heading b1 and its derivatives
    ``heading[3 k:3 k + 3]``). ``work``: (9, 3) scratch."""
    b3, b3_dot, b3_ddot = work[0], work[1], work[2]
    c, c_dot, c_ddot = work[3], work[4], work[5]
    b2, b2_dot, b2_ddot = work[6], work[7], work[8]
    _unit_vector_derivatives(f_d[0], f_d[1], f_d[2], b3, b3_dot, b3_ddot)  # (12)
    _cross_derivatives(b3, b3_dot, b3_ddot, heading[0:3], heading[3:6], heading[6:9], c, c_dot,
                       c_ddot)
    _unit_vector_derivatives(c, c_dot, c_ddot, b2, b2_dot, b2_ddot)
    _cross_derivatives(b2, b2_dot, b2_ddot, b3, b3_dot, b3_ddot, c, c_dot, c_ddot)  # b1
    for k in range(3):  # (13): R_d = [b2 x b3, b2, b3]
        for i in range(3):
            R_d[k, i, 0], R_d[k, i, 1], R_d[k, i, 2] = work[3 + k, i], work[6 + k, i], \
                work[k, i]


@_jit
def _weighted_dot(a, k, b):
    """a . (k * b), k elementwise."""
    s = 0.0
    for i in range(a.shape[0]):
        s += a[i] * (k[i] * b[i])
    return s


@_jit
def _rotation_angle(R):
    c = 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0)
    return math.acos(min(max(c, -1.0), 1.0))


#: The packed gains, in the order the law reads them: (name, size), size -1 for the task's n
#: rows; the names are :class:`~aerial_drake.control.law.GainMatrices`' fields and gravity.
#: The one place the order is written: ``pack_gains`` packs by it, :func:`_gain` reads by it
#: and :func:`_packed_gains_size` counts it (here, so the law recompiles when it changes).
GAIN_LAYOUT = (("K_x", 3), ("D_x", 3), ("k_R", 1), ("k_w", 1), ("Lambda2_bar", 3),
               ("Lambda2_bar_inv", 3), ("K_y", -1), ("K_z", -1), ("gamma1", 1), ("gamma2", 1),
               ("gravity", 1))
_GAIN_SIZES = tuple(size for _, size in GAIN_LAYOUT)
_GAIN_AT = {name: i for i, (name, _) in enumerate(GAIN_LAYOUT)}
_K_X, _D_X, _K_R, _K_W = _GAIN_AT["K_x"], _GAIN_AT["D_x"], _GAIN_AT["k_R"], _GAIN_AT["k_w"]
_L2, _L2_INV, _K_Y, _K_Z = (_GAIN_AT["Lambda2_bar"], _GAIN_AT["Lambda2_bar_inv"],
                            _GAIN_AT["K_y"], _GAIN_AT["K_z"])
_GAMMA1, _GAMMA2, _GRAVITY = _GAIN_AT["gamma1"], _GAIN_AT["gamma2"], _GAIN_AT["gravity"]


@_jit
def _packed_gains_size(n):
    """The packed gains' length for a task of ``n`` rows."""
    size = 0
    for s in _GAIN_SIZES:
        size += n if s < 0 else s
    return size


@_inline
def _gain(gains, i, n):
    """Entry ``i`` of :data:`GAIN_LAYOUT` in the packed ``gains`` (a task of ``n`` rows)."""
    start = 0
    for k in range(i):
        start += n if _GAIN_SIZES[k] < 0 else _GAIN_SIZES[k]
    return gains[start:start + (n if _GAIN_SIZES[i] < 0 else _GAIN_SIZES[i])]


@_inline
def _point_map_into(p_BE, hat, Pp):
    """Pp = [-hat(p_BE), E]: a body's spatial velocity [w; v_Bo] (its frame) to the velocity
    of the point p_BE on it (shared by the law and the tracking errors)."""
    _hat_into(p_BE, hat)
    _zero(Pp)
    for i in range(3):
        Pp[i, 3 + i] = 1.0
        for j in range(3):
            Pp[i, j] = -hat[i, j]


@_inline
def _end_effector_pose_into(R_WB, p_WB, R_BE, p_BE, R_WE, p_WE):
    """X_WE = X_WB X_BE, the end-effector frame's pose from its body's (the law and the
    tracking errors share it, so their poses are the same doubles)."""
    _mm_into(R_WB, R_BE, R_WE)
    _mv_into(R_WB, p_BE, p_WE)
    for i in range(3):
        p_WE[i] = p_WB[i] + p_WE[i]


@_inline
def _sigma_min_J3(J_y, T_inv, w):
    """Assumption 1's margin sigma_min(J_3), J_3 the last n columns of J = J_y T^-1 (17);
    leaves J (w.Jt) and J_3 (w.J3) in the workspace for the law."""
    Jt, J3 = w.Jt, w.J3
    _mm_into(J_y, T_inv, Jt)
    _copy(Jt[:, 6:], J3)
    _mtm_into(J3, J3, w.JtJ)
    return math.sqrt(max(_min_eigenvalue_sym(w.JtJ, w.vn[13:17]), 0.0))


#: The law's limits in the packed arrays, in this order: Assumption 1's sigma_min(J_3) and
#: Assumption 2's |f_d| thresholds, and the singularity-robust inverse's lambda_max and eps
#: (control.law.SingularityRobust's damping and threshold; lambda_max 0: off).
LIMITS_SIZE = 4
_SIGMA_LIMIT, _F_D_LIMIT, _DAMPING, _THRESHOLD = 0, 1, 2, 3


@_inline
def _damping_squared(sigma_min, limits):
    """lambda^2 = lambda_max^2 (1 - (sigma_min / eps)^2) below eps, else 0 (Nakamura and
    Hanafusa's / Chiaverini's variable damping; control.law.SingularityRobust.
    damping_squared)."""
    lambda_max, eps = limits[_DAMPING], limits[_THRESHOLD]
    if not (lambda_max > 0.0 and sigma_min < eps):
        return 0.0
    r = sigma_min / eps
    return lambda_max * lambda_max * (1.0 - r * r)


@_jit
def _damped_inverse_into(J3, lambda2, A, out):
    """out = J3^# = (J3^T J3 + lambda2 E)^-1 J3^T, the damped least-squares inverse (``A``:
    scratch of J3's shape)."""
    _mtm_into(J3, J3, A)
    for i in range(A.shape[0]):
        A[i, i] += lambda2
        for j in range(A.shape[1]):
            out[i, j] = J3[j, i]
    _solve_into(A, out)


#: The law's parameters (after the tree in the packed arrays, see CompiledLaw).
_LawParams = namedtuple("_LawParams",
                        "nq ee_body nj rows joint_q joint_v R_BE p_BE gains limits")


@_jit
def _unpack_law(model, index):
    """The tree and the law's parameters packed by :class:`CompiledLaw`."""
    tree, at, k = _unpack_tree(model, index)
    n = tree.reflected.shape[0] - 6
    R_BE, at = _mat(model, at, 3, 3)
    p_BE, at = _vec(model, at, 3)
    gains, at = _vec(model, at, _packed_gains_size(n))
    limits, at = _vec(model, at, LIMITS_SIZE)
    nj = index[k + 2]
    if at != model.shape[0] or k + 3 + n + 2 * nj != index.shape[0]:
        raise ValueError("the packed arrays do not match the tree")
    rows = index[k + 3:k + 3 + n]
    joint_q = index[k + 3 + n:k + 3 + n + nj]
    joint_v = index[k + 3 + n + nj:k + 3 + n + 2 * nj]
    return tree, _LawParams(index[k], index[k + 1], nj, rows, joint_q, joint_v, R_BE, p_BE,
                            gains, limits)


#: The law's buffers (see :func:`_law_buffers`). Stacks of a quantity and its derivatives:
#: ``Re3``, ``x_t`` (x_t, x_t_dot, x_t_dd), ``f_d``, ``R_d``, ``Omega_d``, ``w_d``, ``top``,
#: ``J_y``, ``J6`` (the whole pose's Jacobian), ``y_d`` and ``y_t``; ``z_d`` is z_d, z_d_dot;
#: the other stacks are scratch.
_LawBuffers = namedtuple(
    "_LawBuffers", "xi Re3 x_t f_d xg_dd e3 R_d S3 Omega_d RtRd RdtR w_d e_R w_t w_b_dot u2_rho "
                   "v3 w_i Pp top hat Rw J_y J6 y6 y_d R_WE p_WE Jt J3 JtJ J3_inv R_err y_t z z_d "
                   "z_t a12 u vn vnv u_prime F force_b")


@_forceinline
def _law_buffers(work, nb, nv):
    """Section II's and the law's buffers in ``work``, and the size they take."""
    n = nv - 6
    s, at = _section2_buffers(work, 0, nb, nv)
    xi, at = _vec(work, at, nv)
    Re3, at = _mat(work, at, 2, 3)
    x_t, at = _mat(work, at, 3, 3)
    f_d, at = _mat(work, at, 3, 3)
    xg_dd, at = _vec(work, at, 3)
    e3, at = _vec(work, at, 3)
    R_d, at = _mats(work, at, 3, 3, 3)
    S3, at = _mats(work, at, 2, 3, 3)
    Omega_d, at = _mat(work, at, 2, 3)
    RtRd, at = _mat(work, at, 3, 3)
    RdtR, at = _mat(work, at, 3, 3)
    w_d, at = _mat(work, at, 2, 3)
    e_R, at = _vec(work, at, 3)
    w_t, at = _vec(work, at, 3)
    w_b_dot, at = _vec(work, at, 3)
    u2_rho, at = _vec(work, at, 3)
    v3, at = _mat(work, at, 9, 3)
    w_i, at = _vec(work, at, 3)
    Pp, at = _mat(work, at, 3, 6)
    top, at = _mats(work, at, 3, 3, nv)
    hat, at = _mat(work, at, 3, 3)
    Rw, at = _mat(work, at, 3, 3)
    J_y, at = _mats(work, at, 2, n, nv)
    J6, at = _mats(work, at, 2, 6, nv)
    y6, at = _vec(work, at, 6)
    y_d, at = _mat(work, at, 2, n)
    R_WE, at = _mat(work, at, 3, 3)
    p_WE, at = _vec(work, at, 3)
    Jt, at = _mat(work, at, n, nv)
    J3, at = _mat(work, at, n, n)
    JtJ, at = _mat(work, at, n, n)
    J3_inv, at = _mat(work, at, n, n)
    R_err, at = _mat(work, at, 3, 3)
    y_t, at = _mat(work, at, 2, n)
    z, at = _vec(work, at, n)
    z_d, at = _mat(work, at, 2, n)
    z_t, at = _vec(work, at, n)
    a12, at = _vec(work, at, 6)
    u, at = _mat(work, at, 4, nv)
    vn, at = _mat(work, at, 18, n)
    vnv, at = _mat(work, at, 3, nv)
    u_prime, at = _vec(work, at, nv)
    F, at = _vec(work, at, nv)
    force_b, at = _vec(work, at, 3)
    return s, _LawBuffers(xi, Re3, x_t, f_d, xg_dd, e3, R_d, S3, Omega_d, RtRd, RdtR, w_d, e_R,
                          w_t, w_b_dot, u2_rho, v3, w_i, Pp, top, hat, Rw, J_y, J6, y6, y_d,
                          R_WE, p_WE, Jt,
                          J3, JtJ, J3_inv, R_err, y_t, z, z_d, z_t, a12, u, vn, vnv, u_prime,
                          F, force_b), at


@_jit
def _workspace_size(nb, nv, law):
    """The size of Section II's buffers, and of the law's with them if ``law``."""
    nowhere = np.empty(0)  # the views are not used: only their offsets
    return _law_buffers(nowhere, nb, nv)[-1] if law else _section2_buffers(nowhere, 0, nb, nv)[-1]


@_inline
def _law_gains(gains, n):
    """The law's gains from the packed ``gains`` (GAIN_LAYOUT): (K_x, D_x, k_R, k_w, L2,
    L2_inv, K_y, K_z, gamma1, gamma2, gravity)."""
    return (_gain(gains, _K_X, n), _gain(gains, _D_X, n), _gain(gains, _K_R, n)[0],
            _gain(gains, _K_W, n)[0], _gain(gains, _L2, n), _gain(gains, _L2_INV, n),
            _gain(gains, _K_Y, n), _gain(gains, _K_Z, n), _gain(gains, _GAMMA1, n)[0],
            _gain(gains, _GAMMA2, n)[0], _gain(gains, _GRAVITY, n)[0])


@_inline
def _com_and_attitude(m, R, s, xi, com, heading, K_x, D_x, k_R, k_w, L2_inv, gravity,
                      f_d_limit, M, C, T_inv, T_dot, w):
    """The CoM control (10)-(11) and the attitude control (12)-(16) with u2 and Gamma23 rho
    of (8), into ``w``'s buffers, shared by both kernels. Returns ``(ok, f_d_norm, u1)``;
    ``ok`` False: Assumption 2 fails (|f_d| not above ``f_d_limit``), nothing after (10)."""
    w_b = xi[3:6]
    x_d, xd1, xd2, xd3, xd4 = com[0:3], com[3:6], com[6:9], com[9:12], com[12:15]
    Re3, Re3_dot = w.Re3[0], w.Re3[1]
    x_t, x_t_dot, x_t_dd = w.x_t[0], w.x_t[1], w.x_t[2]
    f_d, f_d_dot, f_d_ddot = w.f_d[0], w.f_d[1], w.f_d[2]
    e3, xg_dd = w.e3, w.xg_dd
    e3[0], e3[1], e3[2] = 0.0, 0.0, 1.0

    # CoM control (10)-(11).
    for i in range(3):
        Re3[i] = R[i, 2]
        x_t[i] = s.p_WG[i] - x_d[i]
        x_t_dot[i] = xi[i] - xd1[i]
        f_d[i] = m * (xd2[i] + gravity * e3[i]) - K_x[i] * x_t[i] - D_x[i] * x_t_dot[i]  # (10)
    f_d_norm = _norm(f_d)
    if not f_d_norm > f_d_limit:
        return False, f_d_norm, 0.0
    u1 = _dot(f_d, Re3)  # (11)
    for i in range(3):  # (9a), for the attitude feed-forward
        xg_dd[i] = u1 * Re3[i] / m - gravity * e3[i]
        x_t_dd[i] = xg_dd[i] - xd2[i]
        f_d_dot[i] = m * xd3[i] - K_x[i] * x_t_dot[i] - D_x[i] * x_t_dd[i]
    w_e3 = w.v3[0]
    _cross_into(w_b, e3, w_e3)
    _mv_into(R, w_e3, Re3_dot)
    u1_dot = _dot(f_d_dot, Re3) + _dot(f_d, Re3_dot)
    for i in range(3):
        xg_ddd = (u1_dot * Re3[i] + u1 * Re3_dot[i]) / m
        f_d_ddot[i] = m * xd4[i] - K_x[i] * x_t_dd[i] - D_x[i] * (xg_ddd - xd3[i])

    # Attitude control (12)-(16).
    R_d = w.R_d
    _desired_attitude(w.f_d, heading, R_d, w.v3)
    Omega_d, Omega_d_dot = w.Omega_d[0], w.Omega_d[1]
    S, S2 = w.S3[0], w.S3[1]
    _mtm_into(R_d[0], R_d[1], S)
    _vee_into(S, Omega_d)
    _mtm_into(R_d[1], R_d[1], S)
    _mtm_into(R_d[0], R_d[2], S2)
    for i in range(3):
        for j in range(3):
            S[i, j] += S2[i, j]
    _vee_into(S, Omega_d_dot)
    RtRd, RdtR, w_d, w_d_dot = w.RtRd, w.RdtR, w.w_d[0], w.w_d[1]
    _mtm_into(R, R_d[0], RtRd)
    _mv_into(RtRd, Omega_d, w_d)
    _mv_into(RtRd, Omega_d_dot, w_d_dot)
    for i in range(3):
        w_d_dot[i] = -_cross_at(w_b, w_d, i) + w_d_dot[i]
    _mtm_into(R_d[0], R, RdtR)
    e_R, w_t, w_b_dot = w.e_R, w.w_t, w.w_b_dot
    _vee_into(RdtR, e_R)  # (14)
    for i in range(3):
        w_t[i] = w_b[i] - w_d[i]  # (15)
        w_b_dot[i] = w_d_dot[i] - L2_inv[i] * (k_R * e_R[i] + k_w * w_t[i])
    # u2 = Lambda22 w_b_dot + Gamma22 w_b (16), and Gamma23 rho of (8) with it.
    u_b, T_dot_u = w.u[0], w.u[3]  # T^-1 [0; w_b; rho]
    _mv_into(T_inv, xi[3:], u_b, 3)
    _mv_into(T_dot, u_b, T_dot_u)
    _lambda_gamma_times(M, C, T_inv, w_b_dot, 3, u_b, T_dot_u, w.u2_rho, 3, w.vnv)
    return True, f_d_norm, u1


@_inline
def _task_errors(x, task, p, R_WE, p_WE, xi, rho, K_y, T_inv, T_dot, n, w):
    """The task's errors and their references, (17)-(18) and (20), into ``w``'s buffers:
    y~, y~', y_d', y_d'', z, z~, z_d and z_d', with J = J_y T^-1 and J_3 in ``w.Jt``,
    ``w.J3`` and J_y_dot in ``w.J_y[1]``; shared by both kernels."""
    Jt, J3, J_y_dot, T_dot_u = w.Jt, w.J3, w.J_y[1], w.u[3]
    xg_dd, w_b_dot = w.xg_dd, w.w_b_dot
    R_err = w.R_err
    _mm_into(R_WE, task[3:12].reshape((3, 3)).T, R_err)
    y_t, y_t_dot, y6 = w.y_t[0], w.y_t[1], w.y6
    for i in range(3):
        y6[i] = p_WE[i] - task[i]
    _vee_into(R_err, y6[3:6])
    # The task reference's full y_d_dot, y_d_ddot blocks (reference.TaskReferenceLayout).
    nj = p.nj
    full_dot, full_ddot = task[12 + nj:18 + 2 * nj], task[18 + 2 * nj:24 + 3 * nj]
    y_d_dot, y_d_ddot = w.y_d[0], w.y_d[1]
    for i in range(n):
        r = p.rows[i]
        if r < 6:
            y_t[i] = y6[r]
        else:
            y_t[i] = x[p.joint_q[r - 6]] - task[12 + r - 6]
        y_d_dot[i], y_d_ddot[i] = full_dot[r], full_ddot[r]
    _mv_into(Jt, xi, y_t_dot)
    for i in range(n):
        y_t_dot[i] -= y_d_dot[i]  # (17)
    z, z_t, z_d, z_d_dot = w.z, w.z_t, w.z_d[0], w.z_d[1]
    _mv_into(J3, rho, z)
    Jx12, Ja12, jt_dot_x12 = w.vn[0], w.vn[1], w.vn[2]
    _mv_into(Jt, xi[:6], Jx12)  # J1 xg_dot + J2 w_b = Jt [xg_dot; w_b; 0]
    for i in range(n):
        z_d[i] = y_d_dot[i] - Jx12[i] - K_y[i] * y_t[i]
        z_t[i] = z[i] - z_d[i]  # (18)
    a12 = w.a12  # [xg_dd; w_b_dot]
    for i in range(3):
        a12[i], a12[3 + i] = xg_dd[i], w_b_dot[i]
    _mv_into(Jt, a12, Ja12)
    u_x12 = w.u[1]
    _mv_into(T_inv, xi[:6], u_x12)
    _mv_into(T_dot, u_x12, T_dot_u)
    _jt_dot_times(J_y_dot, Jt, u_x12, T_dot_u, jt_dot_x12, w.vn[17])
    for i in range(n):
        z_d_dot[i] = y_d_ddot[i] - Ja12[i] - jt_dot_x12[i] - K_y[i] * y_t_dot[i]  # (20)


@_inline
def _apply_inputs(T, R, command, n, w):
    """(22): the generalized force F = T^T u' from ``w.u_prime``, then the command
    ``[f, mu, tau]``: the thrust and body torques in the vehicle's axes, the joint torques."""
    u_prime, F, force_b = w.u_prime, w.F, w.force_b
    _mtv_into(T, u_prime, F)  # (22)
    mu = w.v3[0]
    _mtv_into(R, F[:3], mu)
    _mtv_into(R, F[3:6], force_b)
    command[0] = force_b[2]
    for i in range(3):
        command[1 + i] = mu[i]
    for i in range(n):
        command[4 + i] = F[6 + i]


@_inline
def _write_diagnostics(diagnostics, m, V_task, sigma_min, f_d_norm, K_x, L2, k_R, gamma1,
                       gamma2, w):
    """V1 of (25), and the diagnostics in diagnostics_layout(n) order, from ``w``'s
    buffers and the law's ``V_task`` (24); shared by both kernels."""
    x_t, x_t_dot, e_R, w_t, RdtR = w.x_t[0], w.x_t[1], w.e_R, w.w_t, w.RdtR
    y_t, z_t, y6, R_err, force_b = w.y_t[0], w.z_t, w.y6, w.R_err, w.force_b
    V1 = (0.5 * m * _dot(x_t_dot, x_t_dot) + 0.5 * _weighted_dot(x_t, K_x, x_t)
          + gamma1 * _dot(x_t, x_t_dot) + 0.5 * _weighted_dot(w_t, L2, w_t)
          + 0.5 * k_R * (3.0 - RdtR[0, 0] - RdtR[1, 1] - RdtR[2, 2])
          + gamma2 * _dot(e_R, w_t))  # (25)
    k = 0
    for block in (x_t, x_t_dot, e_R, w_t, y_t, z_t):
        for i in range(block.shape[0]):
            diagnostics[k] = block[i]
            k += 1
    scalars = (sigma_min, f_d_norm, V1, V_task, V1 + V_task, _norm(x_t),
               _rotation_angle(RdtR), _norm(y6[:3]), _rotation_angle(R_err),
               force_b[0], force_b[1])
    for value in scalars:
        diagnostics[k] = value
        k += 1


@_jit
def _law(x, com, task, heading, command, diagnostics, model, index, work):
    """The law (10)-(22) at state ``x``, as control.compute_control; writes ``command``
    ``[f, mu, tau]`` and ``diagnostics`` (control.law.diagnostics_layout(n)). Returns
    ``(status, f_d_norm, sigma_min)``; on a status other than OK the outputs are incomplete.
    ``model``, ``index``: packed by CompiledLaw; ``work``: sized by :func:`_law_buffers`."""
    for i in range(x.shape[0]):
        if not math.isfinite(x[i]):
            return NONFINITE, 0.0, 0.0
    tree, p = _unpack_law(model, index)
    nv = tree.reflected.shape[0]
    n = nv - 6
    s, w, end = _law_buffers(work, tree.parent.shape[0], nv)
    if end > work.shape[0]:
        raise ValueError("workspace too small")
    q, v = x[:p.nq], x[p.nq:]
    m, base = _section2(q, v, tree, s)
    R, M, C, T, T_dot, T_inv = s.R_all[base], s.M, s.C, s.T, s.T_dot, s.T_inv
    xi = w.xi
    _mv_into(T, v, xi)
    K_x, D_x, k_R, k_w, L2, L2_inv, K_y, K_z, gamma1, gamma2, gravity = _law_gains(p.gains, n)
    ok, f_d_norm, u1 = _com_and_attitude(m, R, s, xi, com, heading, K_x, D_x, k_R, k_w, L2_inv,
                                         gravity, p.limits[_F_D_LIMIT], M, C, T_inv, T_dot, w)
    if not ok:
        return ASSUMPTION_2, f_d_norm, 0.0
    w_b, rho = xi[3:6], xi[6:]
    Re3, T_dot_u = w.Re3[0], w.u[3]

    # Task kinematics: the end-effector frame E on body ee_body, and the task's joints.
    Ri, pi = s.R_all[p.ee_body], s.p_all[p.ee_body]
    Ji, Ji_dot = s.J[p.ee_body], s.J_dot[p.ee_body]
    w_i = w.w_i
    _mv_into(Ji[:3], v, w_i)
    Pp = w.Pp
    _point_map_into(p.p_BE, w.hat, Pp)
    top, top_dot, tmp = w.top[0], w.top[1], w.top[2]
    _mm_into(Pp, Ji, top)
    _mm_into(Pp, Ji_dot, top_dot)
    Rw = w.Rw
    _hat_into(w_i, w.hat)
    _mm_into(Ri, w.hat, Rw)
    J6, J6_dot = w.J6[0], w.J6[1]  # [v_E; w_E] of the whole pose
    _mm_into(Ri, top, J6[0:3])
    _mm_into(Ri, Ji[:3], J6[3:6])
    for (k, A, A_dot) in ((0, top, top_dot), (3, Ji[:3], Ji_dot[:3])):
        _mm_into(Rw, A, J6_dot[k:k + 3])
        _mm_into(Ri, A_dot, tmp)
        for i in range(3):
            for j in range(nv):
                J6_dot[k + i, j] += tmp[i, j]
    # The task's rows of [J6; joint rows] (robots.task: row r < 6 a pose row, else a joint).
    J_y, J_y_dot = w.J_y[0], w.J_y[1]
    for i in range(n):
        r = p.rows[i]
        for j in range(nv):
            if r < 6:
                J_y[i, j], J_y_dot[i, j] = J6[r, j], J6_dot[r, j]
            else:
                J_y[i, j], J_y_dot[i, j] = 0.0, 0.0
        if r >= 6:
            J_y[i, p.joint_v[r - 6]] = 1.0
    R_WE, p_WE = w.R_WE, w.p_WE
    _end_effector_pose_into(Ri, pi, p.R_BE, p.p_BE, R_WE, p_WE)

    # Task control (17)-(20).
    sigma_min = _sigma_min_J3(J_y, T_inv, w)
    Jt, J3 = w.Jt, w.J3
    # With the damped inverse on, no Assumption 1 stop (the caller checks control is kept).
    if p.limits[_DAMPING] == 0.0 and not sigma_min > p.limits[_SIGMA_LIMIT]:
        return ASSUMPTION_1, f_d_norm, sigma_min
    lambda2 = _damping_squared(sigma_min, p.limits)
    _task_errors(x, task, p, R_WE, p_WE, xi, rho, K_y, T_inv, T_dot, n, w)
    Jt, J3, J_y_dot, y_t, z_t, z_d, z_d_dot = (w.Jt, w.J3, w.J_y[1], w.y_t[0], w.z_t,
                                               w.z_d[0], w.z_d[1])
    # (19): Lambda_z = J3^-T Lambda33 J3^-1, Gamma_z = J3^-T (Gamma33 - Lambda33 J3^-1 J3_dot)
    # J3^-1, applied to vectors. Damped (lambda2 > 0): J3^# in place of J3^-1 (below).
    J3_inv = w.J3_inv
    if lambda2 > 0.0:
        _damped_inverse_into(J3, lambda2, w.JtJ, J3_inv)
    else:
        _inv_into(J3, w.JtJ, J3_inv)
    s_d, J3_dot_s, d, a3, lg = w.vn[3], w.vn[4], w.vn[5], w.vn[6], w.vn[7]
    _mv_into(J3_inv, z_d, s_d)  # s = J3^-1 z_d
    u_s = w.u[2]  # T^-1 [0; 0; s]
    _mv_into(T_inv, s_d, u_s, 6)
    _mv_into(T_dot, u_s, T_dot_u)
    _jt_dot_times(J_y_dot, Jt, u_s, T_dot_u, J3_dot_s, w.vn[17])
    # Lambda_z z_d_dot + Gamma_z z_d
    #   = J3^-T (Lambda33 J3^-1 (z_d_dot - J3_dot s) + Gamma33 s).
    for i in range(n):
        d[i] = z_d_dot[i] - J3_dot_s[i]
    _mv_into(J3_inv, d, a3)
    _lambda_gamma_times(M, C, T_inv, a3, 6, u_s, T_dot_u, lg, 6, w.vnv)
    zz, u3 = w.vn[8], w.vn[9]
    if lambda2 > 0.0:
        # u3 = Lambda33 rho_d' + Gamma33 rho_d - J3^T K_z z~ with rho_d = J3^# z_d = s and
        # rho_d' = J3^# (z_d' - J3_dot s) = a3: the product J3^T J3^-T of the undamped
        # u3 = J3^T J3^-T lg - J3^T K_z z~ kept as the identity (control.law.compute_control).
        for i in range(n):
            zz[i] = K_z[i] * z_t[i]
        _mtv_into(J3, zz, u3)
        for i in range(n):
            u3[i] = lg[i] - u3[i]
    else:
        _mtv_into(J3_inv, lg, zz)
        for i in range(n):
            zz[i] = zz[i] - K_z[i] * z_t[i]
        _mtv_into(J3, zz, u3)

    # Input mapping (8), (22).
    u_prime = w.u_prime
    for i in range(3):
        u_prime[i], u_prime[3 + i] = u1 * Re3[i], w.u2_rho[i]
    u_w = w.u[0]  # T^-1 [0; w_b; 0]
    _mv_into(T_inv, w_b, u_w, 3)
    _gamma_t_times(M, C, T_inv, T_dot, u_w, u_prime[6:], 6, w.vnv)
    for i in range(n):
        u_prime[6 + i] = -u_prime[6 + i] + u3[i]
    _apply_inputs(T, R, command, n, w)

    # Diagnostics (24)-(25), in diagnostics_layout(n) order.
    s_t, Lz, Lambda_z_zt = w.vn[10], w.vn[11], w.vn[12]
    _mv_into(J3_inv, z_t, s_t)
    u_t, Mu = w.u[0], w.vnv[0]  # Lambda [0; 0; s_t] = T^-T (M (T^-1 [0; 0; s_t])) (5)
    _mv_into(T_inv, s_t, u_t, 6)
    _mv_into(M, u_t, Mu)
    _mtv_into(T_inv, Mu, Lz, 6)
    _mtv_into(J3_inv, Lz, Lambda_z_zt)
    t = 0.0
    for i in range(n):
        t += y_t[i] * (K_y[i] * K_z[i] * y_t[i])
    V_task = 0.5 * _dot(z_t, Lambda_z_zt) + t  # (24)
    _write_diagnostics(diagnostics, m, V_task, sigma_min, f_d_norm, K_x, L2, k_R, gamma1,
                       gamma2, w)
    return OK, f_d_norm, sigma_min


@_jit
def _tracking(X, com, task, heading, out, model, index, work):
    """The tracking errors at each row of ``X`` (states, as the law's ``x``) and of the
    references ``com``, ``task``, ``heading`` (one row per sample), into ``out``'s rows in
    simulation.tracking.tracking_layout(n) order; a row with a non-finite state is NaN.

    The same quantities as the law's diagnostics of the same names, by the same kernels in
    the same order (so equal to the bit): Section II, the end-effector kinematics, J3 and the
    task error of :func:`_law`, without the control. ``model``, ``index``: packed as for
    CompiledLaw (its gains and limits are not read); ``work``: sized by :func:`_law_buffers`.
    """
    tree, p = _unpack_law(model, index)
    nv = tree.reflected.shape[0]
    n = nv - 6
    s, w, end = _law_buffers(work, tree.parent.shape[0], nv)
    if end > work.shape[0]:
        raise ValueError("workspace too small")
    for k in range(X.shape[0]):
        x, row = X[k], out[k]
        finite = True
        for i in range(x.shape[0]):
            if not math.isfinite(x[i]):
                finite = False
        if not finite:
            for i in range(row.shape[0]):
                row[i] = math.nan
            continue
        _tracking_row(x, com[k], task[k], heading[k], row, tree, p, s, w, n, nv)


@_jit
def _tracking_row(x, com, task, heading, row, tree, p, s, w, n, nv):
    """One row of :func:`_tracking` (the statements are :func:`_law`'s, in its order)."""
    q, v = x[:p.nq], x[p.nq:]
    m, base = _section2(q, v, tree, s)
    R, T, T_inv = s.R_all[base], s.T, s.T_inv
    xi = w.xi
    _mv_into(T, v, xi)
    x_t, x_t_dot = w.x_t[0], w.x_t[1]
    for i in range(3):
        x_t[i] = s.p_WG[i] - com[i]
        x_t_dot[i] = xi[i] - com[3 + i]
    # The end-effector frame's pose and World Jacobian [v_E; w_E], and the task's rows.
    Ri, pi, Ji = s.R_all[p.ee_body], s.p_all[p.ee_body], s.J[p.ee_body]
    Pp = w.Pp
    _point_map_into(p.p_BE, w.hat, Pp)
    top, J6, J_y = w.top[0], w.J6[0], w.J_y[0]
    _mm_into(Pp, Ji, top)
    _mm_into(Ri, top, J6[0:3])
    _mm_into(Ri, Ji[:3], J6[3:6])
    for i in range(n):
        r = p.rows[i]
        for j in range(nv):
            J_y[i, j] = J6[r, j] if r < 6 else 0.0
        if r >= 6:
            J_y[i, p.joint_v[r - 6]] = 1.0
    R_WE, p_WE = w.R_WE, w.p_WE
    _end_effector_pose_into(Ri, pi, p.R_BE, p.p_BE, R_WE, p_WE)
    # Assumption 1's margin.
    sigma_min = _sigma_min_J3(J_y, T_inv, w)
    # The task error (17)-(18): rows of [p_E - p_ed; vee(skew(R_E R_ed^T)); q_j - q_jd].
    R_err, y_t, y6 = w.R_err, w.y_t[0], w.y6
    _mm_into(R_WE, task[3:12].reshape((3, 3)).T, R_err)
    for i in range(3):
        y6[i] = p_WE[i] - task[i]
    _vee_into(R_err, y6[3:6])
    for i in range(n):
        r = p.rows[i]
        y_t[i] = y6[r] if r < 6 else x[p.joint_q[r - 6]] - task[12 + r - 6]
    k = 0
    for block in (x_t, x_t_dot, y_t):
        for i in range(block.shape[0]):
            row[k] = block[i]
            k += 1
    # The heading: the angle about b3 = R e3 from the base's x axis b1 = R e1 to the heading
    # reference b1d projected on the plane normal to b3 (Lee et al.'s b1 of R_d, with the
    # base's own b3); and the tilt, the angle of b3 from World z.
    b1d = heading[0:3]
    along = R[0, 2] * b1d[0] + R[1, 2] * b1d[1] + R[2, 2] * b1d[2]
    c, sn = 0.0, 0.0
    for i in range(3):
        proj = b1d[i] - along * R[i, 2]
        c += R[i, 0] * proj
        sn += R[i, 1] * proj  # (b1 x proj) . b3 = b2 . proj
    scalars = (sigma_min, _norm(x_t), _norm(y6[:3]), _rotation_angle(R_err),
               abs(math.atan2(sn, c)), math.acos(min(max(R[2, 2], -1.0), 1.0)))
    for value in scalars:
        row[k] = value
        k += 1
