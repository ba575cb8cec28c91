"""The scenario's world (aerial_drake.simulation.scenarios.world): the ``plant`` and
``environment`` sections, their checks, and runs with them. Runs are short (0.3 s)."""

import shutil

import numpy as np
import pytest
from pydrake.common.yaml import yaml_dump_typed
from pydrake.multibody.parsing import AddModel, ModelDirective
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlantConfig
from pydrake.systems.framework import DiagramBuilder

from aerial_drake.robots.resources import model_directory
from aerial_drake.simulation.diagram import build_closed_loop
from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import ScenarioError, load_scenario, shipped_scenarios
from aerial_drake.simulation.scenarios import world as dut

DURATION = 0.3  # s
NOMINAL = shipped_scenarios()["nominal"].read_text()
#: A wall 3 m ahead of the nominal trajectory's centre (x = 0.6 m): the end effector's circle
#: (0.5 m) and the arm's reach keep it well out of touch.
WALL = """
environment:
  directives:
  - add_model:
      name: wall
      file: {file}
  - add_weld:
      parent: world
      child: wall::wall
      X_PC:
        translation: [3.6, 0.0, 1.5]
"""
#: A table welded to the floor, a free box resting on it, a discrete SAP plant.
TABLE_AND_BOX = """
plant:
  time_step: 1.0e-3
  discrete_contact_approximation: sap
environment:
  directives:
  - add_model:
      name: table
      file: package://aerial_drake/environments/table.sdf
  - add_weld:
      parent: world
      child: table::table
      X_PC:
        translation: [3.0, 0.0, 0.0]
  - add_model:
      name: box
      file: package://aerial_drake/environments/box.sdf
      default_free_body_pose:
        box:
          translation: [3.0, 0.0, 0.8]
"""


def scenario_file(tmp_path, extra: str, name: str = "world.yaml"):
    path = tmp_path / name
    path.write_text(NOMINAL + extra)
    return path


def load(path, **overrides):
    return load_scenario(path, overrides={"duration": DURATION, **overrides})


def test_default_plant_is_continuous_as_before():
    scenario = load_scenario("nominal")
    assert scenario.plant.time_step == 0.0
    assert scenario.environment.directives == []
    loop = build_closed_loop(scenario)
    assert loop.simulated_plant.plant.time_step() == 0.0
    assert loop.simulated_plant.environment == ()


@pytest.fixture(scope="module")
def nominal_run():
    return run_scenario(load("nominal"), progress=False)


def test_wall_out_of_reach_changes_no_number(tmp_path, nominal_run):
    """The must-show: a scenario with a wall loads and runs in free flight unchanged. The
    plant is continuous and nothing touches, so no contact force is ever added: the logs are
    equal to the last bit."""
    scenario = load(scenario_file(tmp_path, WALL.format(
        file="package://aerial_drake/environments/wall.sdf")))
    loop = build_closed_loop(scenario)
    plant = loop.simulated_plant.plant
    assert [plant.GetModelInstanceName(i) for i in loop.simulated_plant.environment] == ["wall"]
    # The controller's model never holds the environment.
    assert not loop.controller_model.plant.HasModelInstanceNamed("wall")
    walled = run_scenario(scenario, progress=False)
    assert walled.completed
    # With an environment the log adds the contact wrench on the end effector: all zeros.
    assert walled.log.keys() - nominal_run.log.keys() == {"contact_wrench"}
    assert not np.any(walled.log["contact_wrench"])
    for key in nominal_run.log:
        np.testing.assert_array_equal(walled.log[key], nominal_run.log[key], err_msg=key)


def hover_file(tmp_path, extra: str = ""):
    """Nominal's scenario hovering at its trajectory's centre: the arm at postures within its
    joint limits (the paper's trajectory starts with joint 6 past its limit, docs/control.md,
    which a discrete plant enforces and the continuous one does not)."""
    path = tmp_path / f"hover{len(extra)}.yaml"
    path.write_text(NOMINAL.replace("trajectory:\n", "trajectory:\n  kind: hover\n  hover:\n"
                                    "    ee_position: [0.6, 0.0, 1.3]\n", 1) + extra)
    return path


def test_discrete_plant_with_a_table_and_a_free_box_runs(tmp_path):
    """time_step 1e-3 with SAP: the robot hovers as on the continuous plant (the same law, the
    plant stepped every 1 ms instead of integrated by RK3: 2e-3 apart at most over 1 s,
    measured) and the free box rests on the table."""
    continuous = run_scenario(load(hover_file(tmp_path)), progress=False)
    scenario = load(hover_file(tmp_path, TABLE_AND_BOX))
    result = run_scenario(scenario, progress=False)
    assert result.completed
    loop = build_closed_loop(scenario)
    sim = loop.simulated_plant
    assert sim.plant.time_step() == 1e-3
    x = result.log["plant_state"]
    assert np.isfinite(x).all()
    robot = x[:, sim.rigid_state_indices]
    assert robot.shape == continuous.log["plant_state"].shape
    np.testing.assert_allclose(robot, continuous.log["plant_state"], rtol=0, atol=5e-3)
    box = sim.plant.GetBodyByName("box").floating_positions_start()
    # On the table top (0.75 m) to within 3 mm of SAP's compliance: it neither fell nor sank.
    assert abs(x[-1, box + 6] - 0.8) < 3e-3


