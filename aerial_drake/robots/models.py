"""An aerial manipulator as a Drake MultibodyPlant, built from a robot description.

:func:`build_robot` parses a :class:`~aerial_drake.robots.description.RobotDescription`'s model
files into a plant and checks what the paper's law needs of it (the checks name the field to
change): a free vehicle body whose frame is at its centre of mass, every other body hanging
below it, the arm a serial chain of actuated revolute joints from the vehicle to the end
effector, and a task with as many coordinates as the arm has joints (no redundancy).

The shipped robots (``models/sdf/*.robot.yaml``):

- ``helicopter_lwr``, the paper's: a helicopter with a KUKA LWR 4+ under it, with the plant
  variants ``"rigid"`` (one rigid body with Table I's mass and inertia, ``helicopter.sdf``: the
  model the controllers use, and the nominal simulation) and ``"rotors"`` (the same composite
  split into a fuselage and two spinning rotors, ``helicopter_rotors.sdf``: the "disturbed"
  simulation plant of Section IV). The modelling choices are in ``docs/models.md``.

Coordinate order (Drake's): q = [base (7: qw qx qy qz x y z, or 6: roll pitch yaw x y z), ...],
v = [w_WB (3, World), v_WBo (3, World), ...]; joints on the vehicle (rotors) may come before the
arm's. Use the index properties (``arm_velocity_indices``, ``rigid_state_indices``, ...) or the
per-model-instance ports rather than offsets.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pydrake.geometry import Box, Capsule, Cylinder, Role, SceneGraph, Shape, Sphere
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
from pydrake.multibody.parsing import LoadModelDirectives, Parser, ProcessModelDirectives
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, MultibodyPlant
from pydrake.multibody.tree import (
    FixedOffsetFrame,
    Frame,
    Joint,
    JointActuator,
    ModelInstanceIndex,
    RevoluteJoint,
    RigidBody,
    RpyFloatingJoint,
)
from pydrake.systems.framework import Context, DiagramBuilder

from aerial_drake.robots.description import (
    RIGID_VARIANT,
    RobotDescription,
    RobotDescriptionError,
    default_robot,
)
from aerial_drake.robots.resources import model_directory
from aerial_drake.robots.task import TaskLayout, parse_task

FLOATING_BASES = ("quaternion", "rpy")

#: The ROS-style package that ``package://aerial_drake/...`` URLs resolve in.
PACKAGE_NAME = "aerial_drake"
#: Largest distance of the vehicle's centre of mass from its body frame's origin (m).
COM_OFFSET_TOLERANCE = 1e-9
#: The name of the end-effector frame added for a description's ``end_effector.body``.
END_EFFECTOR_FRAME = "aerial_drake_end_effector"


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
    #: The model instance of the vehicle body (which may hold the arm too, e.g. one URDF).
    vehicle: ModelInstanceIndex
    #: The vehicle's body; its frame B is at the vehicle's centre of mass (for a variant with
    #: rotor bodies, at the composite's), z along the thrust.
    base_body: RigidBody
    #: The task frame E on the arm.
    end_effector_frame: Frame
    end_effector_body: RigidBody
    arm_joints: tuple[RevoluteJoint, ...]
    arm_actuators: tuple[JointActuator, ...]
    rotor_joints: tuple[RevoluteJoint, ...]
    rotor_actuators: tuple[JointActuator, ...]
    #: Spin direction (+1 or -1) of each rotor joint.
    rotor_directions: tuple[float, ...]
    variant: str
    floating_base: str
    description: RobotDescription
    #: The task with its joints resolved (finalized plant only; None before).
    task: TaskLayout | None

    # --- Coordinates -------------------------------------------------------------------
    @property
    def n(self) -> int:
        """The arm's number of joints (= the task's dimension)."""
        return len(self.arm_joints)

    @property
    def base_joint(self) -> Joint:
        """The floating joint between World and the vehicle (finalized plant only)."""
        for index in self.plant.GetJointIndices(self.vehicle):
            joint = self.plant.get_joint(index)
            if joint.child_body().index() == self.base_body.index() and joint.num_velocities() == 6:
                return joint
        for index in self.plant.GetJointIndices():
            joint = self.plant.get_joint(index)
            if joint.child_body().index() == self.base_body.index() and joint.num_velocities() == 6:
                return joint
        raise RuntimeError("The vehicle has no floating joint yet: finalize the plant first.")

    @property
    def arm_position_indices(self) -> np.ndarray:
        """Indices of the arm's joint angles in the plant's q."""
        return np.array([j.position_start() for j in self.arm_joints], dtype=int)

    @property
    def arm_velocity_indices(self) -> np.ndarray:
        """Indices of the arm's joint speeds in the plant's v."""
        return np.array([j.velocity_start() for j in self.arm_joints], dtype=int)

    @property
    def rotor_position_indices(self) -> np.ndarray:
        """Indices of the rotor angles in q; empty without rotor joints."""
        return np.array([j.position_start() for j in self.rotor_joints], dtype=int)

    @property
    def rotor_velocity_indices(self) -> np.ndarray:
        """Indices of the rotor speeds in v; empty without rotor joints."""
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
        """Default mass of every body but World [kg] (54.8 kg for the paper's robot)."""
        plant = self.plant
        return float(sum(plant.get_body(plant.GetBodyIndices(i)[k]).default_mass()
                         for i in map(ModelInstanceIndex, range(plant.num_model_instances()))
                         for k in range(len(plant.GetBodyIndices(i)))
                         if plant.GetBodyIndices(i)[k] != plant.world_body().index()))

    def arm_effort_limits(self) -> np.ndarray:
        """Torque limits of the arm's actuators [N m] (the description's, else the model's)."""
        given = self.description.limits.joint_effort
        if given:
            return np.array(given, dtype=float)
        return np.array([a.effort_limit() for a in self.arm_actuators])

    def thrust_limits(self) -> tuple[float, float]:
        """(min, max) thrust [N] of the description."""
        low, high = self.description.limits.thrust
        return float(low), float(high)

    def body_torque_limits(self) -> np.ndarray:
        """Bounds of the body torques about x, y, z [N m] of the description."""
        return np.array(self.description.limits.body_torque, dtype=float)

    def arm_position_limits(self) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) joint limits of the arm [rad]."""
        lower = np.array([j.position_lower_limit() for j in self.arm_joints])
        upper = np.array([j.position_upper_limit() for j in self.arm_joints])
        return lower, upper

    def arm_velocity_limits(self) -> np.ndarray:
        """Joint speed limits of the arm [rad/s] (magnitude, symmetric)."""
        return np.array([j.velocity_upper_limit() for j in self.arm_joints])

    def task_joint_nominal(self) -> np.ndarray:
        """The nominal posture's angles at the task's joint components (task order) [rad]:
        the default desired angles of those components."""
        assert self.task is not None  # a finalized model
        names = [j.name() for j in self.arm_joints]
        q = self.q_nominal_arm()
        return np.array([q[names.index(name)] for name in self.task.joint_names])

    def q_nominal_arm(self) -> np.ndarray:
        """The nominal hover posture of the arm [rad]: the description's, else the arm joints'
        default positions in this plant."""
        if self.description.nominal_posture:
            return np.array(self.description.nominal_posture, dtype=float)
        return np.array([j.get_default_angle() for j in self.arm_joints])


def make_parser(plant: MultibodyPlant, robot: RobotDescription | None = None) -> Parser:
    """A Parser for ``plant`` that knows the ``aerial_drake`` package and ``robot``'s
    ``package_map``, and nothing else.

    Drake's default package map includes ``drake_models``, which downloads on first use; our
    models need nothing but their own files, so every other package is removed and a stray
    ``package://`` URL fails at once instead of reaching for the network.
    """
    parser = Parser(plant)
    package_map = parser.package_map()
    for name in package_map.GetPackageNames():
        package_map.Remove(name)
    package_map.AddPackageXml(str(model_directory() / "package.xml"))
    if robot is not None:
        for name, folder in robot.package_map.items():
            path = Path(folder).expanduser()
            path = path if path.is_absolute() else robot.folder() / path
            if not path.is_dir():
                raise RobotDescriptionError(
                    f"{robot.source}: package_map.{name}: folder {path} does not exist",
                    f"package_map.{name}")
            if package_map.Contains(name):
                raise RobotDescriptionError(
                    f"{robot.source}: package_map.{name}: the name '{name}' is taken by "
                    "aerial_drake's own models; rename the package", f"package_map.{name}")
            package_map.Add(name, str(path))
    return parser


def _model_file(robot: RobotDescription, entry: str, parser: Parser, field: str) -> str:
    """The file of a ``models`` entry: a package:// URL or a path from the description."""
    if entry.startswith("package://"):
        name, _, rest = entry[len("package://"):].partition("/")
        if not parser.package_map().Contains(name):
            raise RobotDescriptionError(
                f"{robot.source}: {field}: '{entry}' names the package '{name}', which is not "
                f"in package_map (known: {', '.join(parser.package_map().GetPackageNames())})",
                field)
        path = Path(parser.package_map().GetPath(name)) / rest
    else:
        path = Path(entry).expanduser()
        path = path if path.is_absolute() else robot.folder() / path
    if not path.is_file():
        raise RobotDescriptionError(f"{robot.source}: {field}: model file {path} not found",
                                    field)
    if not str(path).endswith((".sdf", ".urdf", ".dmd.yaml")):
        raise RobotDescriptionError(
            f"{robot.source}: {field}: {path.name} is not an SDF (.sdf), URDF (.urdf) or "
            "Drake model directives (.dmd.yaml) file", field)
    return str(path)


