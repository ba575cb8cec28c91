"""The arm's joint limits in a run (the scenario's ``joint_limits``, docs/reliability.md):
the limits read from the simulated plant's model files, the ratios of a logged state to them,
the first logged sample past a limit, the message a run stopped there fails with, and the
``joint_limits`` entries of metrics.json.

Position ratio (per joint and sample): q / upper on the upper side, q / lower on the lower
side, measured from a reference point p inside the range, (q - p) / (limit - p):
p = 0 when the limits have opposite signs (every shipped robot's), else the middle of the
range, or 1 rad (or m) inside a one-sided limit. It is 1 at the limit and > 1 past it; an
infinite side is never reached (ratio 0 there); a joint with no finite limit has none (NaN,
null in metrics.json). Velocity ratio: |v| / v_max (NaN where v_max is infinite).

The check reads the log after the run (no per-step call in the loop); the runner also looks
at the plant's state at each of its progress pauses to stop early (:meth:`LimitMonitor.past`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from pydrake.multibody.plant import MultibodyPlant

from aerial_drake.robots.models import AerialManipulator, add_aerial_manipulator

#: A one-sided limit that does not straddle 0: its ratios are measured from this far inside.
_ONE_SIDED_REFERENCE = 1.0


@dataclass(frozen=True)
class ArmLimits:
    """The arm joints' limits of a plant, and where their q and v sit in its state [q; v]."""

    names: tuple[str, ...]
    revolute: tuple[bool, ...]  # angles (rad, shown in degrees too) or lengths (m)
    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray  # |v| limit (rad/s or m/s), inf for none
    q_index: np.ndarray  # the joints' positions in the state x = [q; v]
    v_index: np.ndarray  # their velocities in x

    @classmethod
    def of(cls, model: AerialManipulator) -> ArmLimits:
        """The limits of ``model``'s arm joints, as its model files give them."""
        lower, upper = model.arm_position_limits()
        nq = model.plant.num_positions()
        return cls(names=tuple(j.name() for j in model.arm_joints),
                   revolute=tuple(j.type_name() == "revolute" for j in model.arm_joints),
                   lower=lower, upper=upper, velocity=np.abs(model.arm_velocity_limits()),
                   q_index=model.arm_position_indices,
                   v_index=nq + model.arm_velocity_indices)

    def reference_point(self) -> np.ndarray:
        """Where each joint's position ratio is measured from (the module's docstring)."""
        lo, up = self.lower, self.upper
        with np.errstate(invalid="ignore"):  # (-inf + inf: a side unlimited, not used)
            middle = np.where(np.isfinite(lo) & np.isfinite(up), 0.5 * (lo + up),
                              np.where(np.isfinite(lo), lo + _ONE_SIDED_REFERENCE,
                                       up - _ONE_SIDED_REFERENCE))
        return np.where((lo < 0) & (up > 0), 0.0, middle)

    def position_ratios(self, x: np.ndarray, signed: bool = False) -> np.ndarray:
        """(N, n) position ratios of the states ``x`` (N, nx); NaN for an unlimited joint.
        ``signed``: negative on the lower side (-1 at the lower limit, +1 at the upper)."""
        q = np.asarray(x)[..., self.q_index]
        p = self.reference_point()
        with np.errstate(invalid="ignore", divide="ignore"):
            above = (q - p) / (self.upper - p)  # 0 where the side is infinite
            below = (q - p) / (self.lower - p)
            ratio = np.where(q >= p, above, -below if signed else below)
        unlimited = ~np.isfinite(self.lower) & ~np.isfinite(self.upper)
        return np.where(unlimited, np.nan, ratio)

    def velocity_ratios(self, x: np.ndarray, signed: bool = False) -> np.ndarray:
        """(N, n) |v| / v_max of the states ``x`` (``signed``: v / v_max); NaN where v_max
        is infinite (or 0)."""
        v = np.asarray(x)[..., self.v_index]
        limited = np.isfinite(self.velocity) & (self.velocity > 0)
        ratio = (v if signed else np.abs(v)) / np.where(limited, self.velocity, 1.0)
        return np.where(limited, ratio, np.nan)


def scenario_arm_limits(scenario: Any) -> ArmLimits:
    """The arm's limits in the simulated plant a run of ``scenario`` builds (its variant and
    environment, so the state indices are the log's): to read a run's log afterwards."""
    model = add_aerial_manipulator(
        MultibodyPlant(0.0), scenario.plant_variant, robot=scenario.robot_description(),
        environment=scenario.environment.model_directives(),
        environment_packages=scenario.environment.packages)
    return ArmLimits.of(model)


def _max_or_none(values: np.ndarray) -> float | None:
    finite = values[np.isfinite(values)]
    return float(finite.max()) if finite.size else None


