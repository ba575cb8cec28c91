"""The force task's pure math (docs/contact.md, "The force task"): the desired force's
profile and the admittance that shifts the end effector's reference along the push
direction. No Drake here."""

from __future__ import annotations

import numpy as np

from aerial_drake.control.force.params import ForceTaskParams
from aerial_drake.trajectories.reference import unpack_task_reference


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


def shifted_task(task: np.ndarray, direction: np.ndarray, state: np.ndarray,
                 accel: float) -> np.ndarray:
    """A copy of the packed task reference with ``d direction`` and its derivatives added
    to the end effector's desired position, velocity and acceleration (World)."""
    task = np.array(task, dtype=float)
    ref = unpack_task_reference(task)  # views into the copy
    ref.p_ed[:] += state[0] * direction
    ref.v_ed[:] += state[1] * direction  # also y_d' 's rows 0-2: the same entries
    ref.a_ed[:] += accel * direction
    return task
