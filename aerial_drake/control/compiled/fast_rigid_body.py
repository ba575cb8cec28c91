"""The rigid-body part of the fast law (:mod:`.fast_law`): M, the Christoffel-consistent C,
the CoM, J_g and J_g_dot, and the end-effector body's Jacobian and its derivative, by
recursions over the tree (as Pinocchio's ``crba`` and ``computeCoriolisMatrix``) instead of
the exact kernel's sums over bodies of J^T I J and J^T (I J_dot + A J / 2)
(:func:`.kernels._body_sums`, which also forms every body's Jacobian and its derivative).
The same quantities to round-off, not to the bit.

Everything is in World, spatial vectors ``[w; v]`` about World's origin (docs/control.md,
"The fast kernel"):

- S_k, the motion of velocity k: ``[a; o x a]`` for a revolute joint (axis a through o),
  ``[e_j; o x e_j]`` and ``[0; e_j]`` for the free joint's angular and linear velocities (o
  its frame's origin, whose velocity those are); V_b = V_parent + sum S_k v_k over b's joint.
- S_k's derivative: crm(V_parent) S_k (the joint's axis moves with the parent), plus
  ``[0; v_o x e_j]`` for the free joint's angular columns (its origin o moves).
- Y_b, body b's spatial inertia about World's origin, and B_b = (crf(V_b) Y_b - Y_b crm(V_b)
  + crfbar(Y_b V_b)) / 2, the exact kernel's per-body Coriolis term (crf(V) I + I crm(V) +
  Hbar) / 2 carried to World (crfbar(h) x = crf(x) h); Yc, Bc their sums over a body's
  subtree (composite).
- For velocity k of body b and every velocity j of b or of its ancestors:
  M[j, k] = S_j . Yc_b S_k, C[j, k] = S_j . (Yc_b S_k_dot + Bc_b S_k) and, for j of a strict
  ancestor, C[k, j] = Yc_b S_k . S_j_dot + Bc_b^T S_k . S_j (the sums over bodies of
  J^T Y J and J^T (Y J_dot + B J), taken in the subtree that both columns reach).
- J_g = M's linear rows of the free joint over the total mass (the linear momentum is
  m J_g v), before the reflected inertias; J_g_dot = the same rows of M_dot = C + C^T.

numba caches the fast law keyed on :mod:`.fast_law` only: touch that file after editing this
one.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from aerial_drake.control.compiled.kernels import (
    _add_hbar,
    _section2_buffers,
    _times_crm_into,
    _workspace_size,
)
from aerial_drake.control.compiled.kinematics import _pack_tree, _poses, _unpack_tree
from aerial_drake.control.compiled.views import _forceinline, _inline, _jit, _mat, _mats
from aerial_drake.dynamics.kinematic_tree import FREE, REVOLUTE, KinematicTree

#: The recursions' buffers (see :func:`_fast_rb_buffers`): the motion columns S and their
#: derivatives (one row per velocity), each body's spatial velocity in World, the composite
#: inertias Yc and Coriolis terms Bc, and scratch (Y crm(V) of a body; F: three 6-vectors).
_FastRB = namedtuple("_FastRB", "S S_dot V Yc Bc P F")


def fast_rigid_body_size(nb: int, nv: int) -> int:
    """The size of :func:`_fast_rb_buffers`' buffers for ``nb`` bodies and ``nv`` velocities
    (the fast law's workspace is the exact law's and this much more)."""
    return 12 * nv + 6 * nb + 72 * nb + 36 + 18


@_forceinline
def _fast_rb_buffers(work, at, nb, nv):
    """The recursions' buffers in ``work`` from offset ``at``, and the offset after them."""
    S, at = _mat(work, at, nv, 6)
    S_dot, at = _mat(work, at, nv, 6)
    V, at = _mat(work, at, nb, 6)
    Yc, at = _mats(work, at, nb, 6, 6)
    Bc, at = _mats(work, at, nb, 6, 6)
    P, at = _mat(work, at, 6, 6)
    F, at = _mat(work, at, 3, 6)
    return _FastRB(S, S_dot, V, Yc, Bc, P, F), at


@_inline
def _crm_into(V, a, out):
    """out = crm(V) a = V x a for spatial motion vectors (out a row of a matrix)."""
    wx, wy, wz, ux, uy, uz = V[0], V[1], V[2], V[3], V[4], V[5]
    out[0] = wy * a[2] - wz * a[1]
    out[1] = wz * a[0] - wx * a[2]
    out[2] = wx * a[1] - wy * a[0]
    out[3] = uy * a[2] - uz * a[1] + wy * a[5] - wz * a[4]
    out[4] = uz * a[0] - ux * a[2] + wz * a[3] - wx * a[5]
    out[5] = ux * a[1] - uy * a[0] + wx * a[4] - wy * a[3]


