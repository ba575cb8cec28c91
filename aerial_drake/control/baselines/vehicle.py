"""The vehicle's law of the baselines: Lee, Leok and McClamroch's geometric tracking controller
on SE(3) ("Geometric tracking control of a quadrotor UAV on SE(3)", CDC 2010, eqs. (15)-(16)),
applied to the helicopter body: its own position p_b and attitude R_b, the total mass m for
the hover thrust, and an assumed inertia J_v (the controller passes the whole robot's, locked
at the start posture: :mod:`.tuning`); the arm's motion is unknown to it.

Lee et al. write z down; with z up (ours) their law reads

    F   = m (p_bd'' + g e3) - K_x e_x - D_x e_v,      f = F . R_b e3,
    b3d = F / |F|,  R_d = [b2d x b3d, b2d, b3d],  b2d = b3d x b1d / |b3d x b1d|   ((12)-(13)),
    mu  = -k_R e_R - k_w e_w + w_b x J_v w_b + J_v w_d_dot,

with e_x = p_b - p_bd, e_v = p_b' - p_bd', e_R, e_w of (14)-(15) and
w_d_dot = -w_b x w_d + R_b^T R_d Omega_d_dot (Lee's -J(w_b^ R^T R_d Omega_d - R^T R_d
Omega_d_dot) term). Omega_d and its derivative need F' and F'', taken from the vehicle's own
model m p_b'' = f R_b e3 - m g e3, as the paper does for the CoM ((9a), docs/control.md): the
same functions (:func:`aerial_drake.control.law.desired_force`, :func:`desired_attitude`).
On a rigid body of inertia J_v the closed loop is m e_x'' + D_x e_x' + K_x e_x = 0 (near
hover) and J_v e_w' + k_w e_w + k_R e_R = 0: with Table II's gains and J_v = Lambda2_bar
(Table I's body inertia, as Table II's) the same poles as the paper's (23a)-(23c).
"""

from __future__ import annotations

import typing

import numpy as np

from aerial_drake.control.law import desired_attitude, desired_force
from aerial_drake.dynamics.decoupling import cross, vee

_e3 = np.array([0.0, 0.0, 1.0])


class VehicleCommand(typing.NamedTuple):
    f: float  # thrust along body z (N)
    mu: np.ndarray  # body torques (N m), body frame
    R_d: np.ndarray  # commanded attitude (13)
    e_R: np.ndarray  # (14)
    e_w: np.ndarray  # (15)
    F_norm: float  # |F|, the desired force's norm (Assumption 2's analogue)


def heading_derivatives(b1d: np.ndarray) -> np.ndarray:
    """Rows b1d and its first four derivatives (5, 3) from the reference's first three, for a
    horizontal heading turning at a constant rate w (the paper's (32), phi4 = 0.5 t):
    b1d''' = -w^2 b1d', b1d'''' = -w^2 b1d'', w^2 = |b1d'|^2."""
    w2 = float(b1d[1] @ b1d[1])
    return np.vstack([b1d, -w2 * b1d[1], -w2 * b1d[2]])


def body_reference(com_reference: np.ndarray, b1d: np.ndarray, offset_H: np.ndarray,
                   ) -> np.ndarray:
    """The body position reference p_bd and its first four derivatives (5, 3): the CoM
    reference less a constant CoM offset ``offset_H`` from the body, held in the heading frame
    H = [b1d, e3 x b1d, e3] (the offset at the reference configuration: what a planner for
    the vehicle alone would fly, given (33))."""
    b1 = heading_derivatives(b1d)
    b2 = np.cross(_e3, b1)  # row-wise: e3 x b1^(k)
    shift = offset_H[0] * b1 + offset_H[1] * b2
    shift[0] += offset_H[2] * _e3
    return com_reference - shift


def geometric_vehicle_law(m: float, gravity: float, J_v: np.ndarray, body_ref: np.ndarray,
                          b1d: np.ndarray, p_b: np.ndarray, v_b: np.ndarray, R: np.ndarray,
                          w_b: np.ndarray, K_x: np.ndarray, D_x: np.ndarray, k_R: float,
                          k_w: float) -> VehicleCommand:
    """Lee et al.'s law at one state (module docstring). ``J_v`` is the (3, 3) inertia the law
    assumes, ``w_b`` the body angular velocity in the body frame, ``v_b`` the body origin's
    velocity in World, ``b1d`` the heading rows (3, 3)."""
    e_x, e_v = p_b - body_ref[0], v_b - body_ref[1]
    F = desired_force(m, gravity, body_ref, e_x, e_v, K_x, D_x)
    Re3 = R[:, 2]
    f = float(F @ Re3)
    # F' and F'' from the vehicle's own model m p_b'' = f R e3 - m g e3.
    e_a = f * Re3 / m - gravity * _e3 - body_ref[2]
    F_dot = m * body_ref[3] - K_x * e_v - D_x * e_a
    Re3_dot = R @ cross(w_b, _e3)
    f_dot = F_dot @ Re3 + F @ Re3_dot
    e_j = (f_dot * Re3 + f * Re3_dot) / m - body_ref[3]
    F_ddot = m * body_ref[4] - K_x * e_a - D_x * e_j
    R_d, R_d_dot, R_d_ddot, _ = desired_attitude(F, F_dot, F_ddot, b1d)
    Omega_d = vee(R_d.T @ R_d_dot)
    Omega_d_dot = vee(R_d_dot.T @ R_d_dot + R_d.T @ R_d_ddot)
    RtRd = R.T @ R_d
    w_d = RtRd @ Omega_d
    w_d_dot = -cross(w_b, w_d) + RtRd @ Omega_d_dot
    e_R = vee(R_d.T @ R)
    e_w = w_b - w_d
    mu = -k_R * e_R - k_w * e_w + cross(w_b, J_v @ w_b) + J_v @ w_d_dot
    return VehicleCommand(f=f, mu=mu, R_d=R_d, e_R=e_R, e_w=e_w,
                          F_norm=float(np.linalg.norm(F)))


def static_arm_moment(m: float, gravity: float, x_g: np.ndarray, p_b: np.ndarray,
                      R: np.ndarray) -> np.ndarray:
    """The body torque (body frame) that cancels the arm's static moment about the body's
    centre of mass at the current posture ([3]): the arm's weight m_a g at its CoM p_a is
    m g (x_g - p_b) x e3 about p_b in World (m_a (p_a - p_b) = m (x_g - p_b), the body's own
    weight having no moment about its CoM); the arm's static force, its weight, is already in
    the total-mass hover thrust."""
    return R.T @ (m * gravity * cross(x_g - p_b, _e3))
