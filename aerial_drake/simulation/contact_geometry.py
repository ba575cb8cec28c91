"""The environment's surfaces and the robot's tool as the checks before a contact run see them
(:mod:`aerial_drake.simulation.contact_checks`; docs/contact.md, "Checks before the run").

:class:`Surfaces` reads the simulated plant's SceneGraph: the tool is the end-effector body's
collision geometry, the surfaces are the environment models' collision geometries (the
robot's other links are never a surface). Nothing is simulated: a SceneGraph context of its
own, with the plant's default poses (a welded model where the directives put it, a free one
at its default pose), answers the queries.

- :meth:`Surfaces.trace`: how far a sphere travels along a direction before it touches a
  surface, by sphere tracing on Drake's signed distance to a point
  (``QueryObject.ComputeSignedDistanceToPoint``, every shape in double): at a point whose
  distance to the nearest surface is ``phi``, a sphere of radius ``r`` can move ``phi - r``
  in any direction without touching, so the march never steps through a surface and ends
  on the first one it meets.
- :meth:`Surfaces.point_contact`: whether Drake models that touch as point contact (the
  plant's ``contact_model``; with ``hydroelastic_with_fallback`` the pair's own
  representation decides): asked of SceneGraph itself, with the tool placed 1 mm into the
  surface.
- :func:`point_stiffness`: a geometry's ``drake:point_contact_stiffness``; one without it
  gets SceneGraph's default (``SceneGraphConfig.default_proximity_properties.
  point_stiffness``, 1e6 N/m in Drake 1.51 and later; the context's properties carry it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from pydrake.geometry import (
    Box,
    Capsule,
    Cylinder,
    Ellipsoid,
    FramePoseVector,
    GeometryId,
    Sphere,
)
from pydrake.math import RigidTransform

from aerial_drake.robots.models import AerialManipulator

#: A sphere this close to a surface (m) touches it (sphere tracing's stop).
TOUCH = 1e-6
#: The most sphere-tracing steps (a ray grazing a surface advances slowly; a hit straight
#: ahead takes one or two steps).
MAX_STEPS = 400
#: How far into the surface (m) the tool is put to ask SceneGraph which contact model the
#: pair gets.
PROBE_DEPTH = 1e-3


@dataclass(frozen=True)
class Tool:
    """One collision geometry of the end-effector body, as a sphere: ``p_BC`` its centre in
    the body's frame (m), ``radius`` the sphere's (a sphere's own; for another shape, the
    sphere about its frame's origin that bounds it), ``stiffness`` its point contact
    stiffness (N/m)."""

    geometry: GeometryId
    name: str
    p_BC: np.ndarray
    radius: float
    stiffness: float


@dataclass(frozen=True)
class Hit:
    """The first surface a sphere meets along a direction: ``distance`` it travels first (m;
    0 if it already touches; inf if none within the search distance), the surface's
    geometry, name and point contact stiffness (N/m), and ``depth``, how far the sphere
    already reaches into it where it starts (m; 0 if it does not)."""

    distance: float
    geometry: GeometryId | None = None
    name: str = ""
    stiffness: float = math.nan
    depth: float = 0.0

    @property
    def found(self) -> bool:
        return self.geometry is not None


def bounding_radius(shape) -> float:
    """The radius of the sphere about the shape's frame origin that holds ``shape`` (m); 0
    for a shape with no closed form here (a mesh: the check then sees its frame's origin)."""
    if isinstance(shape, Sphere):
        return shape.radius()
    if isinstance(shape, Box):
        return 0.5 * float(np.linalg.norm([shape.width(), shape.depth(), shape.height()]))
    if isinstance(shape, Capsule):
        return shape.radius() + 0.5 * shape.length()
    if isinstance(shape, Cylinder):
        return math.hypot(shape.radius(), 0.5 * shape.length())
    if isinstance(shape, Ellipsoid):
        return max(shape.a(), shape.b(), shape.c())
    return 0.0


def point_stiffness(inspector, geometry: GeometryId, default: float) -> float:
    """``geometry``'s ``drake:point_contact_stiffness`` (N/m), else ``default``."""
    props = inspector.GetProximityProperties(geometry)
    if props is None:
        return default
    return float(props.GetPropertyOrDefault("material", "point_contact_stiffness", default))


class Surfaces:
    """The tool and the environment's surfaces of the simulated plant ``sim`` (module
    docstring). ``tools``: the end-effector body's collision geometries; ``environment``:
    the environment models' collision geometries; ``unmeasured``: the names of those Drake's
    signed distance to a point does not answer for (a mesh other than OBJ or VTK): the
    traces cannot see them."""

    def __init__(self, sim: AerialManipulator) -> None:
        assert sim.scene_graph is not None  # the simulated plant is registered with one
        self.sim = sim
        plant, scene_graph = sim.plant, sim.scene_graph
        self._scene_graph = scene_graph
        self._context = scene_graph.CreateDefaultContext()
        self._pose_port = scene_graph.get_source_pose_port(plant.get_source_id())
        plant_context = plant.CreateDefaultContext()
        self._poses = plant.get_geometry_pose_output_port().Eval(plant_context)
        self._pose_port.FixValue(self._context, self._poses)
        query = self._query()
        inspector = query.inspector()  # the context's: SceneGraph's defaults filled in
        self.inspector = inspector
        self.default_stiffness = float(
            scene_graph.get_config().default_proximity_properties.point_stiffness)
        self.environment = tuple(
            g for instance in sim.environment for b in plant.GetBodyIndices(instance)
            for g in plant.GetCollisionGeometriesForBody(plant.get_body(b)))
        self.tools = tuple(self._tool(g) for g in
                           plant.GetCollisionGeometriesForBody(sim.end_effector_body))
        measured = {r.id_G for r in query.ComputeSignedDistanceToPoint(np.zeros(3))}
        self.unmeasured = tuple(inspector.GetName(g) for g in self.environment
                                if g not in measured)
        self._frame = plant.GetBodyFrameIdOrThrow(sim.end_effector_body.index())
        self._contact_model = plant.get_contact_model().name.lower()
        self._representation = plant.get_contact_surface_representation()

    def _query(self):
        return self._scene_graph.get_query_output_port().Eval(self._context)

    def _tool(self, geometry: GeometryId) -> Tool:
        inspector = self.inspector
        return Tool(geometry=geometry, name=inspector.GetName(geometry),
                    p_BC=np.array(inspector.GetPoseInFrame(geometry).translation()),
                    radius=bounding_radius(inspector.GetShape(geometry)),
                    stiffness=point_stiffness(inspector, geometry, self.default_stiffness))

    def nearest(self, p_WQ: np.ndarray, within: float = math.inf
                ) -> tuple[float, GeometryId | None]:
        """The signed distance (m) from the World point ``p_WQ`` to the nearest surface of
        the environment, and that surface's geometry; (inf, None) if none is ``within``."""
        wanted = set(self.environment)
        best, which = math.inf, None
        for r in self._query().ComputeSignedDistanceToPoint(p_WQ, within):
            if r.id_G in wanted and r.distance < best:
                best, which = float(r.distance), r.id_G
        return best, which

    def trace(self, p_WC: np.ndarray, direction: np.ndarray, radius: float,
              horizon: float) -> Hit:
        """The first surface a sphere of ``radius`` centred at ``p_WC`` meets moving along
        the unit ``direction`` (sphere tracing, module docstring); a miss within ``horizon``
        metres is ``Hit(inf)``."""
        s = 0.0
        for _ in range(MAX_STEPS):
            phi, geometry = self.nearest(p_WC + s * direction, horizon - s + radius)
            if geometry is None:
                break
            gap = phi - radius
            if gap <= TOUCH:
                return Hit(s, geometry, self.inspector.GetName(geometry),
                           point_stiffness(self.inspector, geometry, self.default_stiffness),
                           depth=max(-gap, 0.0) if s == 0.0 else 0.0)
            s += gap
            if s > horizon:
                break
        return Hit(math.inf)

    def point_contact(self, tool: Tool, X_WB: RigidTransform, direction: np.ndarray,
                      hit: Hit) -> bool:
        """Whether Drake models the touch ``hit`` of ``tool`` (its body at ``X_WB``, moving
        along ``direction``) as point contact: always with ``contact_model: point``; else as
        SceneGraph pairs the two geometries with the tool :data:`PROBE_DEPTH` into the
        surface (``hydroelastic_with_fallback``: point contact where the pair has no
        hydroelastic representation; ``hydroelastic``: never)."""
        if self._contact_model == "kpoint":
            return True
        if self._contact_model == "khydroelastic" or not hit.found:
            return False
        poses = FramePoseVector()
        for frame in self._poses.ids():
            poses.set_value(frame, self._poses.value(frame))
        poses.set_value(self._frame, RigidTransform(
            X_WB.rotation(), X_WB.translation() + (hit.distance + PROBE_DEPTH) * direction))
        self._pose_port.FixValue(self._context, poses)
        try:
            _, pairs = self._query().ComputeContactSurfacesWithFallback(self._representation)
        finally:
            self._pose_port.FixValue(self._context, self._poses)
        pair = {tool.geometry, hit.geometry}
        return any({p.id_A, p.id_B} == pair for p in pairs)