def _parse_models(plant: MultibodyPlant, robot: RobotDescription, variant: str) -> None:
    parser = make_parser(plant, robot)
    field = "models" if variant == RIGID_VARIANT else f"variants[{variant}].models"
    for i, entry in enumerate(robot.variant(variant).models):
        path = _model_file(robot, entry, parser, f"{field}[{i}]")
        try:
            if path.endswith(".dmd.yaml"):
                ProcessModelDirectives(LoadModelDirectives(path), plant, parser)
            else:
                parser.AddModels(path)
        except RuntimeError as err:
            raise RobotDescriptionError(f"{robot.source}: {field}[{i}]: Drake could not parse "
                                        f"{path}: {err}", f"{field}[{i}]") from None


def _find_body(plant: MultibodyPlant, name: str, robot: RobotDescription, field: str
               ) -> RigidBody:
    model, _, body = name.rpartition("::")
    if model:
        if plant.HasModelInstanceNamed(model) and plant.HasBodyNamed(
                body, plant.GetModelInstanceByName(model)):
            return plant.GetBodyByName(body, plant.GetModelInstanceByName(model))
    else:
        matches = [plant.get_body(i) for i in _all_body_indices(plant)
                   if plant.get_body(i).name() == name]
        if len(matches) == 1:
            return matches[0]
        if len(matches) > 1:
            raise RobotDescriptionError(
                f"{robot.source}: {field}: several models have a body '{name}': write "
                f"'model::{name}' (models: "
                f"{', '.join(plant.GetModelInstanceName(b.model_instance()) for b in matches)})",
                field)
    names = [_scoped(plant, plant.get_body(i)) for i in _all_body_indices(plant)]
    raise RobotDescriptionError(f"{robot.source}: {field}: no body '{name}' in the model files;"
                                f" bodies: {', '.join(names)}", field)


