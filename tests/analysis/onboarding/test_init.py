"""``robot init`` on URDFs the project does not ship (tests/hexarm.py: a hexacopter with a
6-joint arm and a welded tool0; tests/own_robot.py: a quadrotor with a 4-joint arm): what it
finds, chooses and writes, its errors, and the hover scenario it writes flying as written."""

import json
import warnings

import numpy as np
import pytest

from aerial_drake.analysis.onboarding import InitOptions, OnboardingError, init_robot
from aerial_drake.analysis.onboarding.discovery import discover
from aerial_drake.analysis.onboarding.gains import TASK_POLE_LIMIT, table_ii
from aerial_drake.analysis.onboarding.posture import BELOW_SHARE, HOVER_TORQUE_SHARE
from aerial_drake.cli import main
from aerial_drake.control.gain_design import GainDesignWarning, loop_roots
from aerial_drake.robots.description import load_robot_description
from aerial_drake.robots.models import make_plant
from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import load_scenario
from aerial_drake.simulation.tracking import entries
from hexarm import write as write_hexarm
from own_robot import urdf as own_urdf


@pytest.fixture(scope="module")
def hexarm(tmp_path_factory):
    """``robot init hexarm.urdf --tool-direction down``, once for the module."""
    folder = tmp_path_factory.mktemp("hexarm")
    model = write_hexarm(folder)
    with warnings.catch_warnings():
        warnings.simplefilter("error", GainDesignWarning)  # the gains it writes pass the check
        result = init_robot(InitOptions(model=model, tool_direction="down"))
    return result


def test_discovery_finds_the_vehicle_the_chain_and_the_tool_frame(tmp_path):
    found = discover(write_hexarm(tmp_path))
    assert found.vehicle_body == "hexacopter" and found.model_name == "hexarm"
    assert found.arm_joints == ("pan_joint", "shoulder_joint", "elbow_joint", "wrist_1_joint",
                                "wrist_2_joint", "wrist_3_joint")
    # tool0, a massless link welded at the flange, is preferred; the flange is a candidate;
    # the weld's own joint frames are not.
    assert found.end_effector == "tool0" and found.end_effector_is_body
    assert set(found.candidates) == {"tool0", "wrist_3"}
    # A wrong name lists the model's frames, not the joints' own frames.
    with pytest.raises(OnboardingError, match="frames: forearm, hexacopter, pan, tool0,") as err:
        discover(tmp_path / "hexarm.urdf", end_effector="nope")
    assert "_parent" not in str(err.value) and "world" not in str(err.value)


def test_init_writes_a_description_and_a_hover_scenario_that_load(hexarm):
    assert hexarm.robot_path.name == "hexarm.robot.yaml"
    assert hexarm.scenario_path.name == "hexarm_hover.yaml"
    robot = load_robot_description(hexarm.robot_path)
    assert robot.vehicle_body == "hexacopter" and robot.end_effector.body == "tool0"
    assert robot.task == ["position", "orientation"]
    np.testing.assert_allclose(robot.nominal_posture, hexarm.posture.q_arm, atol=1e-7)
    scenario = load_scenario(hexarm.scenario_path)
    assert scenario.trajectory.kind == "hover"
    assert scenario.robot == str(hexarm.robot_path)  # resolved from the scenario's folder


def test_the_offsets_are_the_system_com_and_the_end_effector_at_the_nominal_posture(hexarm):
    model = make_plant(robot=load_robot_description(hexarm.robot_path))
    plant = model.plant
    ctx = plant.CreateDefaultContext()
    q = plant.GetPositions(ctx)
    q[model.arm_position_indices] = model.q_nominal_arm()
    plant.SetPositions(ctx, q)
    p_G = plant.CalcCenterOfMassPositionInWorld(ctx)
    X_WE = model.end_effector_frame.CalcPoseInWorld(ctx)
    # r_o of (33) is the CoM minus the end effector; the scenario holds both where they are.
    np.testing.assert_allclose(hexarm.com_offset, p_G - X_WE.translation(), atol=1e-9)
    scenario = load_scenario(hexarm.scenario_path)
    hover = scenario.trajectory.hover
    np.testing.assert_allclose(np.array(hover.ee_position) - hover.com, -hexarm.com_offset,
                               atol=1e-6)
    np.testing.assert_allclose(scenario.trajectory.com_offset, hexarm.com_offset, atol=1e-6)
    # The end effector hangs below the vehicle, the tool z axis points down.
    assert X_WE.translation()[2] <= -BELOW_SHARE * 0.67 + 1e-9
    np.testing.assert_allclose(X_WE.rotation().matrix()[:, 2], [0, 0, -1], atol=1e-6)
    # The locked inertia: every body rigidly at its place, about the CoM, vehicle axes.
    M = plant.CalcSpatialInertia(ctx, model.base_body.body_frame(),
                                 [b for b in plant.GetBodyIndices(model.vehicle)])
    np.testing.assert_allclose(
        hexarm.locked_inertia,
        M.Shift(M.get_com()).CalcRotationalInertia().CopyToFullMatrix3(), atol=1e-12)


