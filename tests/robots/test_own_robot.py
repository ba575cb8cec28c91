"""A user's own robot: a URDF written here (tests/own_robot.py, not one of ours) described by a
robot description, checked before anything is simulated, and flown for a second."""

import subprocess
import sys

import numpy as np
import pytest

from aerial_drake.control.controller import make_controller
from aerial_drake.control.reference_pose import reference_configuration
from aerial_drake.robots.description import RobotDescriptionError, load_robot_description
from aerial_drake.robots.models import make_plant
from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import ScenarioError, load_scenario
from aerial_drake.trajectories.kinds import evaluate_reference
from own_robot import write_robot


def _build(tmp_path, **options):
    description, _ = write_robot(tmp_path, **options)
    return make_plant(robot=load_robot_description(description))


def test_the_urdf_robot_is_built_with_its_task(tmp_path):
    model = _build(tmp_path)
    assert [j.name() for j in model.arm_joints] == ["j1", "j2", "j3", "j4"]
    assert model.n == 4 and model.base_body.name() == "quad"
    assert model.task.rows == (0, 1, 2, 6) and model.task.joint_names == ("j4",)
    assert model.task.joint_velocities == (model.arm_joints[3].velocity_start(),)
    assert model.total_mass() == pytest.approx(5.2)
    np.testing.assert_allclose(model.q_nominal_arm(), [0.0, 0.8, -0.8, 0.0])


