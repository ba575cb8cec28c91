"""The aerial manipulator as a Drake MultibodyPlant: a helicopter with a KUKA LWR 4+ under it.

Two variants of the helicopter (``PLANT_VARIANTS``):

- ``"rigid"``: one rigid body with Table I's mass and inertia (``helicopter.sdf``); the model
  the controllers use, and the nominal simulation.
- ``"rotors"``: the same composite, split into a fuselage and two spinning rotors on revolute
  joints (``helicopter_rotors.sdf``); the "disturbed" simulation plant of Section IV.

The arm and its weld under the helicopter come from ``arm_mount.dmd.yaml`` for both variants,
and that file also holds the nominal hover posture (the arm's default joint positions).
The modelling choices and their numbers are in ``docs/models.md``.

Coordinate order (Drake's, checked by ``tests/robots/test_models.py``):

- ``"rigid"``: q = [base (7: qw qx qy qz x y z, or 6: roll pitch yaw x y z), arm (7)],
  v = [w_WB (3, in World), v_WBo (3, in World), arm (7)].
- ``"rotors"``: Drake puts the rotor joints (children of the helicopter body) before the arm:
  q = [base, rotor_left, rotor_right, arm], v = [w_WB, v_WBo, rotor_left, rotor_right, arm], and
  the actuators are ordered [rotor_left, rotor_right, arm 1..7]. Use the index properties
  (``arm_velocity_indices``, ``rigid_state_indices``, ...) or the per-model-instance ports
  rather than hard-coded offsets.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from pydrake.geometry import Box, Capsule, Cylinder, Role, SceneGraph, Shape, Sphere
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.parsing import LoadModelDirectives, Parser, ProcessModelDirectives
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, MultibodyPlant
from pydrake.multibody.tree import (
    Frame,
    Joint,
    JointActuator,
    ModelInstanceIndex,
    RevoluteJoint,
    RigidBody,
    RpyFloatingJoint,
)
from pydrake.systems.framework import Context, DiagramBuilder

from aerial_drake.robots.resources import model_directory

PLANT_VARIANTS = ("rigid", "rotors")
FLOATING_BASES = ("quaternion", "rpy")

#: The ROS-style package that ``package://aerial_drake/...`` URLs resolve in.
PACKAGE_NAME = "aerial_drake"
HELICOPTER_FILES = {"rigid": "helicopter.sdf", "rotors": "helicopter_rotors.sdf"}
ARM_MOUNT_FILE = "arm_mount.dmd.yaml"
ARM_MODEL_NAME = "lwr"
HELICOPTER_MODEL_NAME = "helicopter"

#: Spin directions of the rotors (left, right) about their joints' axes: counter-rotating, so
#: the spin axes' vertical components of angular momentum cancel and the outward mast tilt
#: leaves 2 (0.12)(26 pi) sin(12.5 deg) = 4.24 N m s along +y of the body at Table I's speed
#: (the speed itself is the scenario's ``rotors.speed``).
ROTOR_DIRECTIONS = (1.0, -1.0)


def _check_choice(what: str, value: str, options: tuple[str, ...]) -> None:
    if value not in options:
        raise ValueError(f"Unknown {what} '{value}'. Valid options are: {', '.join(options)}")


@dataclass(frozen=True)
class AerialManipulator:
    """Handles to the aerial manipulator's parts inside ``plant``.

    The index properties need a finalized plant (``add_aerial_manipulator(finalize=False)``
    returns before Drake assigns coordinates).
    """

    plant: MultibodyPlant
    scene_graph: SceneGraph | None
    helicopter: ModelInstanceIndex
    arm: ModelInstanceIndex
    #: The "helicopter" body; its frame B is at the helicopter's centre of mass (for
    #: "rotors", at the composite fuselage + rotors centre of mass), x forward, z up (thrust).
    base_body: RigidBody
    #: Frame E on the flange of lwr_link_7, aligned with B at the nominal posture.
    end_effector_frame: Frame
    end_effector_body: RigidBody
    arm_joints: tuple[RevoluteJoint, ...]
    arm_actuators: tuple[JointActuator, ...]
    rotor_joints: tuple[RevoluteJoint, ...]
    rotor_actuators: tuple[JointActuator, ...]
    variant: str
    floating_base: str

    # --- Coordinates -------------------------------------------------------------------
    @property
    def base_joint(self) -> Joint:
        """The floating joint between World and the helicopter (finalized plant only)."""
        for index in self.plant.GetJointIndices(self.helicopter):
            joint = self.plant.get_joint(index)
            if joint.child_body().index() == self.base_body.index() and joint.num_velocities() == 6:
                return joint
        raise RuntimeError("The helicopter has no floating joint yet: finalize the plant first.")

    @property
    def arm_position_indices(self) -> np.ndarray:
        """Indices of q1..q7 in the plant's q."""
        return np.array([j.position_start() for j in self.arm_joints])

    @property
    def arm_velocity_indices(self) -> np.ndarray:
        """Indices of q1_dot..q7_dot in the plant's v."""
        return np.array([j.velocity_start() for j in self.arm_joints])

    @property
    def rotor_position_indices(self) -> np.ndarray:
        """Indices of the rotor angles (left, right) in q; empty for "rigid"."""
        return np.array([j.position_start() for j in self.rotor_joints], dtype=int)

    @property
    def rotor_velocity_indices(self) -> np.ndarray:
        """Indices of the rotor speeds (left, right) in v; empty for "rigid"."""
        return np.array([j.velocity_start() for j in self.rotor_joints], dtype=int)

    @property
    def base_position_indices(self) -> np.ndarray:
        """Indices of the base coordinates in q (7 for a quaternion base, 6 for rpy)."""
        joint = self.base_joint
        return np.arange(joint.position_start(), joint.position_start() + joint.num_positions())

    @property
    def base_velocity_indices(self) -> np.ndarray:
        """Indices of [w_WB; v_WBo] in v (always 0..5)."""
        joint = self.base_joint
        return np.arange(joint.velocity_start(), joint.velocity_start() + 6)

    @property
    def rigid_state_indices(self) -> np.ndarray:
        """Indices into this plant's state x = [q; v] that give the "rigid" plant's state.

        The result is [q_base, q_arm, v_base, v_arm] (rotors dropped), the state of the
        controller's model built with the same ``floating_base``; for "rigid" it is 0..nx-1.
        """
        nq = self.plant.num_positions()
        return np.concatenate([
            self.base_position_indices,
            self.arm_position_indices,
            nq + self.base_velocity_indices,
            nq + self.arm_velocity_indices,
        ])

    # --- Properties of the model -------------------------------------------------------
    def total_mass(self) -> float:
        """Default mass of the helicopter's and the arm's bodies [kg] (54.8 kg)."""
        plant = self.plant
        indices = plant.GetBodyIndices(self.helicopter) + plant.GetBodyIndices(self.arm)
        return float(sum(plant.get_body(i).default_mass() for i in indices))

    def arm_effort_limits(self) -> np.ndarray:
        """Torque limits of the arm's actuators [N m] (Table I)."""
        return np.array([a.effort_limit() for a in self.arm_actuators])

    def arm_position_limits(self) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) joint limits of the arm [rad]."""
        lower = np.array([j.position_lower_limit() for j in self.arm_joints])
        upper = np.array([j.position_upper_limit() for j in self.arm_joints])
        return lower, upper

    def arm_velocity_limits(self) -> np.ndarray:
        """Joint speed limits of the arm [rad/s] (magnitude, symmetric)."""
        return np.array([j.velocity_upper_limit() for j in self.arm_joints])

    def q_nominal_arm(self) -> np.ndarray:
        """The nominal hover posture of the arm [rad]: its default positions in this plant."""
        return np.array([j.get_default_angle() for j in self.arm_joints])


def make_parser(plant: MultibodyPlant) -> Parser:
    """A Parser for ``plant`` that knows only the ``aerial_drake`` package.

    Drake's default package map includes ``drake_models``, which downloads on first use; our
    models need nothing but our own files, so every other package is removed and a stray
    ``package://`` URL fails at once instead of reaching for the network.
    """
    parser = Parser(plant)
    package_map = parser.package_map()
    for name in package_map.GetPackageNames():
        package_map.Remove(name)
    package_map.AddPackageXml(str(model_directory() / "package.xml"))
    return parser


def nominal_arm_posture() -> np.ndarray:
    """q_nominal [rad], the arm's nominal hover posture, read from ``arm_mount.dmd.yaml``."""
    directives = LoadModelDirectives(str(model_directory() / ARM_MOUNT_FILE))
    for directive in directives.directives:
        model = directive.add_model
        if model is not None and model.name == ARM_MODEL_NAME:
            positions = model.default_joint_positions
            return np.array([positions[f"lwr_joint_{i}"][0] for i in range(1, 8)])
    raise RuntimeError(f"{ARM_MOUNT_FILE} adds no model named '{ARM_MODEL_NAME}'.")


