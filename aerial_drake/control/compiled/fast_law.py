"""The law (10)-(22), fast kernel: the exact kernel's quantities (:func:`.kernels._law`) with
the arithmetic reordered and Section II's structure exploited, so equal to the exact
kernel's to round-off (about 1e-13 relative), not to the bit. Chosen by the scenario's
``controller.kernel: fast`` (docs/control.md, "The fast kernel"); the default ``exact``
kernel is the paper runs' and stays bit for bit what it was.

The changes, all in :func:`_law_fast` (otherwise :func:`.kernels._law`'s statements, the same
workspace with the recursions' buffers after it, the same outputs and diagnostics):

- The rigid-body part by :func:`.fast_rigid_body._fast_rigid_body`: M and C by recursions
  over the tree (composite inertias in World) instead of the sums over bodies of J^T I J and
  J^T (I J_dot + A J / 2); J_g, J_g_dot from M's rows; no body Jacobian. The end effector's
  World-aligned Jacobian and its derivative (J6) from the recursion's motion columns
  (:func:`.fast_rigid_body._point_jacobians`) instead of its body's body-frame Jacobian and
  derivative and their products with the point map and the rotation.
- Section II by :func:`.fast_section2._fast_transformation`: T^-1 in closed form from T's
  blocks instead of Gaussian elimination on T, one Cholesky factorisation of Z M Z^T for N
  and N_dot (the exact kernel factors it twice).
- J = J_y T^-1 (17) through T^-1's zero blocks and its last columns Z^T; sigma_min(J_3) with
  Laguerre's iteration in place of Newton's on the same tridiagonal reduction
  (:func:`.fast_section2._min_eigenvalue_laguerre`: a handful of steps instead of ten).
- J_3's LU factorisation and three solves instead of forming J_3^-1 (the damped inverse of
  paper_plus is formed as in the exact kernel); u3 = J_3^T (J_3^-T lg - K_z z~) (19)-(21) as
  lg - J_3^T K_z z~ (the exact kernel's form for the damped law), without J_3^-T.
- -Gamma_23^T w_b of (8) as Gamma_32 w_b (Lambda is block diagonal at every state, so
  Lambda_dot = Gamma + Gamma^T (6) has a zero 23 block): one product
  Lambda [0; 0; a] + Gamma [0; w_b; s] gives it with Lambda_z z_d_dot + Gamma_z z_d, instead
  of a second product with Gamma^T.
- The Lyapunov function's z~ . Lambda_z z~ (24) as s . Lambda_33 s with s = J_3^-1 z~ and
  Lambda_33 = Z M Z^T (T^-1's last columns are Z^T), left by Section II, instead of three
  products with T^-1 and M and a solve with J_3^T.

numba caches :func:`_law_fast`'s machine code keyed on this file only (see
:mod:`.kernels`): after editing :mod:`.kernels`, :mod:`.kinematics`, :mod:`.fast_section2` or
:mod:`.fast_rigid_body`, touch this file so that the fast law recompiles with them.
"""

from __future__ import annotations

import math

from aerial_drake.control.compiled.fast_rigid_body import (
    _fast_rb_buffers,
    _fast_rigid_body,
    _point_jacobians,
)
from aerial_drake.control.compiled.fast_section2 import (
    _fast_transformation,
    _lu_factor,
    _lu_solve,
    _min_eigenvalue_laguerre,
)
from aerial_drake.control.compiled.kernels import (
    _D_X,
    _DAMPING,
    _F_D_LIMIT,
    _GAMMA1,
    _GAMMA2,
    _GRAVITY,
    _K_R,
    _K_W,
    _K_X,
    _K_Y,
    _K_Z,
    _L2,
    _L2_INV,
    _SIGMA_LIMIT,
    ASSUMPTION_1,
    ASSUMPTION_2,
    NONFINITE,
    OK,
    _damped_inverse_into,
    _damping_squared,
    _desired_attitude,
    _end_effector_pose_into,
    _gain,
    _jt_dot_times,
    _lambda_gamma_times,
    _law_buffers,
    _rotation_angle,
    _unpack_law,
    _weighted_dot,
)
from aerial_drake.control.compiled.linalg import (
    _copy,
    _cross_at,
    _cross_into,
    _dot,
    _mm_into,
    _mtm_into,
    _mtv_into,
    _mv_into,
    _norm,
    _vee_into,
)
from aerial_drake.control.compiled.views import _inline, _jit