def limit_metrics(states: np.ndarray, limits: ArmLimits) -> dict[str, Any]:
    """metrics.json's ``joint_limits`` (per arm joint: ``position_ratio``, ``velocity_ratio``,
    the maxima over the logged ``states`` (N, nx), > 1 past the limit, null for none; and the
    limits) and ``joint_limits_exceeded`` (the joints past a position or velocity limit)."""
    positions, velocities = limits.position_ratios(states), limits.velocity_ratios(states)
    table, exceeded = {}, []
    for i, name in enumerate(limits.names):
        entry = {"position_ratio": _max_or_none(positions[:, i]),
                 "velocity_ratio": _max_or_none(velocities[:, i]),
                 "lower_rad": float(limits.lower[i]), "upper_rad": float(limits.upper[i]),
                 "velocity_limit_rad_s": float(limits.velocity[i])}
        table[name] = entry
        if any((entry[k] or 0.0) > 1.0 for k in ("position_ratio", "velocity_ratio")):
            exceeded.append(name)
    return {"joint_limits": table, "joint_limits_exceeded": exceeded}


def exceeded_summary(metrics: dict, kinds: tuple[str, ...] = ("position", "velocity")
                     ) -> str | None:
    """One line naming the joints a run took past their limits of ``kinds`` (its metrics'
    entries), e.g. ``lwr_joint_4 position 1.06, lwr_joint_7 position 2.52 velocity 1.51``;
    None if none."""
    parts = []
    for name in metrics.get("joint_limits_exceeded") or []:
        entry = metrics["joint_limits"][name]
        past = [f"{kind} {entry[f'{kind}_ratio']:.2f}" for kind in kinds
                if (entry[f"{kind}_ratio"] or 0.0) > 1.0]
        parts += [f"{name} {' '.join(past)}"] if past else []
    return ", ".join(parts) or None


def _value(value: float, revolute: bool, rate: str = "") -> str:
    if not revolute:
        return f"{value:.4f} m{rate}"
    return f"{math.degrees(value):.1f} deg{rate} ({value:.4f} rad{rate})"


class LimitMonitor:
    """Stops a run at the arm's limits, as the scenario's ``joint_limits`` asks: positions
    when ``positions`` is "stop", velocities when ``velocities`` is "stop"."""

    def __init__(self, limits: ArmLimits, positions: str, velocities: str) -> None:
        self.limits = limits
        self.positions, self.velocities = positions == "stop", velocities == "stop"

    @classmethod
    def of(cls, scenario: Any, model: AerialManipulator) -> LimitMonitor:
        """The monitor of ``scenario`` (its ``joint_limits``) on the simulated plant ``model``."""
        return cls(ArmLimits.of(model), scenario.joint_limits.positions,
                   scenario.joint_limits.velocities)

    def _past(self, x: np.ndarray) -> np.ndarray:
        """(N, n) where each joint of each state ``x`` (N, nx) is past a stopping limit."""
        past = np.zeros(np.shape(x)[:-1] + (len(self.limits.names),), dtype=bool)
        if self.positions:
            past |= self.limits.position_ratios(x) > 1.0
        if self.velocities:
            past |= self.limits.velocity_ratios(x) > 1.0
        return past

    def past(self, x: np.ndarray) -> bool:
        """Whether the one state ``x`` is past a limit the run stops at."""
        return bool(self._past(np.asarray(x)[None, :]).any())

    def first_crossing(self, states: np.ndarray) -> int | None:
        """Index of the first of the logged ``states`` past a limit the run stops at."""
        if not (self.positions or self.velocities) or len(states) == 0:
            return None
        rows = np.flatnonzero(self._past(states).any(axis=1))
        return int(rows[0]) if rows.size else None

    def message(self, t: float, x: np.ndarray) -> str:
        """The failure of a run stopped at the state ``x`` at time ``t`` (s): the joint, its
        value, the limit, and the field that chooses what a limit does."""
        lim = self.limits
        q, ratio = x[lim.q_index], lim.position_ratios(x)
        for i, name in enumerate(lim.names):
            if self.positions and ratio[i] > 1.0:
                side = "upper" if q[i] > lim.reference_point()[i] else "lower"
                bound = lim.upper[i] if side == "upper" else lim.lower[i]
                return (f"t = {t:.4f} s: joint limit: {name} at {_value(q[i], lim.revolute[i])}"
                        f" is past its {side} limit {_value(bound, lim.revolute[i])} (the "
                        "model file's); joint_limits.positions is 'stop': set it to 'report' "
                        "to let the run go on past the limit, or to 'enforce' with a discrete "
                        "plant (plant.time_step, e.g. 0.001) to hold the joint there")
        v, vratio = x[lim.v_index], lim.velocity_ratios(x)
        i = int(np.nanargmax(vratio))
        rate = "/s"
        return (f"t = {t:.4f} s: joint limit: {lim.names[i]} moves at "
                f"{_value(abs(v[i]), lim.revolute[i], rate)}, past its velocity limit "
                f"{_value(lim.velocity[i], lim.revolute[i], rate)} (the model file's); "
                "joint_limits.velocities is 'stop': set it to 'report' to let the run go on")

    def cut(self, arrays: dict[str, np.ndarray], before: int | None = None
            ) -> tuple[dict[str, np.ndarray], float, str] | None:
        """The log ``arrays`` up to its first sample past a stopping limit, that sample's time
        and the failure message; None if no sample is past one (or none before the sample
        ``before``, e.g. the first non-finite one, which then explains the failure)."""
        index = self.first_crossing(arrays["plant_state"])
        if index is None or (before is not None and index > before):
            return None
        arrays = {k: v[:index + 1] for k, v in arrays.items()}
        t = float(arrays["t"][index])
        return arrays, t, self.message(t, arrays["plant_state"][index])
