"""The contact wrench on a body from Drake's contact results, and the wrist force sensor
(aerial_drake.simulation.contact)."""

import numpy as np
import pytest
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlantConfig
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource

from aerial_drake.robots.environment import environment_parser
from aerial_drake.simulation.contact import (
    CONTACT_WRENCH_SIZE,
    ContactWrench,
    ForceSensor,
    contact_slices,
)
from aerial_drake.simulation.scenarios import load_scenario

S = contact_slices()


#: A 1 kg ball of radius 0.05 m with the tool pads' contact properties (models/sdf/lwr.sdf).
BALL = """<?xml version="1.0"?>
<sdf version="1.9" xmlns:drake="http://drake.mit.edu">
  <model name="ball"><link name="ball">
    <inertial><mass>1.0</mass><inertia><ixx>0.001</ixx><iyy>0.001</iyy><izz>0.001</izz>
      <ixy>0</ixy><ixz>0</ixz><iyz>0</iyz></inertia></inertial>
    <collision name="ball"><geometry><sphere><radius>0.05</radius></sphere></geometry>
      <drake:proximity_properties>
        <drake:point_contact_stiffness>3.0e4</drake:point_contact_stiffness>
        <drake:hunt_crossley_dissipation>10.0</drake:hunt_crossley_dissipation>
      </drake:proximity_properties></collision>
  </link></model>
</sdf>"""


def _ball_on_table(config, p_BE=np.zeros(3), height=0.8):
    """The ball on the shipped table (top at 0.75 m) after 1 s, at (0.1, 0.05) on the top;
    the ContactWrench of the ball about the point ``p_BE`` of it."""
    from pydrake.math import RigidTransform
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlant(config, builder)
    parser = environment_parser(plant)
    parser.AddModels(url="package://aerial_drake/environments/table.sdf")
    parser.AddModelsFromString(BALL, "sdf")
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("table"))
    plant.Finalize()
    ball = plant.GetBodyByName("ball")
    wrench = builder.AddSystem(ContactWrench(plant, ball, p_BE, scene_graph.model_inspector()))
    builder.Connect(plant.get_contact_results_output_port(),
                    wrench.GetInputPort("contact_results"))
    builder.Connect(plant.get_body_poses_output_port(), wrench.GetInputPort("body_poses"))
    diagram = builder.Build()
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    plant.SetFreeBodyPose(plant.GetMyMutableContextFromRoot(context), ball,
                          RigidTransform([0.1, 0.05, height]))
    simulator.AdvanceTo(1.0)
    return np.asarray(wrench.GetOutputPort("contact_wrench").Eval(
        wrench.GetMyContextFromRoot(context)))


CONFIGS = {
    "continuous point": MultibodyPlantConfig(time_step=0.0, contact_model="point"),
    "discrete sap": MultibodyPlantConfig(time_step=1e-3, discrete_contact_approximation="sap"),
}


@pytest.mark.parametrize("name", sorted(CONFIGS))
def test_resting_ball_carries_its_weight(name):
    """At rest the table holds the 1 kg ball up with its weight, through the point under its
    centre (its radius below it, on the table's top): about the centre no torque; about a
    point 0.1 m along x of the centre, the weight's moment -0.1 x (m g e3)."""
    w = _ball_on_table(CONFIGS[name])
    assert w.shape == (CONTACT_WRENCH_SIZE,)
    weight = 9.81
    np.testing.assert_allclose(w[S["force"]], [0.0, 0.0, weight], atol=1e-3 * weight)
    np.testing.assert_allclose(w[S["torque"]], 0.0, atol=1e-4)
    np.testing.assert_allclose(w[S["point"]][:2], [0.1, 0.05], atol=1e-6)
    assert abs(w[S["point"]][2] - 0.75) < 1e-3  # within the pad's compression
    assert w[S["contacts"]][0] == 1
    moved = _ball_on_table(CONFIGS[name], p_BE=np.array([0.1, 0.0, 0.0]))
    np.testing.assert_allclose(moved[S["torque"]], [0.0, 0.1 * weight, 0.0], rtol=1e-3,
                               atol=1e-4)