@_inline
def _world_inertia_into(I_B, m, c_B, R, p, Y, mc):
    """Y: the spatial inertia about World's origin in World of a body of mass m, centre of
    mass c_B and rotational inertia I_B about its origin (both in its frame), at pose (R, p);
    m times the centre of mass in World added to ``mc``."""
    cx = p[0] + R[0, 0] * c_B[0] + R[0, 1] * c_B[1] + R[0, 2] * c_B[2]
    cy = p[1] + R[1, 0] * c_B[0] + R[1, 1] * c_B[1] + R[1, 2] * c_B[2]
    cz = p[2] + R[2, 0] * c_B[0] + R[2, 1] * c_B[1] + R[2, 2] * c_B[2]
    # About the centre of mass in the body frame: I_B - m hat(c_B) hat(c_B)^T.
    bx, by, bz = c_B[0], c_B[1], c_B[2]
    bb = bx * bx + by * by + bz * bz
    G00 = I_B[0, 0] - m * (bb - bx * bx)
    G11 = I_B[1, 1] - m * (bb - by * by)
    G22 = I_B[2, 2] - m * (bb - bz * bz)
    G01 = I_B[0, 1] + m * bx * by
    G02 = I_B[0, 2] + m * bx * bz
    G12 = I_B[1, 2] + m * by * bz
    # R G R^T + m hat(c) hat(c)^T, with G's rows times R^T first.
    cc = cx * cx + cy * cy + cz * cz
    for i in range(3):
        r0, r1, r2 = R[i, 0], R[i, 1], R[i, 2]
        t0 = G00 * r0 + G01 * r1 + G02 * r2
        t1 = G01 * r0 + G11 * r1 + G12 * r2
        t2 = G02 * r0 + G12 * r1 + G22 * r2
        for j in range(i, 3):
            Y[i, j] = R[j, 0] * t0 + R[j, 1] * t1 + R[j, 2] * t2
    cW = (cx, cy, cz)
    for i in range(3):
        Y[i, i] += m * cc
        for j in range(i, 3):
            Y[i, j] -= m * cW[i] * cW[j]
            Y[j, i] = Y[i, j]
    # m hat(c) and its transpose, and m E.
    for i in range(3):
        for j in range(3):
            Y[3 + i, 3 + j] = m if i == j else 0.0
            Y[i, 3 + j] = 0.0
        Y[i, 3 + i] = 0.0
    Y[0, 4], Y[0, 5], Y[1, 5] = -m * cz, m * cy, -m * cx
    Y[1, 3], Y[2, 3], Y[2, 4] = m * cz, -m * cy, m * cx
    for i in range(3):
        for j in range(3):
            Y[3 + j, i] = Y[i, 3 + j]
    mc[0] += m * cx
    mc[1] += m * cy
    mc[2] += m * cz


@_inline
def _coriolis_world_into(Y, V, P, B):
    """B = (crf(V) Y - Y crm(V) + crfbar(Y V)) / 2 (module docstring), with P = Y crm(V)
    (crf(V) Y = -P^T, Y being symmetric)."""
    _times_crm_into(Y, V, P)
    for i in range(6):
        for j in range(i, 6):
            d = -0.5 * (P[i, j] + P[j, i])
            B[i, j], B[j, i] = d, d
    _add_hbar(B, Y, V, 0.5)  # crfbar(Y V) / 2


@_inline
def _joint_width(joint_type):
    """The number of velocities of a joint."""
    if joint_type == FREE:
        return 6
    if joint_type == REVOLUTE:
        return 1
    return 0


