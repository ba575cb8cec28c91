"""The two files ``robot init`` writes, as commented YAML whose comments give the source of
every number (docs/robots.md, "robot init"): ``NAME.robot.yaml`` (the description) and
``NAME_hover.yaml`` (a hover scenario that runs as written)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from aerial_drake.control.gains import Gains

#: The hover scenario's start offsets (the runs' convergence is the check that it flies).
START_POSITION_OFFSET = (0.01, -0.01, -0.01)
START_RPY_OFFSET = (0.0, 0.0, 0.01)
#: Where the hover scenario holds the system's CoM (World, m).
HOVER_COM = (0.0, 0.0, 1.5)
HOVER_DURATION = 5.0
CONTROLLER_PERIOD = 0.001


def _list(values, digits: int = 6) -> str:
    return "[" + ", ".join(f"{float(v):.{digits}g}" for v in values) + "]"


@dataclass(frozen=True)
class RobotFile:
    """What the description file holds, with the figures its comments quote."""

    name: str
    model: str  # the model file, relative to the description's folder
    vehicle_body: str
    arm_joints: tuple[str, ...]
    end_effector: str
    end_effector_is_body: bool
    task: tuple[str, ...]
    thrust: tuple[float, float]
    thrust_to_weight: float
    body_torque: tuple[float, float, float]
    body_torque_note: str
    joint_effort: tuple[float, ...]
    nominal_posture: np.ndarray
    posture_note: str
    workspace_radius: float
    workspace_note: str
    mass: float


def robot_text(f: RobotFile) -> str:
    ee = (f"{{body: {f.end_effector}}}" if f.end_effector_is_body
          else f"{{frame: {f.end_effector}}}")
    task = "[" + ", ".join(f'"{c}"' if ":" in c else c for c in f.task) + "]"
    return f"""# Written by `aerial-drake robot init` from {f.model}; field by field:
# docs/robots.md. Every number below is computed from the model; the comments say how.
name: {f.name}
description: >-
  {f.name}: {len(f.arm_joints)}-joint arm on the vehicle '{f.vehicle_body}', {f.mass:.4g} kg in
  all; task {list(f.task)}.
models: [{f.model}]
vehicle_body: {f.vehicle_body}
thrust_axis: [0.0, 0.0, 1.0]
# The chain of actuated joints from the vehicle to the end effector.
arm_joints: [{", ".join(f.arm_joints)}]
end_effector: {ee}
task: {task}
limits:
  # [0, {f.thrust_to_weight:g} x the robot's weight ({f.mass:.4g} kg x 9.81 m/s^2): the stated
  # thrust-to-weight ratio (--thrust-to-weight).
  thrust: {_list(f.thrust)}
  # {f.body_torque_note}
  body_torque: {_list(f.body_torque)}
  # The model's effort limits.
  joint_effort: {_list(f.joint_effort)}
# {f.posture_note}
nominal_posture: {_list(f.nominal_posture, 8)}
reflected_inertia: []
# {f.workspace_note}
workspace_radius: {f.workspace_radius:.3g}
variants: []
"""


@dataclass(frozen=True)
class HoverFile:
    name: str
    robot_file: str  # the description, relative to the scenario's folder
    gains: Gains
    gains_note: str
    com_offset: np.ndarray  # r_o of (33), World = heading frame at heading 0 (m)
    ee_position: np.ndarray  # World (m)
    ee_quaternion: np.ndarray  # [w, x, y, z]


def hover_text(h: HoverFile) -> str:
    g = h.gains
    return f"""# Written by `aerial-drake robot init`: the robot holding its nominal posture in
# hover, started off it by 1 cm and 10 mrad. Runs as written: aerial-drake run {h.name}.yaml
name: {h.name}
description: >-
  Hover at the nominal posture from a small start offset: the gains and limits robot init
  computed (docs/robots.md, "robot init").
robot: {h.robot_file}
duration: {HOVER_DURATION}
controller_period: {CONTROLLER_PERIOD}
log_period: {CONTROLLER_PERIOD}
simulator:
  integration_scheme: runge_kutta3
  max_step_size: {CONTROLLER_PERIOD}
  accuracy: 1.0e-6
  use_error_control: false
  target_realtime_rate: 0.0
