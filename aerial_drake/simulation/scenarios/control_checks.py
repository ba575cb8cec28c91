"""The scenario's controller and observer sections, checked for :mod:`.validation` (its one
validation pass): the controller type and its options, and the wrench observer's."""

from __future__ import annotations

import dataclasses
from typing import Any

from aerial_drake.control.force.params import PAPER_FORCE, ForceTaskParams
from aerial_drake.control.plus.params import PAPER_PLUS
from aerial_drake.control.registry import (
    BUILT_IN_TYPES,
    LAW_KERNEL_CHOICES,
    PAPER_CONTROLLER,
    controller_types,
)
from aerial_drake.simulation.scenarios.checks import (
    BANDWIDTH,
    ScenarioError,
    flag,
    number,
    show,
)


def check_controller(s: Any, n: int, mass: float) -> None:
    """The type, and the baselines' and paper_plus's sections (``n``: the task's rows);
    paper_plus's force feed-forward and wrench compensation need the observer (their one
    source in a run)."""
    controller, period = s.controller, s.controller_period
    types = controller_types()
    # paper_force is paper_plus with a force task: every paper_plus rule holds for it.
    plus_like = controller.type in (PAPER_PLUS, PAPER_FORCE)
    if controller.type not in types:
        raise ScenarioError(f"controller.type: '{controller.type}' is not one of {types}",
                            "controller.type")
    if plus_like and period == 0:
        raise ScenarioError(f"controller.type: {controller.type} needs controller_period > 0 (its "
                            "integrators are discrete state at that period); set "
                            "controller_period, e.g. 0.001", "controller_period")
    _check_kernel(controller.kernel, controller.type)
    try:
        controller.baseline.validate()
        controller.plus.validate(n)
        if controller.type == PAPER_FORCE:
            controller.force.validate()
    except ValueError as err:
        # Each section's message starts with the field's dotted name.
        raise ScenarioError(str(err), str(err).split(" ", 1)[0]) from None
    # A force task on a built-in controller that has none would be ignored, silently (a
    # registered controller of one's own may read it).
    if controller.type != PAPER_FORCE and controller.type in BUILT_IN_TYPES:
        default = ForceTaskParams()
        for f in dataclasses.fields(ForceTaskParams):
            value = getattr(controller.force, f.name)
            if value != getattr(default, f.name):
                raise ScenarioError(
                    f"controller.force.{f.name} = {show(value)}: controller.force is the force "
                    f"task of controller.type {PAPER_FORCE}, which controller.type "
                    f"{controller.type} does not run: set controller.type: {PAPER_FORCE}, or "
                    "remove controller.force", f"controller.force.{f.name}")
    if plus_like and any(controller.plus.com_gain()):
        # The bound needs the robot's total mass (the robot's facts, read once per robot).
        unstable = controller.plus.com_gain_error(mass, s.gains.K_x, s.gains.D_x)
        if unstable:
            raise ScenarioError(unstable, "controller.plus.com_integral_gain")
    plus = controller.plus
    if (plus_like and plus.singularity_damping > 0
            and not plus.singularity_threshold > s.sigma_min_J3_limit):
        # With damping on the Assumption 1 stop is off: an eps at or below its limit would
        # run the exact inverse through a near-singular J_3 with nothing to stop it.
        raise ScenarioError(
            f"controller.plus.singularity_threshold = {plus.singularity_threshold:g} must be "
            f"above sigma_min_J3_limit = {s.sigma_min_J3_limit:g} when singularity_damping is "
            "on (the damping replaces the Assumption 1 stop below the threshold): raise it, "
            "e.g. 0.05", "controller.plus.singularity_threshold")
    # In a run only the observer feeds these options' ports; unfed, they would read zero,
    # silently.
    for name, what in (("vehicle_force_feedforward", "the force on the vehicle"),
                       ("wrench_compensation", "the external generalized force")):
        if (plus_like and getattr(controller.plus, name)
                and not s.observer.enabled):
            raise ScenarioError(
                f"controller.plus.{name}: true needs an estimate of {what}, which the wrench "
                "observer provides, but observer.enabled is false: set observer.enabled: true, "
                f"or {name}: false", f"controller.plus.{name}")


def _check_kernel(kernel: Any, controller_type: str) -> None:
    """``controller.kernel``: one of LAW_KERNEL_CHOICES, and other than the default only for the
    controllers built on the compiled law (elsewhere it would be ignored, silently)."""
    if not isinstance(kernel, str) or kernel not in LAW_KERNEL_CHOICES:
        raise ScenarioError(
            f"controller.kernel: {show(kernel)} is not one of {', '.join(LAW_KERNEL_CHOICES)} "
            "(exact: the paper runs' arithmetic, bit for bit; fast: the same law to "
            "round-off, faster): write e.g. controller.kernel: exact", "controller.kernel")
    if kernel != LAW_KERNEL_CHOICES[0] and controller_type not in (PAPER_CONTROLLER, PAPER_PLUS,
                                                                  PAPER_FORCE):
        raise ScenarioError(
            f"controller.kernel: {kernel} chooses the compiled law of {PAPER_CONTROLLER}, "
            f"{PAPER_PLUS} and {PAPER_FORCE}, which controller.type {controller_type} does not "
            f"run: remove controller.kernel (or set it to {LAW_KERNEL_CHOICES[0]})",
            "controller.kernel")


def check_observer(observer: Any, period: float) -> None:
    """The wrench observer runs at the controller's period: a sampled controller only."""
    flag("observer.enabled", observer.enabled)
    number("observer.bandwidth", observer.bandwidth, BANDWIDTH)
    if observer.enabled and period == 0:
        raise ScenarioError("observer.enabled: the observer samples at controller_period, "
                            "which is 0 (continuous feedback): set controller_period (e.g. "
                            "0.001) or disable the observer", "observer.enabled")
