"""Where the baselines' vehicle law gets its inertia, and what its attitude loop's poles are.

The rule (docs/baselines.md, "Tuning"): Lee et al.'s attitude law assumes the rotational
inertia ``J_v`` of what it flies. With the arm on board that is the whole robot's, locked at
its posture, about the system's centre of mass: :func:`locked_inertia`, taken once at the
reference configuration of t = 0 (a constant, as a user would identify it, beside the total
mass the vehicle law already uses). The gains k_R, k_w stay Table II's; :func:`attitude_poles`
gives the closed-loop poles of one axis of ``J s^2 + k_w s + k_R`` with the first-order
actuator lag of the disturbed plant, ``J tau s^3 + J s^2 + k_w s + k_R = 0``.
"""

from __future__ import annotations

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import BodyIndex, RigidBody


def locked_inertia(plant: MultibodyPlant, base_body: RigidBody, q: np.ndarray) -> np.ndarray:
    """The rotational inertia (3, 3), kg m^2, of every body of ``plant`` rigidly locked at
    positions ``q``, about the system's centre of mass, expressed in ``base_body``'s frame."""
    ctx = plant.CreateDefaultContext()
    plant.SetPositions(ctx, q)
    bodies = [BodyIndex(i) for i in range(1, plant.num_bodies())]  # all but World
    M_So_B = plant.CalcSpatialInertia(ctx, base_body.body_frame(), bodies)
    return M_So_B.Shift(M_So_B.get_com()).CalcRotationalInertia().CopyToFullMatrix3()


def attitude_poles(inertia: float, k_R: float, k_w: float, lag_time_constant: float = 0.0
                   ) -> np.ndarray:
    """The closed-loop poles (1/s) of one attitude axis of inertia ``inertia`` (kg m^2)
    under ``mu = -k_R e_R - k_w e_w`` (linearised), the torque lagging by a first-order
    system of time constant ``lag_time_constant`` (s; 0: no lag), sorted by real part."""
    J, tau = float(inertia), float(lag_time_constant)
    coefficients = [J * tau, J, k_w, k_R] if tau > 0 else [J, k_w, k_R]
    roots = np.roots(coefficients)
    return roots[np.argsort(-roots.real)]


def tilt_loop_poles(inertia: float, assumed_inertia: float, m: float, gravity: float,
                    K_x: float, D_x: float, k_R: float, k_w: float,
                    lag_time_constant: float = 0.0) -> np.ndarray:
    """The closed-loop poles (1/s, sorted by real part) of one tilt axis of the vehicle law
    with its body-position loop, linearised at hover: ``m x'' = m g phi``,
    ``inertia phi'' = mu`` (``mu`` lagging the command by ``lag_time_constant``), and the
    command ``-k_R (phi - phi_d) - k_w (phi' - w_d) + assumed_inertia w_d'`` with ``phi_d``,
    ``w_d``, ``w_d'`` from ``F = -K_x x - D_x x'`` and its derivatives through the vehicle's
    own model ``x'' = g phi`` (:func:`.vehicle.geometric_vehicle_law`). Without the lag and
    with ``assumed_inertia == inertia`` they are the roots of ``m s^2 + D_x s + K_x`` and of
    ``inertia s^2 + k_w s + k_R``."""
    J, J_v, tau, mg = float(inertia), float(assumed_inertia), float(lag_time_constant), m * gravity

    def rates(s: np.ndarray) -> np.ndarray:
        x, v, phi, w, mu = s
        phi_d = (-K_x * x - D_x * v) / mg
        w_d = (-K_x * v - D_x * gravity * phi) / mg  # F' with the model's x'' = g phi
        w_d_dot = (-K_x * gravity * phi - D_x * gravity * w) / mg
        command = -k_R * (phi - phi_d) - k_w * (w - w_d) + J_v * w_d_dot
        if tau > 0:
            return np.array([v, gravity * phi, w, mu / J, (command - mu) / tau])
        return np.array([v, gravity * phi, w, command / J, 0.0])

    A = np.column_stack([rates(e) for e in np.eye(5)])
    if not tau > 0:
        A = A[:4, :4]
    poles = np.linalg.eigvals(A)
    return poles[np.argsort(-poles.real)]
