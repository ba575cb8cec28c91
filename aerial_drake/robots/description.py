"""Robot descriptions: what is flown, as a typed YAML file (``*.robot.yaml``).

A description names the model files, the vehicle body, the arm's joints, the end-effector frame,
the task and the input limits; :func:`aerial_drake.robots.models.make_plant` turns it into a
MultibodyPlant and checks it against the paper's assumptions. The shipped robots are
``models/sdf/*.robot.yaml`` (``helicopter_lwr``: the paper's); a scenario's ``robot`` field
names one of them or gives the path of the user's own. Field by field in ``docs/robots.md``.

Do not add ``from __future__ import annotations``: Drake's ``yaml_load_typed`` needs the real
field types.
"""

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

from pydrake.common.yaml import yaml_load_typed

from aerial_drake.robots.resources import model_directory
from aerial_drake.robots.task import TaskError, parse_task

ROBOT_SUFFIX = ".robot.yaml"
MODEL_SUFFIXES = (".sdf", ".urdf", ".dmd.yaml")
#: The plant variant every description has: its ``models``, also the controller's model.
RIGID_VARIANT = "rigid"


class RobotDescriptionError(ValueError):
    """A robot description is invalid; ``field`` is the dotted name of the field to blame."""

    def __init__(self, message: str, field: str | None = None) -> None:
        super().__init__(message)
        self.field = field


@dataclass
class EndEffector:
    """The task frame E: a frame of the model files (``frame``), or fixed to a body of the
    arm at an offset (``body`` and the offsets)."""

    # A frame the model files define on the arm (its name; "model::frame" to scope it).
    frame: str = ""
    # Or the body E is fixed to (its name in the model; "model::body" if several have it).
    body: str = ""
    # E's origin in that body's frame (m).
    offset_xyz: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    # E's orientation in that body's frame, roll-pitch-yaw about the body's axes (rad).
    offset_rpy: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])


@dataclass
class Limits:
    """Input limits of (1): what the actuators can give (the saturation's bounds)."""

    # Thrust range [min, max] along the vehicle's body z axis (N).
    thrust: list[float] = field(default_factory=list)
    # Bound of each body torque about the vehicle's x, y, z axes (N m), symmetric.
    body_torque: list[float] = field(default_factory=list)
    # Effort limit of each arm joint, in arm_joints order (N m); empty: the model files'.
    joint_effort: list[float] = field(default_factory=list)


@dataclass
class PlantVariant:
    """Another plant to simulate in place of ``models`` (e.g. the helicopter with spinning
    rotor bodies); the controller keeps the rigid model."""

    # Its name, used by a scenario's plant_variant.
    name: str = ""
    # Model files parsed in place of the description's models.
    models: list[str] = field(default_factory=list)
    # Joints on the vehicle whose speed a drive holds (spinning rotors); not arm joints.
    rotor_joints: list[str] = field(default_factory=list)
    # Spin direction (+1 or -1) of each rotor joint about its axis (the speed's sign).
    rotor_directions: list[float] = field(default_factory=list)


