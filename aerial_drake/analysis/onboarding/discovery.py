"""What a model file holds, found before any description exists (``robot init``, step 1): the
free body that carries the arm (the vehicle), the arm's chain of actuated revolute joints, and
the frames the end effector could be.

The rules, in the order they are applied (docs/robots.md, "robot init"):

- the **vehicle** is a free body (no joint attaches it to World or to another body) with at
  least one actuated joint below it; ``--vehicle`` names it when the model has several;
- the **arm** is the chain of actuated joints from the vehicle to the end effector: without
  ``--end-effector`` the actuated joints below the vehicle must form one chain (a branch is
  refused, naming it: give the end effector to choose);
- the **end-effector candidates** are the frames fixed to the chain's last link: its body
  frame, the frames the model defines on it, and the links welded below it (a URDF's
  ``tool0`` or ``ee_link``). The default is the first candidate whose name says it is a tool
  (:data:`TOOL_NAMES`), else the deepest welded link, else the last link itself.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import Frame, Joint, JointIndex, ModelInstanceIndex, RigidBody

from aerial_drake.analysis.onboarding.errors import OnboardingError
from aerial_drake.robots.parsing import make_parser

#: Names (lower case, as substrings) that mark a frame as the tool, in order of preference.
TOOL_NAMES = ("tcp", "tool0", "tool", "end_effector", "ee", "flange", "gripper")


@dataclass(frozen=True)
class Discovery:
    """The model's parts that ``robot init`` names in the description."""

    model: Path
    model_name: str  # the model instance's name (a URDF's robot name)
    vehicle_body: str  # as the description names it (scoped when needed)
    arm_joints: tuple[str, ...]  # from the vehicle outward
    end_effector: str  # the chosen frame's name (a body's frame or a frame)
    end_effector_is_body: bool  # the name is a body's (``end_effector.body``)
    candidates: tuple[str, ...]  # every end-effector candidate, the chosen one first


def _all_joints(plant: MultibodyPlant) -> list[Joint]:
    return [plant.get_joint(i) for i in plant.GetJointIndices()]


def _bodies(plant: MultibodyPlant) -> list[RigidBody]:
    world = plant.world_body().index()
    return [plant.get_body(i) for m in range(plant.num_model_instances())
            for i in plant.GetBodyIndices(ModelInstanceIndex(m)) if i != world]


def _actuated(plant: MultibodyPlant) -> set[int]:
    return {int(plant.get_joint_actuator(i).joint().index())
            for i in plant.GetJointActuatorIndices()}


def _parse(model: Path) -> MultibodyPlant:
    if not model.is_file():
        raise OnboardingError(f"{model}: no such file: give the path of a URDF or SDF model",
                              "model")
    if model.suffix.lower() not in (".urdf", ".sdf"):
        raise OnboardingError(f"{model}: '{model.suffix}' is not a model file 'robot init' "
                              "reads: give a .urdf or .sdf file (a .dmd.yaml scene can be "
                              "named in a description's models by hand)", "model")
    plant = MultibodyPlant(0.0)
    try:
        make_parser(plant).AddModels(str(model))
    except RuntimeError as err:  # Drake's parser names the file and line
        raise OnboardingError(f"{model}: Drake could not parse it: {err}", "model") from err
    return plant


def _find_body(plant: MultibodyPlant, name: str, option: str) -> RigidBody:
    scope, _, short = name.rpartition("::")
    matches = [b for b in _bodies(plant) if b.name() == short and (
        not scope or plant.GetModelInstanceName(b.model_instance()) == scope)]
    if len(matches) == 1:
        return matches[0]
    names = ", ".join(b.name() for b in _bodies(plant))
    why = "several bodies have that name: write 'model::body'" if matches else "no such body"
    raise OnboardingError(f"{option} {name}: {why}; the model's bodies: {names}", option)


