"""The scenario's world, as in Drake's hardware_sim example: the ``plant`` section (Drake's own
``MultibodyPlantConfig``: time step, contact model, discrete contact approximation) and the
``environment`` section (Drake model directives: walls, tables, objects welded to the world or
free; docs/world.md), their checks, and the paths of the environment made absolute at load.

The continuous plant (``time_step: 0``) is the default, as the paper's runs have it.
"""

# No "from __future__ import annotations": pydrake's yaml_load_typed needs real type objects.
import copy
import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pydrake.multibody.parsing import ModelDirective, ModelDirectives
from pydrake.multibody.plant import MultibodyPlant, MultibodyPlantConfig

from aerial_drake import drake_compat
from aerial_drake.control.force.params import PAPER_FORCE
from aerial_drake.robots.description import RobotDescription, RobotDescriptionError
from aerial_drake.robots.environment import WorldError, environment_parser
from aerial_drake.robots.models import add_aerial_manipulator
from aerial_drake.simulation.scenarios.checks import (
    Range,
    ScenarioError,
    flag,
    is_number,
    number,
    show,
    text,
)

#: The choices of MultibodyPlantConfig's text fields (Drake's documentation of the struct;
#: tests/simulation/test_world.py holds them against Drake's own parser of each).
CONTACT_MODELS = ("point", "hydroelastic", "hydroelastic_with_fallback")
# The installed Drake release's choices (1.58 has no TAMSI): aerial_drake.drake_compat.
DISCRETE_CONTACT_APPROXIMATIONS = drake_compat.DISCRETE_CONTACT_APPROXIMATIONS
CONTACT_SURFACE_REPRESENTATIONS = ("triangle", "polygon")
#: A discrete plant's step must divide the controller's period to this relative tolerance.
_STEP_TOLERANCE = 1e-9


def continuous_plant() -> MultibodyPlantConfig:
    """Drake's MultibodyPlantConfig defaults but ``time_step = 0``: the continuous plant."""
    return MultibodyPlantConfig(time_step=0.0)


@dataclass
class Environment:
    """What the robot flies among: Drake model directives, as hardware_sim's ``directives``
    (``add_model``, ``add_weld``, ``add_frame``, ``add_directives`` ...). A model left unwelded
    is a free body (its pose: ``add_model``'s ``default_free_body_pose``)."""

    # Folders holding a package.xml (relative to the scenario file), whose package:// URLs the
    # directives use; package://aerial_drake/ (the shipped models: environments/wall.sdf,
    # table.sdf, box.sdf) is always known.
    packages: list[str] = field(default_factory=list)
    # The directives, in order. A ``file`` is a package:// URL or a path relative to the
    # scenario file (a *.sdf/*.urdf for add_model, a *.dmd.yaml for add_directives).
    directives: list[ModelDirective] = field(default_factory=list)

    def model_directives(self) -> ModelDirectives | None:
        """The directives as Drake's ``ModelDirectives`` (None without any: nothing to add)."""
        return ModelDirectives(directives=list(self.directives)) if self.directives else None


@dataclass
class ForceSensor:
    """The wrist force sensor the force task reads (``paper_force``;
    :class:`aerial_drake.simulation.contact.ForceSensor`): the true contact force on the end
    effector through a first-order low-pass, plus Gaussian noise per sample, at the
    controller's period."""

    # The low-pass's cut-off (Hz); .inf: none. A 6-axis wrist sensor's output filter is
    # typically set between 100 Hz and 1 kHz (ATI Nano/Mini series: 0-1 kHz selectable).
    bandwidth: float = 200.0
    # Noise standard deviation per axis and sample (N); ATI Mini45's resolution is 1/16 N.
    noise_std: float = 0.05
    seed: int = 0


def find_bad_world_field(data: dict) -> str | None:
    """The dotted name of the first value of a scenario file's ``plant`` or
    ``environment.directives`` that does not fit its type, with what was expected (Drake's
    loader says what failed, not where); None if none."""
    plant = data.get("plant", {})
    if not isinstance(plant, dict):
        return f"plant (expected a section of fields, got {show(plant)})"
    kinds = {f.name: f.type for f in MultibodyPlantConfig.__fields__}
    for key, value in plant.items():
        if key not in kinds:
            return f"plant.{key} (not a field of plant; fields: {', '.join(kinds)})"
        kind = kinds[key]
        if kind is float and not is_number(value) and not _number_text(value):
            return f"plant.{key} (expected a number, got {show(value)})"
        if kind in (bool, str) and not isinstance(value, kind):
            return f"plant.{key} (expected {'true or false' if kind is bool else 'text'}, " \
                   f"got {show(value)})"
    environment = data.get("environment", {})
    directives = environment.get("directives") if isinstance(environment, dict) else None
    names = [f.name for f in ModelDirective.__fields__]
    for i, directive in enumerate(directives if isinstance(directives, list) else []):
        if not isinstance(directive, dict) or len(directive) != 1 or any(
                k not in names for k in directive):
            return f"environment.directives[{i}] (expected one of {', '.join(names)}, got " \
                   f"{show(directive)})"
    return None


