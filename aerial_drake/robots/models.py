"""An aerial manipulator as a Drake MultibodyPlant, built from a robot description.

:func:`add_aerial_manipulator` (and :func:`make_plant`, a plant of its own) parses a
:class:`~aerial_drake.robots.description.RobotDescription`'s model files into a plant and
checks what the paper's law needs of it (the checks name the field to change): a free
vehicle body whose frame is at its centre of mass, every other body of the robot below it, the
arm a serial chain of actuated revolute joints from the vehicle to the end effector, and a task
with as many coordinates as the arm has joints (no redundancy).

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

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from pydrake.geometry import SceneGraph
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.parsing import ModelDirectives
from pydrake.multibody.plant import (
    AddMultibodyPlant,
    AddMultibodyPlantSceneGraph,
    MultibodyPlant,
    MultibodyPlantConfig,
)
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
from aerial_drake.robots.environment import add_environment
from aerial_drake.robots.parsing import make_parser, parse_models
from aerial_drake.robots.structure import (
    actuator_of,
    check_structure,
    check_task,
    end_effector_frame,
    end_effector_mount,
    find_body,
)
from aerial_drake.robots.task import TaskLayout

__all__ = ["AerialManipulator", "FLOATING_BASES", "add_aerial_manipulator", "add_to_builder",
           "make_parser", "make_plant", "nominal_end_effector_offset", "set_nominal_posture"]

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
    #: The robot's model instances, and the environment's (walls, tables, objects).
    model_instances: tuple[ModelInstanceIndex, ...] = ()
    environment: tuple[ModelInstanceIndex, ...] = ()

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
        """Default mass of the robot's bodies [kg] (54.8 kg for the paper's robot)."""
        plant = self.plant
        return float(sum(plant.get_body(b).default_mass() for i in self.model_instances
                         for b in plant.GetBodyIndices(i)))

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


def add_aerial_manipulator(
    plant: MultibodyPlant,
    variant: str = RIGID_VARIANT,
    *,
    floating_base: str = "quaternion",
    finalize: bool = True,
    scene_graph: SceneGraph | None = None,
    robot: RobotDescription | None = None,
    environment: ModelDirectives | None = None,
    environment_packages: Sequence[str] = (),
) -> AerialManipulator:
    """Parses ``robot``'s models (its plant ``variant``) into ``plant`` and checks them, then
    the ``environment`` directives (:mod:`aerial_drake.robots.environment`).

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
        environment: model directives of the world around the robot (None: none), parsed
            after the robot (its coordinates come first) with ``environment_packages``.

    Raises:
        RobotDescriptionError: naming the field of the description to change.
        WorldError: naming the environment's directive, file or package at fault.
    """
    robot = robot if robot is not None else default_robot()
    _check_choice("floating_base", floating_base, FLOATING_BASES)
    _check_choice("plant variant", variant, robot.variant_names())
    first = plant.num_model_instances()
    parse_models(plant, robot, variant)
    own = tuple(map(ModelInstanceIndex, range(first, plant.num_model_instances())))
    base_body = find_body(plant, robot.vehicle_body, robot, "vehicle_body")
    structure = check_structure(plant, robot, variant, base_body, own)
    com = base_body.default_com()
    if variant == RIGID_VARIANT and np.linalg.norm(com) > COM_OFFSET_TOLERANCE:
        raise RobotDescriptionError(
            f"{robot.source}: vehicle_body: the centre of mass of '{base_body.name()}' is at "
            f"{np.round(com, 6).tolist()} m in its body frame: the paper's frame B (thrust "
            "point and axis) is at the vehicle's centre of mass. Move the body frame there "
            "in the model (and its inertia with it)", "vehicle_body")
    arm_actuators = tuple(actuator_of(plant, j) for j in structure.arm_joints)
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
    frame = end_effector_frame(plant, robot)
    body, X_BE = end_effector_mount(plant, robot)
    if not robot.end_effector.frame or frame.body().index() != body.index():  # (the massless)
        frame = plant.AddFrame(FixedOffsetFrame(END_EFFECTOR_FRAME, body.body_frame(), X_BE))
    world = () if environment is None else add_environment(
        plant, environment, environment_packages, robot=own)
    task = None
    if finalize:
        plant.Finalize()
        task = check_task(plant, robot, structure.arm_joints)
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
        rotor_actuators=tuple(actuator_of(plant, j) for j in structure.rotor_joints),
        rotor_directions=tuple(float(d) for d in v.rotor_directions),
        variant=variant,
        floating_base=floating_base,
        description=robot,
        task=task,
        model_instances=own,
        environment=world,
    )


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
    plant_config: MultibodyPlantConfig | None = None,
    environment: ModelDirectives | None = None,
    environment_packages: Sequence[str] = (),
) -> AerialManipulator:
    """Adds a plant and SceneGraph holding the finalized aerial manipulator (and the
    ``environment``, :func:`add_aerial_manipulator`) to ``builder``: Drake's
    ``AddMultibodyPlant(plant_config)`` if given (its ``time_step`` wins), else
    ``AddMultibodyPlantSceneGraph(builder, time_step)``."""
    plant, scene_graph = (AddMultibodyPlantSceneGraph(builder, time_step) if plant_config is None
                          else AddMultibodyPlant(plant_config, builder))
    return add_aerial_manipulator(
        plant, variant, floating_base=floating_base, scene_graph=scene_graph, robot=robot,
        environment=environment, environment_packages=environment_packages)


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
