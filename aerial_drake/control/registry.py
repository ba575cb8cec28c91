"""Choosing the controller of a closed loop: by the scenario's ``controller.type``, from the
built-in ones or those registered here.

A controller factory is ``factory(scenario, model) -> system``: ``model`` is the controller's
rigid :class:`~aerial_drake.robots.models.AerialManipulator` (a fresh one per closed loop) and
the system has the ports of :mod:`aerial_drake.control.interface`, most simply as a subclass
of :class:`aerial_drake.control.base.ControllerBase`. Register your own with
:func:`register_controller` (then ``controller: {type: NAME}`` in a scenario selects it), or
hand a factory straight to :func:`aerial_drake.simulation.runner.run_scenario`
(``controller_factory=``); ``diagrams/custom_controller.py`` shows both. A factory that
takes a ``reference`` keyword also gets the run's
:class:`~aerial_drake.trajectories.base.ReferenceSource` (:func:`make_controller_system`).
"""

from __future__ import annotations

import inspect
from typing import Any, Callable

import numpy as np

from aerial_drake.control.baselines.params import BASELINE_TYPES
from aerial_drake.control.force.params import PAPER_FORCE
from aerial_drake.control.plus.params import PAPER_PLUS
from aerial_drake.robots.models import AerialManipulator
from aerial_drake.trajectories.base import ReferenceSource

# The scenario argument is a :class:`aerial_drake.simulation.scenarios.Scenario` (the layer
# above): a factory reads its fields (gains, controller_period, controller, trajectory).
ControllerFactory = Callable[[Any, AerialManipulator], object]

#: ``controller.type`` of the paper's controller (Section III), the default.
PAPER_CONTROLLER = "paper"
#: ``controller.kernel``: the paper law's compiled kernels (``paper``, ``paper_plus``,
#: ``paper_force``), ``exact`` the default
#: (:data:`aerial_drake.control.compiled.law.LAW_KERNEL_NAMES`).
LAW_KERNEL_CHOICES = ("exact", "fast")
#: Where a baseline's attitude inertia comes from, as its gain-design warning says.
LOCKED_SOURCE = "(the robot locked at its start, principal moments)"


# The controllers' modules are imported when a loop is built, not when a scenario is loaded
# (the scenarios import this module to check ``controller.type``): they bring pydrake's systems
# and the compiled law's numba.
def _paper(scenario: Any, model: AerialManipulator):
    from aerial_drake.control.controller import make_controller
    return make_controller(model, scenario.gains, sigma_min_J3_limit=scenario.sigma_min_J3_limit,
                           f_d_limit=scenario.f_d_limit, period=scenario.controller_period,
                           kernel=scenario.controller.kernel)


def _paper_plus(scenario: Any, model: AerialManipulator):
    from aerial_drake.control.limits import command_limits
    from aerial_drake.control.plus.controller import make_paper_plus
    return make_paper_plus(scenario, model, command_limits(scenario.actuation, model))


def _paper_force(scenario: Any, model: AerialManipulator):
    from aerial_drake.control.force.controller import make_paper_force
    from aerial_drake.control.limits import command_limits
    return make_paper_force(scenario, model, command_limits(scenario.actuation, model))


def zero_controller(scenario: Any, model: AerialManipulator):
    """:class:`~aerial_drake.control.controller.ZeroController`: the paper controller's ports
    and sampling, a zero command. The benchmarks' baseline: a run that costs the plant, the
    reference and the logging but no control law."""
    from aerial_drake.control.controller import make_controller
    return make_controller(model, scenario.gains, period=scenario.controller_period, zero=True)


def _baseline(kind: str) -> ControllerFactory:
    def factory(scenario: Any, model: AerialManipulator,
                reference: ReferenceSource | None = None):
        from aerial_drake.control.baselines.controller import BaselineController
        from aerial_drake.control.baselines.tuning import locked_inertia
        from aerial_drake.control.reference_pose import (
            body_offset_in_heading_frame,
            reference_configuration,
        )
        assert model.task is not None
        q0 = reference_configuration(scenario, model, reference=reference)
        J = locked_inertia(model.plant, model.base_body, q0)
        if not scenario.controller.baseline.vehicle_inertia:
            # Checked here, not at load: the locked inertia needs the run's reference.
            from aerial_drake.control.gain_design import warn_if_slow
            plant = model.plant
            warn_if_slow(plant.CalcTotalMass(plant.CreateDefaultContext()), scenario.gains,
                         np.linalg.eigvalsh(J), LOCKED_SOURCE)
        return BaselineController(
            model.plant, model.base_body, model.end_effector_frame, model.task,
            scenario.gains, kind=kind,
            body_offset_H=body_offset_in_heading_frame(scenario, model, reference),
            locked_inertia=J,
            params=scenario.controller.baseline, period=scenario.controller_period)
    return factory


_REGISTRY: dict[str, ControllerFactory] = {PAPER_CONTROLLER: _paper, PAPER_PLUS: _paper_plus,
                                           PAPER_FORCE: _paper_force}
_REGISTRY.update({kind: _baseline(kind) for kind in BASELINE_TYPES})
_BUILT_IN = tuple(_REGISTRY)
#: The controller types that ship with the package (register_controller adds others).
BUILT_IN_TYPES = _BUILT_IN


def register_controller(name: str, factory: ControllerFactory) -> None:
    """Make ``controller: {type: name}`` select ``factory`` (module docstring); the built-in
    names cannot be replaced."""
    if not isinstance(name, str) or not name.strip():
        raise ValueError(f"register_controller: name must be a non-empty text (the "
                         f"scenario's controller.type); got {name!r}")
    if name in _BUILT_IN:
        raise ValueError(f"'{name}' is a built-in controller; choose another name")
    if not callable(factory):
        raise TypeError(f"register_controller('{name}', factory): factory must be callable, "
                        f"factory(scenario, model) -> a LeafSystem (e.g. a ControllerBase "
                        f"subclass); got {type(factory).__name__} {factory!r}")
    _REGISTRY[name] = factory


def controller_types() -> tuple[str, ...]:
    """The names ``controller.type`` accepts now."""
    return tuple(_REGISTRY)


def controller_factory(scenario: Any) -> ControllerFactory:
    """The factory of ``scenario.controller.type`` (checked when the scenario is validated;
    a KeyError naming the options otherwise)."""
    try:
        return _REGISTRY[scenario.controller.type]
    except KeyError:
        raise KeyError(f"controller.type: '{scenario.controller.type}' is not one of "
                       f"{controller_types()} (register your own with aerial_drake."
                       "control.registry.register_controller)") from None


def make_controller_system(factory: ControllerFactory, scenario: Any, model: AerialManipulator,
                           reference: ReferenceSource):
    """``factory(scenario, model)``, with ``reference=`` the run's reference if the factory
    takes that keyword (the baselines' do: their body offset is measured on it)."""
    try:
        takes_reference = "reference" in inspect.signature(factory).parameters
    except (TypeError, ValueError):  # a callable without a signature Python can read
        takes_reference = False
    if takes_reference:
        return factory(scenario, model, reference=reference)  # type: ignore[call-arg]
    return factory(scenario, model)