def _end_effector_frame(plant: MultibodyPlant, robot: RobotDescription) -> Frame:
    """The description's end-effector frame, or (for ``body``) that body's frame."""
    ee = robot.end_effector
    if not ee.frame:
        return _find_body(plant, ee.body, robot, "end_effector.body").body_frame()
    model, _, name = ee.frame.rpartition("::")
    for m in range(plant.num_model_instances()):
        instance = ModelInstanceIndex(m)
        if model and plant.GetModelInstanceName(instance) != model:
            continue
        if plant.HasFrameNamed(name, instance):
            return plant.GetFrameByName(name, instance)
    raise RobotDescriptionError(f"{robot.source}: end_effector.frame: no frame '{ee.frame}' "
                                "in the model files", "end_effector.frame")


def _all_body_indices(plant: MultibodyPlant) -> list:
    world = plant.world_body().index()
    return [i for m in range(plant.num_model_instances())
            for i in plant.GetBodyIndices(ModelInstanceIndex(m)) if i != world]


def _scoped(plant: MultibodyPlant, body: RigidBody) -> str:
    return f"{plant.GetModelInstanceName(body.model_instance())}::{body.name()}"


def _all_joints(plant: MultibodyPlant) -> list[Joint]:
    return [plant.get_joint(i) for i in plant.GetJointIndices()]


def _find_joint(plant: MultibodyPlant, name: str, robot: RobotDescription, field: str) -> Joint:
    model, _, short = name.rpartition("::")
    matches = [j for j in _all_joints(plant) if j.name() == short and (
        not model or plant.GetModelInstanceName(j.model_instance()) == model)]
    if len(matches) == 1:
        return matches[0]
    if matches:
        raise RobotDescriptionError(f"{robot.source}: {field}: several models have a joint "
                                    f"'{name}': write 'model::{short}'", field)
    names = [j.name() for j in _all_joints(plant) if j.num_velocities() > 0]
    raise RobotDescriptionError(f"{robot.source}: {field}: no joint '{name}' in the model "
                                f"files; joints: {', '.join(names)}", field)


