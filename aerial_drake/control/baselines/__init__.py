"""Baseline controllers the paper improves on (docs/baselines.md): the ``uncoupled`` common
practice (Lee-Leok-McClamroch geometric control of the vehicle alone, task-space computed
torque of the arm on its fixed-base model) and ``static_compensation`` (as uncoupled, plus the
arm's static wrench fed forward, the paper's reference [3])."""

from aerial_drake.control.baselines.controller import BaselineController
from aerial_drake.control.baselines.params import BASELINE_TYPES, BaselineParams

__all__ = ["BASELINE_TYPES", "BaselineController", "BaselineParams"]
