"""How far the desired end effector can move from the nominal posture's along each heading-frame
direction with the CoM, the base attitude, the end effector's orientation and the task's
joints held: the configurations are followed by Newton steps
(:func:`~aerial_drake.dynamics.equilibrium.track_configuration`, the full solve
:func:`~aerial_drake.dynamics.equilibrium.solve_configuration` as its fallback) in steps of
:data:`REACH_STEP`, until sigma_min(J_3) reaches the scenario's Assumption-1 limit, a joint
its position limit, or no configuration exists; then bisected to :data:`REACH_TOLERANCE`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from aerial_drake.analysis.onboarding.check_subject import CheckSubject
from aerial_drake.analysis.onboarding.margins import DIRECTIONS
from aerial_drake.control.reference_pose import realising_targets
from aerial_drake.dynamics.equilibrium import (
    UnreachablePose,
    kinematic_J3,
    solve_configuration,
    track_configuration,
)

#: The march's step (m) and the bisection's final bracket (m).
REACH_STEP = 0.01
REACH_TOLERANCE = 0.001
#: The search stops here (m): reported as "at least".
REACH_CAP = 3.0


@dataclass(frozen=True)
class Reach:
    """How far the end effector moves along one direction from the nominal posture."""

    direction: str  # "+x", ... (heading frame)
    distance: float  # m
    capped: bool  # nothing binds up to REACH_CAP
    binding: str  # what stops it
    sigma_min: float  # sigma_min(J_3) at ``distance``

    def to_json(self) -> dict:
        return {"direction": self.direction, "distance_m": self.distance,
                "capped": self.capped, "binding": self.binding,
                "sigma_min_J3": self.sigma_min}


def _configuration(subject: CheckSubject, targets: dict, q_guess: np.ndarray, ctx
                   ) -> np.ndarray | None:
    q = track_configuration(subject.model, q_guess, ctx, **targets)
    if q is not None:
        return q
    try:
        return solve_configuration(subject.model, **targets, q_guess=q_guess,
                                   respect_joint_limits=False)
    except UnreachablePose:
        return None


def _limits(subject: CheckSubject, q: np.ndarray, ctx, sigma_limit: float
            ) -> tuple[str, float]:
    """What the configuration ``q`` violates ("" when nothing) and its sigma_min(J_3)."""
    model = subject.model
    model.plant.SetPositions(ctx, q)
    sigma = float(np.linalg.svd(kinematic_J3(model, ctx), compute_uv=False)[-1])
    if not sigma > sigma_limit:
        return (f"Assumption 1: sigma_min(J_3) reaches the limit {sigma_limit:g}", sigma)
    if subject.scenario.joint_limits.positions == "report":  # runs go past them
        return "", sigma
    lower, upper = model.arm_position_limits()
    q_arm = q[model.arm_position_indices]
    for joint, value, low, high in zip(model.arm_joints, q_arm, lower, upper):
        if not low <= value <= high:
            return (f"joint '{joint.name()}' reaches its position limit "
                    f"{high if value > high else low:.3f} rad", sigma)
    return "", sigma


def reach(subject: CheckSubject) -> list[Reach]:
    """The :class:`Reach` of each of the six directions (module docstring)."""
    model = subject.model
    ctx = model.plant.CreateDefaultContext()
    sigma_limit = float(subject.scenario.sigma_min_J3_limit)
    base = realising_targets(model, subject.hover, (subject.mass, subject.gravity))
    p0 = np.asarray(base["p_WE"], dtype=float)
    out = []
    for label, axis, sign in DIRECTIONS:
        u = sign * subject.heading_axes[:, axis]

        def at(d: float, q_guess: np.ndarray) -> tuple[np.ndarray | None, str, float]:
            q = _configuration(subject, {**base, "p_WE": p0 + d * u}, q_guess, ctx)
            if q is None:
                return None, "the arm's workspace ends (no configuration realises it)", 0.0
            why, sigma = _limits(subject, q, ctx, sigma_limit)
            return (None, why, sigma) if why else (q, "", sigma)

        lo, q_lo, sigma_lo = 0.0, subject.q0, _limits(subject, subject.q0, ctx, 0.0)[1]
        hi, why = None, ""
        while lo < REACH_CAP:
            q, why_d, sigma = at(lo + REACH_STEP, q_lo)
            if q is None:
                hi, why = lo + REACH_STEP, why_d
                break
            lo, q_lo, sigma_lo = lo + REACH_STEP, q, sigma
        if hi is None:
            out.append(Reach(label, lo, True, "", sigma_lo))
            continue
        while hi - lo > REACH_TOLERANCE:
            mid = 0.5 * (lo + hi)
            q, why_d, sigma = at(mid, q_lo)
            if q is None:
                hi, why = mid, why_d
            else:
                lo, q_lo, sigma_lo = mid, q, sigma
        out.append(Reach(label, lo, False, why, sigma_lo))
    return out
