"""The compiled forward kinematics: the packed :class:`KinematicTree`, body poses and
body-frame Jacobians, and the Jacobians' time derivatives (as Drake's
``CalcJacobianSpatialVelocity`` and :class:`~aerial_drake.dynamics.decoupling.DecoupledDynamics`
compute them), for the kernels of Section II.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from aerial_drake.control.compiled.linalg import _copy, _copy_vec
from aerial_drake.control.compiled.views import _inline, _jit, _mat, _mats, _vec
from aerial_drake.dynamics.kinematic_tree import FREE, REVOLUTE, KinematicTree

#: The arrays of :class:`KinematicTree` (parents before children), and each body's Jacobian
#: columns: ``cols[b, :num_cols[b]]``, the velocities of its ancestors' joints from the body up,
#: all below ``width[b]``; ``span[b, c]``, the range of ``cols[b, c:num_cols[b]]``.
_Tree = namedtuple("_Tree", "parent joint_type q_start v_start num_cols cols width span R_PF "
                            "p_PF R_MC p_MC axis_F inertia mass com_B reflected")


def _pack_tree(tree: KinematicTree) -> tuple[np.ndarray, np.ndarray]:
    """The tree as one float and one integer array, in the order :func:`_unpack_tree` reads."""
    nb, nv = tree.parent.size, tree.reflected_inertia.size
    widths = {FREE: 6, REVOLUTE: 1}
    num_cols, cols = np.zeros(nb, dtype=np.int64), np.zeros((nb, nv), dtype=np.int64)
    for b in range(nb):
        a = b
        while a >= 0:
            for j in range(widths.get(int(tree.joint_type[a]), 0)):
                cols[b, num_cols[b]] = tree.v_start[a] + j
                num_cols[b] += 1
            a = tree.parent[a]
    width = np.array([cols[b, :num_cols[b]].max(initial=-1) + 1 for b in range(nb)])
    span = np.zeros((nb, nv, 2), dtype=np.int64)
    for b in range(nb):
        for c in range(num_cols[b]):
            span[b, c] = cols[b, c:num_cols[b]].min(), cols[b, c:num_cols[b]].max() + 1
    ints = np.concatenate([[nb, nv], tree.parent, tree.joint_type, tree.q_start, tree.v_start,
                           num_cols, cols.ravel(), width, span.ravel()]).astype(np.int64)
    floats = np.concatenate([np.ravel(a) for a in (
        tree.R_PF, tree.p_PF, tree.R_MC, tree.p_MC, tree.axis_F, tree.spatial_inertia,
        tree.mass, tree.com_B, tree.reflected_inertia)]).astype(float)
    return floats, ints


@_jit
def _unpack_tree(model, index):
    """The tree packed by :func:`_pack_tree` at the start of ``model`` and ``index``, as views,
    and the offsets after it in each."""
    nb, nv = index[0], index[1]
    parent, k = _vec(index, 2, nb)
    joint_type, k = _vec(index, k, nb)
    q_start, k = _vec(index, k, nb)
    v_start, k = _vec(index, k, nb)
    num_cols, k = _vec(index, k, nb)
    cols, k = _mat(index, k, nb, nv)
    width, k = _vec(index, k, nb)
    span, k = _mats(index, k, nb, nv, 2)
    R_PF, at = _mats(model, 0, nb, 3, 3)
    p_PF, at = _mat(model, at, nb, 3)
    R_MC, at = _mats(model, at, nb, 3, 3)
    p_MC, at = _mat(model, at, nb, 3)
    axis_F, at = _mat(model, at, nb, 3)
    inertia, at = _mats(model, at, nb, 6, 6)
    mass, at = _vec(model, at, nb)
    com_B, at = _mat(model, at, nb, 3)
    reflected, at = _vec(model, at, nv)
    return (_Tree(parent, joint_type, q_start, v_start, num_cols, cols, width, span, R_PF, p_PF,
                  R_MC, p_MC, axis_F, inertia, mass, com_B, reflected), at, k)



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


@_inline
def _mm3_into(A, B, out):
    for i in range(3):
        for j in range(3):
            out[i, j] = A[i, 0] * B[0, j] + A[i, 1] * B[1, j] + A[i, 2] * B[2, j]


@_inline
def _affine_into(p, R, x, out):
    """out = p + R x (3-vectors)."""
    for i in range(3):
        out[i] = p[i] + R[i, 0] * x[0] + R[i, 1] * x[1] + R[i, 2] * x[2]


@_jit
def _kinematics(q, tree, s):
    """Body poses in World (``s.R_all``, ``s.p_all``) and body-frame spatial velocity Jacobians
    ``[w; v]`` about each body origin (``s.J``: Drake's ``CalcJacobianSpatialVelocity(kV, B, 0,
    World, B)``)."""
    _poses(q, tree, s)
    for b in range(tree.parent.shape[0]):
        _body_jacobian(b, tree, s)


@_inline
def _poses(q, tree, s):
    """Body poses in World (``s.R_all``, ``s.p_all``), the joints' axes and origins in World
    (``s.axis_W``, ``s.origin_W``)."""
    parent, joint_type, q_start, axis_F = tree.parent, tree.joint_type, tree.q_start, tree.axis_F
    R_all, p_all, axis_W, origin_W = s.R_all, s.p_all, s.axis_W, s.origin_W
    R_WF, R_FM, R_WM, p_WF = s.frames[0], s.frames[1], s.frames[2], s.frames[3, 0]
    for b in range(parent.shape[0]):
        P = parent[b]
        if P < 0:
            _copy(tree.R_PF[b], R_WF)
            _copy_vec(tree.p_PF[b], p_WF)
        else:
            _mm3_into(R_all[P], tree.R_PF[b], R_WF)
            _affine_into(p_all[P], R_all[P], tree.p_PF[b], p_WF)
        i = q_start[b]
        if joint_type[b] == FREE:
            _quaternion_matrix_into(q[i], q[i + 1], q[i + 2], q[i + 3], R_FM)
            _mm3_into(R_WF, R_FM, R_WM)
            _affine_into(p_WF, R_WF, q[i + 4:i + 7], origin_W[b])
        elif joint_type[b] == REVOLUTE:
            _axis_angle_matrix_into(axis_F[b], q[i], R_FM)
            _mm3_into(R_WF, R_FM, R_WM)
            _copy_vec(p_WF, origin_W[b])
            a = axis_F[b]
            for r in range(3):
                axis_W[b, r] = R_WF[r, 0] * a[0] + R_WF[r, 1] * a[1] + R_WF[r, 2] * a[2]
        else:
            _copy(R_WF, R_WM)
            _copy_vec(p_WF, origin_W[b])
        _mm3_into(R_WM, tree.R_MC[b], R_all[b])
        _affine_into(origin_W[b], R_WM, tree.p_MC[b], p_all[b])


@_inline
def _body_jacobian(b, tree, s):
    """Body b's body-frame Jacobian ``s.J[b]`` (see :func:`_kinematics`), from the poses."""
    parent, joint_type = tree.parent, tree.joint_type
    R_all, p_all, axis_W, origin_W = s.R_all, s.p_all, s.axis_W, s.origin_W
    J = s.J  # at the bodies' Jacobian columns only (see _section2_buffers)
    R = R_all[b]
    a = b
    while a >= 0:
        k = tree.v_start[a]
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


