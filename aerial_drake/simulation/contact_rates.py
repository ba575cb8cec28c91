"""Two more checks of a force task before the run (docs/contact.md, "Checks before the
run"): rates the contact adds that a step must resolve, beside
:mod:`aerial_drake.simulation.contact_checks`'s contact stiffness.

1. :func:`check_force_loop`: the force task's admittance closes a loop through the contact
   sampled at the controller's period T. Against a surface of stiffness k (the tool's and
   the surface's in series), a force error e moves the reference by about T e / D per
   sample and the force by k T e / D: a discrete loop of gain k T / D, which oscillates
   past 2 (the tool bounced at 2.5-3.3, measured with stiffened tools on the wall press).
   Refused above :data:`MAX_FORCE_LOOP_GAIN`; the field is
   ``controller.force.admittance_damping``.
2. :func:`check_friction`: on the continuous plant Drake's friction grows linearly with the
   slip speed below ``plant.stiction_tolerance`` v_s, a damping c = mu F / v_s at the
   pressing force F. Across the push the robot's apparent mass m_t must let an explicit
   fixed step h resolve it: c h / m_t <= :data:`MAX_FRICTION_STEP` (measured on the wall
   presses: the tangential force flipped sign every few steps at 3.2 (helicopter, Drake's
   1e-4 m/s) and 2.4 (UR3e, 1e-3 m/s), held still at 0.32 and 0.8).
"""

from __future__ import annotations

import math

import numpy as np
from pydrake.multibody.plant import CoulombFriction
from pydrake.multibody.tree import JacobianWrtVariable

from aerial_drake.control.force.params import ForceTaskParams
from aerial_drake.robots.models import AerialManipulator
from aerial_drake.simulation.scenarios import Scenario, ScenarioError

#: The largest force-loop gain k T / D accepted (the discrete loop's limit is 2).
MAX_FORCE_LOOP_GAIN = 1.0
#: The largest c h / m_t accepted for friction's regularised damping.
MAX_FRICTION_STEP = 1.0
#: The friction coefficient assumed for a geometry without one (conservative).
DEFAULT_FRICTION = 1.0


def check_force_loop(scenario: Scenario, force: ForceTaskParams, k: float, pair: str) -> None:
    """Refuse a force loop gain k T / D above :data:`MAX_FORCE_LOOP_GAIN` (module
    docstring); ``k``: the contact's stiffness in series (N/m) of ``pair`` (named)."""
    period = scenario.controller_period
    gain = k * period / force.admittance_damping
    if gain <= MAX_FORCE_LOOP_GAIN:
        return
    raise ScenarioError(
        f"controller.force.admittance_damping = {force.admittance_damping:g} N s/m is too "
        f"small for the contact {pair} (k = {k:.3g} N/m in series) sampled every "
        f"controller_period = {period:g} s: the force loop's gain per sample k T / D = "
        f"{gain:.3g} is above {MAX_FORCE_LOOP_GAIN:g} (past 2 the tool bounces; "
        f"docs/contact.md). Fix: admittance_damping >= {k * period / MAX_FORCE_LOOP_GAIN:.3g}"
        " N s/m, a softer tool pad (its drake:point_contact_stiffness), or a shorter "
        "controller_period", "controller.force.admittance_damping")


def apparent_mass(model: AerialManipulator, q: np.ndarray, p_WC: np.ndarray,
                  direction: np.ndarray) -> float:
    """The robot's apparent mass at the World point ``p_WC`` (fixed on the end-effector
    body) along the unit ``direction``: 1 / (d^T J M^-1 J^T d), J the point's translational
    Jacobian in v, at positions ``q`` of ``model`` (the floating base free: the vehicle
    recoils too)."""
    plant = model.plant
    context = plant.CreateDefaultContext()
    plant.SetPositions(context, q)
    body = model.end_effector_body
    p_BC = plant.EvalBodyPoseInWorld(context, body).inverse().multiply(p_WC)
    J = plant.CalcJacobianTranslationalVelocity(
        context, JacobianWrtVariable.kV, body.body_frame(), p_BC, plant.world_frame(),
        plant.world_frame())
    a = J.T @ direction
    return float(1.0 / (a @ np.linalg.solve(plant.CalcMassMatrix(context), a)))


def pair_friction(inspector, a, b) -> float:
    """The dynamic friction coefficient Drake uses between geometries ``a`` and ``b``:
    2 mu_a mu_b / (mu_a + mu_b), :data:`DEFAULT_FRICTION` for one without its own."""
    mus = []
    for geometry in (a, b):
        props = inspector.GetProximityProperties(geometry)
        # (HasProperty first: Drake 1.58's GetPropertyOrDefault refuses a None default.)
        friction = (props.GetProperty("material", "coulomb_friction")
                    if props is not None and props.HasProperty("material", "coulomb_friction")
                    else None)
        mus.append(friction.dynamic_friction() if isinstance(friction, CoulombFriction)
                   else DEFAULT_FRICTION)
    return 2 * mus[0] * mus[1] / (mus[0] + mus[1]) if sum(mus) > 0 else 0.0


def tangential_mass(model: AerialManipulator, q: np.ndarray, p_WC: np.ndarray,
                    direction: np.ndarray) -> float:
    """The robot's smallest apparent mass at ``p_WC`` across ``direction`` (two orthogonal
    axes across it, :func:`apparent_mass`)."""
    axis = np.eye(3)[int(np.argmin(np.abs(direction)))]
    t1 = np.cross(direction, axis)
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(direction, t1)
    return min(apparent_mass(model, q, p_WC, t1), apparent_mass(model, q, p_WC, t2))


def check_friction(scenario: Scenario, force: ForceTaskParams, mu: float, m_t: float,
                   h: float, pair: str) -> None:
    """Refuse friction's regularised damping c = mu F / v_s that an explicit fixed step
    ``h`` cannot resolve on the apparent mass ``m_t`` across the push (module docstring).
    The caller checks that the plant is continuous and integrated so."""
    v_s = float(scenario.plant.stiction_tolerance)
    c = mu * force.force / v_s
    ratio = c * h / m_t
    if ratio <= MAX_FRICTION_STEP or math.isnan(ratio):
        return
    needed = mu * force.force * h / (MAX_FRICTION_STEP * m_t)
    raise ScenarioError(
        f"plant.stiction_tolerance = {v_s:g} m/s is too small for the force task's "
        f"friction: the contact {pair} (mu {mu:.3g}) pressed with {force.force:g} N has a "
        f"regularised friction damping mu F / v_s = {c:.3g} N s/m, and across the push the "
        f"robot's apparent mass is {m_t:.3g} kg, so c h / m = {ratio:.3g} at the step "
        f"h = {h:g} s, above {MAX_FRICTION_STEP:g}: the tangential force would flip sign "
        f"every few steps (docs/contact.md, \"Which plant\"). Fix: plant.stiction_tolerance "
        f">= {needed:.3g} m/s (the pad then creeps under a steady tangential load), a "
        "shorter simulator.max_step_size, or a discrete plant (plant.time_step: 0.001, "
        "discrete_contact_approximation: sap)", "plant.stiction_tolerance")
