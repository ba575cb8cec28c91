"""The control law of Section III, (10)-(22), as pure math on a :class:`Decomposition`.

No Drake systems here: :func:`compute_control` takes the decoupled dynamics at one state, the
end-effector kinematics and the reference, and returns the inputs ``f, mu, tau`` of (22) and the
diagnostics. :mod:`aerial_drake.control.controller` wraps it in a LeafSystem.

Choices where the paper is silent (also in ``docs/control.md``):

- The task is rows of ``y_full = [p_E; orientation of E; q_j]`` (the paper's (27) is all of
  them with q_j = q3; :mod:`aerial_drake.robots.task`). Its velocity is rows of
  ``[v_E; w_E; q_j_dot]`` (World) and its orientation error is
  ``e_o = vee(skew(R_E R_ed^T))`` (World), whose derivative at zero error is ``w_E - w_ed``.
  The task velocity error is velocity-level, ``J xi - y_d_dot`` (17).
- The feed-forwards take the CoM acceleration and jerk from the model (9a) and the base angular
  acceleration from the closed loop (16), as the paper suggests.
- Near the singularity of J_3, with :class:`SingularityRobust`'s damping on, J_3^-1 is
  replaced by a damped least-squares inverse and the Assumption 1 stop by a loss-of-control
  check (docs/control.md, "Graceful degradation"); off by default (the paper's law).
- ``V1`` of (25) uses ``k_R / 2 tr(E3 - R_d^T R_b)`` (Lee et al.'s ``k_R Psi``; the paper's
  print drops the 1/2, without which ``dV1/dt`` has an uncancelled ``e_R . w~`` term).

Scalar types: the law runs unchanged on float arrays and on numpy object arrays of AutoDiffXd
(a :class:`Decomposition` from an AutoDiffXd plant, for ``Linearize``); the assumption checks
and the diagnostics' norms and angles are then taken on the values.
"""


from dataclasses import dataclass
from typing import Any

import numpy as np

# The gains live in their own module (one rule set); importable from here as before.
from aerial_drake.control.gains import GainMatrices as GainMatrices
from aerial_drake.control.gains import Gains as Gains
from aerial_drake.dynamics.decoupling import Decomposition, cross, cross_rows, inv, value_of, vee

_E3 = np.eye(3)
_e3 = np.array([0.0, 0.0, 1.0])


#: Default thresholds of the checks of Assumption 1 (sigma_min(J_3)) and 2 (|f_d|, N); a
#: scenario may set its own (``sigma_min_J3_limit``, ``f_d_limit``).
SIGMA_MIN_J3_LIMIT = 1e-3
F_D_LIMIT = 1.0


class AssumptionViolation(RuntimeError):
    """Raised when Assumption 1 (J_3 nonsingular) or 2 (|f_d| > 0) of the paper fails."""


def assumption_1_message(sigma_min: float, limit: float) -> str:
    return (f"Assumption 1 violated: J_3 is singular, sigma_min(J_3) = {sigma_min:.3g} "
            f"(limit {limit:g})")


def control_lost_message(sigma_min: float, ee_error: float, bound: float) -> str:
    return (f"control lost near the singularity of J_3: the end-effector position error "
            f"{ee_error:.3g} m exceeds singularity_lost_error = {bound:g} m while the task "
            f"inverse is damped (sigma_min(J_3) = {sigma_min:.3g})")


@dataclass(frozen=True)
class SingularityRobust:
    """The singularity-robust inverse of J_3 in (19)-(20) and when control counts as lost
    (docs/control.md, "Graceful degradation"). ``damping`` 0 (the default): off, the paper's
    law with its Assumption 1 stop.

    With ``damping`` = lambda_max > 0, below ``threshold`` = eps the law uses the damped
    least-squares inverse J_3^# = (J_3^T J_3 + lambda^2 E)^-1 J_3^T with Nakamura and
    Hanafusa's / Chiaverini's variable damping lambda^2 = lambda_max^2 (1 - (sigma_min /
    eps)^2) (:func:`damping_squared`); the Assumption 1 stop is replaced by: control is lost
    when the inverse is damped and the end effector's position error exceeds ``lost_error``
    (m)."""

    damping: float = 0.0
    threshold: float = 0.05
    lost_error: float = 0.1

    def damping_ratio(self, sigma_min: float) -> float:
        """lambda^2 / lambda_max^2 at ``sigma_min`` = sigma_min(J_3): 1 - (sigma_min / eps)^2
        below eps with the damping on, else 0 (0: the exact inverse, 1: full damping)."""
        if not (self.damping > 0.0 and sigma_min < self.threshold):
            return 0.0
        r = sigma_min / self.threshold
        return 1.0 - r * r

    def damping_squared(self, sigma_min: float) -> float:
        """lambda^2 = lambda_max^2 (1 - (sigma_min / eps)^2) below eps, else 0 (the kernel's
        ``_damping_squared``, the same expression)."""
        return self.damping * self.damping * self.damping_ratio(sigma_min)

    def check_control_kept(self, sigma_min: float, ee_error: float) -> None:
        """Raise AssumptionViolation if control is lost: the inverse damped at ``sigma_min``
        and the end-effector position error ``ee_error`` (m) beyond ``lost_error``."""
        if self.damping_squared(sigma_min) > 0.0 and ee_error > self.lost_error:
            raise AssumptionViolation(control_lost_message(sigma_min, ee_error,
                                                           self.lost_error))