@_jit
def _fast_rigid_body(q, v, tree, s, f):
    """Section II's rigid-body quantities by the recursions of the module docstring: body poses,
    M, C, J_g, J_g_dot and the CoM into ``s`` (Section II's buffers, as
    :func:`.kernels._body_sums`; not the body Jacobians), the motion columns and their
    derivatives into ``f`` (the buffers of :func:`_fast_rb_buffers`). Returns the total mass
    and the base body's index."""
    nb, nv = tree.parent.shape[0], v.shape[0]
    parent, joint_type, v_start = tree.parent, tree.joint_type, tree.v_start
    _poses(q, tree, s)
    M, C, J_g, J_g_dot, p_WG = s.M, s.C, s.J_g, s.J_g_dot, s.p_WG
    s.sums[:] = 0.0
    S, S_dot, V, Yc, Bc, P = f.S, f.S_dot, f.V, f.Yc, f.Bc, f.P
    m = 0.0
    base = -1
    # Forward: the motion columns and their derivatives, the bodies' velocities, inertias and
    # Coriolis terms.
    for b in range(nb):
        Pb = parent[b]
        for i in range(6):
            V[b, i] = V[Pb, i] if Pb >= 0 else 0.0
        k0, o, a = v_start[b], s.origin_W[b], s.axis_W[b]
        if joint_type[b] == REVOLUTE:
            S[k0, 0], S[k0, 1], S[k0, 2] = a[0], a[1], a[2]
            S[k0, 3] = o[1] * a[2] - o[2] * a[1]
            S[k0, 4] = o[2] * a[0] - o[0] * a[2]
            S[k0, 5] = o[0] * a[1] - o[1] * a[0]
        elif joint_type[b] == FREE:
            base = b
            for j in range(6):
                for i in range(6):
                    S[k0 + j, i] = 0.0
            for j in range(3):
                S[k0 + j, j] = 1.0
                S[k0 + 3 + j, 3 + j] = 1.0
            S[k0, 4], S[k0, 5] = o[2], -o[1]  # o x e_x
            S[k0 + 1, 3], S[k0 + 1, 5] = -o[2], o[0]
            S[k0 + 2, 3], S[k0 + 2, 4] = o[1], -o[0]
        nj = _joint_width(joint_type[b])
        for j in range(k0, k0 + nj):
            if Pb >= 0:
                _crm_into(V[Pb], S[j], S_dot[j])
            else:
                for i in range(6):
                    S_dot[j, i] = 0.0
        if joint_type[b] == FREE:  # [0; v_o x e_j] on the angular columns
            ux, uy, uz = v[k0 + 3], v[k0 + 4], v[k0 + 5]
            S_dot[k0, 4] += uz
            S_dot[k0, 5] -= uy
            S_dot[k0 + 1, 3] -= uz
            S_dot[k0 + 1, 5] += ux
            S_dot[k0 + 2, 3] += uy
            S_dot[k0 + 2, 4] -= ux
        for j in range(k0, k0 + nj):
            for i in range(6):
                V[b, i] += S[j, i] * v[j]
        mb = tree.mass[b]
        m += mb
        if mb == 0.0:
            for i in range(6):
                for j in range(6):
                    Yc[b, i, j], Bc[b, i, j] = 0.0, 0.0
        else:
            _world_inertia_into(tree.inertia[b], mb, tree.com_B[b], s.R_all[b], s.p_all[b],
                                Yc[b], p_WG)
            _coriolis_world_into(Yc[b], V[b], P, Bc[b])
    for i in range(3):
        p_WG[i] /= m
    # Backward: composites, and for each velocity k of body b its entries with b's and its
    # ancestors' velocities.
    F1, F2, F3 = f.F[0], f.F[1], f.F[2]
    for b in range(nb - 1, -1, -1):
        Y, B = Yc[b], Bc[b]
        k0 = v_start[b]
        for k in range(k0, k0 + _joint_width(joint_type[b])):
            Sk, Sdk = S[k], S_dot[k]
            for i in range(6):
                t1, t2, t3 = 0.0, 0.0, 0.0
                for j in range(6):
                    t1 += Y[i, j] * Sk[j]
                    t2 += B[j, i] * Sk[j]
                    t3 += Y[i, j] * Sdk[j] + B[i, j] * Sk[j]
                F1[i], F2[i], F3[i] = t1, t2, t3
            a = b
            while a >= 0:
                ka = v_start[a]
                for j in range(ka, ka + _joint_width(joint_type[a])):
                    Sj, Sdj = S[j], S_dot[j]
                    t1, t3 = 0.0, 0.0
                    for i in range(6):
                        t1 += Sj[i] * F1[i]
                        t3 += Sj[i] * F3[i]
                    M[j, k], M[k, j] = t1, t1
                    C[j, k] = t3
                    if a != b:
                        t = 0.0
                        for i in range(6):
                            t += F1[i] * Sdj[i] + F2[i] * Sj[i]
                        C[k, j] = t
                a = parent[a]
        Pb = parent[b]
        if Pb >= 0:
            for i in range(6):
                for j in range(6):
                    Yc[Pb, i, j] += Y[i, j]
                    Bc[Pb, i, j] += B[i, j]
    # J_g, J_g_dot: the free joint's linear rows of M and of C + C^T, over the mass.
    kb = v_start[base] + 3
    for i in range(3):
        for k in range(nv):
            J_g[i, k] = M[kb + i, k] / m
            J_g_dot[i, k] = (C[kb + i, k] + C[k, kb + i]) / m
    for i in range(nv):
        M[i, i] += tree.reflected[i]
    return m, base


