"""The scenario's robot: its description (read once per file version) and the facts the
value checks need (sizes, variants, thrust range; its plant built once per description)."""

from pathlib import Path
from typing import Any

from pydrake.multibody.tree import BodyIndex

from aerial_drake.robots.description import (
    RobotDescription,
    RobotDescriptionError,
    load_robot_description,
    shipped_robots,
)
from aerial_drake.robots.models import AerialManipulator, make_plant
from aerial_drake.simulation.scenarios.checks import RobotFacts, ScenarioError


def robot_description(robot: str) -> RobotDescription:
    """The description named by a scenario's ``robot`` field (a shipped name or an absolute
    path, as :func:`load_scenario` leaves it), read once per file version."""
    if not isinstance(robot, str) or not robot.strip():
        raise ScenarioError(f"robot: {robot!r} is not a shipped robot's name "
                            f"({', '.join(shipped_robots())}) or a robot description file's "
                            "path", "robot")
    path = shipped_robots().get(robot, Path(robot))
    try:
        stamp = path.stat().st_mtime_ns
    except OSError:
        stamp = -1
    key = (str(path), stamp)
    if key not in _DESCRIPTIONS:
        try:
            _DESCRIPTIONS[key] = load_robot_description(robot)
        except RobotDescriptionError as err:
            raise ScenarioError(f"robot: {err}", "robot" if err.field in (None, "robot")
                                else f"robot: {err.field}") from None
    return _DESCRIPTIONS[key]


_DESCRIPTIONS: dict[tuple[str, int], RobotDescription] = {}
_FACTS: dict[tuple[str, str], RobotFacts] = {}


def robot_facts(scenario: Any) -> RobotFacts:
    """Sizes and options of ``scenario``'s robot (a :class:`.schema.Scenario`), for the value
    checks (the robot's plant is built, and its description checked, once per
    description)."""
    description = robot_description(scenario.robot)
    key = (str(description.source), repr(description))
    if key not in _FACTS:
        try:
            model = make_plant(robot=description)
            rotor_variants = tuple(v.name for v in description.variants if v.rotor_joints)
            bodies = [(description.variant_names()[0], _massive_body_names(model))]
            for variant in description.variant_names()[1:]:
                # Its checks, before any run.
                bodies.append((variant, _massive_body_names(make_plant(variant,
                                                                       robot=description))))
        except RobotDescriptionError as err:
            raise ScenarioError(f"robot: {err}", f"robot: {err.field}") from None
        assert model.task is not None
        _FACTS[key] = RobotFacts(n=model.n, n_task_joints=model.task.n_joints,
                                 variants=description.variant_names(),
                                 rotor_variants=rotor_variants,
                                 thrust=model.thrust_limits(),
                                 joint_nominal=tuple(model.task_joint_nominal()),
                                 mass=model.total_mass(),
                                 bodies=tuple(bodies))
    return _FACTS[key]


def _massive_body_names(model: AerialManipulator) -> tuple[str, ...]:
    """The names of ``model``'s bodies with mass (World has none), in index order."""
    plant = model.plant
    return tuple(plant.get_body(BodyIndex(i)).name() for i in range(1, plant.num_bodies())
                 if plant.get_body(BodyIndex(i)).default_mass() > 0)