#: The paper's law: no damping.
NO_DAMPING = SingularityRobust()


def assumption_2_message(f_d_norm: float, limit: float) -> str:
    return (f"Assumption 2 violated: the desired thrust vanishes, |f_d| = {f_d_norm:.3g} N "
            f"(limit {limit:g} N)")


@dataclass(frozen=True)
class TaskKinematics:
    """The task ``y`` at one state: end-effector pose, the task's joint angles, and
    ``y_dot = J_y v``."""

    p_WE: np.ndarray  # (3)
    R_WE: np.ndarray  # (3, 3)
    q_j: np.ndarray  # (n_j) the task's joint angles
    J_y: np.ndarray  # (n, nv): the task's rows of [v_E (World); w_E (World); q_j_dot]
    J_y_dot: np.ndarray
    rows: tuple[int, ...]  # the task's rows of y_full (robots.task)


@dataclass(frozen=True)
class Reference:
    """The desired trajectory at one instant (see :mod:`aerial_drake.trajectories.reference`)."""

    com: np.ndarray  # (5, 3): x_d and its first four derivatives
    p_ed: np.ndarray
    R_ed: np.ndarray
    q_jd: np.ndarray  # (n_j)
    y_d_dot: np.ndarray  # (n): the task's rows of [v_ed; w_ed; q_jd_dot]
    y_d_ddot: np.ndarray  # (n): the task's rows of [a_ed; dw_ed; q_jd_ddot]
    b1d: np.ndarray  # (3, 3): b1d and its first two derivatives


def diagnostics_layout(n: int) -> tuple[tuple[str, int], ...]:
    """The diagnostics vector's layout, (name, size) pairs, for a task of ``n`` rows.
    ``ee_position_error`` and ``ee_orientation_error`` are of the whole end-effector pose
    (whatever rows the task tracks)."""
    return (
        ("x_tilde", 3), ("x_tilde_dot", 3), ("e_R", 3), ("w_tilde", 3), ("y_tilde", n),
        ("z_tilde", n), ("sigma_min_J3", 1), ("f_d_norm", 1), ("V1", 1), ("V_task", 1),
        ("V", 1), ("com_error", 1), ("base_attitude_error", 1), ("ee_position_error", 1),
        ("ee_orientation_error", 1), ("thrust_residual", 2),
    )


def diagnostics_slices(layout: "int | tuple[tuple[str, int], ...] | list"
                       ) -> dict[str, slice]:
    """Name -> slice into the diagnostics vector, for a task of ``layout`` rows or for a
    ``layout`` of (name, size) pairs (e.g. the one stored in a log)."""
    pairs = diagnostics_layout(layout) if isinstance(layout, int) else layout
    out, start = {}, 0
    for name, size in pairs:
        out[name] = slice(start, start + size)
        start += size
    return out


def task_size_of_diagnostics(width: int) -> int:
    """The task's size n of a diagnostics vector (or log) of ``width`` entries."""
    n, rest = divmod(int(width) - diagnostics_size(0), 2)
    if n < 0 or rest:
        raise ValueError(f"{width} entries is not a diagnostics vector's size (23 + 2 n)")
    return n


def diagnostics_size(n: int) -> int:
    """Length of the diagnostics vector for a task of ``n`` rows."""
    return sum(size for _, size in diagnostics_layout(n))


@dataclass(frozen=True)
class ControlOutput:
    f: float  # thrust along the body z axis (N)
    mu: np.ndarray  # body torques (N m), base frame
    tau: np.ndarray  # joint torques (N m)
    diagnostics: np.ndarray  # diagnostics_layout(n)
    # Intermediate quantities, for analysis and tests.
    u_prime: np.ndarray  # u' of (8)
    R_d: np.ndarray
    w_d: np.ndarray
    w_d_dot: np.ndarray
    Lambda_z: np.ndarray
    Gamma_z: np.ndarray
    J3: np.ndarray