# {h.gains_note}
gains:
  K_x: {_list(g.K_x)}
  D_x: {_list(g.D_x)}
  k_R: {g.k_R:.6g}
  k_w: {g.k_w:.6g}
  Lambda2_bar: {_list(g.Lambda2_bar)}
  K_y: {_list(g.K_y)}
  K_z: {_list(g.K_z)}
trajectory:
  kind: hover
  # r_o of (33): the system's CoM minus the end effector at the nominal posture, in the
  # heading frame (what kind: waypoints with com: offset and the paper kind add to p_ed).
  com_offset: {_list(h.com_offset, 10)}
  hover:
    # The end effector where the nominal posture puts it with the CoM at {list(HOVER_COM)}.
    ee_position: {_list(h.ee_position, 10)}
    ee_orientation: {{quaternion: {_list(h.ee_quaternion, 9)}}}
    heading: 0.0
    com: {_list(HOVER_COM)}
initial:
  base_position_offset: {_list(START_POSITION_OFFSET)}
  base_rpy_offset: {_list(START_RPY_OFFSET)}
actuation:
  lag_rise_time: 0.0
  saturate: true
disturbances: []
"""


#: The pick-and-place cycle ``robot init`` writes: (time s, end-effector displacement from its
#: hover position m (World), heading rad), the shipped pick_and_place's shape: approach,
#: descend, hold (grasp), lift, move while turning a quarter turn, descend, hold (release),
#: lift. The vehicle carries the arm (the CoM follows at r_o, (33)): the distances are the
#: vehicle's, not the arm's reach.
PICK_AND_PLACE = ((0.0, (0.0, 0.0, 0.0), 0.0), (2.0, (0.3, 0.3, -0.1), 0.0),
                  (3.5, (0.3, 0.3, -0.4), 0.0), (5.0, (0.3, 0.3, -0.4), 0.0),
                  (6.5, (0.3, 0.3, -0.1), 0.0), (9.5, (-0.2, 0.9, -0.1), math.pi / 2),
                  (11.0, (-0.2, 0.9, -0.4), math.pi / 2), (12.5, (-0.2, 0.9, -0.4), math.pi / 2),
                  (14.0, (-0.2, 0.9, -0.1), math.pi / 2))
PICK_AND_PLACE_DURATION = 15.0


def _quaternion_times_z(q: np.ndarray, angle: float) -> np.ndarray:
    """The quaternion of R_z(angle) R(q), [w, x, y, z]."""
    c, s = math.cos(angle / 2), math.sin(angle / 2)
    w, x, y, z = q
    return np.array([c * w - s * z, c * x - s * y, c * y + s * x, c * z + s * w])


def pick_and_place_text(h: HoverFile, hover_text_: str) -> str:
    """The hover scenario's file with its trajectory replaced by :data:`PICK_AND_PLACE` from
    the hover's end-effector pose, the tool turning with the heading."""
    head, _, rest = hover_text_.partition("trajectory:\n")
    _, _, tail = rest.partition("initial:\n")
    head = head.replace(f"name: {h.name}", f"name: {h.name.removesuffix('_hover')}"
                        "_pick_and_place").replace(
        f"duration: {HOVER_DURATION}", f"duration: {PICK_AND_PLACE_DURATION}")
    head = head.replace("""description: >-
  Hover at the nominal posture from a small start offset: the gains and limits robot init
  computed (docs/robots.md, "robot init").""", """description: >-
  Pick and place (waypoints, rest to rest): approach, descend, hold, lift, move with a
  quarter turn, descend, hold, lift; the gains and limits robot init computed.""")
    lines = []
    for time, move, heading in PICK_AND_PLACE:
        p = np.asarray(h.ee_position) + move
        q = _quaternion_times_z(np.asarray(h.ee_quaternion), heading)
        lines.append(f"      - {{time: {time:g}, ee_position: {_list(p, 10)}, ee_orientation: "
                     f"{{quaternion: {_list(q, 9)}}}, heading: {heading:.10g}}}")
    trajectory = f"""trajectory:
  kind: waypoints
  # r_o of (33): the CoM follows the end effector at this offset, turned with the heading.
  com_offset: {_list(h.com_offset, 10)}
  waypoints:
    com: offset
    heading: given
    points:
{chr(10).join(lines)}
"""
    return head + trajectory + "initial:\n" + tail