def test_the_posture_keeps_its_margins(hexarm):
    p = hexarm.posture
    assert p.sigma_min_J3 > 0.05  # Assumption 1 with room
    assert p.joint_margin > 0.3  # every joint away from its limits
    assert p.hover_torque_share <= HOVER_TORQUE_SHARE
    assert p.pointing_error < 1e-5


def test_the_gains_follow_the_rule(hexarm):
    II, by_kind, m_II = table_ii()
    g = hexarm.gains.gains
    np.testing.assert_allclose(g.K_x, np.array(II.K_x) * hexarm.mass / m_II, rtol=5e-3)
    np.testing.assert_allclose(g.D_x, np.array(II.D_x) * hexarm.mass / m_II, rtol=5e-3)
    np.testing.assert_allclose(g.Lambda2_bar, np.diag(hexarm.gains.Lambda_22), rtol=5e-3)
    roots = loop_roots(hexarm.mass, g.K_x, g.D_x, g.k_R, g.k_w, g.Lambda2_bar)
    assert roots.separation >= 3.0  # the attitude loop 3x faster than the CoM loop
    poles = -hexarm.gains.task_poles.real
    assert poles.min() > 0 and poles.max() <= TASK_POLE_LIMIT / 0.001 * (1 + 1e-9)
    # ... and at the postures about the nominal a run visits (0.3 rad on each joint).
    assert hexarm.gains.fastest_nearby <= TASK_POLE_LIMIT / 0.001 * (1 + 1e-9)
    # Rows whose K_z was not lowered keep Table II's K_z and K_y (the position rows here).
    for i in range(3):
        if i not in hexarm.gains.capped_rows:
            assert (g.K_y[i], g.K_z[i]) == by_kind["position"]
    # The wrist's rows are lowered (its task inertia is tiny) and take the position K_y.
    assert {3, 4, 5} <= set(hexarm.gains.capped_rows)
    assert all(g.K_y[i] == by_kind["position"][0] for i in hexarm.gains.capped_rows)


def test_the_limits_come_from_the_model_and_the_ratio(hexarm):
    limits = hexarm.limits
    assert limits.thrust == pytest.approx((0.0, 2.0 * hexarm.mass * 9.81))
    assert limits.joint_effort == (28.0, 28.0, 14.0, 6.0, 6.0, 6.0)
    # The rotor discs reach 0.45 + 0.12 m from the axis: R is that (docs/robots.md).
    assert limits.radius_source == "geometry"
    assert limits.vehicle_radius == pytest.approx(0.57, abs=1e-3)
    assert limits.body_torque[0] == pytest.approx(0.25 * limits.thrust[1] * 0.57, rel=1e-3)
    assert limits.body_torque[2] == pytest.approx(0.1 * limits.body_torque[0])


def test_the_hover_scenario_flies_as_written_and_converges(hexarm):
    scenario = load_scenario(hexarm.scenario_path)
    result = run_scenario(scenario, progress=False)
    assert result.completed, result.failure
    t = result.log["t"]
    ee = entries(result.log["tracking"], result.layouts["tracking"])["ee_position_error"][:, 0]
    # Measured 0.035 mm after 3 s (from 18.7 mm at the start); the issue asks < 1 mm.
    assert ee[t >= 3.0].max() < 1e-3
    assert ee[0] > 0.01  # it did start off


