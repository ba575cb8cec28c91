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
