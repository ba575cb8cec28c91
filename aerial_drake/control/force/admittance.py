"""The force task's pure math (docs/contact.md, "The force task"): the desired force's
profile and the admittance that shifts the end effector's reference along the push
direction. No Drake here."""

from __future__ import annotations

import functools

import numpy as np

from aerial_drake.control.force.params import ForceTaskParams
from aerial_drake.trajectories.reference import TaskReferenceLayout, task_joint_count


def _smoothstep(s: float) -> float:
    """0 at s <= 0, 1 at s >= 1, C^2 in between (the quintic 10 s^3 - 15 s^4 + 6 s^5)."""
    s = min(max(s, 0.0), 1.0)
    return s * s * s * (10.0 + s * (-15.0 + 6.0 * s))


def desired_force(t: float, params: ForceTaskParams) -> float:
    """The desired pressing force at ``t`` (N): 0 outside the window, ``force`` over the
    hold, smooth steps of ``ramp`` seconds between."""
    rise = _smoothstep((t - params.start) / params.ramp)
    fall = _smoothstep((params.stop - t) / params.ramp)
    return params.force * min(rise, fall)


def pressing_force(measured: np.ndarray, direction: np.ndarray) -> float:
    """The force the tool presses with along ``direction`` (N): the surface pushes the tool
    back, so it is minus the measured contact force's component along ``direction``."""
    return -float(np.dot(measured, direction))


def admittance_acceleration(t: float, state: np.ndarray, pressing: float,
                            params: ForceTaskParams) -> float:
    """d'' of ``M d'' + D d' + K d = F_d - F`` at ``state`` = (d, d'); K = 0 inside the
    window, ``release_stiffness`` outside."""
    inside = params.start <= t <= params.stop
    stiffness = 0.0 if inside else params.release_stiffness
    error = desired_force(t, params) - pressing
    return (error - params.admittance_damping * state[1] - stiffness * state[0]
            ) / params.admittance_mass


def admittance_step(state: np.ndarray, accel: float, h: float, bound: float) -> np.ndarray:
    """(d, d') after ``h`` seconds at acceleration ``accel`` (semi-implicit Euler); d kept
    within +-``bound``, its rate zeroed there."""
    rate = state[1] + h * accel
    shift = state[0] + h * rate
    if abs(shift) > bound:
        shift, rate = float(np.clip(shift, -bound, bound)), 0.0
    return np.array([shift, rate])


@functools.lru_cache(maxsize=16)
def _position_entries(task_size: int) -> tuple[slice, slice, slice]:
    """Where p_ed, v_ed and a_ed sit in a packed task reference of ``task_size`` entries."""
    at = TaskReferenceLayout.of(task_joint_count(task_size))
    return at.p, at.v, at.a


def shifted_task(task: np.ndarray, direction: np.ndarray, state: np.ndarray,
                 accel: float) -> np.ndarray:
    """A copy of the packed task reference with ``d direction`` and its derivatives added
    to the end effector's desired position, velocity and acceleration (World; v_ed is also
    rows 0-2 of y_d', the same entries)."""
    task = np.array(task, dtype=float)
    p, v, a = _position_entries(task.shape[-1])
    task[p] += state[0] * direction
    task[v] += state[1] * direction
    task[a] += accel * direction
    return task
