"""aerial_drake: the inertially decoupled task-space controller of Garofalo, Beck and Ott,
"Task-space tracking control for underactuated aerial manipulators", as Drake systems.

The public API is the names below (``from aerial_drake import run_scenario``); everything
else is internal and may change between releases (docs/api: "Public API" and "Internals").

Scenarios and runs:
    :func:`load_scenario`, :class:`Scenario`, :class:`ScenarioError`,
    :func:`apply_overrides`, :func:`parse_assignments`, :func:`shipped_scenarios`,
    :func:`run_scenario`, :class:`RunResult`, :class:`SimulationFailed`,
    :class:`SimulationInterrupted`, :func:`load_run`, :class:`Run`.
Controllers:
    :class:`ControllerBase` (write your own: one method), :func:`register_controller`,
    :func:`controller_types`.
Diagrams:
    :func:`build_closed_loop`, :func:`build_simulation`, :class:`TrackingErrors`.
Robots:
    :func:`load_robot_description`, :func:`make_plant`.
Batches:
    :func:`run_paper`, :func:`run_compare`.

The names are imported on first use (PEP 562), so ``import aerial_drake`` loads neither Drake
nor numba: the command line starts at once and ``aerial-drake --help`` costs nothing.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

#: Public name -> the module that defines it.
_PUBLIC = {
    "load_scenario": "aerial_drake.simulation.scenarios",
    "Scenario": "aerial_drake.simulation.scenarios",
    "ScenarioError": "aerial_drake.simulation.scenarios",
    "apply_overrides": "aerial_drake.simulation.scenarios",
    "parse_assignments": "aerial_drake.simulation.scenarios",
    "shipped_scenarios": "aerial_drake.simulation.scenarios",
    "run_scenario": "aerial_drake.simulation.runner",
    "RunResult": "aerial_drake.simulation.runner",
    "SimulationFailed": "aerial_drake.simulation.runner",
    "SimulationInterrupted": "aerial_drake.simulation.runner",
    "load_run": "aerial_drake.simulation.run_folder",
    "Run": "aerial_drake.simulation.run_folder",
    "ControllerBase": "aerial_drake.control.base",
    "register_controller": "aerial_drake.control.registry",
    "controller_types": "aerial_drake.control.registry",
    "build_closed_loop": "aerial_drake.simulation.diagram",
    "build_simulation": "aerial_drake.simulation.diagram",
    "TrackingErrors": "aerial_drake.simulation.tracking",
    "load_robot_description": "aerial_drake.robots.description",
    "make_plant": "aerial_drake.robots.models",
    "run_paper": "aerial_drake.studies.paper",
    "run_compare": "aerial_drake.studies.compare",
}

__all__ = [
    "__version__", "load_scenario", "Scenario", "ScenarioError", "apply_overrides",
    "parse_assignments", "shipped_scenarios", "run_scenario", "RunResult", "SimulationFailed",
    "SimulationInterrupted", "load_run", "Run", "ControllerBase", "register_controller",
    "controller_types", "build_closed_loop", "build_simulation", "TrackingErrors",
    "load_robot_description", "make_plant", "run_paper", "run_compare",
]

if TYPE_CHECKING:  # the type checker sees the names as if imported here
    from aerial_drake.control.base import ControllerBase
    from aerial_drake.control.registry import controller_types, register_controller
    from aerial_drake.robots.description import load_robot_description
    from aerial_drake.robots.models import make_plant
    from aerial_drake.simulation.diagram import build_closed_loop, build_simulation
    from aerial_drake.simulation.run_folder import Run, load_run
    from aerial_drake.simulation.runner import (
        RunResult,
        SimulationFailed,
        SimulationInterrupted,
        run_scenario,
    )
    from aerial_drake.simulation.scenarios import (
        Scenario,
        ScenarioError,
        apply_overrides,
        load_scenario,
        parse_assignments,
        shipped_scenarios,
    )
    from aerial_drake.simulation.tracking import TrackingErrors
    from aerial_drake.studies.compare import run_compare
    from aerial_drake.studies.paper import run_paper


def __getattr__(name: str) -> Any:
    if name not in _PUBLIC:
        raise AttributeError(f"module 'aerial_drake' has no attribute {name!r}; the public "
                             f"names are {sorted(_PUBLIC)}")
    value = getattr(importlib.import_module(_PUBLIC[name]), name)
    globals()[name] = value  # once: later lookups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