@dataclass
class RobotDescription:
    """One aerial manipulator: a floating vehicle with thrust along its body z axis and three
    body torques (B of (2)), and an n-joint serial arm below it."""

    # A short name.
    name: str = ""
    description: str = ""
    # Model files parsed in order: SDF (.sdf), URDF (.urdf) or Drake model directives
    # (.dmd.yaml). A path relative to this file's folder, absolute, or package://NAME/...
    models: list[str] = field(default_factory=list)
    # package:// names used by the model files -> their folders (relative to this file).
    package_map: dict[str, str] = field(default_factory=dict)
    # The vehicle's body (a free body: no joint to World); its frame is at the vehicle's
    # centre of mass with z along the thrust (the paper's frame B).
    vehicle_body: str = ""
    # The thrust direction in the vehicle's body frame: must be [0, 0, 1] (B of (2)).
    thrust_axis: list[float] = field(default_factory=lambda: [0.0, 0.0, 1.0])
    # The arm's joints from the vehicle outward; empty: every actuated joint below the vehicle
    # (rotor joints excepted), in order along the chain.
    arm_joints: list[str] = field(default_factory=list)
    end_effector: EndEffector = field(default_factory=EndEffector)
    # The task y (robots/task.py): as many rows as arm joints, e.g. [position, orientation].
    task: list[str] = field(default_factory=lambda: ["position", "orientation"])
    limits: Limits = field(default_factory=Limits)
    # The arm's nominal hover posture (rad, arm_joints order); empty: the model's default
    # joint positions.
    nominal_posture: list[float] = field(default_factory=list)
    # Reflected drive inertia of each arm joint (kg m^2); empty: the model files' (Drake's
    # rotor_inertia times gear_ratio squared).
    reflected_inertia: list[float] = field(default_factory=list)
    # How far (m) the desired end effector may stray from its nominal offset to the desired
    # CoM (the system's; heading frame) before a scenario's reference is refused as out of
    # the arm's reach.
    workspace_radius: float = 0.2
    # Other plants to simulate (each a name and its model files).
    variants: list[PlantVariant] = field(default_factory=list)

    #: The file this description was read from (set by the loader; not a YAML field).
    source: Path | None = field(default=None, repr=False, compare=False)

    def variant_names(self) -> tuple[str, ...]:
        return (RIGID_VARIANT, *(v.name for v in self.variants))

    def variant(self, name: str) -> PlantVariant:
        """The variant ``name`` ("rigid": the description's own models)."""
        if name == RIGID_VARIANT:
            return PlantVariant(name=RIGID_VARIANT, models=list(self.models))
        for v in self.variants:
            if v.name == name:
                return v
        raise RobotDescriptionError(
            f"robot '{self.name}' has no plant variant '{name}'; it has: "
            f"{', '.join(self.variant_names())}", "plant_variant")

    def folder(self) -> Path:
        """Where relative paths in this description start."""
        return self.source.parent if self.source is not None else model_directory()

    def validate(self) -> "RobotDescription":
        """Check the values that need no plant (the rest when the plant is built:
        :func:`aerial_drake.robots.structure.check_structure`). Returns self."""
        where = f"{self.source}: " if self.source is not None else ""

        def fail(name: str, message: str):
            raise RobotDescriptionError(f"{where}{name}: {message}", name)

        if not self.models:
            fail("models", "no model files: list the SDF, URDF or .dmd.yaml files to parse")
        if not self.vehicle_body:
            fail("vehicle_body", "empty: name the vehicle's body (the free body that carries "
                 "the thrust)")
        axis = [float(a) for a in self.thrust_axis]
        if axis != [0.0, 0.0, 1.0]:
            fail("thrust_axis", f"{self.thrust_axis} is not supported: the law of (1)-(2) "
                 "takes the thrust along the vehicle body frame's +z axis. Rotate the "
                 "vehicle body's frame in the model so that +z is the thrust, and write "
                 "[0, 0, 1]")
        try:
            parse_task(self.task)
        except TaskError as err:
            fail("task", str(err))
        thrust = self.limits.thrust
        if len(thrust) != 2 or not all(_finite(x) for x in thrust) or not (
                0.0 <= thrust[0] < thrust[1]):
            fail("limits.thrust", f"{thrust} must be [min, max] in N with 0 <= min < max")
        torque = self.limits.body_torque
        if len(torque) != 3 or not all(_finite(x) and x > 0 for x in torque):
            fail("limits.body_torque", f"{torque} must be 3 positive bounds in N m (x, y, z)")
        for name in ("joint_effort", "reflected"):
            values = (self.limits.joint_effort if name == "joint_effort"
                      else self.reflected_inertia)
            label = "limits.joint_effort" if name == "joint_effort" else "reflected_inertia"
            low_ok = (lambda x: x > 0) if name == "joint_effort" else (lambda x: x >= 0)
            if not all(_finite(x) and low_ok(x) for x in values):
                fail(label, f"{values} must hold finite numbers "
                     f"{'> 0' if name == 'joint_effort' else '>= 0'} (or be empty)")
        if not (_finite(self.workspace_radius) and self.workspace_radius > 0):
            fail("workspace_radius", f"{self.workspace_radius} must be > 0 (m)")
        if not all(_finite(x) for x in self.nominal_posture):
            fail("nominal_posture", f"{self.nominal_posture} must hold finite angles (rad)")
        for k, off in (("end_effector.offset_xyz", self.end_effector.offset_xyz),
                       ("end_effector.offset_rpy", self.end_effector.offset_rpy)):
            if len(off) != 3 or not all(_finite(x) for x in off):
                fail(k, f"{off} must be 3 finite numbers")
        ee = self.end_effector
        if bool(ee.body) == bool(ee.frame):
            fail("end_effector", "give either frame (a frame of the model files) or body (with "
                 "offset_xyz, offset_rpy), not both and not neither")
        if ee.frame and (any(ee.offset_xyz) or any(ee.offset_rpy)):
            fail("end_effector.offset_xyz", "offsets apply to body, not to frame: move the "
                 "offset into the model's frame, or give body instead of frame")
        names = [v.name for v in self.variants]
        for i, v in enumerate(self.variants):
            if not v.name or v.name == RIGID_VARIANT or names.count(v.name) > 1:
                fail(f"variants[{i}].name", f"'{v.name}' must be a unique name other than "
                     f"'{RIGID_VARIANT}'")
            if not v.models:
                fail(f"variants[{i}].models", "no model files")
            if len(v.rotor_directions) != len(v.rotor_joints) or not all(
                    d in (1.0, -1.0) for d in v.rotor_directions):
                fail(f"variants[{i}].rotor_directions", f"{v.rotor_directions}: one +1 or -1 "
                     f"per rotor joint ({len(v.rotor_joints)})")
        return self


