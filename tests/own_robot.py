"""A robot that is not one of ours, written as a URDF in a test's folder: a 5.2 kg quadrotor
box with a 4-joint arm (roll, pitch, pitch, wrist yaw) hanging below it, its robot
description and a scenario, each with options that break one thing (tests/robots/
test_own_robot.py)."""

from __future__ import annotations

from pathlib import Path

#: The arm's joints: name, parent link, child link, origin in the parent, axis.
JOINTS = (("j1", "quad", "l1", (0, 0, -0.08), (1, 0, 0)),
          ("j2", "l1", "l2", (0, 0, -0.06), (0, 1, 0)),
          ("j3", "l2", "l3", (0, 0, -0.3), (0, 1, 0)),
          ("j4", "l3", "l4", (0, 0, -0.25), (0, 0, 1)))
#: Links: name, mass (kg), principal inertia (kg m^2), centre of mass (m).
LINKS = (("quad", 4.0, (0.08, 0.08, 0.14), (0, 0, 0)),
         ("l1", 0.3, (0.001, 0.001, 0.001), (0, 0, -0.03)),
         ("l2", 0.4, (0.003, 0.003, 0.0005), (0, 0, -0.15)),
         ("l3", 0.3, (0.002, 0.002, 0.0004), (0, 0, -0.12)),
         ("l4", 0.2, (0.0003, 0.0003, 0.0003), (0, 0, -0.03)))


def _xyz(v) -> str:
    return " ".join(str(x) for x in v)


def urdf(*, joint_types: dict[str, str] | None = None, world_weld: bool = False,
         extra: str = "", vehicle_com=(0, 0, 0)) -> str:
    """The URDF text; ``joint_types`` replaces joints' types (e.g. {"j2": "prismatic"}),
    ``world_weld`` fixes the vehicle to the world, ``extra`` adds URDF elements."""
    types = joint_types or {}
    out = ['<?xml version="1.0"?>', '<robot name="quad_arm">']
    if world_weld:
        out.append('  <link name="world"/>')
        out.append('  <joint name="to_world" type="fixed"><parent link="world"/>'
                   '<child link="quad"/></joint>')
    for name, mass, (ixx, iyy, izz), com in LINKS:
        com = vehicle_com if name == "quad" else com
        visual = ('<visual><geometry><box size="0.6 0.6 0.1"/></geometry></visual>'
                  if name == "quad" else "")
        out.append(f'  <link name="{name}"><inertial><origin xyz="{_xyz(com)}"/>'
                   f'<mass value="{mass}"/><inertia ixx="{ixx}" iyy="{iyy}" izz="{izz}" '
                   f'ixy="0" ixz="0" iyz="0"/></inertial>{visual}</link>')
    for name, parent, child, origin, axis in JOINTS:
        kind = types.get(name, "revolute")
        out.append(f'  <joint name="{name}" type="{kind}"><parent link="{parent}"/>'
                   f'<child link="{child}"/><origin xyz="{_xyz(origin)}"/>'
                   f'<axis xyz="{_xyz(axis)}"/><limit lower="-3" upper="3" effort="50" '
                   'velocity="3"/></joint>')
        out.append(f'  <transmission name="{name}_tr"><type>transmission_interface/'
                   f'SimpleTransmission</type><joint name="{name}"><hardwareInterface>'
                   'EffortJointInterface</hardwareInterface></joint><actuator '
                   f'name="{name}_motor"><mechanicalReduction>1</mechanicalReduction>'
                   '</actuator></transmission>')
    out.append(extra)
    out.append("</robot>")
    return "\n".join(out) + "\n"


DESCRIPTION = """name: quad_arm
models: [quad_arm.urdf]
vehicle_body: {vehicle}
end_effector: {{body: {ee_body}, offset_xyz: [0, 0, -0.06]}}
task: {task}
limits: {{thrust: [0.0, 150.0], body_torque: [30.0, 30.0, 15.0]}}
nominal_posture: {posture}
workspace_radius: 0.1
"""

SCENARIO = """name: quad_arm
robot: quad_arm.robot.yaml
duration: {duration}
controller_period: 0.001
log_period: 0.001
simulator: {{integration_scheme: runge_kutta3, max_step_size: 0.001, accuracy: 1.0e-6,
            use_error_control: false}}
gains:
  K_x: [76.0, 76.0, 76.0]
  D_x: [40.0, 40.0, 40.0]
  k_R: 25.0
  k_w: 20.0
  Lambda2_bar: [0.15, 0.15, 0.15]
  K_y: [30.0, 30.0, 30.0, 10.0]
  # The wrist's task inertia is about 3e-4 kg m^2: K_z = 0.01 there puts its pole at
  # about 30 rad/s (K_z = 30 would put it far past the 1 kHz sampling).
  K_z: [30.0, 30.0, 30.0, 0.01]
trajectory:
  center: [0.0, 0.0, 1.5]
  basic_amplitude: 0.1
  basic_frequency: 0.5
  basic_climb_rate: 0.0
  agile_amplitude: 0.02
  agile_frequency: 2.0
  orientation_amplitudes: [0.0, 0.0, 0.0]
  orientation_frequency: 1.0
  heading_initial: 0.0
  heading_rate: 0.2
  # Minus the nominal end-effector offset from the CoM.
  com_offset: [0.186, 0.0, 0.583]
initial:
  base_position_offset: [0.02, -0.02, -0.02]
  base_rpy_offset: [0.0, 0.0, 0.03]
disturbances: []
"""


def write_robot(folder: Path, *, vehicle: str = "quad", ee_body: str = "l4",
                task: str = '[position, "joint:j4"]', posture: str = "[0.0, 0.8, -0.8, 0.0]",
                duration: float = 1.0, **urdf_options) -> tuple[Path, Path]:
    """Writes quad_arm.urdf, quad_arm.robot.yaml and quad_arm.yaml into ``folder``; returns
    (description, scenario) paths."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "quad_arm.urdf").write_text(urdf(**urdf_options))
    description = folder / "quad_arm.robot.yaml"
    description.write_text(DESCRIPTION.format(vehicle=vehicle, ee_body=ee_body, task=task,
                                              posture=posture))
    scenario = folder / "quad_arm.yaml"
    scenario.write_text(SCENARIO.format(duration=duration))
    return description, scenario
