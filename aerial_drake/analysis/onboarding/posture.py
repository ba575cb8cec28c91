"""The nominal hover posture ``robot init`` chooses (docs/robots.md, "robot init").

The vehicle level at the origin, the arm at ``q``; the posture maximises

    score(q) = min( sigma_min(J_3(q)) / sigma_ref ,  joint margin(q) ,  p_task(q) / p_CoM )

the margins the paper's law lives on: Assumption 1, the room each joint has to move before
its limit, and how fast the task loop can be made there.

- ``sigma_ref``: the largest sigma_min(J_3) among the random draws (so each term is about 1
  at its best);
- ``joint margin``: the smallest of ``2 min(q - lower, upper - q) / (upper - lower)`` over
  the joints (1 at mid-range, 0 at a limit; a joint without limits counts 1);
- ``p_task``: the slowest pole of ``-Lambda_z^-1 K_z`` with the K_z rule of
  :mod:`~aerial_drake.analysis.onboarding.gains` at ``q``,
  over ``p_CoM`` = :data:`TASK_SPEED_TARGET`, Table II's slowest CoM root. Where the task's
  inertia is ill conditioned (a light wrist whose orientation moves heavy links) the K_z the
  sampling allows leaves a task root far slower than the vehicle's: 0.65 1/s at a hexacopter
  arm's first posture, whose end effector then turned 0.8 rad under a slowly growing push.

Subject to: the tool axis pointing where asked (``tool direction``; a minimum-norm Newton
projection after every step), the arm's weight held at hover with at most
:data:`HOVER_TORQUE_SHARE` of each body torque bound (the arm hanging far to one side would
spend the vehicle's torque on holding it), and the end effector at least
:data:`BELOW_SHARE` of the arm's length below the vehicle's frame (an arm folded up beside
the vehicle reaches into its rotors). A random search over the joint ranges, then a
shrinking random local search from the best: no gradient is needed, and sigma_min is not
smooth where singular values cross. Drake's ``InverseKinematics`` is not used here: the
pointing constraint alone is two equations that a minimum-norm Newton step meets to 1e-6 rad
in a few iterations, and a mathematical program per candidate (800 of them) would cost more
than the score it serves; the run's start posture is still solved with it
(:func:`aerial_drake.dynamics.equilibrium.solve_configuration`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from aerial_drake.analysis.equilibria import hover_inputs
from aerial_drake.analysis.onboarding.errors import OnboardingError
from aerial_drake.analysis.onboarding.gains import slowest_task_pole, table_ii_K_z
from aerial_drake.analysis.onboarding.writer import CONTROLLER_PERIOD
from aerial_drake.control.law import SIGMA_MIN_J3_LIMIT
from aerial_drake.dynamics.equilibrium import kinematic_J3
from aerial_drake.robots.models import AerialManipulator

#: The share of each body torque bound the arm's weight may take at hover.
HOVER_TORQUE_SHARE = 0.3
#: The task speed the score's third term asks for (1/s): Table II's slowest CoM root.
TASK_SPEED_TARGET = 3.5
#: How far below the vehicle's frame the end effector must be, in arm lengths.
BELOW_SHARE = 0.3
#: Pointing is met when the tool axis is within this angle of the direction (rad).
POINTING_TOLERANCE = 1e-6
#: The range searched for a joint without position limits (rad).
UNBOUNDED_RANGE = (-np.pi, np.pi)


@dataclass(frozen=True)
class Posture:
    """The chosen posture and its margins."""

    q_arm: np.ndarray  # (n) rad
    sigma_min_J3: float
    joint_margin: float  # 0 (at a limit) .. 1 (every joint mid-range)
    task_speed: float  # the slowest task pole under the K_z rule (1/s)
    hover_torque_share: float  # max over axes of |mu_hover| / bound
    pointing_error: float  # rad (0 without a tool direction)
    score: float
    ee_height: float  # the end effector's height above the vehicle's frame (m)


def arm_length(manip: AerialManipulator, ctx) -> float:
    """The distance along the chain from the first joint to the end effector (m): the joints'
    origins and the end effector at the positions in ``ctx`` (the same at any posture)."""
    points = [j.frame_on_child().CalcPoseInWorld(ctx).translation() for j in manip.arm_joints]
    points.append(manip.end_effector_frame.CalcPoseInWorld(ctx).translation())
    return float(sum(np.linalg.norm(b - a) for a, b in zip(points, points[1:])))


class _Evaluator:
    """The score's terms at a posture, with the plant's context reused."""

    def __init__(self, manip: AerialManipulator, tool_axis: np.ndarray,
                 direction: np.ndarray | None) -> None:
        self.manip, self.plant = manip, manip.plant
        self.ctx = self.plant.CreateDefaultContext()
        self.q = self.plant.GetPositions(self.ctx)  # the base level at the origin
        self.arm = manip.arm_position_indices
        self.arm_v = manip.arm_velocity_indices
        lower, upper = manip.arm_position_limits()
        self.bounded = np.isfinite(lower) & np.isfinite(upper)
        self.lower = np.where(self.bounded, lower, UNBOUNDED_RANGE[0])
        self.upper = np.where(self.bounded, upper, UNBOUNDED_RANGE[1])
        self.axis, self.direction = tool_axis, direction
        self.torque_bound = manip.body_torque_limits()
        self.K_z0 = table_ii_K_z(manip)
        self.plant.SetPositions(self.ctx, self.q)
        self.min_depth = BELOW_SHARE * arm_length(manip, self.ctx)

    def _set(self, q_arm: np.ndarray) -> np.ndarray:
        q = self.q.copy()
        q[self.arm] = q_arm
        self.plant.SetPositions(self.ctx, q)
        return q

    def pointing(self, q_arm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The rotation (World) that would turn the tool axis onto the direction, and the
        arm's columns of the end effector's angular-velocity Jacobian."""
        from pydrake.multibody.tree import JacobianWrtVariable

        self._set(q_arm)
        frame, world = self.manip.end_effector_frame, self.plant.world_frame()
        a = frame.CalcPoseInWorld(self.ctx).rotation().matrix() @ self.axis
        d = self.direction
        assert d is not None
        s = np.cross(a, d)
        angle = np.arctan2(np.linalg.norm(s), float(a @ d))
        w = s / np.linalg.norm(s) * angle if np.linalg.norm(s) > 1e-15 else (
            np.zeros(3) if a @ d > 0 else np.cross(a, [1.0, 0.0, 0.0]) * np.pi)
        J = self.plant.CalcJacobianSpatialVelocity(self.ctx, JacobianWrtVariable.kV, frame,
                                                   np.zeros(3), world, world)[:3, self.arm_v]
        return w, J

    def project(self, q_arm: np.ndarray) -> tuple[np.ndarray, float]:
        """``q_arm`` moved the least (Newton, minimum norm) to point the tool; the angle
        left."""
        if self.direction is None:
            return q_arm, 0.0
        q = q_arm.copy()
        for _ in range(30):
            w, J = self.pointing(q)
            if np.linalg.norm(w) < POINTING_TOLERANCE:
                break
            q = np.clip(q + np.linalg.lstsq(J, w, rcond=None)[0], self.lower, self.upper)
        return q, float(np.linalg.norm(self.pointing(q)[0]))

    def terms(self, q_arm: np.ndarray) -> tuple[float, float, float, float, float]:
        """(sigma_min(J_3), joint margin, slowest task pole (1/s), hover torque share, how far
        the end effector is above the lowest it may be (m; > 0 too high)) at ``q_arm``."""
        q = self._set(q_arm)
        height = float(self.manip.end_effector_frame.CalcPoseInWorld(self.ctx).translation()[2]
                       - self.q[self.manip.base_position_indices][-1])
        sigma = float(np.linalg.svd(kinematic_J3(self.manip, self.ctx), compute_uv=False)[-1])
        room = np.minimum(q_arm - self.lower, self.upper - q_arm) / (self.upper - self.lower)
        margin = float(np.min(np.where(self.bounded, 2.0 * room, 1.0), initial=1.0))
        _, mu, _, _ = hover_inputs(self.manip, q)
        share = float(np.max(np.abs(mu) / self.torque_bound))
        # The task speed only where the constraints hold (it costs nine mass matrices).
        keep = share <= HOVER_TORQUE_SHARE and height + self.min_depth <= 0.0
        speed = (slowest_task_pole(self.manip, q, self.K_z0, CONTROLLER_PERIOD)
                 if sigma > SIGMA_MIN_J3_LIMIT and keep else 0.0)
        return sigma, margin, speed, share, height + self.min_depth