def _finite(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def shipped_robots() -> dict[str, Path]:
    """Name -> path of the robot descriptions shipped with the package."""
    return {p.name[:-len(ROBOT_SUFFIX)]: p
            for p in sorted(model_directory().glob("*" + ROBOT_SUFFIX))}


def robot_path(name_or_path: str, relative_to: Path | None = None) -> Path:
    """The file of a shipped robot's name, or a path (relative to ``relative_to``)."""
    shipped = shipped_robots()
    if name_or_path in shipped:
        return shipped[name_or_path]
    path = Path(name_or_path).expanduser()
    if not path.is_absolute() and relative_to is not None:
        path = relative_to / path
    if not path.is_file():
        raise RobotDescriptionError(
            f"robot '{name_or_path}': neither a shipped robot ({', '.join(shipped)}) nor a "
            f"robot description file{f' (looked for {path})' if path.suffix else ''}", "robot")
    return path


def load_robot_description(name_or_path: str | Path, relative_to: Path | None = None
                           ) -> RobotDescription:
    """Read and validate a robot description: a shipped name (``"helicopter_lwr"``) or a path
    (relative paths start at ``relative_to``, e.g. the scenario's folder)."""
    path = robot_path(str(name_or_path), relative_to)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise RobotDescriptionError(f"{path}: cannot be read ({err})", "robot") from None
    try:
        description = yaml_load_typed(schema=RobotDescription, data=text)
    except (RuntimeError, ValueError, TypeError) as err:
        raise RobotDescriptionError(f"{path}: {err}", "robot") from None
    return dataclasses.replace(description, source=path.resolve()).validate()


def default_robot() -> RobotDescription:
    """The paper's helicopter with the KUKA LWR 4+."""
    return load_robot_description(DEFAULT_ROBOT)


#: The robot a scenario flies unless it names another.
DEFAULT_ROBOT = "helicopter_lwr"
