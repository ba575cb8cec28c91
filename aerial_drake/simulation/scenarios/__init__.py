"""Scenario files: one dataclass tree, loaded with Drake's ``yaml_load_typed``; the shipped
YAML files live in this package's folder.

A scenario YAML holds every number of a run: Table II's gains, the trajectory constants of
(28)-(33), the initial offset, the actuator limits of Table I, the disturbance windows, the
integrator. The package has one module per job:

- :mod:`.schema` (and :mod:`.perturbations`): the dataclasses, each field with its unit;
- :mod:`.loading`: :func:`load_scenario`, the schema's defaults, then the file, then the
  overrides (:mod:`.overrides`: dotted names, and ``KEY=VALUE`` texts by
  :func:`parse_assignments`); a misspelt key or a wrong type is an error naming the field;
- :mod:`.validation`: the one pass over the values (:meth:`Scenario.validate`), each field
  checked once with its rule of :mod:`.checks` (the ranges) or of the module owning it.
"""

from aerial_drake.simulation.scenarios.checks import (
    DISTURBANCE_TARGETS,
    ScenarioError,
    folder_name,
)
from aerial_drake.simulation.scenarios.loading import (
    load_scenario,
    scenario_directory,
    shipped_scenarios,
)
from aerial_drake.simulation.scenarios.overrides import apply_overrides, parse_assignments
from aerial_drake.simulation.scenarios.perturbations import (
    ModelMismatch,
    Payload,
    RandomDisturbances,
    Sensing,
    Wind,
)
from aerial_drake.simulation.scenarios.robot import robot_description, robot_facts
from aerial_drake.simulation.scenarios.schema import (
    Actuation,
    ControllerConfig,
    Disturbance,
    InitialCondition,
    JointLimits,
    Rotors,
    Scenario,
)

__all__ = ["Scenario", "Disturbance", "InitialCondition", "Actuation", "Rotors",
           "ControllerConfig", "JointLimits", "ModelMismatch", "Payload", "Wind", "Sensing",
           "RandomDisturbances", "ScenarioError", "DISTURBANCE_TARGETS", "folder_name",
           "load_scenario", "shipped_scenarios", "scenario_directory", "apply_overrides",
           "parse_assignments", "robot_description", "robot_facts"]