@_inline
def _fast_sigma_min_J3(J_y, T_inv, w):
    """As :func:`.kernels._sigma_min_J3` (J = J_y T^-1 into ``w.Jt``, J_3 into ``w.J3``,
    sigma_min(J_3) returned), the product over T^-1's nonzero blocks: its first three rows
    are zero but in columns 3:6, and its last n columns are Z^T (nonzero in rows 3:6 and
    the identity below)."""
    Jt, J3 = w.Jt, w.J3
    n, nv = J_y.shape[0], J_y.shape[1]
    for i in range(n):
        for c in range(3):
            t = 0.0
            for p in range(3, nv):
                t += J_y[i, p] * T_inv[p, c]
            Jt[i, c] = t
        for c in range(3, 6):
            t = 0.0
            for p in range(nv):
                t += J_y[i, p] * T_inv[p, c]
            Jt[i, c] = t
        for k in range(n):
            t = J_y[i, 6 + k] + (J_y[i, 3] * T_inv[3, 6 + k] + J_y[i, 4] * T_inv[4, 6 + k]
                                 + J_y[i, 5] * T_inv[5, 6 + k])
            Jt[i, 6 + k] = t
            J3[i, k] = t
    _mtm_into(J3, J3, w.JtJ)
    return math.sqrt(max(_min_eigenvalue_laguerre(w.JtJ, w.vn[13:17]), 0.0))


@_inline
def _j3_solve(J3_inv, piv, damped, b, out):
    """out = J_3^-1 b from J_3's LU factors in ``J3_inv``, or J_3^# b with the damped
    inverse J_3^# formed in ``J3_inv`` (``damped``)."""
    if damped:
        _mv_into(J3_inv, b, out)
    else:
        _lu_solve(J3_inv, piv, b, out)


