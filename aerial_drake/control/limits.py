"""The limits of the applied command ``[f, mu, tau]``: what the closed loop's saturation
clips at (:func:`aerial_drake.simulation.diagram.input_limits`) and what a controller that
guards against saturation (``paper_plus``'s anti-windup) compares its command with."""

from __future__ import annotations

from typing import Any

import numpy as np

from aerial_drake.robots.models import AerialManipulator


def command_limits(actuation: Any, model: AerialManipulator) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper limits of the applied ``[f, mu, tau]``: the robot's thrust range and
    body torque bounds (its description, or ``actuation``'s overrides: a scenario's
    ``actuation`` section) and the arm's effort limits; infinite where ``actuation`` does not
    saturate."""
    effort = model.arm_effort_limits()
    if not actuation.saturate:
        inf = np.full(4 + effort.size, np.inf)
        return -inf, inf
    low, high = model.thrust_limits()
    low = low if np.isnan(actuation.thrust_min) else actuation.thrust_min
    high = high if np.isnan(actuation.thrust_max) else actuation.thrust_max
    tm = model.body_torque_limits()
    if not np.isnan(actuation.body_torque_max):
        tm = np.full(3, actuation.body_torque_max)
    lower = np.concatenate([[low], -tm, -effort])
    upper = np.concatenate([[high], tm, effort])
    return lower, upper
