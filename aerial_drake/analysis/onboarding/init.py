"""``robot init``: from a URDF or SDF to a robot description and a hover scenario that run as
written (docs/robots.md, "robot init"). The steps, each in its module:

1. :mod:`.discovery`: the vehicle, the arm's chain, the end-effector candidates;
2. the task (:func:`task_candidates`): the pose for a 6-joint arm; otherwise the position
   (and the orientation from 6 joints up) with joint components for the rest, the joints
   chosen where the posture search finds the largest margin;
3. :mod:`~aerial_drake.analysis.onboarding.limits`: thrust from the thrust-to-weight
   ratio, body torques, efforts;
4. :mod:`.posture`: the nominal posture (Assumption 1 and joint-limit margins, the tool
   pointing where asked);
5. at that posture: the system's CoM, the end effector's offset r_o of (33), the locked
   inertia (every body rigidly locked, about the CoM);
6. :mod:`~aerial_drake.analysis.onboarding.gains`: Table II scaled by the documented rule;
7. :mod:`.writer`: the three files; :mod:`.workspace`: the workspace radius from the end
   effector's reach (``robot check``'s); then the scenarios loaded back and validated as a
   run would (so what was written runs).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import TextIO

import numpy as np

from aerial_drake.analysis.onboarding.discovery import Discovery, discover
from aerial_drake.analysis.onboarding.errors import OnboardingError
from aerial_drake.analysis.onboarding.gains import ScaledGains, scaled_gains
from aerial_drake.analysis.onboarding.limits import (
    ROLL_PITCH_SHARE,
    YAW_SHARE,
    InputLimits,
    input_limits,
)
from aerial_drake.analysis.onboarding.posture import Posture, arm_length, choose_posture
from aerial_drake.analysis.onboarding.workspace import REACH_SHARE, reach_radius
from aerial_drake.analysis.onboarding.writer import (
    CONTROLLER_PERIOD,
    HOVER_COM,
    HoverFile,
    RobotFile,
    hover_text,
    pick_and_place_text,
    robot_text,
)
from aerial_drake.control.baselines.tuning import locked_inertia
from aerial_drake.robots.description import EndEffector, Limits, RobotDescription
from aerial_drake.robots.models import make_plant
from aerial_drake.simulation.outputs import finite_or_none, write_text_atomically

#: The most task candidates tried (joint components chosen among the arm's joints).
MAX_TASK_CANDIDATES = 12
#: The workspace radius written first, as a share of the arm's length at the nominal posture
#: (the files need one to load; then replaced by the reach's, :mod:`.workspace`).
WORKSPACE_SHARE = 0.3
_AXES = {"x": (1, 0, 0), "y": (0, 1, 0), "z": (0, 0, 1)}
_DIRECTIONS = {"down": (0.0, 0.0, -1.0), "forward": (1.0, 0.0, 0.0), "up": (0.0, 0.0, 1.0)}


@dataclass
class InitOptions:
    """``robot init``'s options (the command line's, typed)."""

    model: Path
    vehicle: str | None = None
    end_effector: str | None = None
    name: str | None = None
    out: Path | None = None
    thrust_to_weight: float = 2.0
    body_torque: list[float] | None = None
    tool_axis: str = "z"
    tool_direction: str = "any"
    task: list[str] | None = None
    force: bool = False
    seed: int = 0


@dataclass
class InitResult:
    """What ``robot init`` found, chose and wrote."""

    robot_path: Path
    scenario_path: Path  # the hover
    pick_and_place_path: Path
    discovery: Discovery
    task: tuple[str, ...]
    #: (task, its posture's score), the singular ones (J_3 singular everywhere) at 0.
    tasks_tried: list[tuple[tuple[str, ...], float]]
    posture: Posture
    limits: InputLimits
    gains: ScaledGains
    mass: float
    com_offset: np.ndarray  # r_o (m)
    ee_offset: np.ndarray  # p_E - p_G, level vehicle (m)
    locked_inertia: np.ndarray  # (3, 3) about the CoM, vehicle axes (kg m^2)
    workspace_radius: float
    notes: list[str] = field(default_factory=list)

    def to_json(self) -> dict:
        """Strict JSON (finite numbers only)."""
        g = self.gains.gains
        return finite_or_none({
            "robot": str(self.robot_path), "scenario": str(self.scenario_path),
            "pick_and_place": str(self.pick_and_place_path),
            "vehicle_body": self.discovery.vehicle_body,
            "arm_joints": list(self.discovery.arm_joints),
            "end_effector": self.discovery.end_effector,
            "end_effector_candidates": list(self.discovery.candidates),
            "task": list(self.task),
            "tasks_tried": [{"task": list(t), "score": s} for t, s in self.tasks_tried],
            "nominal_posture": self.posture.q_arm.tolist(),
            "sigma_min_J3": self.posture.sigma_min_J3,
            "joint_margin": self.posture.joint_margin,
            "hover_torque_share": self.posture.hover_torque_share,
            "mass": self.mass, "com_offset": self.com_offset.tolist(),
            "ee_offset": self.ee_offset.tolist(),
            "locked_inertia": self.locked_inertia.tolist(),
            "workspace_radius": self.workspace_radius,
            "limits": {"thrust": list(self.limits.thrust),
                       "body_torque": list(self.limits.body_torque),
                       "joint_effort": list(self.limits.joint_effort)},
            "gains": {"K_x": g.K_x, "D_x": g.D_x, "k_R": g.k_R, "k_w": g.k_w,
                      "Lambda2_bar": g.Lambda2_bar, "K_y": g.K_y, "K_z": g.K_z},
            "task_poles": sorted(float(p.real) for p in self.gains.task_poles),
            "notes": self.notes,
        })


def _unit(text: str, option: str, table: dict) -> np.ndarray | None:
    key = text.strip().lower()
    if key == "any":
        return None
    sign = -1.0 if key.startswith("-") else 1.0
    if key.lstrip("-") in table:
        return sign * np.array(table[key.lstrip("-")], float)
    try:
        v = np.array([float(x) for x in key.split(",")])
    except ValueError:
        v = np.zeros(0)
    if v.size != 3 or not np.all(np.isfinite(v)) or np.linalg.norm(v) == 0:
        raise OnboardingError(f"{option} {text}: give one of {', '.join(table)}, any, or a "
                              "non-zero vector 'x,y,z'", option)
    return v / np.linalg.norm(v)


def task_candidates(arm_joints: tuple[str, ...]) -> list[tuple[str, ...]]:
    """The tasks tried for an arm with these joints (module docstring, step 2)."""
    n = len(arm_joints)
    if n < 3:
        raise OnboardingError(f"the arm has {n} joints: robot init chooses a task for 3 or "
                              "more; give --task (e.g. position_x,position_z)", "--task")
    pose = ("position",) if n < 6 else ("position", "orientation")
    extra = n - 3 * len(pose)
    combos = list(itertools.combinations(arm_joints, extra))
    if len(combos) > MAX_TASK_CANDIDATES:
        raise OnboardingError(f"{len(combos)} ways to choose the task's {extra} joint "
                              f"components of {n} joints: give --task", "--task")
    return [pose + tuple(f"joint:{j}" for j in c) for c in combos]


def _description(d: Discovery, name: str, model_entry: str, task: tuple[str, ...],
                 source: Path) -> RobotDescription:
    ee = (EndEffector(body=d.end_effector) if d.end_effector_is_body
          else EndEffector(frame=d.end_effector))
    # Limits for the first build only (the real ones need the plant's mass).
    return RobotDescription(name=name, models=[model_entry], vehicle_body=d.vehicle_body,
                            arm_joints=list(d.arm_joints), end_effector=ee, task=list(task),
                            limits=Limits(thrust=[0.0, 1.0], body_torque=[1.0, 1.0, 1.0]),
                            source=source)


def _say(stream: TextIO | None, text: str) -> None:
    if stream is not None:
        print(text, file=stream, flush=True)


def init_robot(options: InitOptions, stream: TextIO | None = None) -> InitResult:
    """The steps of the module docstring; returns what was found and written."""
    model = options.model.expanduser().resolve()
    _say(stream, f"robot init: reading {model}")
    found = discover(model, options.vehicle, options.end_effector)
    name = re.sub(r"[^A-Za-z0-9_.-]", "_", options.name or found.model_name)
    out = (options.out or model.parent).expanduser().resolve()
    robot_path, scenario_path = out / f"{name}.robot.yaml", out / f"{name}_hover.yaml"
    for path in (robot_path, scenario_path, out / f"{name}_pick_and_place.yaml"):
        if path.exists() and not options.force:
            raise OnboardingError(f"{path} exists: give --force to overwrite it, or --name/"
                                  "--out to write elsewhere", "--force")
    axis = _unit(options.tool_axis, "--tool-axis", _AXES)
    assert axis is not None
    direction = _unit(options.tool_direction, "--tool-direction", _DIRECTIONS)
    tasks = ([tuple(options.task)] if options.task else task_candidates(found.arm_joints))
    model_entry = Path(str(model)).relative_to(out).as_posix() if model.is_relative_to(
        out) else str(model)
    tried, limits = [], None
    singular: list[tuple[str, ...]] = []  # tasks J_3 cannot hold anywhere
    for task in tasks:
        robot = _description(found, name, model_entry, task, robot_path)
        manip = make_plant(robot=robot)
        if limits is None:
            limits = input_limits(manip, robot, options.thrust_to_weight, options.body_torque)
        robot.limits = Limits(thrust=list(limits.thrust), body_torque=list(limits.body_torque))
        draws = 400 if len(tasks) == 1 else 120
        try:
            posture = choose_posture(manip, tool_axis=axis, direction=direction, draws=draws,
                                     refinements=draws, seed=options.seed)
        except OnboardingError:
            if len(tasks) == 1:
                raise
            _say(stream, f"  task {list(task)}: J_3 singular at every posture drawn")
            singular.append(task)
            continue
        tried.append((task, posture, robot, manip))
        _say(stream, f"  task {list(task)}: sigma_min(J_3) {posture.sigma_min_J3:.4g}, joint "
             f"margin {posture.joint_margin:.2f}")
    if not tried:
        raise OnboardingError(f"no task of {[list(t) for t in tasks]} can be held by this arm "
                              "(J_3 singular at every posture drawn): give --task", "--task")
    assert limits is not None
    sigma_all = max(t[1].sigma_min_J3 for t in tried)

    def key(t) -> float:
        return min(t[1].sigma_min_J3 / sigma_all, t[1].joint_margin)

    task, posture, robot, manip = max(tried, key=key)
    if len(tried) > 1:  # the chosen task's posture, searched as long as a single task's
        posture = choose_posture(manip, tool_axis=axis, direction=direction,
                                 seed=options.seed)
    if direction is not None and posture.pointing_error > 1e-3:
        raise OnboardingError(f"--tool-direction {options.tool_direction}: the arm cannot "
                              f"point its {options.tool_axis} axis there within its joint "
                              f"limits (best: {math.degrees(posture.pointing_error):.1f} deg "
                              "off); give another direction, or any", "--tool-direction")
    robot.nominal_posture = [float(f"{x:.8g}") for x in posture.q_arm]
    manip = make_plant(robot=robot)
    result = _finish(options, found, name, task, tried, key, posture, limits, robot, manip,
                     robot_path, scenario_path, model_entry, stream)
    result.tasks_tried += [(t, 0.0) for t in singular]
    return result


def _finish(options, found, name, task, tried, key, posture, limits, robot, manip,
            robot_path, scenario_path, model_entry, stream) -> InitResult:
    """Steps 5-7 of the module docstring."""
    plant = manip.plant
    ctx = plant.CreateDefaultContext()
    q = plant.GetPositions(ctx)
    q[manip.arm_position_indices] = robot.nominal_posture
    plant.SetPositions(ctx, q)
    p_G = plant.CalcCenterOfMassPositionInWorld(ctx)
    X_WE = manip.end_effector_frame.CalcPoseInWorld(ctx)
    ee_offset = X_WE.translation() - p_G
    com_offset = -ee_offset  # r_o of (33), heading 0
    inertia = locked_inertia(plant, manip.base_body, q)
    length = arm_length(manip, ctx)
    workspace = float(f"{WORKSPACE_SHARE * length:.3g}")
    gains = scaled_gains(manip, q, CONTROLLER_PERIOD)
    mass = manip.total_mass()
    rule = (f"the rule of docs/robots.md: {ROLL_PITCH_SHARE:g} x T_max x R (R = "
            f"{limits.vehicle_radius:.3g} m, from the vehicle's {limits.radius_source}) in roll "
            f"and pitch, {YAW_SHARE:g} of it in yaw" if limits.body_torque_source == "rule"
            else "given (--body-torque)")
    robot_file = RobotFile(
        name=name, model=model_entry, vehicle_body=found.vehicle_body,
        arm_joints=found.arm_joints, end_effector=found.end_effector,
        end_effector_is_body=found.end_effector_is_body, task=task, thrust=limits.thrust,
        thrust_to_weight=options.thrust_to_weight, body_torque=limits.body_torque,
        body_torque_note=f"Body torque bounds: {rule}.", joint_effort=limits.joint_effort,
        nominal_posture=np.array(robot.nominal_posture),
        posture_note=(f"Nominal posture (robot init's search): sigma_min(J_3) "
                      f"{posture.sigma_min_J3:.4g}, joint-limit margin "
                      f"{posture.joint_margin:.2f}, hover torque {posture.hover_torque_share:.0%}"
                      " of the bound; locked inertia about the CoM diag "
                      f"{_list3(np.diag(inertia))} kg m^2."),
        workspace_radius=workspace,
        workspace_note=(f"{WORKSPACE_SHARE:g} x the arm's length along its chain at the "
                        f"nominal posture ({length:.3g} m)."),
        mass=mass)
    quaternion = X_WE.rotation().ToQuaternion()
    hover = HoverFile(
        name=f"{name}_hover", robot_file=robot_path.name, gains=gains.gains,
        gains_note=(f"Table II scaled by robot init's rule (docs/robots.md): K_x, D_x x "
                    f"{mass:.4g} / {gains.paper_mass:.4g} kg; Lambda2_bar = diag Lambda_22 at "
                    "the nominal posture; k_R, k_w: attitude roots 3x the CoM's; K_y, K_z by "
                    f"row kind, K_z lowered on rows {list(gains.capped_rows)} (K_y 30 there) "
                    f"so no task pole passes {0.3 / CONTROLLER_PERIOD:.0f} 1/s (poles "
                    f"{min(-gains.task_poles.real):.3g} to "
                    f"{max(-gains.task_poles.real):.3g} 1/s)."),
        com_offset=com_offset, ee_position=np.array(HOVER_COM) + ee_offset,
        ee_quaternion=np.array([quaternion.w(), quaternion.x(), quaternion.y(),
                                quaternion.z()]))
    hover_yaml = hover_text(hover)
    pick_path = scenario_path.with_name(f"{name}_pick_and_place.yaml")
    robot_path.parent.mkdir(parents=True, exist_ok=True)  # --out may name a new folder
    write_text_atomically(robot_path, robot_text(robot_file))
    write_text_atomically(scenario_path, hover_yaml)
    write_text_atomically(pick_path, pick_and_place_text(hover, hover_yaml))
    # The radius from the reach needs the written files (robot check's subject).
    radius, reaches = reach_radius(scenario_path)
    if not radius > 0:
        raise OnboardingError(
            f"the end effector cannot move from the nominal posture in some direction "
            f"({', '.join(f'{r.direction}: {r.binding}' for r in reaches if r.distance <= 0)})"
            ": give another --tool-direction or --task", "--tool-direction")
    robot_file = dataclasses.replace(robot_file, workspace_radius=radius, workspace_note=(
        f"{REACH_SHARE:g} x the smallest reach of the end effector from the nominal posture "
        f"(robot check): {', '.join(f'{r.direction} {1e3 * r.distance:.0f}' for r in reaches)}"
        " mm."))
    workspace = radius
    write_text_atomically(robot_path, robot_text(robot_file))
    _say(stream, f"  wrote {robot_path.name}, {scenario_path.name} and {pick_path.name}")
    from aerial_drake.simulation.scenarios import load_scenario

    for path in (scenario_path, pick_path):  # what was written loads and validates as a run's
        load_scenario(path)
    return InitResult(
        robot_path=robot_path, scenario_path=scenario_path, pick_and_place_path=pick_path,
        discovery=found, task=task,
        tasks_tried=[(t[0], key(t)) for t in tried], posture=posture, limits=limits,
        gains=gains, mass=mass, com_offset=com_offset, ee_offset=ee_offset,
        locked_inertia=inertia, workspace_radius=workspace)


def _list3(v) -> str:
    return "[" + ", ".join(f"{x:.4g}" for x in v) + "]"


def format_init(r: InitResult) -> str:
    """The result as the command line prints it."""
    g = r.gains.gains
    lines = [f"robot init: {r.robot_path.name}, {r.scenario_path.name} and "
             f"{r.pick_and_place_path.name} in {r.robot_path.parent}",
             f"  vehicle '{r.discovery.vehicle_body}', arm {list(r.discovery.arm_joints)}, end "
             f"effector '{r.discovery.end_effector}' (candidates: "
             f"{', '.join(r.discovery.candidates)})",
             f"  task {list(r.task)}" + (f" (best of {len(r.tasks_tried)} tried)"
                                         if len(r.tasks_tried) > 1 else ""),
             f"  mass {r.mass:.4g} kg; nominal posture {_list3(r.posture.q_arm)} rad: "
             f"sigma_min(J_3) {r.posture.sigma_min_J3:.4g}, joint margin "
             f"{r.posture.joint_margin:.2f}, hover torque {r.posture.hover_torque_share:.0%} "
             "of the bound",
             f"  end effector from the CoM {_list3(r.ee_offset)} m (com_offset r_o = "
             f"{_list3(r.com_offset)}); locked inertia diag {_list3(np.diag(r.locked_inertia))}"
             " kg m^2",
             f"  limits: thrust {_list3(r.limits.thrust)} N, body torque "
             f"{_list3(r.limits.body_torque)} N m, joint effort {_list3(r.limits.joint_effort)}"
             " N m",
             f"  gains: K_x {g.K_x[0]:g}, D_x {g.D_x[0]:g}, k_R {g.k_R:g}, k_w {g.k_w:g}, "
             f"Lambda2_bar {_list3(g.Lambda2_bar)}, K_y {_list3(g.K_y)}, K_z "
             f"{_list3(g.K_z)}; task poles -{min(-r.gains.task_poles.real):.3g} to "
             f"-{max(-r.gains.task_poles.real):.3g} 1/s",
             f"  next: aerial-drake run {r.scenario_path}   and   aerial-drake robot check "
             f"{r.robot_path}"]
    return "\n".join(lines + [f"  note: {n}" for n in r.notes])