def test_relative_paths_start_at_the_scenario_file(tmp_path):
    folder = tmp_path / "scenarios"
    folder.mkdir()
    shutil.copy(model_directory() / "environments" / "wall.sdf", folder / "my_wall.sdf")
    scenario = load(scenario_file(folder, WALL.format(file="my_wall.sdf")))
    file = scenario.environment.directives[0].add_model.file
    assert file == (folder / "my_wall.sdf").resolve().as_uri()
    # The scenario as a run folder stores it loads again from elsewhere.
    again = tmp_path / "elsewhere" / "scenario.yaml"
    again.parent.mkdir()
    again.write_text(yaml_dump_typed(scenario))
    assert load_scenario(again).environment.directives[0].add_model.file == file


@pytest.mark.parametrize(("extra", "field", "message"), [
    ("plant:\n  time_step: -1.0e-3\n", "plant.time_step", "finite, >= 0"),
    ("plant:\n  time_step: 3.0e-4\n", "plant.time_step", "whole number of times"),
    ("plant:\n  contact_model: soft\n", "plant.contact_model", "hydroelastic_with_fallback"),
    ("plant:\n  discrete_contact_approximation: fast\n", "plant.discrete_contact_approximation",
     "sap"),
    ("plant:\n  penetration_allowance: 0.0\n", "plant.penetration_allowance", "> 0"),
    (WALL.format(file="package://nowhere/wall.sdf"), "environment.directives[0].add_model.file",
     "names the package 'nowhere'"),
    (WALL.format(file="no_such_wall.sdf"), "environment", "Drake could not process"),
    ("environment:\n  packages: [no_such_folder]\n", "environment.packages[0]",
     "no package.xml"),
    # Misspelt or mistyped, found before Drake's loader (which says what, not where).
    ("plant:\n  time_stepp: 1.0\n", "plant.time_stepp", "not a field of plant"),
    ("plant: 5\n", "plant", "expected a section of fields"),
    ("plant:\n  time_step: abc\n", "plant.time_step", "expected a number"),
    ("environment:\n  directives:\n  - add_modell: {name: x}\n", "environment.directives[0]",
     "expected one of add_model, "),
    ("environment:\n  directives:\n  - 5\n", "environment.directives[0]", "got 5"),
])
def test_bad_world_is_a_scenario_error(tmp_path, extra, field, message):
    with pytest.raises(ScenarioError, match=message) as err:
        load(scenario_file(tmp_path, extra))
    assert err.value.field == field


def test_bad_directives_file_is_a_scenario_error(tmp_path):
    (tmp_path / "broken.dmd.yaml").write_text("directives:\n- add_model: {name: x, nofile: 1}\n")
    extra = "environment:\n  directives:\n  - add_directives:\n      file: broken.dmd.yaml\n"
    with pytest.raises(ScenarioError, match="broken.dmd.yaml") as err:
        load(scenario_file(tmp_path, extra))
    assert err.value.field == "environment"


def test_discrete_plant_needs_a_sampled_controller(tmp_path):
    with pytest.raises(ScenarioError, match="continuous feedback"):
        load(scenario_file(tmp_path, "plant:\n  time_step: 1.0e-3\n"), controller_period=0.0)


def test_listed_choices_are_drakes():
    """Each choice the checks allow, Drake accepts; a name outside them, Drake refuses."""
    for model in dut.CONTACT_MODELS:
        for approximation in dut.DISCRETE_CONTACT_APPROXIMATIONS:
            for surface in dut.CONTACT_SURFACE_REPRESENTATIONS:
                AddMultibodyPlant(MultibodyPlantConfig(
                    time_step=1e-3, contact_model=model, contact_surface_representation=surface,
                    discrete_contact_approximation=approximation), DiagramBuilder())
    for wrong in ({"contact_model": "soft"}, {"discrete_contact_approximation": "fast"},
                  {"contact_surface_representation": "quad"}):
        with pytest.raises(RuntimeError):
            AddMultibodyPlant(MultibodyPlantConfig(time_step=1e-3, **wrong), DiagramBuilder())


def test_resolving_leaves_the_callers_environment_alone(tmp_path):
    relative = dut.Environment(packages=["pkg"], directives=[
        ModelDirective(add_model=AddModel(name="w", file="wall.sdf")),
        ModelDirective(add_model=AddModel(name="v", file="package://aerial_drake/x.sdf"))])
    resolved = dut.resolve_environment(relative, tmp_path)
    assert relative.directives[0].add_model.file == "wall.sdf"
    assert relative.packages == ["pkg"]
    assert resolved.directives[0].add_model.file == (tmp_path / "wall.sdf").as_uri()
    assert resolved.directives[1].add_model.file == "package://aerial_drake/x.sdf"
    assert resolved.packages == [str(tmp_path / "pkg")]
