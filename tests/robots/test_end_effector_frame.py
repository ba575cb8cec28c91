"""The end effector as a frame on a massless link welded to the arm's last link (the common
URDF ``tool0``/``ee`` pattern, issue 27): the law follows that frame's pose through the body
with mass it is welded to; a massless link that moves is refused, and a wrong frame name lists
the model's frames."""

import numpy as np
import pytest

from aerial_drake.robots.description import RobotDescriptionError, load_robot_description
from aerial_drake.robots.models import END_EFFECTOR_FRAME, make_plant, nominal_end_effector_offset
from own_robot import write_robot

#: tool0 on l4 through a massless flange, each weld with a rotation and a sideways part.
TOOL = """
  <link name="flange"/>
  <joint name="l4-flange" type="fixed"><parent link="l4"/><child link="flange"/>
    <origin xyz="0.01 -0.02 -0.05" rpy="0.2 -0.1 0.4"/></joint>
  <link name="tool0"/>
  <joint name="flange-tool0" type="{kind}"><parent link="flange"/><child link="tool0"/>
    <origin xyz="0.03 0.0 -0.02" rpy="0.0 0.3 -0.5"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <transmission name="tool_tr"><type>transmission_interface/SimpleTransmission</type>
    <joint name="flange-tool0"><hardwareInterface>EffortJointInterface</hardwareInterface>
    </joint><actuator name="tool_motor"><mechanicalReduction>1</mechanicalReduction>
    </actuator></transmission>
"""


def _build(tmp_path, frame: str = "tool0", kind: str = "fixed"):
    tool = TOOL.format(kind=kind)
    if kind == "fixed":
        tool = tool[:tool.index("  <transmission")]
    description, _ = write_robot(tmp_path, extra=tool)
    text = description.read_text()
    old = "end_effector: {body: l4, offset_xyz: [0, 0, -0.06]}"
    assert old in text
    description.write_text(text.replace(old, f"end_effector: {{frame: {frame}}}"))
    return make_plant(robot=load_robot_description(description))


def test_a_frame_on_a_massless_welded_link_is_followed_through_its_body(tmp_path):
    model = _build(tmp_path)
    frame = model.end_effector_frame
    assert frame.name() == END_EFFECTOR_FRAME and frame.body().name() == "l4"
    assert model.end_effector_body.name() == "l4"
    plant = model.plant
    tool0 = plant.GetFrameByName("tool0")
    context = plant.CreateDefaultContext()
    rng = np.random.default_rng(5)
    q = plant.GetPositions(context)
    q[7:] = rng.uniform(-1.0, 1.0, q.size - 7)
    plant.SetPositions(context, q)
    X_mount, X_tool = frame.CalcPoseInWorld(context), tool0.CalcPoseInWorld(context)
    np.testing.assert_allclose(X_mount.GetAsMatrix4(), X_tool.GetAsMatrix4(), atol=1e-14)
    # The law's offset of E from the system's CoM is tool0's, not l4's origin's.
    description, _ = write_robot(tmp_path / "plain")
    plain = make_plant(robot=load_robot_description(description))
    assert np.linalg.norm(nominal_end_effector_offset(model)
                          - nominal_end_effector_offset(plain)) > 0.02


def test_a_frame_on_a_massless_link_that_moves_is_refused(tmp_path):
    with pytest.raises(RobotDescriptionError) as err:
        _build(tmp_path, kind="revolute")
    assert err.value.field == "end_effector.frame"
    assert "massless body 'tool0'" in str(err.value)
    assert "revolute joint 'flange-tool0'" in str(err.value)


def test_a_wrong_frame_name_lists_the_frames(tmp_path):
    with pytest.raises(RobotDescriptionError) as err:
        _build(tmp_path, frame="tool_0")
    assert err.value.field == "end_effector.frame"
    message = str(err.value)
    assert "no frame 'tool_0'" in message and "frames: " in message
    assert "quad_arm::tool0" in message and "quad_arm::flange" in message
