"""The world around the robot (aerial_drake.robots.environment): the shipped environment models,
the robots' tool collision geometry, and the robot's checks beside other models."""

from pathlib import Path

import numpy as np
import pytest
from pydrake.geometry import Role, SceneGraph
from pydrake.multibody.parsing import (
    AddModel,
    AddWeld,
    ModelDirective,
    ModelDirectives,
    Parser,
)
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, MultibodyPlant
from pydrake.systems.framework import DiagramBuilder

from aerial_drake.robots import environment as dut
from aerial_drake.robots.description import load_robot_description
from aerial_drake.robots.models import add_aerial_manipulator, make_plant
from aerial_drake.robots.resources import model_directory

PAPER_MASS = 54.8  # kg, Table I
#: Box sizes (m) of each shipped environment model's collision geometry, as its file says.
SHIPPED = {
    "wall": {"slab": (0.1, 4.0, 3.0)},
    "table": {"top": (1.2, 0.8, 0.04), **{f"leg_{n}": (0.05, 0.05, 0.71) for n in (
        "0p55_0p35", "0p55_m0p35", "m0p55_0p35", "m0p55_m0p35")}},
    "box": {"box": (0.1, 0.1, 0.1)},
}
#: The tool sphere's radius (m) in each shipped robot's arm model (its flange housing's).
TOOL_RADIUS = {"helicopter_lwr": 0.04, "quadrotor_ur3e": 0.032}


def directives(*items: ModelDirective) -> ModelDirectives:
    return ModelDirectives(directives=list(items))


def model(name: str, file: str) -> ModelDirective:
    return ModelDirective(add_model=AddModel(name=name, file=file))


def weld(parent: str, child: str) -> ModelDirective:
    return ModelDirective(add_weld=AddWeld(parent=parent, child=child))


def shipped(name: str) -> ModelDirective:
    return model(name, f"package://aerial_drake/environments/{name}.sdf")


def geometry_by_role(plant: MultibodyPlant, scene_graph: SceneGraph, body, role: Role) -> dict:
    inspector = scene_graph.model_inspector()
    frame = plant.GetBodyFrameIdOrThrow(body.index())
    return {inspector.GetName(g).split("::")[-1]: inspector.GetShape(g)
            for g in inspector.GetGeometries(frame, role)}


@pytest.mark.parametrize("name", sorted(SHIPPED))
def test_shipped_environment_model_has_its_documented_geometry(name):
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, 0.0)
    added = dut.add_environment(plant, directives(shipped(name)))
    assert [plant.GetModelInstanceName(i) for i in added] == [name]
    body = plant.GetBodyByName(name)
    collision = geometry_by_role(plant, scene_graph, body, Role.kProximity)
    visual = geometry_by_role(plant, scene_graph, body, Role.kIllustration)
    assert {k: (s.width(), s.depth(), s.height()) for k, s in collision.items()} == SHIPPED[name]
    assert set(visual) == set(collision)  # what it collides with is what is drawn
    assert body.default_mass() > 0


def test_shipped_environment_models_are_in_the_model_directory():
    assert sorted(p.stem for p in (model_directory() / "environments").glob("*.sdf")) == sorted(
        SHIPPED)


@pytest.mark.parametrize("robot", sorted(TOOL_RADIUS))
def test_tool_collision_sphere_is_on_the_end_effector(robot):
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, 0.0)
    manip = add_aerial_manipulator(plant, robot=load_robot_description(robot),
                                   scene_graph=scene_graph)
    inspector = scene_graph.model_inspector()
    collisions = inspector.GetAllGeometryIds(Role.kProximity)
    assert len(collisions) == 1  # the tool's only: the robot cannot collide with itself
    (tool,) = collisions
    assert inspector.GetFrameId(tool) == plant.GetBodyFrameIdOrThrow(
        manip.end_effector_body.index())
    assert inspector.GetShape(tool).radius() == TOOL_RADIUS[robot]
    # Centred on the end-effector frame's origin (the flange face).
    X_BG = inspector.GetPoseInFrame(tool)
    X_BE = manip.end_effector_frame.GetFixedPoseInBodyFrame()
    np.testing.assert_array_equal(X_BG.translation(), X_BE.translation())