def _number_text(value: Any) -> bool:
    """YAML 1.1 reads 1e-3 as text; Drake's loader converts it."""
    if not isinstance(value, str):
        return False
    try:
        return math.isfinite(float(value))
    except ValueError:
        return False


def resolve_environment(environment: Environment, folder: Path) -> Environment:
    """A copy of ``environment`` with its relative paths (packages, directive files) made
    absolute from ``folder`` (the scenario file's), so that the scenario written into a run
    folder finds them again; directive files become file:// URLs, which Drake resolves."""
    def absolute(entry: str) -> Path:
        path = Path(entry).expanduser()
        return path if path.is_absolute() else (folder / path).resolve()

    directives = copy.deepcopy(environment.directives)
    for directive in directives:
        for item in (directive.add_model, directive.add_directives):
            if item is not None and "://" not in item.file:
                item.file = absolute(item.file).as_uri()
    return dataclasses.replace(environment, directives=directives,
                               packages=[str(absolute(p)) for p in environment.packages])


def check_plant(config: MultibodyPlantConfig, controller_period: float) -> None:
    """The ``plant`` section's values, each against its allowed range or choices."""
    step = number("plant.time_step", config.time_step, Range(
        0.0, 0.1, "s", fix="0 is the continuous plant (the default, the paper's); a discrete "
        "plant steps e.g. every 1e-3 s"))
    number("plant.penetration_allowance", config.penetration_allowance,
           Range(0.0, 1.0, "m", low_open=True, fix="Drake's default is 1e-3 m"))
    number("plant.stiction_tolerance", config.stiction_tolerance,
           Range(0.0, 1.0, "m/s", low_open=True, fix="Drake's default is 1e-4 m/s"))
    number("plant.sap_near_rigid_threshold", config.sap_near_rigid_threshold,
           Range(0.0, math.inf, fix="Drake's default is 1"))
    text("plant.contact_model", config.contact_model, CONTACT_MODELS)
    text("plant.discrete_contact_approximation", config.discrete_contact_approximation,
         DISCRETE_CONTACT_APPROXIMATIONS)
    text("plant.contact_surface_representation", config.contact_surface_representation,
         CONTACT_SURFACE_REPRESENTATIONS)
    flag("plant.adjacent_bodies_collision_filters", config.adjacent_bodies_collision_filters)
    flag("plant.use_sampled_output_ports", config.use_sampled_output_ports)
    if step == 0.0:
        return
    ratio = controller_period / step
    if controller_period <= 0.0 or abs(ratio - round(ratio)) > _STEP_TOLERANCE * ratio \
            or round(ratio) < 1:
        raise ScenarioError(
            f"plant.time_step: a discrete plant's step ({step:g} s) must divide the "
            f"controller's period (controller_period: {controller_period:g} s) a whole number "
            "of times, so that every sample reads a state the plant has just stepped to "
            "(continuous feedback, period 0, needs the continuous plant). Supported: "
            "time_step 0 (continuous, the default), or e.g. 1e-3 or 5e-4 with the 1 kHz "
            "controller", "plant.time_step")


def check_environment(environment: Environment, robot: RobotDescription, variant: str) -> None:
    """Parse the environment beside the robot into a scratch plant (no simulation): a missing
    file, an unknown package, a model Drake cannot read, a weld to the robot all fail here,
    before a run, as a ScenarioError naming ``environment``."""
    if not isinstance(environment.packages, list):
        raise ScenarioError(f"environment.packages must be a list of folders; got "
                            f"{show(environment.packages)}", "environment.packages")
    for i, folder in enumerate(environment.packages):
        text(f"environment.packages[{i}]", folder)
    if not isinstance(environment.directives, list) or not all(
            isinstance(d, ModelDirective) for d in environment.directives):
        raise ScenarioError("environment.directives must be a list of Drake model directives "
                            "(add_model, add_weld, ...; docs/world.md); got "
                            f"{show(environment.directives)}", "environment.directives")
    try:
        if environment.directives:
            add_aerial_manipulator(MultibodyPlant(0.0), variant, robot=robot,
                                   environment=environment.model_directives(),
                                   environment_packages=environment.packages)
        elif environment.packages:
            environment_parser(MultibodyPlant(0.0), environment.packages)
    except WorldError as err:
        field_name = str(err).split(":", 1)[0]
        raise ScenarioError(str(err), field_name) from None
    except RobotDescriptionError as err:  # checked before, by robot_facts
        raise ScenarioError(f"robot: {err}", "robot") from None


def check_world(scenario: Any) -> None:
    """The ``plant`` and ``environment`` sections of ``scenario`` (a Scenario)."""
    check_plant(scenario.plant, scenario.controller_period)
    check_environment(scenario.environment, scenario.robot_description(),
                      scenario.plant_variant)
    if scenario.controller.type == PAPER_FORCE and not scenario.environment.directives:
        # The rest of the force task's surface, its contact and its loads need the built
        # model: simulation.contact_checks, before the run.
        raise ScenarioError(
            f"environment: controller.type {PAPER_FORCE} presses the tool on a surface "
            "along controller.force.direction, but the scenario has no environment: add the "
            "surface as environment.directives (e.g. add_model "
            "package://aerial_drake/environments/wall.sdf and add_weld it to world; "
            "docs/world.md), or choose another controller.type", "environment")
