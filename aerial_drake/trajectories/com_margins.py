"""The arm's margin at the postures that realise a reference with the vehicle level:
sigma_min(J_3) of Assumption 1 and the distance to the joint limits, along the run
(:func:`posture_margins`), and the posture solve they share with the CoM planner
(:class:`LevelPostures`, :mod:`aerial_drake.trajectories.com_planning`).

"Level" is the quasi-static choice: the vehicle's roll and pitch zero, its yaw the reference
heading (b1d). The closed loop's attitude is R_d of (13), tilted by x_d'' (at most about a
degree on the shipped references), so the margins here are those of the planned postures, not
of the flown ones (those the scenario checks, simulation/feasibility.py, report too).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from aerial_drake.dynamics.equilibrium import (
    UnreachablePose,
    kinematic_J3,
    solve_configuration,
    task_residual,
    track_configuration,
)
from aerial_drake.robots.models import AerialManipulator
from aerial_drake.trajectories.base import ReferenceSource
from aerial_drake.trajectories.reference import ReferenceSample

__all__ = ["LevelPostures", "PostureMargins", "posture_margins", "level_attitude"]


def level_attitude(b1d: np.ndarray) -> np.ndarray:
    """R_WB of the level vehicle facing the heading b1d (a rotation about World z)."""
    phi = math.atan2(float(b1d[1]), float(b1d[0]))
    c, s = math.cos(phi), math.sin(phi)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


class LevelPostures:
    """The posture with the system CoM at a point, the vehicle level at the reference heading
    and the task on the reference (Newton from the last posture, Drake's InverseKinematics
    where that fails: :func:`~aerial_drake.dynamics.equilibrium.track_configuration`,
    :func:`~aerial_drake.dynamics.equilibrium.solve_configuration`), and its margins."""

    def __init__(self, model: AerialManipulator) -> None:
        self.model = model
        self.context = model.plant.CreateDefaultContext()
        self.lower, self.upper = model.arm_position_limits()
        self.q: np.ndarray | None = None  # the last posture solved

    def targets(self, ref: ReferenceSample, com: np.ndarray) -> dict:
        """solve_configuration's targets: CoM at ``com``, level base, task at ``ref``."""
        return dict(p_WG=np.asarray(com, dtype=float), R_WB=level_attitude(ref.b1d[0]),
                    p_WE=ref.p_ed, R_WE=ref.R_ed, q_j=ref.q_jd)

    def solve(self, targets: dict, q_guess: np.ndarray | None, *, fallback: bool = True
              ) -> np.ndarray | None:
        """The posture for ``targets`` near ``q_guess`` (None: from the nominal posture);
        None if Newton fails and ``fallback`` is False. The context is left at it."""
        q = None if q_guess is None else track_configuration(
            self.model, q_guess, self.context, **targets)
        if q is None and fallback:
            q = solve_configuration(self.model, **targets, q_guess=q_guess,
                                    respect_joint_limits=False)
            self.model.plant.SetPositions(self.context, q)
        return q

    def sigmas(self) -> np.ndarray:
        """Singular values of J_3 of (17) at the context's posture (descending)."""
        return np.linalg.svd(kinematic_J3(self.model, self.context), compute_uv=False)

    def limit_fractions(self, q: np.ndarray) -> np.ndarray:
        """Each arm joint's distance to its nearer limit as a fraction of its range (< 0:
        past it; inf for a joint without limits)."""
        q_arm = q[self.model.arm_position_indices]
        span = self.upper - self.lower
        with np.errstate(invalid="ignore"):
            fraction = np.minimum(q_arm - self.lower, self.upper - q_arm) / span
        return np.where(np.isfinite(span), fraction, np.inf)

    def limit_ratios(self, q: np.ndarray) -> np.ndarray:
        """Each arm joint's q / (its limit on that side): 1 at the limit."""
        q_arm = q[self.model.arm_position_indices]
        return np.where(q_arm >= 0.0, q_arm / self.upper, q_arm / self.lower)

    def residual(self, q: np.ndarray, targets: dict) -> float:
        """Largest miss of the task and the CoM at ``q`` (m or rad)."""
        plant = self.model.plant
        plant.SetPositions(self.context, q)
        task = task_residual(self.model, self.context, q, targets["p_WE"], targets["R_WE"],
                             targets["q_j"])
        com = plant.CalcCenterOfMassPositionInWorld(self.context) - targets["p_WG"]
        return float(max(np.abs(task).max(initial=0.0), np.abs(com).max()))


@dataclasses.dataclass(frozen=True)
class PostureMargins:
    """The margins of a reference's postures (vehicle level) over sampled times."""

    #: The smallest sigma_min(J_3) (Assumption 1) and when (s).
    sigma_min: float
    sigma_time_s: float
    #: The smallest distance of an arm joint to its limit, as a fraction of its range, when
    #: and which joint (1-based); negative: past the limit.
    limit_fraction: float
    limit_time_s: float
    limit_joint: int
    #: The largest |q| / limit of any arm joint (1 at a limit).
    max_limit_ratio: float
    #: The largest miss of the task and the CoM by the solved postures (m or rad).
    max_residual: float

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


def posture_margins(source: ReferenceSource, model: AerialManipulator, times: np.ndarray
                    ) -> PostureMargins:
    """The margins of the postures that realise ``source`` (its x_d, the vehicle level at its
    heading) at each of ``times`` (increasing), each solved from the last. ValueError naming
    the time where no posture reaches the task."""
    postures = LevelPostures(model)
    ref = source.sample(np.asarray(times, dtype=float))
    sigma, fraction, ratio, residual = [], [], [], []
    q = None
    for k, t in enumerate(times):
        sample = sample_at(ref, k)
        targets = postures.targets(sample, sample.com[0])
        try:
            q = postures.solve(targets, q)
        except UnreachablePose as err:
            raise ValueError(f"no posture realises the reference at t = {t:.3f} s with the "
                             f"vehicle level: {err}") from None
        assert q is not None
        sigma.append(postures.sigmas()[-1])
        fraction.append(postures.limit_fractions(q))
        ratio.append(postures.limit_ratios(q).max())
        residual.append(postures.residual(q, targets))
    fractions = np.array(fraction)
    k_s = int(np.argmin(sigma))
    k_l, joint = np.unravel_index(int(np.argmin(fractions)), fractions.shape)
    return PostureMargins(sigma_min=float(sigma[k_s]), sigma_time_s=float(times[k_s]),
                          limit_fraction=float(fractions[k_l, joint]),
                          limit_time_s=float(times[k_l]), limit_joint=int(joint) + 1,
                          max_limit_ratio=float(np.max(ratio)),
                          max_residual=float(np.max(residual)))


def sample_at(ref: ReferenceSample, k: int) -> ReferenceSample:
    """Sample ``k`` of a time-sampled reference."""
    return ReferenceSample(**{f.name: getattr(ref, f.name)[k]
                              for f in dataclasses.fields(ref)})
