"""The arm's law of the baselines: task-space computed torque on the arm's own fixed-base
model, the base treated as inertial (Khatib's operational-space formulation, "A unified
approach for motion and force control of robot manipulators", IEEE J. Robot. Autom. 1987;
Siciliano et al., "Robotics", 2009, sec. 8.6), tracking the paper's task y_d (27) with the
paper's task gains K_y, K_z in the paper's cascade (17)-(19). Its errors are measured as the
paper's are, in World from the full state (the vehicle's state estimate gives the base's pose
and twist, so the base's motion is seen kinematically); its dynamics are the fixed-base
arm's, blind to the base's acceleration and to the coupling:

    y~ = task_error(...),   y~' = y' - y_d'  (measured, World: y' = J_y v),
    s  = y~' + K_y y~                                   (the analogue of z~, (18)),
    tau = J_a^T [Lambda_a (y_d'' - K_y y~' - J_a' q') - K_z s] + C_aa q' + g_a,

with J_a the task Jacobian's arm columns, J_a' q' its bias at zero base velocity, M_aa the arm
block of M, C_aa q' + g_a the arm rows of the bias and gravity terms at zero base velocity,
and Lambda_a = (J_a M_aa^{-1} J_a^T)^{-1}. On a fixed base the closed loop is
Lambda_a s' + K_z s = 0, y~' + K_y y~ = s: the paper's (23d)-(23e) with the fixed-base task
inertia Lambda_a in place of Lambda_z (and its Coriolis term cancelled by C_aa q').
"""

from __future__ import annotations

import typing

import numpy as np


class ArmCommand(typing.NamedTuple):
    tau: np.ndarray  # joint torques (N m)
    s: np.ndarray  # y~' + K_y y~ (the arm's estimate)
    sigma_min: float  # smallest singular value of J_a


def fixed_base_task_torque(J_a: np.ndarray, bias: np.ndarray, M_aa: np.ndarray,
                           h_a: np.ndarray, y_dot: np.ndarray, y_t: np.ndarray,
                           y_d_dot: np.ndarray, y_d_ddot: np.ndarray, K_y: np.ndarray,
                           K_z: np.ndarray) -> ArmCommand:
    """The law of the module docstring; ``bias`` = J_a' q', ``h_a`` = C_aa q' + g_a (the
    generalized force the arm's motors must supply at zero acceleration), ``y_dot`` the
    measured task velocity."""
    sigma_min = float(np.sqrt(max(np.linalg.eigvalsh(J_a.T @ J_a)[0], 0.0)))
    y_t_dot = y_dot - y_d_dot
    s = y_t_dot + K_y * y_t
    qdd = np.linalg.solve(J_a, y_d_ddot - K_y * y_t_dot - bias)
    # M_aa J_a^{-1} Lambda_a^{-1} = J_a^T: the K_z term needs no inverse of M.
    tau = M_aa @ qdd - J_a.T @ (K_z * s) + h_a
    return ArmCommand(tau=tau, s=s, sigma_min=sigma_min)
