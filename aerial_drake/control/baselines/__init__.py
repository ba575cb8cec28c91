"""Baseline controllers the paper improves on (docs/baselines.md): the ``uncoupled`` common
practice (Lee-Leok-McClamroch geometric control of the vehicle alone, task-space computed
torque of the arm on its fixed-base model) and ``static_compensation`` (as uncoupled, plus the
arm's static wrench fed forward, the paper's reference [3])."""

from typing import Any

from aerial_drake.control.baselines.params import BASELINE_TYPES, BaselineParams

__all__ = ["BASELINE_TYPES", "BaselineController", "BaselineParams"]


def __getattr__(name: str) -> Any:
    # The LeafSystem (and through it the compiled law's numba) on first use only: loading a
    # scenario reads BaselineParams and must stay light.
    if name == "BaselineController":
        from aerial_drake.control.baselines.controller import BaselineController
        return BaselineController
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