def add_aerial_manipulator(
    plant: MultibodyPlant,
    variant: str = "rigid",
    *,
    floating_base: str = "quaternion",
    finalize: bool = True,
    scene_graph: SceneGraph | None = None,
) -> AerialManipulator:
    """Parses the helicopter (``variant``) and the arm into ``plant``.

    Args:
        plant: an unfinalized plant, registered with a SceneGraph (visual geometry is then
            added) or not.
        variant: one of ``PLANT_VARIANTS``.
        floating_base: "quaternion" leaves the helicopter a free body (Drake's
            QuaternionFloatingJoint); "rpy" adds an RpyFloatingJoint named "base" from World,
            whose q = [roll, pitch, yaw, p_WB] linearises without a unit-norm constraint.
            Both have v = [w_WB (World), v_WBo (World)].
        finalize: finalize the plant (the index properties need it).
        scene_graph: stored on the result for convenience; the plant's own registration
            decides whether geometry is added.
    """
    _check_choice("variant", variant, PLANT_VARIANTS)
    _check_choice("floating_base", floating_base, FLOATING_BASES)
    folder = model_directory()
    parser = make_parser(plant)
    (helicopter,) = parser.AddModels(str(folder / HELICOPTER_FILES[variant]))
    ProcessModelDirectives(LoadModelDirectives(str(folder / ARM_MOUNT_FILE)), plant, parser)
    arm = plant.GetModelInstanceByName(ARM_MODEL_NAME)
    base_body = plant.GetBodyByName(HELICOPTER_MODEL_NAME, helicopter)
    if floating_base == "rpy":
        # Must precede Finalize, which would otherwise give the body a quaternion joint.
        plant.AddJoint(RpyFloatingJoint("base", plant.world_frame(), base_body.body_frame()))
    if finalize:
        plant.Finalize()

    arm_joints = tuple(plant.GetJointByName(f"lwr_joint_{i}", arm) for i in range(1, 8))
    rotor_joints = tuple(
        plant.GetJointByName(f"rotor_{side}_joint", helicopter)
        for side in ("left", "right")
        if variant == "rotors"
    )
    return AerialManipulator(
        plant=plant,
        scene_graph=scene_graph,
        helicopter=helicopter,
        arm=arm,
        base_body=base_body,
        end_effector_frame=plant.GetFrameByName("end_effector", arm),
        end_effector_body=plant.GetBodyByName("lwr_link_7", arm),
        arm_joints=arm_joints,
        arm_actuators=tuple(plant.GetJointActuatorByName(j.name(), arm) for j in arm_joints),
        rotor_joints=rotor_joints,
        rotor_actuators=tuple(
            plant.GetJointActuatorByName(j.name(), helicopter) for j in rotor_joints
        ),
        variant=variant,
        floating_base=floating_base,
    )