_Found = tuple[np.ndarray, float, float, float, float, float, float]  # q, terms, pointing


def _score(found: _Found, sigma_ref: float) -> float:
    _, sigma, margin, speed, share, too_high, pointing = found
    penalty = (10.0 * max(0.0, share - HOVER_TORQUE_SHARE) + 10.0 * max(0.0, too_high)
               + 1e3 * pointing)
    return min(sigma / sigma_ref, margin, speed / TASK_SPEED_TARGET) - penalty


def choose_posture(manip: AerialManipulator, *, tool_axis: np.ndarray,
                   direction: np.ndarray | None, draws: int = 400, refinements: int = 400,
                   seed: int = 0) -> Posture:
    """The posture of the module docstring (reproducible: ``seed``), for the task of
    ``manip``; ``direction`` None: the tool may point anywhere."""
    ev = _Evaluator(manip, np.asarray(tool_axis, float), direction)
    rng = np.random.default_rng(seed)
    span = ev.upper - ev.lower
    # Keep the draws off the limits: a posture at a limit has no margin anyway.
    lo, hi = ev.lower + 0.1 * span, ev.upper - 0.1 * span
    found: list[_Found] = []
    for q in [np.clip(manip.q_nominal_arm(), lo, hi)] + [rng.uniform(lo, hi) for _ in
                                                         range(draws)]:
        q, pointing = ev.project(q)
        found.append((q, *ev.terms(q), pointing))
    sigma_ref = max(f[1] for f in found)
    if not sigma_ref > SIGMA_MIN_J3_LIMIT:
        raise OnboardingError(f"task {list(manip.description.task)}: J_3 is singular at every "
                              "posture drawn, so the arm cannot hold this task (Assumption 1): "
                              "choose other components with --task", "--task")
    best = max(found, key=lambda f: _score(f, sigma_ref))
    best_score = _score(best, sigma_ref)
    step = 0.2 * span
    for i in range(refinements):
        q, pointing = ev.project(np.clip(best[0] + rng.normal(0.0, 1.0, span.size) * step,
                                         ev.lower, ev.upper))
        trial: _Found = (q, *ev.terms(q), pointing)
        score = _score(trial, sigma_ref)
        if score > best_score:
            best, best_score = trial, score
        elif i % 20 == 19:
            step = step * 0.7  # narrow down where no step has helped lately
    q, sigma, margin, speed, share, too_high, pointing = best
    return Posture(q_arm=q, sigma_min_J3=sigma, joint_margin=margin, task_speed=speed,
                   hover_torque_share=share,
                   pointing_error=pointing, score=best_score,
                   ee_height=too_high - ev.min_depth)
