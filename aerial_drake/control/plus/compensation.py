"""``paper_plus``'s wrench compensation (pure numpy; docs/control.md, "Wrench compensation").

The law (16), (19)-(20) predicts the vehicle's angular and the arm's task accelerations from the
model, which has no external wrench: a wrench on the end effector is resisted only through the
error it causes (K_z z~ = J_3^-T times its share; docs/baselines.md, "Wrench amplification").
With an estimate tau^ of the external generalized force (the momentum observer's, in Drake's
velocities v = [w_WB; v_WBo; q_dot]), the decoupled coordinates xi = T v of (3) see
T^-T tau^: the total force on the CoM rows, the moment about the CoM on w_b's, and on rho's
the joint torques of the wrench relative to the CoM. The vehicle force is the CoM law's
business (``vehicle_force_feedforward``, (10)). The other two are fully actuated: adding
-(T^-T tau^) on w_b's and rho's rows of u' in (8) cancels them, which is (16) and (20) with the
model's accelerations corrected by the observer. Through (22), F = T^T u', that is

    F_c = T^T [0; -(T^-T tau^)_2; -(T^-T tau^)_3] = -(tau^ - J_g^T F^),    F^ = tau^'s force rows,

using T^T T^-T = I and T's first block row J_g (x_g' = J_g v); T^-T tau^'s first block is F^
because T^-1's first block column is [0; I; 0] (moving x_g alone translates the whole robot).
F_c's force rows are -F^ + F^ = 0 (J_g's v_WBo columns are I): the thrust is untouched, the
compensation goes to the vehicle moment (mu = R^T F_c's moment rows, body axes, as (22)) and
the arm torques (F_c's joint rows).
"""

from __future__ import annotations

import numpy as np


def compensation(tau_hat: np.ndarray, J_g: np.ndarray, R_WB: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
    """(mu_c (3, body axes), tau_c (n)): what is added to the law's vehicle moment and arm
    torques to cancel the estimated external generalized force ``tau_hat`` (nv, Drake's
    velocities) but for its total force (module docstring).

    Args:
        tau_hat: the external generalized force estimate (nv): moment about the base origin
            (World), force (World), joint torques.
        J_g: the CoM's translational velocity Jacobian (3, nv), World, w.r.t. Drake's v.
        R_WB: the vehicle's attitude (3, 3).
    """
    F_c = J_g.T @ tau_hat[3:6] - tau_hat  # -(tau^ - J_g^T F^)
    return R_WB.T @ F_c[:3], F_c[6:]
