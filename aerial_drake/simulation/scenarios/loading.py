"""Loading a scenario: a shipped name or a YAML file, read with Drake's ``yaml_load_typed``
over the schema's defaults, then the overrides, then validated (:func:`load_scenario`)."""


import dataclasses
from pathlib import Path

from pydrake.common.yaml import yaml_dump, yaml_load_typed

from aerial_drake.drake_compat import SimulatorFieldError, translate_simulator_section
from aerial_drake.robots.description import shipped_robots
from aerial_drake.simulation.scenarios.checks import ScenarioError, current_target
from aerial_drake.simulation.scenarios.fields import find_bad_field
from aerial_drake.simulation.scenarios.overrides import apply_overrides
from aerial_drake.simulation.scenarios.reading import read_scenario_file
from aerial_drake.simulation.scenarios.schema import Scenario
from aerial_drake.simulation.scenarios.trajectory import resolve_python_path
from aerial_drake.simulation.scenarios.world import find_bad_world_field, resolve_environment

__all__ = ["load_scenario", "shipped_scenarios", "scenario_directory"]


def scenario_directory() -> Path:
    """The folder holding the scenario YAML files shipped with the package (beside this
    module, installed or in a checkout)."""
    return Path(__file__).resolve().parent


def shipped_scenarios() -> dict[str, Path]:
    """Name -> path of the scenario files shipped with the package."""
    return {p.stem: p for p in sorted(scenario_directory().glob("*.yaml"))}


def load_scenario(name_or_path: str | Path, *, overrides: dict | None = None,
                  validate: bool = True) -> Scenario:
    """Load a shipped scenario by name (``"nominal"``) or a YAML file by path, and validate it.

    Layered as Drake's ``yaml_load_typed`` layers defaults: the schema's defaults, then the
    file's fields, then ``overrides`` (dotted names into the nested sections, e.g.
    ``{"duration": 2.0, "gains.k_R": 300}``: :func:`.overrides.apply_overrides`; an unknown
    name or a value of the wrong type is a ScenarioError naming it); then one validation pass
    (:meth:`Scenario.validate`). Every error names the file. ``validate=False`` skips that
    pass (it builds the robot and the reference, importing a ``python`` kind's module): for
    reading a run folder's scenario.yaml, already checked when it ran.
    """
    if not isinstance(name_or_path, (str, Path)):
        raise ScenarioError(f"scenario: expected a shipped scenario's name or a path to a "
                            f"YAML file, got {type(name_or_path).__name__} {name_or_path!r}")
    path = Path(name_or_path)
    if not path.suffix:  # a shipped name first; else a path (e.g. a folder given by mistake)
        shipped = shipped_scenarios()
        if str(name_or_path) in shipped:
            path = shipped[str(name_or_path)]
        elif not path.exists():
            raise ScenarioError(f"no scenario named '{name_or_path}'; shipped scenarios: "
                                f"{', '.join(sorted(shipped))}, or give a path to a .yaml file")
    text, data = read_scenario_file(path)
    if _translate_old_fields(data, path):
        text = yaml_dump(data)
    try:
        # A field only some Drake releases have: checked and removed in one place.
        if translate_simulator_section(data.get("simulator"), "simulator"):
            text = yaml_dump(data)
        bad = find_bad_field(data, Scenario) or find_bad_world_field(data)
        if bad:
            raise ScenarioError(f"{path}: {bad}", bad.split(" ")[0])
        scenario = yaml_load_typed(schema=Scenario, data=text)
    except SimulatorFieldError as err:
        raise ScenarioError(f"{path}: {err}", "simulator") from None
    except (RuntimeError, ValueError, TypeError, AssertionError) as err:
        if isinstance(err, ScenarioError):
            raise
        where = find_bad_field(data, Scenario)
        raise ScenarioError(f"{path}: {where + ': ' if where else ''}{err or type(err).__name__}",
                            where.split(" ")[0] if where else None) from None
    if overrides:
        scenario = apply_overrides(scenario, overrides)
    scenario = resolve_python_path(_resolve_robot(scenario, path), path)
    scenario = dataclasses.replace(scenario, environment=resolve_environment(
        scenario.environment, path.resolve().parent))
    if not validate:
        return scenario
    try:
        return scenario.validate()
    except ScenarioError as err:
        raise ScenarioError(f"{path}: {err}", err.field) from None


def _translate_old_fields(data: dict, path: Path) -> bool:
    """Fields of earlier releases, read as today's (run folders written before keep loading):
    ``trajectory.q3_desired: x`` is ``joint_targets: [x]``; a disturbance's ``target:
    helicopter`` is ``vehicle`` (a FutureWarning naming the file and the fix). Returns whether
    ``data`` changed."""
    changed = False
    for section, many in (("disturbances", True), ("random_disturbances", False)):
        items = data.get(section)
        for i, item in enumerate((items if isinstance(items, list) else []) if many
                                 else [items]):
            if isinstance(item, dict) and "target" in item:
                where = f"{path}: {section}{f'[{i}]' if many else ''}.target"
                new = current_target(item["target"], where)
                changed |= new != item["target"]
                item["target"] = new
    trajectory = data.get("trajectory")
    if isinstance(trajectory, dict) and "q3_desired" in trajectory:
        if "joint_targets" in trajectory:
            raise ScenarioError("trajectory: q3_desired and joint_targets are both set: keep "
                                "joint_targets (q3_desired is its earlier name)",
                                "trajectory.q3_desired")
        trajectory["joint_targets"] = [trajectory.pop("q3_desired")]
        return True
    return changed


def _resolve_robot(scenario: Scenario, path: Path) -> Scenario:
    """``robot`` as a shipped name or an absolute path (a relative path starts at the
    scenario file's folder), so the scenario written into a run folder finds it again."""
    if scenario.robot in shipped_robots() or not isinstance(scenario.robot, str):
        return scenario
    robot = Path(scenario.robot).expanduser()
    if not robot.is_absolute():
        robot = (path.resolve().parent / robot).resolve()
    return dataclasses.replace(scenario, robot=str(robot))