@_jit
def _law_fast(x, com, task, heading, command, diagnostics, model, index, work):
    """The law (10)-(22) at state ``x``: :func:`.kernels._law`'s statements with the
    changes of the module docstring; its arguments, outputs and workspace."""
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
    f, end = _fast_rb_buffers(work, end, tree.parent.shape[0], nv)
    if end > work.shape[0]:
        raise ValueError("workspace too small")
    m, base = _fast_rigid_body(q, v, tree, s, f)
    _fast_transformation(v, s.R_all[base], s)
    R, M, C, T, T_dot, T_inv = s.R_all[base], s.M, s.C, s.T, s.T_dot, s.T_inv
    xi = w.xi
    _mv_into(T, v, xi)
    gains = p.gains
    K_x, D_x = _gain(gains, _K_X, n), _gain(gains, _D_X, n)
    k_R, k_w = _gain(gains, _K_R, n)[0], _gain(gains, _K_W, n)[0]
    L2, L2_inv = _gain(gains, _L2, n), _gain(gains, _L2_INV, n)
    K_y, K_z = _gain(gains, _K_Y, n), _gain(gains, _K_Z, n)
    gamma1, gamma2 = _gain(gains, _GAMMA1, n)[0], _gain(gains, _GAMMA2, n)[0]
    gravity = _gain(gains, _GRAVITY, n)[0]
    w_b, rho = xi[3:6], xi[6:]
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
    if not f_d_norm > p.limits[_F_D_LIMIT]:
        return ASSUMPTION_2, f_d_norm, 0.0
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

    # Task kinematics: the end-effector frame E on body ee_body (its World-aligned Jacobian
    # from the motion columns), and the task's joints.
    R_WE, p_WE = w.R_WE, w.p_WE
    _end_effector_pose_into(s.R_all[p.ee_body], s.p_all[p.ee_body], p.R_BE, p.p_BE, R_WE, p_WE)
    J6, J6_dot = w.J6[0], w.J6[1]  # [v_E; w_E] of the whole pose
    _point_jacobians(p_WE, v, tree, p.ee_body, f, J6, J6_dot)
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

    # Task control (17)-(20).
    sigma_min = _fast_sigma_min_J3(J_y, T_inv, w)
    Jt, J3 = w.Jt, w.J3
    # With the damped inverse on, no Assumption 1 stop (the caller checks control is kept).
    if p.limits[_DAMPING] == 0.0 and not sigma_min > p.limits[_SIGMA_LIMIT]:
        return ASSUMPTION_1, f_d_norm, sigma_min
    lambda2 = _damping_squared(sigma_min, p.limits)
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
    # (19): Lambda_z = J3^-T Lambda33 J3^-1, Gamma_z = J3^-T (Gamma33 - Lambda33 J3^-1 J3_dot)
    # J3^-1, applied to vectors. Damped (lambda2 > 0): J3^# in place of J3^-1 (below).
    # Undamped: J3's LU factors in J3_inv's buffer, and solves in place of J3^-1's products.
    J3_inv, piv, damped = w.J3_inv, w.vn[13], lambda2 > 0.0
    if damped:
        _damped_inverse_into(J3, lambda2, w.JtJ, J3_inv)
    else:
        _copy(J3, J3_inv)
        _lu_factor(J3_inv, piv)
    s_d, J3_dot_s, d, a3, lg = w.vn[3], w.vn[4], w.vn[5], w.vn[6], w.vn[7]
    _j3_solve(J3_inv, piv, damped, z_d, s_d)  # s = J3^-1 z_d
    u_s = w.u[2]  # T^-1 [0; 0; s]
    _mv_into(T_inv, s_d, u_s, 6)
    _mv_into(T_dot, u_s, T_dot_u)
    _jt_dot_times(J_y_dot, Jt, u_s, T_dot_u, J3_dot_s, w.vn[17])
    # Lambda_z z_d_dot + Gamma_z z_d
    #   = J3^-T (Lambda33 J3^-1 (z_d_dot - J3_dot s) + Gamma33 s).
    for i in range(n):
        d[i] = z_d_dot[i] - J3_dot_s[i]
    _j3_solve(J3_inv, piv, damped, d, a3)
    # -Gamma23^T w_b of (8) is Gamma32 w_b (Lambda is block diagonal at every state, so
    # Lambda_dot = Gamma + Gamma^T (6) has a zero block 23): with Gamma33 s, the last rows of
    # one product Lambda [0; 0; a3] + Gamma [0; w_b; s].
    ws, u_ws = w.F[:3 + n], w.u[0]  # (F is written last; u[0] held u_b, used)
    for i in range(3):
        ws[i] = w_b[i]
    for i in range(n):
        ws[3 + i] = s_d[i]
    _mv_into(T_inv, ws, u_ws, 3)
    _mv_into(T_dot, u_ws, T_dot_u)
    _lambda_gamma_times(M, C, T_inv, a3, 6, u_ws, T_dot_u, lg, 6, w.vnv)
    # u3 = J3^T (J3^-T lg - K_z z~) = lg - J3^T K_z z~: the product J3^T J3^-T as the
    # identity, as the exact kernel does for the damped law (damped or not, here); u3 here
    # includes -Gamma23^T w_b.
    zz, u3 = w.vn[8], w.vn[9]
    for i in range(n):
        zz[i] = K_z[i] * z_t[i]
    _mtv_into(J3, zz, u3)
    for i in range(n):
        u3[i] = lg[i] - u3[i]

    # Input mapping (8), (22).
    u_prime, F, force_b = w.u_prime, w.F, w.force_b
    for i in range(3):
        u_prime[i], u_prime[3 + i] = u1 * Re3[i], w.u2_rho[i]
    for i in range(n):
        u_prime[6 + i] = u3[i]
    _mtv_into(T, u_prime, F)  # (22)
    mu = w.v3[0]
    _mtv_into(R, F[:3], mu)
    _mtv_into(R, F[3:6], force_b)
    command[0] = force_b[2]
    for i in range(3):
        command[1 + i] = mu[i]
    for i in range(n):
        command[4 + i] = F[6 + i]

    # Diagnostics (24)-(25), in diagnostics_layout(n) order.
    # z~ . Lambda_z z~ = z~ . J3^-T Lambda33 J3^-1 z~ = s_t . Lambda33 s_t, s_t = J3^-1 z~
    # (J3^# z~ damped, as the exact kernel), Lambda33 = Z M Z^T (T^-1's last columns are
    # Z^T), left by Section II.
    s_t, Lz = w.vn[10], w.vn[11]
    _j3_solve(J3_inv, piv, damped, z_t, s_t)
    _mv_into(s.ZZ[0], s_t, Lz)
    t = 0.0
    for i in range(n):
        t += y_t[i] * (K_y[i] * K_z[i] * y_t[i])
    V_task = 0.5 * _dot(s_t, Lz) + t  # (24)
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
    return OK, f_d_norm, sigma_min