@_jit
def _point_jacobians(p_E, v, tree, b, f, J6, J6_dot):
    """J6 with [v_E; w_E] = J6 v for the point p_E (in World) of body b, both World-aligned,
    and its derivative J6_dot, from the motion columns of :func:`_fast_rigid_body` (in ``f``):
    column k of b's velocities [b_k + a_k x p_E; a_k] for S_k = [a_k; b_k], whose derivative
    is [b_k' + a_k' x p_E + a_k x v_E; a_k'] (zero columns for the others)."""
    S, S_dot = f.S, f.S_dot
    px, py, pz = p_E[0], p_E[1], p_E[2]
    for i in range(6):
        for k in range(J6.shape[1]):
            J6[i, k], J6_dot[i, k] = 0.0, 0.0
    vx, vy, vz = 0.0, 0.0, 0.0
    for c in range(tree.num_cols[b]):
        k = tree.cols[b, c]
        a0, a1, a2 = S[k, 0], S[k, 1], S[k, 2]
        l0 = S[k, 3] + (a1 * pz - a2 * py)
        l1 = S[k, 4] + (a2 * px - a0 * pz)
        l2 = S[k, 5] + (a0 * py - a1 * px)
        J6[0, k], J6[1, k], J6[2, k], J6[3, k], J6[4, k], J6[5, k] = l0, l1, l2, a0, a1, a2
        vx += l0 * v[k]
        vy += l1 * v[k]
        vz += l2 * v[k]
    for c in range(tree.num_cols[b]):
        k = tree.cols[b, c]
        a0, a1, a2 = S[k, 0], S[k, 1], S[k, 2]
        d0, d1, d2 = S_dot[k, 0], S_dot[k, 1], S_dot[k, 2]
        J6_dot[0, k] = S_dot[k, 3] + (d1 * pz - d2 * py) + (a1 * vz - a2 * vy)
        J6_dot[1, k] = S_dot[k, 4] + (d2 * px - d0 * pz) + (a2 * vx - a0 * vz)
        J6_dot[2, k] = S_dot[k, 5] + (d0 * py - d1 * px) + (a0 * vy - a1 * vx)
        J6_dot[3, k], J6_dot[4, k], J6_dot[5, k] = d0, d1, d2


@_jit
def _fast_rigid_body_at(q, v, model, index, work):
    """:func:`_fast_rigid_body` at ``(q, v)`` with the packed tree, and :func:`_point_jacobians`
    at every body's origin; copies of the results (see :func:`fast_rigid_body`)."""
    tree, _, _ = _unpack_tree(model, index)
    nb, nv = tree.parent.shape[0], v.shape[0]
    s, at = _section2_buffers(work, 0, nb, nv)
    f, end = _fast_rb_buffers(work, at, nb, nv)
    if end > work.shape[0]:
        raise ValueError("workspace too small")
    m, base = _fast_rigid_body(q, v, tree, s, f)
    J6 = np.empty((nb, 2, 6, nv))
    for b in range(nb):
        _point_jacobians(s.p_all[b], v, tree, b, f, J6[b, 0], J6[b, 1])
    return (m, base, s.M.copy(), s.C.copy(), s.J_g.copy(), s.J_g_dot.copy(), s.p_WG.copy(),
            J6)


def fast_rigid_body(tree: KinematicTree, q: np.ndarray, v: np.ndarray) -> dict:
    """The fast kernel's rigid-body quantities at ``(q, v)`` by name: ``m``, ``base``, ``M``,
    ``C``, ``J_g``, ``J_g_dot``, ``p_WG``, and ``J6`` (per body of ``tree``, the World-aligned
    Jacobian [v; w] of its origin and its derivative, (nb, 2, 6, nv)). For tests."""
    model, index = _pack_tree(tree)
    nb, nv = tree.parent.size, tree.reflected_inertia.size
    size = _workspace_size(nb, nv, False) + fast_rigid_body_size(nb, nv)
    values = _fast_rigid_body_at(np.ascontiguousarray(q, dtype=float),
                                 np.ascontiguousarray(v, dtype=float), model, index,
                                 np.zeros(size))
    return dict(zip(("m", "base", "M", "C", "J_g", "J_g_dot", "p_WG", "J6"), values))