def _norm(a):
    """Euclidean norm of a float or AutoDiffXd (object) vector."""
    return np.sqrt(a @ a) if a.dtype == object else np.linalg.norm(a)


def unit_vector_derivatives(a: np.ndarray, a_dot: np.ndarray, a_ddot: np.ndarray
                            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``b = a/|a|`` and its first two time derivatives."""
    n = _norm(a)
    b = a / n
    ad_b = a_dot @ b
    b_dot = (a_dot - b * ad_b) / n
    # d/dt(a_dot - b (a_dot.b)) / n - (a_dot - b (a_dot.b)) n_dot / n^2, with n_dot = a_dot.b
    b_ddot = (a_ddot - b_dot * ad_b - b * (a_ddot @ b + a_dot @ b_dot)) / n - b_dot * ad_b / n
    return b, b_dot, b_ddot


#: Smallest |b3 x b1d| for which :func:`desired_attitude` defines R_d (13).
HEADING_LIMIT = 1e-9


def desired_attitude(f_d: np.ndarray, f_d_dot: np.ndarray, f_d_ddot: np.ndarray,
                     b1d: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, Any]:
    """R_d of (12)-(13) and its first two time derivatives, from f_d and the heading b1d, and
    |b3 x b1d| (a float, or an AutoDiffXd on that path)."""
    b3, b3_dot, b3_ddot = unit_vector_derivatives(f_d, f_d_dot, f_d_ddot)  # (12)
    b1, b1_dot, b1_ddot = b1d
    # c = b3 x b1 and its derivatives (Leibniz), six cross products in one call.
    x = cross_rows(np.column_stack([b3, b3_dot, b3, b3_ddot, b3_dot, b3]),
                    np.column_stack([b1, b1, b1_dot, b1, b1_dot, b1_ddot]))
    c, c_dot, c_ddot = x[:, 0], x[:, 1] + x[:, 2], x[:, 3] + 2.0 * x[:, 4] + x[:, 5]
    norm_c = _norm(c)
    norm_value = float(norm_c.value() if hasattr(norm_c, "value") else norm_c)
    if not norm_value > HEADING_LIMIT:  # (13) undefined: b2 = c / |c|
        raise AssumptionViolation(
            f"the heading b1d is parallel to the desired thrust direction b3 (|b3 x b1d| = "
            f"{norm_value:.3g}, limit {HEADING_LIMIT:g}): R_d of (13) is "
            "undefined; the desired force must not point along the heading (a horizontal "
            "b1d and a thrust that is not horizontal)")
    b2, b2_dot, b2_ddot = unit_vector_derivatives(c, c_dot, c_ddot)
    # (13): R_d = [b2 x b3, b2, b3], and its derivatives.
    y = cross_rows(np.column_stack([b2, b2_dot, b2, b2_ddot, b2_dot, b2]),
                    np.column_stack([b3, b3, b3_dot, b3, b3_dot, b3_ddot]))
    R_d = np.column_stack([y[:, 0], b2, b3])
    R_d_dot = np.column_stack([y[:, 1] + y[:, 2], b2_dot, b3_dot])
    R_d_ddot = np.column_stack([y[:, 3] + 2.0 * y[:, 4] + y[:, 5], b2_ddot, b3_ddot])
    return R_d, R_d_dot, R_d_ddot, norm_c


def desired_force(m: float, gravity: float, com_reference: np.ndarray, x_t: np.ndarray,
                  x_t_dot: np.ndarray, K_x: np.ndarray, D_x: np.ndarray) -> np.ndarray:
    """(10): f_d = m x_d'' + m g e3 - K_x x~ - D_x x~_dot (K_x, D_x diagonals).

    ``com_reference`` holds x_d and its derivatives as rows (5, 3)."""
    return m * (com_reference[2] + gravity * _e3) - K_x * x_t - D_x * x_t_dot


def rotation_angle(R: np.ndarray) -> float:
    """Geodesic angle of a rotation matrix (rad)."""
    R = value_of(R)
    return float(np.arccos(np.clip(0.5 * (np.trace(R) - 1.0), -1.0, 1.0)))


def task_error(p_WE: np.ndarray, R_WE: np.ndarray, q_j, p_ed: np.ndarray, R_ed: np.ndarray,
               q_jd, rows) -> tuple[np.ndarray, np.ndarray]:
    """The task error y~ of (17)-(18) and ``R_E R_ed^T``: the task's ``rows`` of
    ``[p_E - p_ed; vee(skew(R_E R_ed^T)); q_j - q_jd]`` (World). Every controller's
    diagnostics use this definition (:mod:`aerial_drake.control.interface`)."""
    R_err = R_WE @ R_ed.T
    full = np.concatenate([p_WE - p_ed, vee(R_err), np.asarray(q_j) - np.asarray(q_jd)])
    return full[list(rows)], R_err


def compute_control(d: Decomposition, task: TaskKinematics, ref: Reference, K: "GainMatrices",
                    gravity: float, *,
                    sigma_min_J3_limit: float = SIGMA_MIN_J3_LIMIT,
                    f_d_limit: float = F_D_LIMIT,
                    singularity: SingularityRobust = NO_DAMPING,
                    ) -> ControlOutput:
    """The whole law (10)-(22) at one state; near the singularity of J_3 with the damped
    inverse of ``singularity`` when its damping is on.

    Raises:
        AssumptionViolation: when sigma_min(J_3) < ``sigma_min_J3_limit`` (Assumption 1; not
            checked with damping on), when the damped law has lost control
            (:class:`SingularityRobust`) or when |f_d| < ``f_d_limit`` N (Assumption 2).
    """
    m, R = d.m, d.R
    xi = d.xi
    xg_dot, w_b, rho = xi[:3], xi[3:6], xi[6:]
    x_d, xd1, xd2, xd3, xd4 = ref.com
    Re3 = R[:, 2]
    ge3 = gravity * _e3

    # CoM control (10)-(11).
    x_t = d.p_WG - x_d
    x_t_dot = xg_dot - xd1
    f_d = desired_force(m, gravity, ref.com, x_t, x_t_dot, K.K_x, K.D_x)  # (10)
    f_d_norm = float(np.linalg.norm(value_of(f_d)))
    if not f_d_norm > f_d_limit:
        raise AssumptionViolation(assumption_2_message(f_d_norm, f_d_limit))
    u1 = f_d @ Re3  # (11)
    # CoM acceleration and jerk from the model (9a), for the attitude feed-forward.
    xg_dd = u1 * Re3 / m - ge3
    x_t_dd = xg_dd - xd2
    f_d_dot = m * xd3 - K.K_x * x_t_dot - K.D_x * x_t_dd
    Re3_dot = R @ cross(w_b, _e3)
    u1_dot = f_d_dot @ Re3 + f_d @ Re3_dot
    xg_ddd = (u1_dot * Re3 + u1 * Re3_dot) / m
    f_d_ddot = m * xd4 - K.K_x * x_t_dd - K.D_x * (xg_ddd - xd3)

    # Attitude control (12)-(16).
    R_d, R_d_dot, R_d_ddot, _ = desired_attitude(f_d, f_d_dot, f_d_ddot, ref.b1d)
    Omega_d = vee(R_d.T @ R_d_dot)
    Omega_d_dot = vee(R_d_dot.T @ R_d_dot + R_d.T @ R_d_ddot)
    RtRd = R.T @ R_d
    w_d = RtRd @ Omega_d
    w_d_dot = -cross(w_b, w_d) + RtRd @ Omega_d_dot
    e_R = vee(R_d.T @ R)  # (14): vee() takes the skew part, 1/2 (A - A^T)
    w_t = w_b - w_d  # (15)
    # Under (16) the base's angular acceleration is this (used again by the task feed-forward).
    w_b_dot = w_d_dot - K.Lambda2_bar_inv * (K.k_R * e_R + K.k_w * w_t)
    Lambda22, Gamma22 = d.Lambda[3:6, 3:6], d.Gamma[3:6, 3:6]
    Gamma23 = d.Gamma[3:6, 6:]
    u2 = Gamma22 @ w_b + Lambda22 @ w_b_dot  # (16)

    # Task control (17)-(20).
    J = task.J_y @ d.T_inv
    J_dot = (task.J_y_dot - J @ d.T_dot) @ d.T_inv  # d/dt T^{-1} = -T^{-1} T_dot T^{-1}
    J1, J2, J3 = J[:, :3], J[:, 3:6], J[:, 6:]
    J1_dot, J2_dot, J3_dot = J_dot[:, :3], J_dot[:, 3:6], J_dot[:, 6:]
    J3_value = value_of(J3)
    # sigma_min from the smallest eigenvalue of J3^T J3 (a symmetric n x n: cheaper than an SVD;
    # accurate to ~1e-16 sigma_max^2 / sigma_min, far below the check's threshold).
    sigma_min = float(np.sqrt(max(np.linalg.eigvalsh(J3_value.T @ J3_value)[0], 0.0)))
    if singularity.damping == 0.0 and not sigma_min > sigma_min_J3_limit:
        raise AssumptionViolation(assumption_1_message(sigma_min, sigma_min_J3_limit))
    lambda2 = singularity.damping_squared(sigma_min)
    y_t, R_err = task_error(task.p_WE, task.R_WE, task.q_j, ref.p_ed, ref.R_ed, ref.q_jd,
                            task.rows)
    y_t_dot = J @ xi - ref.y_d_dot  # (17)
    z = J3 @ rho
    z_d = ref.y_d_dot - J1 @ xg_dot - J2 @ w_b - K.K_y * y_t
    z_t = z - z_d  # (18)
    z_d_dot = (ref.y_d_ddot - J1 @ xg_dd - J1_dot @ xg_dot - J2 @ w_b_dot - J2_dot @ w_b
               - K.K_y * y_t_dot)  # (20)
    Lambda33, Gamma33 = d.Lambda[6:, 6:], d.Gamma[6:, 6:]
    if lambda2 > 0.0:  # damped: J3^# = (J3^T J3 + lambda^2 E)^-1 J3^T in place of J3^-1
        J3_inv = inv(J3.T @ J3 + lambda2 * np.eye(J3.shape[1])) @ J3.T
    else:
        J3_inv = inv(J3)
    Lambda_z = J3_inv.T @ Lambda33 @ J3_inv  # (19)
    Gamma_z = J3_inv.T @ (Gamma33 - Lambda33 @ J3_inv @ J3_dot) @ J3_inv
    if lambda2 > 0.0:
        # The undamped u3 below is J3^T J3^-T (Lambda33 rho_d' + Gamma33 rho_d) - J3^T K_z z~
        # (J3^T Lambda_z = Lambda33 J3^-1, ...); damped, the product J3^T J3^-T (the
        # identity) is kept as the identity:
        #   u3 = Lambda33 rho_d' + Gamma33 rho_d - J3^T K_z z~,
        #   rho_d = J3^# z_d, rho_d' = J3^# (z_d' - J3_dot rho_d),
        # bounded by |J3^#| <= 1 / (2 lambda).
        rho_d = J3_inv @ z_d
        rho_d_dot = J3_inv @ (z_d_dot - J3_dot @ rho_d)
        u3 = Lambda33 @ rho_d_dot + Gamma33 @ rho_d - J3.T @ (K.K_z * z_t)
    else:
        u3 = J3.T @ (Lambda_z @ z_d_dot + Gamma_z @ z_d - K.K_z * z_t)

    # Input mapping (8), (22): F = T^T u' is the generalized force J_b^T B psi + Q^T tau.
    u_prime = np.concatenate([u1 * Re3, Gamma23 @ rho + u2, -Gamma23.T @ w_b + u3])  # (8)
    F = d.T.T @ u_prime  # (22)
    mu = R.T @ F[:3]
    force_b = R.T @ F[3:6]
    tau = F[6:]

    # Diagnostics: errors, assumptions, Lyapunov function (24)-(25).
    V_task = 0.5 * z_t @ Lambda_z @ z_t + y_t @ (K.K_y * K.K_z * y_t)  # (24)
    V1 = (0.5 * m * x_t_dot @ x_t_dot + 0.5 * x_t @ (K.K_x * x_t)
          + K.gamma1 * x_t @ x_t_dot + 0.5 * w_t @ (K.Lambda2_bar * w_t)
          + 0.5 * K.k_R * np.trace(_E3 - R_d.T @ R) + K.gamma2 * e_R @ w_t)  # (25)
    ee_error = float(np.linalg.norm(value_of(task.p_WE - ref.p_ed)))
    singularity.check_control_kept(sigma_min, ee_error)
    diagnostics = np.concatenate([
        x_t, x_t_dot, e_R, w_t, y_t, z_t,
        [sigma_min, f_d_norm, V1, V_task, V1 + V_task,
         np.linalg.norm(value_of(x_t)), rotation_angle(R_d.T @ R),
         ee_error, rotation_angle(R_err)],
        force_b[:2]])
    f = force_b[2] if force_b.dtype == object else float(force_b[2])
    return ControlOutput(f=f, mu=mu, tau=tau, diagnostics=diagnostics,
                         u_prime=u_prime, R_d=R_d, w_d=w_d, w_d_dot=w_d_dot,
                         Lambda_z=Lambda_z, Gamma_z=Gamma_z, J3=J3)