@_inline
def _column6(A, k):
    """Column k of a six-row matrix as a tuple: values, not a view (views inside loops cost
    their reference counting's calls)."""
    return A[0, k], A[1, k], A[2, k], A[3, k], A[4, k], A[5, k]


@_inline
def _row6(A, i):
    """Row i of a six-column matrix as a tuple (see _column6)."""
    return A[i, 0], A[i, 1], A[i, 2], A[i, 3], A[i, 4], A[i, 5]


@_inline
def _crm_times_into(s, a, out, col):
    """out[:, col] = crm(s) a for spatial vectors, crm([w; v]) = [[w x, 0], [v x, w x]] (``s``
    a 6-vector or a 6-tuple)."""
    wx, wy, wz, vx, vy, vz = s[0], s[1], s[2], s[3], s[4], s[5]
    out[0, col] = wy * a[2] - wz * a[1]
    out[1, col] = wz * a[0] - wx * a[2]
    out[2, col] = wx * a[1] - wy * a[0]
    out[3, col] = vy * a[2] - vz * a[1] + wy * a[5] - wz * a[4]
    out[4, col] = vz * a[0] - vx * a[2] + wz * a[3] - wx * a[5]
    out[5, col] = vx * a[1] - vy * a[0] + wx * a[4] - wy * a[3]


@_jit
def _jacobian_derivative(Jb, Vb, v, R, cols, J_dot, work):
    """d/dt of one body-frame Jacobian into ``J_dot``, as
    DecoupledDynamics._jacobian_derivatives (the free joint's six velocities first, then 1-DoF
    joints; KinematicTree guarantees both). ``cols``: the body's Jacobian columns from the body
    up (the only nonzero ones; its 1-DoF joints' velocities in decreasing order). ``work``: a
    6-vector of scratch space."""
    after = work  # sum over later joint columns m > k of J[:, m] v_m
    after[:] = 0.0
    for c in range(cols.shape[0]):
        k = cols[c]
        if k < 6:
            continue  # the free joint's, below
        _crm_times_into(_column6(Jb, k), after, J_dot, k)
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