def _children(plant: MultibodyPlant) -> dict[int, list[Joint]]:
    out: dict[int, list[Joint]] = {}
    for joint in _all_joints(plant):
        out.setdefault(int(joint.parent_body().index()), []).append(joint)
    return out


def _subtree_joints(plant: MultibodyPlant, body: RigidBody) -> list[Joint]:
    """Every joint below ``body``, depth first."""
    children, out, stack = _children(plant), [], [body]
    while stack:
        b = stack.pop()
        for joint in children.get(int(b.index()), []):
            out.append(joint)
            stack.append(joint.child_body())
    return out


def _vehicle(plant: MultibodyPlant, given: str | None) -> RigidBody:
    inboard = {int(j.child_body().index()) for j in _all_joints(plant)}
    actuated = _actuated(plant)
    free = [b for b in _bodies(plant) if int(b.index()) not in inboard]
    carriers = [b for b in free if any(int(j.index()) in actuated
                                       for j in _subtree_joints(plant, b))]
    if given is not None:
        body = _find_body(plant, given, "--vehicle")
        if int(body.index()) in inboard:
            joint = next(j for j in _all_joints(plant) if j.child_body().index() == body.index())
            raise OnboardingError(
                f"--vehicle {given}: the body is attached to '{joint.parent_body().name()}' by "
                f"the {joint.type_name()} joint '{joint.name()}': the vehicle must be a free "
                "body (remove that joint, e.g. a URDF's weld to 'world')", "--vehicle")
        return body
    if len(carriers) == 1:
        return carriers[0]
    if not carriers:
        raise OnboardingError(
            "the model has no free body with actuated joints below it: the vehicle must be a "
            "free body (no joint to 'world') and the arm's joints need actuators (a URDF "
            "<transmission> per joint); free bodies: "
            f"{', '.join(b.name() for b in free) or 'none'}", "--vehicle")
    raise OnboardingError(f"several free bodies carry actuated joints: "
                          f"{', '.join(b.name() for b in carriers)}; name the vehicle with "
                          "--vehicle BODY", "--vehicle")


def _chain_to(plant: MultibodyPlant, vehicle: RigidBody, body: RigidBody) -> list[Joint]:
    """The joints from ``vehicle`` down to ``body`` (welds included), outward."""
    inboard = {int(j.child_body().index()): j for j in _all_joints(plant)}
    path, b = [], body
    while b.index() != vehicle.index():
        joint = inboard.get(int(b.index()))
        if joint is None:
            raise OnboardingError(f"--end-effector: '{body.name()}' is not below the vehicle "
                                  f"'{vehicle.name()}'", "--end-effector")
        path.append(joint)
        b = joint.parent_body()
    return path[::-1]


def _tip_of_chain(plant: MultibodyPlant, vehicle: RigidBody) -> RigidBody:
    """The last link of the one chain of actuated joints below ``vehicle``."""
    actuated = _actuated(plant)
    joints = [j for j in _subtree_joints(plant, vehicle) if int(j.index()) in actuated]
    if not joints:
        raise OnboardingError(f"no actuated joint below the vehicle '{vehicle.name()}'",
                              "--vehicle")
    parents: dict[int, list[Joint]] = {}
    for joint in joints:  # actuated joints grouped by the actuated joint above them
        above = [j for j in _chain_to(plant, vehicle, joint.parent_body())
                 if int(j.index()) in actuated]
        key = int(above[-1].index()) if above else -1
        parents.setdefault(key, []).append(joint)
    for key, below in parents.items():
        if len(below) > 1:
            where = ("the vehicle" if key < 0
                     else f"the joint '{plant.get_joint(JointIndex(key)).name()}'")
            raise OnboardingError(
                f"the arm branches below {where} (actuated joints "
                f"{', '.join(j.name() for j in below)}): the law needs one serial chain; give "
                "--end-effector FRAME to choose the branch", "--end-effector")
    last = next(j for j in joints if int(j.index()) not in parents)
    return last.child_body()