@dataclass(frozen=True)
class _Structure:
    """What :func:`_check_structure` found: the arm's joints in chain order, the rotors."""

    arm_joints: tuple[Joint, ...]
    rotor_joints: tuple[Joint, ...]
    end_effector_body: RigidBody


def _check_structure(plant: MultibodyPlant, robot: RobotDescription, variant: str,
                     vehicle: RigidBody) -> _Structure:
    """The checks of the module docstring on an unfinalized plant (before Drake adds floating
    joints to free bodies)."""
    src = robot.source
    joints = _all_joints(plant)
    inboard = {j.child_body().index(): j for j in joints}
    if vehicle.index() in inboard:
        j = inboard[vehicle.index()]
        raise RobotDescriptionError(
            f"{src}: vehicle_body: '{vehicle.name()}' is attached to "
            f"'{j.parent_body().name()}' by the {j.type_name()} joint '{j.name()}': the vehicle "
            "must be a free body (no joint to World or to another body; Drake gives it a "
            "floating joint). Remove that joint from the model, or name the right body",
            "vehicle_body")
    # Every body must hang below the vehicle.
    children: dict = {}
    for j in joints:
        children.setdefault(j.parent_body().index(), []).append(j)
    below, stack = {vehicle.index()}, [vehicle.index()]
    while stack:
        for j in children.get(stack.pop(), []):
            below.add(j.child_body().index())
            stack.append(j.child_body().index())
    stray = [plant.get_body(i) for i in _all_body_indices(plant) if i not in below]
    if stray:
        raise RobotDescriptionError(
            f"{src}: body '{_scoped(plant, stray[0])}' is not connected to the vehicle "
            f"'{vehicle.name()}': every body must hang below the vehicle (the arm a chain "
            "below it). Weld or join it to the vehicle or the arm, or remove it", "models")
    v = robot.variant(variant)
    rotor_joints = tuple(_find_joint(plant, name, robot, f"variants[{variant}].rotor_joints")
                         for name in v.rotor_joints)
    rotor_ids = {j.index() for j in rotor_joints}
    for j in rotor_joints:
        if j.parent_body().index() != vehicle.index() or j.type_name() != "revolute":
            raise RobotDescriptionError(
                f"{src}: variants[{variant}].rotor_joints: '{j.name()}' must be a revolute "
                f"joint on the vehicle body '{vehicle.name()}'", f"variants[{variant}]")
    moving = [j for j in joints if j.num_velocities() > 0 and j.index() not in rotor_ids]
    for j in moving:
        if j.type_name() != "revolute":
            raise RobotDescriptionError(
                f"{src}: joint '{j.name()}' is a {j.type_name()} joint: the law handles arms "
                "of revolute joints (welds elsewhere). Model it as revolute, or weld it",
                "arm_joints")
    actuated = {a.joint().index() for a in (plant.get_joint_actuator(i)
                                            for i in plant.GetJointActuatorIndices())}
    for j in moving:
        if j.index() not in actuated:
            raise RobotDescriptionError(
                f"{src}: joint '{j.name()}' has no actuator: every arm joint needs one (the "
                "arm is fully actuated, tau of (1)). Add a transmission/actuator to it",
                "arm_joints")
    ee = _end_effector_frame(plant, robot).body()
    # The chain: the joints from the end effector's body up to the vehicle.
    path: list[Joint] = []
    body = ee.index()
    while body != vehicle.index():
        if body not in inboard:
            raise RobotDescriptionError(
                f"{src}: end_effector.body: '{ee.name()}' is not below the vehicle",
                "end_effector.body")
        j = inboard[body]
        if j.num_velocities() > 0:
            path.append(j)
        body = j.parent_body().index()
    path.reverse()
    if not path:
        raise RobotDescriptionError(
            f"{src}: end_effector.body: '{ee.name()}' is not on the arm (no arm joint lies "
            "between it and the vehicle): put the end-effector frame on the arm's last link",
            "end_effector.body")
    on_path = {j.index() for j in path}
    if robot.arm_joints:
        listed = tuple(_find_joint(plant, name, robot, "arm_joints") for name in robot.arm_joints)
        if len({j.index() for j in listed}) != len(listed):
            raise RobotDescriptionError(f"{src}: arm_joints: a joint is listed twice",
                                        "arm_joints")
    else:
        listed = tuple(path)
    for j in moving:
        if j.index() not in on_path:
            raise RobotDescriptionError(
                f"{src}: joint '{j.name()}' is not on the chain from the vehicle to the end "
                f"effector body '{ee.name()}': the arm must be one serial chain and the end "
                "effector on its last link (a branch would be unactuated by the task). Weld "
                "it, or move the end effector", "arm_joints")
    if [j.index() for j in listed] != [j.index() for j in path]:
        raise RobotDescriptionError(
            f"{src}: arm_joints {[j.name() for j in listed]} are not the chain from the "
            f"vehicle to the end effector, {[j.name() for j in path]} (in that order); "
            "leave arm_joints empty to take the chain", "arm_joints")
    return _Structure(tuple(path), rotor_joints, ee)