def make_plant(
    variant: str = "rigid", *, floating_base: str = "quaternion", time_step: float = 0.0
) -> AerialManipulator:
    """A standalone finalized plant without SceneGraph (e.g. a controller's internal model)."""
    plant = MultibodyPlant(time_step)
    return add_aerial_manipulator(plant, variant, floating_base=floating_base)


def nominal_end_effector_offset(model: AerialManipulator) -> np.ndarray:
    """p_GE in B [m]: the end effector's position (frame E's origin) minus the system's centre
    of mass, in the helicopter frame B, at the plant's default positions (the helicopter level
    and the arm at q_nominal, as ``make_plant()`` builds it): about (0.3, 0, -0.6) m."""
    plant = model.plant
    ctx = plant.CreateDefaultContext()
    X_WB = plant.EvalBodyPoseInWorld(ctx, model.base_body)
    return X_WB.rotation().inverse() @ (
        model.end_effector_frame.CalcPoseInWorld(ctx).translation()
        - plant.CalcCenterOfMassPositionInWorld(ctx))


def add_to_builder(
    builder: DiagramBuilder,
    variant: str = "rigid",
    *,
    time_step: float = 0.0,
    floating_base: str = "quaternion",
) -> AerialManipulator:
    """Adds a plant and SceneGraph (``AddMultibodyPlantSceneGraph``) holding the finalized
    aerial manipulator to ``builder``."""
    _check_choice("variant", variant, PLANT_VARIANTS)
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step)
    return add_aerial_manipulator(
        plant, variant, floating_base=floating_base, scene_graph=scene_graph
    )