def test_no_contact_is_all_zeros():
    """The box held above the table: nothing touches."""
    from pydrake.math import RigidTransform
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlant(MultibodyPlantConfig(time_step=1e-3), builder)
    parser = environment_parser(plant)
    parser.AddModels(url="package://aerial_drake/environments/box.sdf")
    parser.AddModels(url="package://aerial_drake/environments/table.sdf")
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("table"))
    plant.Finalize()
    box = plant.GetBodyByName("box")
    wrench = builder.AddSystem(ContactWrench(plant, box, np.zeros(3),
                                             scene_graph.model_inspector()))
    builder.Connect(plant.get_contact_results_output_port(),
                    wrench.GetInputPort("contact_results"))
    builder.Connect(plant.get_body_poses_output_port(), wrench.GetInputPort("body_poses"))
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    plant.SetFreeBodyPose(plant.GetMyMutableContextFromRoot(context), box,
                          RigidTransform([0.0, 0.0, 1.5]))
    out = wrench.GetOutputPort("contact_wrench").Eval(wrench.GetMyContextFromRoot(context))
    assert not np.any(out)


def _sensor_samples(force, bandwidth, noise_std, seed=3, samples=2000, period=1e-3):
    builder = DiagramBuilder()
    wrench = np.zeros(CONTACT_WRENCH_SIZE)
    wrench[S["force"]] = force
    source = builder.AddSystem(ConstantVectorSource(wrench))
    sensor = builder.AddSystem(ForceSensor(period, bandwidth, noise_std, seed,
                                           samples * period))
    builder.Connect(source.get_output_port(), sensor.GetInputPort("contact_wrench"))
    diagram = builder.Build()
    simulator = Simulator(diagram)
    context = sensor.GetMyContextFromRoot(simulator.get_mutable_context())
    out = []
    for k in range(1, samples + 1):
        simulator.AdvanceTo(k * period)
        out.append(np.array(sensor.GetOutputPort("measured_contact_force").Eval(context)))
    return np.array(out)


def test_force_sensor_low_pass_step_response():
    """A 10 N step through the 20 Hz first-order low-pass sampled at 1 kHz: after k samples
    10 (1 - exp(-2 pi 20 k T)), exactly (the discrete filter's step response)."""
    out = _sensor_samples([0.0, 0.0, 10.0], bandwidth=20.0, noise_std=0.0)
    k = np.arange(1, len(out) + 1)
    np.testing.assert_allclose(out[:, 2], 10.0 * (1 - np.exp(-2 * np.pi * 20.0 * k * 1e-3)),
                               rtol=1e-12, atol=1e-12)
    # The time constant: 63 % after 1 / (2 pi 20 Hz) = 7.96 ms, between samples 7 and 8.
    assert out[6, 2] < 6.32 < out[7, 2]


def test_force_sensor_noise_statistics_and_seed():
    a = _sensor_samples([1.0, 2.0, 3.0], bandwidth=np.inf, noise_std=0.5, seed=1)
    b = _sensor_samples([1.0, 2.0, 3.0], bandwidth=np.inf, noise_std=0.5, seed=1)
    c = _sensor_samples([1.0, 2.0, 3.0], bandwidth=np.inf, noise_std=0.5, seed=2)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    noise = a - [1.0, 2.0, 3.0]
    assert np.std(noise, axis=0) == pytest.approx([0.5] * 3, rel=0.06)  # 2000 samples
    assert np.abs(np.mean(noise, axis=0)).max() < 0.05


@pytest.mark.parametrize("field, value, words", [
    ("bandwidth", -1.0, "force_sensor.bandwidth must be a number > 0"),
    ("bandwidth", float("nan"), "force_sensor.bandwidth must be a number > 0"),
    ("noise_std", -0.1, "force_sensor.noise_std must be finite, >= 0"),
    ("seed", -3, "force_sensor.seed must be an integer"),
])
def test_a_bad_force_sensor_is_refused_at_load(field, value, words):
    from aerial_drake.simulation.scenarios import ScenarioError
    with pytest.raises(ScenarioError, match=words):
        load_scenario("wall_press", overrides={f"force_sensor.{field}": value})


def test_a_sensor_without_filter_passes_the_force_through():
    out = _sensor_samples([0.0, 0.0, 10.0], bandwidth=np.inf, noise_std=0.0, samples=3)
    np.testing.assert_array_equal(out[:, 2], [10.0, 10.0, 10.0])