def _strip_collisions(text: str) -> str:
    while "<collision" in text:
        start = text.index("<collision")
        text = text[:start] + text[text.index("</collision>", start) + len("</collision>"):]
    return text


@pytest.mark.parametrize("arm", ["lwr.sdf", "ur3e.sdf"])
def test_collision_geometry_changes_no_mass_property(arm):
    """Every body's spatial inertia is the same with the collision elements and without."""
    path = model_directory() / arm
    inertias = []
    for text in (path.read_text(), _strip_collisions(path.read_text())):
        plant = MultibodyPlant(0.0)
        Parser(plant).AddModelsFromString(text, "sdf")
        plant.Finalize()
        context = plant.CreateDefaultContext()
        inertias.append([plant.get_body(i).CalcSpatialInertiaInBodyFrame(context).CopyToFullMatrix6()
                         for i in plant.GetBodyIndices(plant.GetModelInstanceByName(
                             arm.removesuffix(".sdf")))])
    assert "<collision" not in _strip_collisions(path.read_text())
    for with_it, without in zip(*inertias):
        np.testing.assert_array_equal(with_it, without)


def test_robot_beside_an_environment_added_before_it():
    """The structure check looks at the robot's models only: a table already in the plant is
    not a stray body, nor part of the robot's mass."""
    plant = MultibodyPlant(0.0)
    dut.add_environment(plant, directives(shipped("table"), weld("world", "table::table")))
    manip = add_aerial_manipulator(plant)
    assert manip.total_mass() == pytest.approx(PAPER_MASS)
    assert manip.n == 7


def test_robot_with_an_environment_keeps_its_coordinates_first():
    alone = make_plant()
    plant = MultibodyPlant(0.0)
    manip = add_aerial_manipulator(plant, environment=directives(
        shipped("wall"), weld("world", "wall::wall"), shipped("box")))
    assert [plant.GetModelInstanceName(i) for i in manip.environment] == ["wall", "box"]
    assert manip.total_mass() == pytest.approx(alone.total_mass(), abs=0, rel=0)
    # The free box adds 7 positions and 6 velocities after the robot's.
    assert plant.num_positions() == alone.plant.num_positions() + 7
    np.testing.assert_array_equal(manip.base_velocity_indices, np.arange(6))
    nx = alone.plant.num_multibody_states()
    np.testing.assert_array_equal(manip.rigid_state_indices[:alone.plant.num_positions()],
                                  np.arange(alone.plant.num_positions()))
    assert manip.rigid_state_indices.size == nx


def test_environment_welded_to_the_robot_is_refused():
    plant = MultibodyPlant(0.0)
    with pytest.raises(dut.WorldError, match="payload"):
        add_aerial_manipulator(plant, environment=directives(
            shipped("box"), weld("lwr::lwr_link_7", "box::box")))


def test_unknown_package_names_the_known_ones():
    with pytest.raises(dut.WorldError, match=r"directives\[0\].add_model.file.*'nowhere'.*"
                                             r"known: aerial_drake"):
        dut.add_environment(MultibodyPlant(0.0), directives(model("x", "package://nowhere/x.sdf")))


def test_file_that_is_not_a_url_is_refused():
    with pytest.raises(dut.WorldError, match="is not a URL"):
        dut.add_environment(MultibodyPlant(0.0), directives(model("x", "wall.sdf")))


def test_missing_model_file_is_a_world_error():
    with pytest.raises(dut.WorldError, match="Drake could not process"):
        dut.add_environment(MultibodyPlant(0.0), directives(
            model("x", "package://aerial_drake/environments/no_such.sdf")))


def test_package_folder_without_package_xml(tmp_path):
    with pytest.raises(dut.WorldError, match=r"packages\[0\].*no package.xml"):
        dut.add_environment(MultibodyPlant(0.0), directives(), [tmp_path])


def test_own_package_resolves(tmp_path):
    (tmp_path / "package.xml").write_text(
        '<?xml version="1.0"?><package format="2"><name>my_world</name></package>')
    wall = (model_directory() / "environments" / "wall.sdf").read_text()
    (tmp_path / "my_wall.sdf").write_text(wall)
    plant = MultibodyPlant(0.0)
    added = dut.add_environment(plant, directives(model("w", "package://my_world/my_wall.sdf")),
                                [Path(tmp_path)])
    assert [plant.GetModelInstanceName(i) for i in added] == ["w"]
