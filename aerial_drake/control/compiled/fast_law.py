"""The law (10)-(22), fast kernel: the exact kernel's quantities (:func:`.kernels._law`) with
the arithmetic reordered and Section II's structure exploited, so equal to the exact
kernel's to round-off (about 1e-13 relative), not to the bit. Chosen by the scenario's
``controller.kernel: fast`` (docs/control.md, "The fast kernel"); the default ``exact``
kernel is the paper runs' and stays bit for bit what it was.

The changes, all in :func:`_law_fast`; the parts that are the same, the CoM and attitude
control (10)-(16), the task errors (17)-(20), the input mapping (22) and the diagnostics, are
:mod:`.kernels`' helpers that :func:`.kernels._law` calls too (the same workspace with the
recursions' buffers after it, the same outputs and diagnostics):

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
    _DAMPING,
    _F_D_LIMIT,
    _SIGMA_LIMIT,
    ASSUMPTION_1,
    ASSUMPTION_2,
    NONFINITE,
    OK,
    _apply_inputs,
    _com_and_attitude,
    _damped_inverse_into,
    _damping_squared,
    _end_effector_pose_into,
    _jt_dot_times,
    _lambda_gamma_times,
    _law_buffers,
    _law_gains,
    _task_errors,
    _unpack_law,
    _write_diagnostics,
)
from aerial_drake.control.compiled.linalg import (
    _copy,
    _dot,
    _mtm_into,
    _mtv_into,
    _mv_into,
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
    K_x, D_x, k_R, k_w, L2, L2_inv, K_y, K_z, gamma1, gamma2, gravity = _law_gains(p.gains, n)
    ok, f_d_norm, u1 = _com_and_attitude(m, R, s, xi, com, heading, K_x, D_x, k_R, k_w, L2_inv,
                                         gravity, p.limits[_F_D_LIMIT], M, C, T_inv, T_dot, w)
    if not ok:
        return ASSUMPTION_2, f_d_norm, 0.0
    w_b, rho = xi[3:6], xi[6:]
    Re3, T_dot_u = w.Re3[0], w.u[3]

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
    _task_errors(x, task, p, R_WE, p_WE, xi, rho, K_y, T_inv, T_dot, n, w)
    Jt, J3, J_y_dot, y_t, z_t, z_d, z_d_dot = (w.Jt, w.J3, w.J_y[1], w.y_t[0], w.z_t,
                                               w.z_d[0], w.z_d[1])
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
    u_prime = w.u_prime
    for i in range(3):
        u_prime[i], u_prime[3 + i] = u1 * Re3[i], w.u2_rho[i]
    for i in range(n):
        u_prime[6 + i] = u3[i]
    _apply_inputs(T, R, command, n, w)

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
    _write_diagnostics(diagnostics, m, V_task, sigma_min, f_d_norm, K_x, L2, k_R, gamma1,
                       gamma2, w)
    return OK, f_d_norm, sigma_min
