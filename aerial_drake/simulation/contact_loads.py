"""Whether the robot can hold a force task's pressing force (docs/contact.md, "Checks
before the run"): the statics of the robot at the reference posture, pressing with F along
the unit direction d at the tool's contact point (the surface pushes back with -F d).

- the thrust vector m (x_d'' + g e3) + F d (holding still: m g e3 + F d): its norm within
  [max(thrust minimum, f_d_limit), thrust maximum];
- the body torques about the vehicle frame B's origin, where the thrust acts: those of the
  robot's weight and of the contact force, (p_G - p_B) x m g e3 + F (p_C - p_B) x d, in B,
  within the body torque bounds;
- the arm's joint torques, -tau_g + F (J_C^T d) (tau_g Drake's gravity generalized force,
  J_C the contact point's translational Jacobian), within the effort limits.

Each is affine in F (the thrust's norm convex), so the largest F that keeps every one within
its limits has a closed form per sample; over the window the desired force is ``force``
times its profile, and the largest feasible ``controller.force.force`` is the smallest of
the samples' bounds over their profile. The limits are the run's command limits
(:func:`aerial_drake.control.limits.command_limits`: the robot's, or the scenario's
``actuation`` overrides); a scenario that does not saturate (``actuation.saturate: false``)
has none, as the reference's own thrust check (:func:`aerial_drake.simulation.feasibility.
check_thrust`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from pydrake.multibody.tree import JacobianWrtVariable

from aerial_drake.control.force.params import ForceTaskParams
from aerial_drake.control.limits import command_limits
from aerial_drake.control.reference_pose import mass_and_gravity
from aerial_drake.robots.models import AerialManipulator
from aerial_drake.simulation.scenarios import Scenario, ScenarioError


def largest_in_box(v0: np.ndarray, a: np.ndarray, lower: np.ndarray, upper: np.ndarray
                   ) -> tuple[float, int]:
    """The largest F >= 0 with ``lower <= v0 + F a <= upper`` for every F' in [0, F] (inf if
    none binds), and the index of the row that binds (-1 if none); 0 if ``v0`` is already
    outside."""
    best, row = math.inf, -1
    for i, (v, s, lo, hi) in enumerate(zip(v0, a, lower, upper)):
        if not lo <= v <= hi:
            return 0.0, i
        bound = (hi - v) / s if s > 0 else (lo - v) / s if s < 0 else math.inf
        if bound < best:
            best, row = float(bound), i
    return best, row


def largest_thrust_force(a: np.ndarray, d: np.ndarray, low: float, high: float
                         ) -> tuple[float, str]:
    """The largest F >= 0 with ``low <= |a + F d| <= high`` for every F' in [0, F] (``d``
    unit), and which bound binds ("maximum", "minimum", or "" if none)."""
    ad, aa = float(a @ d), float(a @ a)
    if not low <= math.sqrt(aa) <= high:
        return 0.0, "maximum" if math.sqrt(aa) > high else "minimum"
    # |a + F d|^2 = F^2 + 2 F (a.d) + |a|^2: first decreasing (a.d < 0) to its least value
    # |a|^2 - (a.d)^2 at F = -a.d, then increasing.
    up = -ad + math.sqrt(ad * ad - aa + high * high) if math.isfinite(high) else math.inf
    down = math.inf
    if ad < 0 and aa - ad * ad < low * low:
        down = -ad - math.sqrt(ad * ad - aa + low * low)
    if down < up:
        return down, "minimum"
    return up, "maximum" if math.isfinite(up) else ""


def check_force(scenario: Scenario, model: AerialManipulator, samples: list[Any],
                force: ForceTaskParams, direction: np.ndarray) -> float:
    """Raise ScenarioError naming ``controller.force.force`` if the robot cannot hold it at a
    sample (a :class:`~aerial_drake.simulation.contact_checks.ContactSample`) of the window
    (module docstring); returns the largest force it can hold (N; inf without limits)."""
    lower, upper = command_limits(scenario.actuation, model)
    m, g = mass_and_gravity(model)
    plant = model.plant
    context = plant.CreateDefaultContext()
    arm = model.arm_velocity_indices
    names = [j.name() for j in model.arm_joints]
    e3 = np.array([0.0, 0.0, 1.0])
    worst = (math.inf, None, "")
    for sample in samples:
        if sample.share <= 0:
            continue
        plant.SetPositions(context, sample.q)
        p_WC = sample.contact_point(direction)
        X_WV = plant.EvalBodyPoseInWorld(context, model.base_body)  # thrust and torques: B
        p_B = X_WV.translation()
        R_BW = X_WV.rotation().inverse().matrix()
        thrust = m * (sample.com_accel + g * e3)
        bound, binds = largest_thrust_force(
            thrust, direction, max(float(lower[0]), scenario.f_d_limit), float(upper[0]))
        what = f"the thrust {binds}" if binds else ""
        p_G = plant.CalcCenterOfMassPositionInWorld(context)
        mu0 = R_BW @ np.cross(p_G - p_B, m * g * e3)
        mu_a = R_BW @ np.cross(p_WC - p_B, direction)
        b, row = largest_in_box(mu0, mu_a, lower[1:4], upper[1:4])
        if b < bound:
            bound, what = b, f"the body torque about the vehicle's {'xyz'[row]} axis"
        p_BC = sample.X_WB.inverse().multiply(p_WC)
        J = plant.CalcJacobianTranslationalVelocity(
            context, JacobianWrtVariable.kV, model.end_effector_body.body_frame(), p_BC,
            plant.world_frame(), plant.world_frame())
        tau0 = -plant.CalcGravityGeneralizedForces(context)[arm]
        b, row = largest_in_box(tau0, (J.T @ direction)[arm], lower[4:], upper[4:])
        if b < bound:
            bound, what = b, f"joint '{names[row]}''s effort limit"
        if bound / sample.share < worst[0]:
            worst = (bound / sample.share, sample, what)
    largest, sample, what = worst
    if force.force > largest:
        assert sample is not None
        at_zero = largest == 0.0
        raise ScenarioError(
            f"controller.force.force: {force.force:g} N is more than the robot can press "
            f"with along {np.round(direction, 3).tolist()}: "
            + (f"even without pressing, {what} is exceeded at t = {sample.t:.3f} s "
               "(the reference posture's own load)" if at_zero else
               f"the largest force it holds is {largest:.4g} N, where {what} binds at t = "
               f"{sample.t:.3f} s")
            + f" (statics at the reference posture: the thrust m g e3 + F d, m = {m:.3g} kg; "
            "the body torques of the weight and of the contact force about the vehicle "
            "frame; the joint torques of gravity and J^T F; against the command limits: the "
            "robot's limits or the actuation section). Fix: "
            + (f"lower controller.force.force to at most {largest:.4g} N, or " if not at_zero
               else "")
            + "change the posture (the end-effector waypoints: a shorter lever from the "
            "vehicle, an arm posture the force loads less), or the direction, or raise the "
            "actuation limits if the robot has them", "controller.force.force")
    return largest