def test_the_compiled_law_serves_the_urdf_robot_and_matches_the_reference(tmp_path):
    _, scenario_path = write_robot(tmp_path)
    scenario = load_scenario(scenario_path)
    model = scenario.controller_model()
    controller = make_controller(model, scenario.gains)
    assert controller.compiled, controller.not_compiled_reason
    rng = np.random.default_rng(3)
    q = reference_configuration(scenario, model)
    for t in (0.0, 0.4):
        x = np.concatenate([q, 0.3 * rng.standard_normal(model.plant.num_velocities())])
        x[:4] /= np.linalg.norm(x[:4])
        refs = evaluate_reference(scenario.trajectory, t, model.task_joint_nominal())
        command, diagnostics = controller.evaluate(x, *refs.to_vectors())
        out = controller.solve(x, *refs.to_vectors())
        reference = np.concatenate([[out.f], out.mu, out.tau])
        np.testing.assert_allclose(command, reference, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(diagnostics, out.diagnostics, rtol=1e-9, atol=1e-10)


def test_the_urdf_robot_flies_for_a_second(tmp_path):
    _, scenario_path = write_robot(tmp_path, duration=1.0)
    result = run_scenario(load_scenario(scenario_path), progress=False)
    assert result.completed, result.failure
    ee = result.metrics["phases"][0]["ee_position_error_m"]
    assert ee["max"] < 0.05  # it starts 34 mm off
    log = result.log
    t, d = log["t"], log["diagnostics"]
    assert t[-1] == pytest.approx(1.0)
    # The task converges: position rows of y_tilde below 0.1 mm in the last 0.2 s.
    late = t >= 0.8
    assert np.abs(d[late, 12:15]).max() < 1e-4
    assert log["command"].shape[1] == 4 + 4


@pytest.mark.parametrize("options, field, words", [
    (dict(world_weld=True), "vehicle_body", "must be a free body"),
    (dict(joint_types={"j2": "prismatic"}), "arm_joints", "prismatic joint"),
    (dict(extra='<link name="side"><inertial><mass value="0.1"/><inertia ixx="1e-4" '
                'iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial></link>'
                '<joint name="side_joint" type="revolute"><parent link="l2"/>'
                '<child link="side"/><axis xyz="1 0 0"/><limit effort="5" lower="-1" '
                'upper="1" velocity="1"/></joint><transmission name="side_tr"><type>'
                'transmission_interface/SimpleTransmission</type><joint name="side_joint">'
                '<hardwareInterface>EffortJointInterface</hardwareInterface></joint>'
                '<actuator name="side_motor"><mechanicalReduction>1</mechanicalReduction>'
                '</actuator></transmission>'), "arm_joints", "not on the chain"),
    (dict(task="[position, orientation]"), "task", "has 6 coordinates but the arm has 4"),
    (dict(ee_body="quad"), "end_effector.body", "not on the arm"),
    (dict(vehicle="l9"), "vehicle_body", "no body 'l9'"),
    (dict(vehicle_com=(0.0, 0.0, 0.01)), "vehicle_body", "centre of mass"),
    (dict(task="[position, orientation_z]"), "task", "not supported"),
])
def test_a_description_the_law_cannot_serve_is_refused_naming_the_field(
        tmp_path, options, field, words):
    with pytest.raises(RobotDescriptionError) as err:
        _build(tmp_path, **options)
    assert err.value.field == field
    assert words in str(err.value)
    assert "quad_arm.robot.yaml" in str(err.value)  # names the file


def test_a_scenario_of_a_bad_robot_is_refused_before_simulating(tmp_path):
    write_robot(tmp_path, task="[position]")
    with pytest.raises(ScenarioError) as err:
        load_scenario(tmp_path / "quad_arm.yaml")
    assert "robot" in str(err.value) and "has 3 coordinates but the arm has 4" in str(err.value)


def test_a_singular_start_posture_is_refused_before_simulating(tmp_path, monkeypatch):
    _, scenario_path = write_robot(tmp_path)
    text = scenario_path.read_text() + "sigma_min_J3_limit: 0.5\n"
    scenario_path.write_text(text)  # above sigma_min(J_3) = 0.11 of the start posture
    with pytest.raises(ScenarioError, match="Assumption 1 fails along the reference"):
        run_scenario(load_scenario(scenario_path), progress=False)
    # The start posture's own check, behind the check of the whole reference.
    monkeypatch.setattr("aerial_drake.simulation.runner.check_reference", lambda *a: None)
    with pytest.raises(ScenarioError) as err:
        run_scenario(load_scenario(scenario_path), progress=False)
    assert "Assumption 1 fails at the start posture (t = 0)" in str(err.value)
    assert "sigma_min(J_3) = 0.11" in str(err.value)


def test_the_command_line_exits_2_on_a_bad_robot(tmp_path):
    write_robot(tmp_path, joint_types={"j3": "prismatic"})
    proc = subprocess.run([sys.executable, "-m", "aerial_drake", "run",
                           str(tmp_path / "quad_arm.yaml"), "--out", str(tmp_path / "out")],
                          capture_output=True, text=True)
    assert proc.returncode == 2, proc.stderr
    assert "joint 'j3' is a prismatic joint" in proc.stderr
    assert not (tmp_path / "out").exists()


def _edit(description, old, new):
    text = description.read_text()
    assert old in text
    description.write_text(text.replace(old, new))


def test_model_files_through_a_package_map(tmp_path):
    description, _ = write_robot(tmp_path / "robot")
    _edit(description, "models: [quad_arm.urdf]",
          "models: ['package://mine/quad_arm.urdf']\npackage_map: {mine: .}")
    model = make_plant(robot=load_robot_description(description))
    assert model.n == 4
    _edit(description, "package_map: {mine: .}", "package_map: {other: .}")
    with pytest.raises(RobotDescriptionError, match="names the package 'mine'"):
        make_plant(robot=load_robot_description(description))


def test_reflected_inertia_and_effort_limits_of_the_description(tmp_path):
    description, _ = write_robot(tmp_path)
    plain = make_plant(robot=load_robot_description(description))
    _edit(description, "workspace_radius: 0.1",
          "workspace_radius: 0.1\nreflected_inertia: [0.5, 0.0, 0.0, 0.0]\n"
          "limits: {thrust: [0.0, 150.0], body_torque: [30.0, 30.0, 15.0], "
          "joint_effort: [1.0, 2.0, 3.0, 4.0]}")
    _edit(description, "limits: {thrust: [0.0, 150.0], body_torque: [30.0, 30.0, 15.0]}\n", "")
    driven = make_plant(robot=load_robot_description(description))
    M = [m.plant.CalcMassMatrix(m.plant.CreateDefaultContext()) for m in (plain, driven)]
    i = driven.arm_velocity_indices[0]
    assert M[1][i, i] - M[0][i, i] == pytest.approx(0.5)
    np.testing.assert_array_equal(driven.arm_effort_limits(), [1.0, 2.0, 3.0, 4.0])
    np.testing.assert_array_equal(plain.arm_effort_limits(), [50.0] * 4)  # the URDF's


def test_arm_joints_out_of_chain_order_are_refused(tmp_path):
    description, _ = write_robot(tmp_path)
    _edit(description, "vehicle_body: quad", "vehicle_body: quad\narm_joints: [j2, j1, j3, j4]")
    with pytest.raises(RobotDescriptionError, match="are not the chain from the vehicle"):
        make_plant(robot=load_robot_description(description))