def _candidates(plant: MultibodyPlant, link: RigidBody) -> list[tuple[str, bool, int]]:
    """(name, is a body, depth of welds below the link) of every frame fixed to ``link``."""
    out = [(link.name(), True, 0)]
    welded, depth = [link], {int(link.index()): 0}
    children = _children(plant)
    while welded:
        b = welded.pop()
        for joint in children.get(int(b.index()), []):
            if joint.type_name() == "weld":
                child = joint.child_body()
                depth[int(child.index())] = depth[int(b.index())] + 1
                out.append((child.name(), True, depth[int(child.index())]))
                welded.append(child)
    bodies = {name for name, _, _ in out}
    joint_frames = {f.name() for j in _all_joints(plant)
                    for f in (j.frame_on_parent(), j.frame_on_child())}
    for i in plant.GetFrameIndices(link.model_instance()):
        frame: Frame = plant.get_frame(i)
        if (frame.name() not in bodies | joint_frames and not frame.name().startswith("__")
                and int(frame.body().index()) in depth):
            out.append((frame.name(), False, depth[int(frame.body().index())]))
    return out


def _preferred(candidates: list[tuple[str, bool, int]]) -> tuple[str, bool]:
    for tool in TOOL_NAMES:
        for name, is_body, _ in candidates:
            if tool in name.lower():
                return name, is_body
    name, is_body, _ = max(candidates, key=lambda c: c[2])
    return name, is_body


def discover(model: Path, vehicle: str | None = None, end_effector: str | None = None
             ) -> Discovery:
    """The vehicle, the arm's joints and the end effector of ``model`` (the module's rules);
    OnboardingError naming the option to give when a choice is ambiguous."""
    plant = _parse(model)
    base = _vehicle(plant, vehicle)
    actuated = _actuated(plant)
    if end_effector is not None:
        name, is_body = end_effector, any(b.name() == end_effector for b in _bodies(plant))
        frames = [plant.get_frame(i) for m in range(plant.num_model_instances())
                  for i in plant.GetFrameIndices(ModelInstanceIndex(m))]
        if not is_body and not any(f.name() == end_effector for f in frames):
            joint_frames = {f.name() for j in _all_joints(plant)
                            for f in (j.frame_on_parent(), j.frame_on_child())}
            bodies = {b.name() for b in _bodies(plant)}
            names = sorted({f.name() for f in frames if not f.name().startswith("__")
                            and (f.name() in bodies or f.name() not in joint_frames)
                            and f.name() != "world"})
            raise OnboardingError(f"--end-effector {end_effector}: no such frame or body; "
                                  f"frames: {', '.join(names)}", "--end-effector")
        frame_body = (_find_body(plant, name, "--end-effector") if is_body else next(
            f.body() for f in frames if f.name() == end_effector))
        chain = [j for j in _chain_to(plant, base, frame_body) if int(j.index()) in actuated]
        tip = chain[-1].child_body() if chain else base
        candidates = _candidates(plant, tip)
    else:
        tip = _tip_of_chain(plant, base)
        candidates = _candidates(plant, tip)
        name, is_body = _preferred(candidates)
        chain_body = next(plant.GetBodyByName(c[0]) for c in candidates if c[0] == tip.name())
        chain = [j for j in _chain_to(plant, base, chain_body) if int(j.index()) in actuated]
    bad = [j for j in chain if j.type_name() != "revolute"]
    if bad:
        raise OnboardingError(
            f"{model}: the arm's joint '{bad[0].name()}' is {bad[0].type_name()}: the law "
            "takes actuated revolute joints only (docs/robots.md, \"What the law needs of a "
            "robot\")", "model")
    names = [c[0] for c in candidates]
    ordered = (name, *[c for c in names if c != name])
    return Discovery(model=model, model_name=plant.GetModelInstanceName(base.model_instance()),
                     vehicle_body=base.name(), arm_joints=tuple(j.name() for j in chain),
                     end_effector=name, end_effector_is_body=is_body, candidates=ordered)