@dataclass(frozen=True)
class HelicopterExtent:
    """A vertical cylinder about the system's centre of mass G that holds the helicopter's
    illustration geometry at the nominal posture (helicopter level, arm at q_nominal) [m]."""

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
    raise TypeError(f"helicopter_extent: no bounding points for a {type(shape).__name__}")


@functools.lru_cache(maxsize=None)
def helicopter_extent(variant: str = "rigid") -> HelicopterExtent:
    """The :class:`HelicopterExtent` of ``variant``, from the shapes and poses of the
    helicopter bodies' illustration geometry (SceneGraph's model inspector) at the plant's
    default positions (rotor angles 0). For the shipped models about: radius 1.39 m (the rotor
    discs, 1.27 m in radius about hubs 0.15 m off the centre line, tilted 12.5 deg outward),
    top 0.64 m (their outer rims), bottom 0.41 m (the skids)."""
    builder = DiagramBuilder()
    model = add_to_builder(builder, variant)
    assert model.scene_graph is not None  # add_to_builder registers the plant with one
    plant, inspector = model.plant, model.scene_graph.model_inspector()
    ctx = plant.CreateDefaultContext()
    X_BW = plant.EvalBodyPoseInWorld(ctx, model.base_body).inverse()
    p_BG = X_BW @ plant.CalcCenterOfMassPositionInWorld(ctx)
    points = []
    for index in plant.GetBodyIndices(model.helicopter):
        X_BA = X_BW @ plant.EvalBodyPoseInWorld(ctx, plant.get_body(index))
        frame = plant.GetBodyFrameIdOrThrow(index)
        for geometry in inspector.GetGeometries(frame, Role.kIllustration):
            X_BS = X_BA @ inspector.GetPoseInFrame(geometry)
            points.append(X_BS.multiply(_shape_points(inspector.GetShape(geometry)).T).T)
    p_GP = np.vstack(points) - p_BG
    return HelicopterExtent(radius=float(np.linalg.norm(p_GP[:, :2], axis=1).max()),
                            top=float(p_GP[:, 2].max()), bottom=float(-p_GP[:, 2].min()))


def set_nominal_posture(
    manip: AerialManipulator,
    context: Context,
    p_WB: tuple[float, float, float] | np.ndarray = (0.0, 0.0, 0.0),
    yaw: float = 0.0,
) -> None:
    """Sets the helicopter level at ``p_WB`` with heading ``yaw`` [rad] and the arm at
    q_nominal; rotor angles and all velocities are left as they are.

    ``context`` is the plant's context or the root context of a diagram holding the plant.
    """
    plant = manip.plant
    try:
        plant.ValidateContext(context)
        plant_context = context
    except RuntimeError:
        plant_context = plant.GetMyMutableContextFromRoot(context)
    X_WB = RigidTransform(RotationMatrix.MakeZRotation(yaw), np.asarray(p_WB, dtype=float))
    manip.base_joint.SetPose(plant_context, X_WB)
    for joint, angle in zip(manip.arm_joints, manip.q_nominal_arm()):
        joint.set_angle(plant_context, angle)
