"""What the law needs of a robot's plant, checked before Finalize (before Drake gives free
bodies their floating joints): a free vehicle body, every body below it, the arm a serial chain
of actuated revolute joints from the vehicle to the end effector, the task's size and joints.
Each failure is a RobotDescriptionError naming the description's field to change."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import Frame, Joint, JointActuator, ModelInstanceIndex, RigidBody

from aerial_drake.robots.description import RobotDescription, RobotDescriptionError
from aerial_drake.robots.task import TaskLayout, parse_task


def find_body(plant: MultibodyPlant, name: str, robot: RobotDescription, field: str
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


def end_effector_frame(plant: MultibodyPlant, robot: RobotDescription) -> Frame:
    """The description's end-effector frame, or (for ``body``) that body's frame."""
    ee = robot.end_effector
    if not ee.frame:
        return find_body(plant, ee.body, robot, "end_effector.body").body_frame()
    model, _, name = ee.frame.rpartition("::")
    for m in range(plant.num_model_instances()):
        instance = ModelInstanceIndex(m)
        if model and plant.GetModelInstanceName(instance) != model:
            continue
        if plant.HasFrameNamed(name, instance):
            return plant.GetFrameByName(name, instance)
    frames = [f"{plant.GetModelInstanceName(ModelInstanceIndex(m))}::{f.name()}"
              for m in range(1, plant.num_model_instances())  # 0: World's
              for f in map(plant.get_frame, plant.GetFrameIndices(ModelInstanceIndex(m)))
              if not f.name().startswith("__")]
    raise RobotDescriptionError(f"{robot.source}: end_effector.frame: no frame '{ee.frame}' "
                                f"in the model files; frames: {', '.join(frames)}",
                                "end_effector.frame")


def end_effector_mount(plant: MultibodyPlant, robot: RobotDescription
                       ) -> tuple[RigidBody, RigidTransform]:
    """The body with mass the end effector E is fixed to, and E's pose in it X_BE: the named
    frame's pose in its body (or, for ``body``, the description's offsets), carried up through
    weld joints past massless bodies (the common URDF ``tool0``/``ee`` link on a fixed joint):
    the law's kinematics (:mod:`aerial_drake.dynamics.decoupling`) keep bodies with mass only.
    RobotDescriptionError if E is on a massless body that moves."""
    ee = robot.end_effector
    frame = end_effector_frame(plant, robot)
    field = "end_effector.frame" if ee.frame else "end_effector.body"
    if ee.frame:
        X_BE = frame.GetFixedPoseInBodyFrame()
    else:
        X_BE = RigidTransform(RollPitchYaw(ee.offset_rpy), np.asarray(ee.offset_xyz, float))
    body = frame.body()
    inboard = {j.child_body().index(): j for j in _all_joints(plant)}
    while not body.default_mass() > 0.0:
        joint = inboard.get(body.index())
        if joint is None or joint.type_name() != "weld":
            how = "is free" if joint is None else f"moves on the {joint.type_name()} joint " \
                f"'{joint.name()}'"
            raise RobotDescriptionError(
                f"{robot.source}: {field}: '{ee.frame or ee.body}' is on the massless body "
                f"'{body.name()}', which {how}: the law follows bodies with mass. Give that "
                "body a mass, or put the end effector on a body with mass (or on a massless "
                "link welded to one)", field)
        # X_PE = X_PF X_FM X_MC X_CE: parent frame, the weld, the child body's frame.
        X_CE = X_BE
        X_BE = (joint.frame_on_parent().GetFixedPoseInBodyFrame() @ joint.X_FM()
                @ joint.frame_on_child().GetFixedPoseInBodyFrame().inverse() @ X_CE)
        body = joint.parent_body()
    return body, X_BE


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
class Structure:
    """What :func:`check_structure` found: the arm's joints in chain order, the rotors."""

    arm_joints: tuple[Joint, ...]
    rotor_joints: tuple[Joint, ...]
    end_effector_body: RigidBody


def check_structure(plant: MultibodyPlant, robot: RobotDescription, variant: str,
                    vehicle: RigidBody, instances: Sequence[ModelInstanceIndex] | None = None,
                    ) -> Structure:
    """The checks of the module docstring on an unfinalized plant (before Drake adds floating
    joints to free bodies), over the robot's model ``instances`` (None: every model in the
    plant); other models' bodies and joints (the environment's) are not the robot's."""
    src = robot.source
    own = None if instances is None else {int(i) for i in instances}
    joints = [j for j in _all_joints(plant) if own is None or int(j.model_instance()) in own]
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
    stray = [plant.get_body(i) for i in _all_body_indices(plant) if i not in below
             and (own is None or int(plant.get_body(i).model_instance()) in own)]
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
    ee = end_effector_mount(plant, robot)[0]
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
    return Structure(tuple(path), rotor_joints, ee)


def check_task(plant: MultibodyPlant, robot: RobotDescription, arm: tuple[Joint, ...]
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


def actuator_of(plant: MultibodyPlant, joint: Joint) -> JointActuator:
    for i in plant.GetJointActuatorIndices():
        actuator = plant.get_joint_actuator(i)
        if actuator.joint().index() == joint.index():
            return actuator
    raise RobotDescriptionError(f"joint '{joint.name()}' has no actuator", "arm_joints")