def _check_task(plant: MultibodyPlant, robot: RobotDescription, arm: tuple[Joint, ...]
                ) -> TaskLayout:
    parsed = parse_task(robot.task)
    if parsed.size != len(arm):
        raise RobotDescriptionError(
            f"{robot.source}: task: {list(robot.task)} has {parsed.size} coordinates but the "
            f"arm has {len(arm)} joints: the paper's law needs exactly as many task "
            "coordinates as joints (no redundancy). Add or remove task components "
            "(position, orientation, position_x, position_y, position_z, joint:<name>)", "task")
    by_name = {j.name(): j for j in arm}
    joints = []
    for name in parsed.joint_names:
        if name not in by_name:
            raise RobotDescriptionError(
                f"{robot.source}: task: joint:{name} is not an arm joint "
                f"({', '.join(by_name)})", "task")
        joints.append(by_name[name])
    return TaskLayout(components=parsed.components, rows=parsed.rows,
                      joint_names=parsed.joint_names,
                      joint_positions=tuple(j.position_start() for j in joints),
                      joint_velocities=tuple(j.velocity_start() for j in joints))


def add_aerial_manipulator(
    plant: MultibodyPlant,
    variant: str = RIGID_VARIANT,
    *,
    floating_base: str = "quaternion",
    finalize: bool = True,
    scene_graph: SceneGraph | None = None,
    robot: RobotDescription | None = None,
) -> AerialManipulator:
    """Parses ``robot``'s models (its plant ``variant``) into ``plant`` and checks them.

    Args:
        plant: an unfinalized plant, registered with a SceneGraph (visual geometry is then
            added) or not.
        variant: "rigid" (the description's models) or one of its ``variants``.
        floating_base: "quaternion" leaves the vehicle a free body (Drake's
            QuaternionFloatingJoint); "rpy" adds an RpyFloatingJoint named "base" from World,
            whose q = [roll, pitch, yaw, p_WB] linearises without a unit-norm constraint.
            Both have v = [w_WB (World), v_WBo (World)].
        finalize: finalize the plant (the index properties and the task need it).
        scene_graph: stored on the result for convenience; the plant's own registration
            decides whether geometry is added.
        robot: the description (default: the paper's helicopter with the LWR).

    Raises:
        RobotDescriptionError: naming the field of the description to change.
    """
    robot = robot if robot is not None else default_robot()
    _check_choice("floating_base", floating_base, FLOATING_BASES)
    _check_choice("plant variant", variant, robot.variant_names())
    _parse_models(plant, robot, variant)
    base_body = _find_body(plant, robot.vehicle_body, robot, "vehicle_body")
    structure = _check_structure(plant, robot, variant, base_body)
    com = base_body.default_com()
    if variant == RIGID_VARIANT and np.linalg.norm(com) > COM_OFFSET_TOLERANCE:
        raise RobotDescriptionError(
            f"{robot.source}: vehicle_body: the centre of mass of '{base_body.name()}' is at "
            f"{np.round(com, 6).tolist()} m in its body frame: the paper's frame B (thrust "
            "point and axis) is at the vehicle's centre of mass. Move the body frame there "
            "in the model (and its inertia with it)", "vehicle_body")
    arm_actuators = tuple(_actuator_of(plant, j) for j in structure.arm_joints)
    if robot.reflected_inertia:
        if len(robot.reflected_inertia) != len(arm_actuators):
            raise RobotDescriptionError(
                f"{robot.source}: reflected_inertia: {len(robot.reflected_inertia)} values "
                f"for {len(arm_actuators)} arm joints", "reflected_inertia")
        for actuator, value in zip(arm_actuators, robot.reflected_inertia):
            actuator.set_default_rotor_inertia(float(value))
            actuator.set_default_gear_ratio(1.0)
    if robot.limits.joint_effort and len(robot.limits.joint_effort) != len(arm_actuators):
        raise RobotDescriptionError(
            f"{robot.source}: limits.joint_effort: {len(robot.limits.joint_effort)} values "
            f"for {len(arm_actuators)} arm joints", "limits.joint_effort")
    if robot.nominal_posture and len(robot.nominal_posture) != len(arm_actuators):
        raise RobotDescriptionError(
            f"{robot.source}: nominal_posture: {len(robot.nominal_posture)} angles for "
            f"{len(arm_actuators)} arm joints", "nominal_posture")
    if floating_base == "rpy":
        # Must precede Finalize, which would otherwise give the body a quaternion joint.
        plant.AddJoint(RpyFloatingJoint("base", plant.world_frame(), base_body.body_frame()))
    frame = _end_effector_frame(plant, robot)
    if not robot.end_effector.frame:
        ee = robot.end_effector
        X_BE = RigidTransform(RollPitchYaw(ee.offset_rpy), np.asarray(ee.offset_xyz, float))
        frame = plant.AddFrame(FixedOffsetFrame(
            END_EFFECTOR_FRAME, structure.end_effector_body.body_frame(), X_BE))
    task = None
    if finalize:
        plant.Finalize()
        task = _check_task(plant, robot, structure.arm_joints)
    v = robot.variant(variant)
    return AerialManipulator(
        plant=plant,
        scene_graph=scene_graph,
        vehicle=base_body.model_instance(),
        base_body=base_body,
        end_effector_frame=frame,
        end_effector_body=structure.end_effector_body,
        arm_joints=structure.arm_joints,  # type: ignore[arg-type]  # revolute, checked
        arm_actuators=arm_actuators,
        rotor_joints=structure.rotor_joints,  # type: ignore[arg-type]
        rotor_actuators=tuple(_actuator_of(plant, j) for j in structure.rotor_joints),
        rotor_directions=tuple(float(d) for d in v.rotor_directions),
        variant=variant,
        floating_base=floating_base,
        description=robot,
        task=task,
    )


