"""The input limits ``robot init`` writes (docs/robots.md, "robot init", "Limits"):

- **thrust** ``[0, r m g]``: ``r`` the thrust-to-weight ratio the user states
  (``--thrust-to-weight``; a model file has no thrust figure), ``m`` the whole robot's mass;
- **body torque** (when not given): a multirotor's differential thrust at the vehicle's
  radius ``R``, ``tau_x = tau_y =`` :data:`ROLL_PITCH_SHARE` ``T_max R`` (a quarter of the
  thrust shifted across the vehicle: the rest stays for lift), and ``tau_z =``
  :data:`YAW_SHARE` ``tau_x`` (yaw comes from rotor drag, about a tenth of the thrust's
  lever). ``R`` is the vehicle's largest horizontal extent from its frame in its collision or
  visual geometry, else (no geometry) that of a uniform disc with the vehicle's mass and yaw
  inertia, ``sqrt(2 I_zz / m_v)``. The shipped quadrotor's published figures (513 N,
  90/90/12 N m, docs/models.md) give the same order: 0.25 x 513 N x 0.7 m = 90 N m;
- **joint effort**: the model's effort limits (a joint without one is refused: the law's
  saturation and ``robot check``'s wrench margins need them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from pydrake.geometry import Box, Capsule, Cylinder, Mesh, Sphere
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.systems.framework import DiagramBuilder

from aerial_drake.analysis.onboarding.errors import OnboardingError
from aerial_drake.robots.description import RobotDescription
from aerial_drake.robots.models import AerialManipulator, add_aerial_manipulator

ROLL_PITCH_SHARE = 0.25
YAW_SHARE = 0.1
GRAVITY = 9.81


@dataclass(frozen=True)
class InputLimits:
    thrust: tuple[float, float]  # N
    body_torque: tuple[float, float, float]  # N m
    joint_effort: tuple[float, ...]  # N m, arm order
    vehicle_radius: float  # m (R of the module docstring)
    radius_source: str  # "geometry" or "inertia"
    body_torque_source: str  # "given" or "rule"


def _shape_radius(shape, X_BG) -> float:
    """The largest horizontal distance from the body frame's z axis of ``shape`` posed at
    ``X_BG`` (a bound: the shape's bounding sphere about its centre)."""
    if isinstance(shape, Box):
        r = float(np.linalg.norm(shape.size()) / 2)
    elif isinstance(shape, (Cylinder, Capsule)):
        r = math.hypot(shape.radius(), shape.length() / 2) + (
            shape.radius() if isinstance(shape, Capsule) else 0.0)
    elif isinstance(shape, Sphere):
        r = shape.radius()
    else:  # a mesh: its size is not known here without loading it
        return 0.0
    return float(np.linalg.norm(X_BG.translation()[:2]) + r)


def vehicle_radius(robot: RobotDescription) -> tuple[float, str]:
    """R of the module docstring and where it came from."""
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, 0.0)
    manip = add_aerial_manipulator(plant, robot=robot, scene_graph=scene_graph)
    inspector = scene_graph.model_inspector()
    body = manip.base_body
    radius = 0.0
    for geometry in plant.GetCollisionGeometriesForBody(body) + plant.GetVisualGeometriesForBody(
            body):
        shape = inspector.GetShape(geometry)
        if not isinstance(shape, Mesh):
            radius = max(radius, _shape_radius(shape, inspector.GetPoseInFrame(geometry)))
    if radius > 0:
        return radius, "geometry"
    I_zz = body.default_rotational_inertia().get_moments()[2]
    return math.sqrt(2.0 * I_zz / body.default_mass()), "inertia"


def input_limits(manip: AerialManipulator, robot: RobotDescription, thrust_to_weight: float,
                 body_torque: list[float] | None) -> InputLimits:
    """The limits of the module docstring for ``manip`` (built from ``robot``)."""
    if not (math.isfinite(thrust_to_weight) and thrust_to_weight > 1.0):
        raise OnboardingError(f"--thrust-to-weight {thrust_to_weight}: must be a number > 1 "
                              "(the vehicle must lift the robot; 1.5-2.5 is common)",
                              "--thrust-to-weight")
    t_max = thrust_to_weight * manip.total_mass() * GRAVITY
    radius, source = vehicle_radius(robot)
    if body_torque is not None:
        if len(body_torque) != 3 or not all(math.isfinite(x) and x > 0 for x in body_torque):
            raise OnboardingError(f"--body-torque {body_torque}: give 3 positive bounds (N m)",
                                  "--body-torque")
        torque = (float(body_torque[0]), float(body_torque[1]), float(body_torque[2]))
    else:
        xy = ROLL_PITCH_SHARE * t_max * radius
        torque = (xy, xy, YAW_SHARE * xy)
    efforts = [a.effort_limit() for a in manip.arm_actuators]
    for joint, effort in zip(manip.arm_joints, efforts):
        if not (math.isfinite(effort) and effort > 0):
            raise OnboardingError(
                f"the arm joint '{joint.name()}' has no effort limit in the model ({effort}): "
                "write one (URDF <limit effort=...>, SDF <effort>) from the actuator's data "
                "sheet", "model")
    return InputLimits(thrust=(0.0, t_max), body_torque=torque, joint_effort=tuple(efforts),
                       vehicle_radius=radius, radius_source=source,
                       body_torque_source="given" if body_torque is not None else "rule")