def test_the_pick_and_place_it_writes_is_flown(hexarm):
    """Approach, descend, hold, lift, move with a quarter turn, descend, hold, lift: the vehicle
    carries the arm at its nominal posture (the CoM at r_o, (33))."""
    path = hexarm.pick_and_place_path
    assert path.name == "hexarm_pick_and_place.yaml"
    result = run_scenario(load_scenario(path), progress=False)
    assert result.completed, result.failure
    t = result.log["t"]
    tracking = entries(result.log["tracking"], result.layouts["tracking"])
    moving = t >= 3.0
    # Measured: 0.036 mm and 3.05 mrad at 3-5 s, at most 0.004 mm and 0.33 mrad from 5 s on
    # (the slowest task pole is 1.1 1/s); no input at a limit after 0.5 s.
    assert tracking["ee_position_error"][moving].max() < 0.1e-3
    assert tracking["ee_orientation_error"][t >= 5.0].max() < 1e-3
    assert all(v == 0.0 for v in result.metrics["saturated_s_after_0.5s"].values())
    assert result.metrics["heading_error_rad"]["max"] < 0.02


def test_a_four_joint_arm_gets_the_one_task_its_joints_can_hold(tmp_path):
    model = tmp_path / "quad_arm.urdf"
    model.write_text(own_urdf())
    result = init_robot(InitOptions(model=model))
    # position + j1, j2 or j3 leave the position to joints that cannot all move it (j4 turns
    # the end effector about its own axis): J_3 is singular; the wrist's angle is the task.
    assert result.task == ("position", "joint:j4")
    assert len(result.tasks_tried) == 4


@pytest.mark.parametrize("urdf_options, options, field, words", [
    (dict(world_weld=True), {}, "--vehicle", "no free body with actuated joints"),
    (dict(joint_types={"j2": "prismatic"}), {}, "model", "is prismatic"),
    ({}, dict(end_effector="nowhere"), "--end-effector", "no such frame or body"),
    ({}, dict(vehicle="l2"), "--vehicle", "must be a free body"),
    ({}, dict(thrust_to_weight=0.9), "--thrust-to-weight", "must be a number > 1"),
    ({}, dict(tool_direction="sideways"), "--tool-direction", "give one of"),
    ({}, dict(task=["position", "joint:j1"]), "--task", "J_3 is singular"),
])
def test_bad_models_and_options_are_named(tmp_path, urdf_options, options, field, words):
    model = tmp_path / "quad_arm.urdf"
    model.write_text(own_urdf(**urdf_options))
    with pytest.raises(OnboardingError, match=words) as err:
        init_robot(InitOptions(model=model, **options))
    assert err.value.field == field
    assert not list(tmp_path.glob("*.yaml"))  # nothing written


def test_a_branching_arm_asks_for_the_end_effector(tmp_path):
    branch = ('<link name="side"><inertial><mass value="0.1"/><inertia ixx="1e-4" iyy="1e-4" '
              'izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial></link><joint name="side_joint" '
              'type="revolute"><parent link="l2"/><child link="side"/><axis xyz="1 0 0"/>'
              '<limit effort="5" lower="-1" upper="1" velocity="1"/></joint><transmission '
              'name="side_tr"><type>transmission_interface/SimpleTransmission</type><joint '
              'name="side_joint"><hardwareInterface>EffortJointInterface</hardwareInterface>'
              '</joint><actuator name="side_motor"><mechanicalReduction>1</mechanicalReduction>'
              '</actuator></transmission>')
    model = tmp_path / "quad_arm.urdf"
    model.write_text(own_urdf(extra=branch))
    with pytest.raises(OnboardingError, match="branches below the joint 'j2'"):
        discover(model)
    assert discover(model, end_effector="l4").arm_joints == ("j1", "j2", "j3", "j4")


def test_the_command_line_writes_refuses_to_overwrite_and_exits_2(tmp_path, capsys):
    model = tmp_path / "quad_arm.urdf"
    model.write_text(own_urdf())
    assert main(["robot", "init", str(model), "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "quad_arm.robot.yaml, quad_arm_hover.yaml and quad_arm_pick_and_place.yaml" in out
    assert "next: aerial-drake run" in out
    assert main(["robot", "init", str(model), "--quiet"]) == 2
    assert "exists: give --force" in capsys.readouterr().err
    assert main(["robot", "init", str(model), "--quiet", "--force", "--name", "other"]) == 0
    assert (tmp_path / "other.robot.yaml").is_file()
    assert main(["robot", "init", str(model), "--quiet", "--out", str(tmp_path / "new" / "dir"),
                 "--json"]) == 0  # a folder that does not exist yet
    assert (tmp_path / "new" / "dir" / "quad_arm_hover.yaml").is_file()
    out = capsys.readouterr().out
    assert json.loads(out[out.index("{"):])["task"] == ["position", "joint:j4"]
    assert main(["robot", "init", str(tmp_path / "missing.urdf")]) == 2
    assert "no such file" in capsys.readouterr().err
