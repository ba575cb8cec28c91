"""The vehicle's size for the camera: a vertical cylinder about the system's centre of mass that
holds the illustration geometry of the vehicle and its rotors (Meshcat framing)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydrake.geometry import Box, Capsule, Cylinder, Role, Shape, Sphere
from pydrake.systems.framework import DiagramBuilder

from aerial_drake.robots.description import RIGID_VARIANT, RobotDescription, default_robot
from aerial_drake.robots.models import add_to_builder, set_nominal_posture


@dataclass(frozen=True)
class VehicleExtent:
    """A vertical cylinder about the system's centre of mass G that holds the vehicle's
    illustration geometry at the nominal posture (vehicle level, arm at q_nominal) [m]."""

    radius: float  # largest horizontal distance from the vertical through G
    top: float  # highest point above G (the outer rims of the tilted rotor discs)
    bottom: float  # lowest point below G (the skids), positive


def _shape_points(shape: Shape, n: int = 72) -> np.ndarray:
    """Points (N, 3) in the shape's frame whose convex hull holds ``shape``: the corners of a
    box; two rims of ``n`` points of a cylinder (of a capsule or sphere: of the cylinder about
    it, which bounds it)."""
    if isinstance(shape, Box):
        signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
        return signs * (shape.size() / 2)
    if isinstance(shape, (Cylinder, Capsule, Sphere)):
        r = shape.radius()
        half = 0.0 if isinstance(shape, Sphere) else shape.length() / 2
        if not isinstance(shape, Cylinder):
            half += r
        a = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
        rim = np.column_stack([r * np.cos(a), r * np.sin(a), np.zeros(n)])
        return np.vstack([rim - [0.0, 0.0, half], rim + [0.0, 0.0, half]])
    raise TypeError(f"vehicle_extent: no bounding points for a {type(shape).__name__}")


def vehicle_extent(variant: str = RIGID_VARIANT, robot: RobotDescription | None = None
                   ) -> VehicleExtent:
    """The :class:`VehicleExtent` of ``robot``'s plant ``variant``, from the shapes and poses
    of the illustration geometry of the vehicle body and the bodies on its rotor joints
    (SceneGraph's model inspector) at the nominal posture. For the paper's helicopter about:
    radius 1.39 m (the rotor discs, 1.27 m in radius about hubs 0.15 m off the centre line,
    tilted 12.5 deg outward), top 0.64 m (their outer rims), bottom 0.41 m (the skids)."""
    robot = robot if robot is not None else default_robot()
    key = (str(robot.source), repr(robot), variant)
    if key not in _EXTENTS:
        _EXTENTS[key] = _compute_vehicle_extent(variant, robot)
    return _EXTENTS[key]


_EXTENTS: dict[tuple[str, str, str], VehicleExtent] = {}


def _compute_vehicle_extent(variant: str, robot: RobotDescription) -> VehicleExtent:
    builder = DiagramBuilder()
    model = add_to_builder(builder, variant, robot=robot)
    assert model.scene_graph is not None  # add_to_builder registers the plant with one
    plant, inspector = model.plant, model.scene_graph.model_inspector()
    ctx = plant.CreateDefaultContext()
    set_nominal_posture(model, ctx)
    X_BW = plant.EvalBodyPoseInWorld(ctx, model.base_body).inverse()
    p_BG = X_BW @ plant.CalcCenterOfMassPositionInWorld(ctx)
    bodies = [model.base_body.index()] + [j.child_body().index() for j in model.rotor_joints]
    points = []
    for index in bodies:
        X_BA = X_BW @ plant.EvalBodyPoseInWorld(ctx, plant.get_body(index))
        frame = plant.GetBodyFrameIdOrThrow(index)
        for geometry in inspector.GetGeometries(frame, Role.kIllustration):
            X_BS = X_BA @ inspector.GetPoseInFrame(geometry)
            points.append(X_BS.multiply(_shape_points(inspector.GetShape(geometry)).T).T)
    if not points:  # no illustration geometry: a point at the vehicle's frame
        points.append(np.zeros((1, 3)))
    p_GP = np.vstack(points) - p_BG
    return VehicleExtent(radius=float(np.linalg.norm(p_GP[:, :2], axis=1).max()),
                         top=float(p_GP[:, 2].max()), bottom=float(-p_GP[:, 2].min()))