def _actuator_of(plant: MultibodyPlant, joint: Joint) -> JointActuator:
    for i in plant.GetJointActuatorIndices():
        actuator = plant.get_joint_actuator(i)
        if actuator.joint().index() == joint.index():
            return actuator
    raise RobotDescriptionError(f"joint '{joint.name()}' has no actuator", "arm_joints")


def make_plant(
    variant: str = RIGID_VARIANT, *, floating_base: str = "quaternion", time_step: float = 0.0,
    robot: RobotDescription | None = None,
) -> AerialManipulator:
    """A standalone finalized plant without SceneGraph (e.g. a controller's internal model)."""
    plant = MultibodyPlant(time_step)
    return add_aerial_manipulator(plant, variant, floating_base=floating_base, robot=robot)


def nominal_end_effector_offset(model: AerialManipulator) -> np.ndarray:
    """p_GE in B [m]: the end effector's position (frame E's origin) minus the system's centre
    of mass, in the vehicle frame B, with the vehicle level and the arm at its nominal posture
    (about (0.3, 0, -0.6) m for the paper's robot)."""
    plant = model.plant
    ctx = plant.CreateDefaultContext()
    set_nominal_posture(model, ctx)
    X_WB = plant.EvalBodyPoseInWorld(ctx, model.base_body)
    return X_WB.rotation().inverse() @ (
        model.end_effector_frame.CalcPoseInWorld(ctx).translation()
        - plant.CalcCenterOfMassPositionInWorld(ctx))


def add_to_builder(
    builder: DiagramBuilder,
    variant: str = RIGID_VARIANT,
    *,
    time_step: float = 0.0,
    floating_base: str = "quaternion",
    robot: RobotDescription | None = None,
) -> AerialManipulator:
    """Adds a plant and SceneGraph (``AddMultibodyPlantSceneGraph``) holding the finalized
    aerial manipulator to ``builder``."""
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step)
    return add_aerial_manipulator(
        plant, variant, floating_base=floating_base, scene_graph=scene_graph, robot=robot
    )


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


def set_nominal_posture(
    manip: AerialManipulator,
    context: Context,
    p_WB: tuple[float, float, float] | np.ndarray = (0.0, 0.0, 0.0),
    yaw: float = 0.0,
) -> None:
    """Sets the vehicle level at ``p_WB`` with heading ``yaw`` [rad] and the arm at
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
