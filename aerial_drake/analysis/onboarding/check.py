"""``robot check FILE``: the margins at the nominal posture (docs/robots.md, "robot check").

- sigma_min(J_3) at the posture against the scenario's Assumption-1 limit;
- the reach along +-x, +-y, +-z of the heading frame (:mod:`.reach`) against the
  description's ``workspace_radius``;
- the push margins: the largest constant force on the vehicle along each direction whose
  static equilibrium under the paper's law keeps every limit (:mod:`.margins`,
  :mod:`.loaded_rest`), with the CoM's deflection there and the binding limit;
- the wrench the arm can hold: the same for a force, and a torque, at the end effector;
- the closed loop's roots at the hover (:func:`~aerial_drake.analysis.linearization.
  predicted_eigenvalues`) and the CoM/attitude separation
  (:mod:`aerial_drake.control.gain_design`);
- warnings where a margin is tight (the thresholds below).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TextIO

import numpy as np

from aerial_drake.analysis.linearization import predicted_eigenvalues
from aerial_drake.analysis.onboarding.check_subject import CheckSubject, load_subject
from aerial_drake.analysis.onboarding.loaded_rest import RestLoop, RestState
from aerial_drake.analysis.onboarding.margins import Margin, direction_margins
from aerial_drake.analysis.onboarding.reach import Reach, reach
from aerial_drake.control.gain_design import LoopRoots, gain_design_message, loop_roots
from aerial_drake.simulation.outputs import finite_or_none

#: sigma_min(J_3) at the posture within this factor of the limit is tight.
SIGMA_TIGHT_FACTOR = 1.5
#: A push margin below this fraction of the robot's weight m g is tight.
PUSH_TIGHT_WEIGHTS = 0.1
#: An end-effector force margin below this fraction of the weight is tight.
EE_FORCE_TIGHT_WEIGHTS = 0.05
#: A closed-loop root faster than this fraction of the sampling rate 1 / controller_period
#: (rad/s) is near what the sampling survives (docs/robots.md, "Flying your own robot"; the
#: paper's own attitude root about b2, -554 1/s at 1 kHz, is within it).
FAST_ROOT_SAMPLING = 1.0


@dataclass(frozen=True)
class RobotCheck:
    """The report of :func:`check_robot`."""

    subject: CheckSubject
    rest: RestState  # the loop at rest at the nominal posture
    reach: list[Reach]
    push: list[Margin]
    ee_force: list[Margin]
    ee_torque: list[Margin]
    roots: list[dict]  # predicted_eigenvalues at the hover
    loop_roots: LoopRoots
    com_compliance: np.ndarray  # (3) m/N: the CoM's static deflection per N, heading axes
    warnings: list[str]

    @property
    def sigma_limit(self) -> float:
        return float(self.subject.scenario.sigma_min_J3_limit)

    @property
    def workspace_radius(self) -> float:
        return float(self.subject.model.description.workspace_radius)

    def to_json(self) -> dict:
        """Strict JSON (no NaN or infinity)."""
        s, model = self.subject, self.subject.model
        return finite_or_none({
            "file": str(s.file), "scenario": s.scenario_source,
            "robot": model.description.name, "mass_kg": s.mass, "weight_N": s.weight,
            "task": list(model.task.components) if model.task else [],
            "posture": {"arm_joints_rad": s.q0[model.arm_position_indices].tolist(),
                        "joint_names": [j.name() for j in model.arm_joints],
                        "sigma_min_J3": self.rest.sigma_min,
                        "sigma_min_J3_limit": self.sigma_limit,
                        "command": self.rest.command.tolist()},
            "workspace_radius_m": self.workspace_radius,
            "reach": [r.to_json() for r in self.reach],
            "push": [m.to_json() for m in self.push],
            "ee_force": [m.to_json() for m in self.ee_force],
            "ee_torque": [m.to_json() for m in self.ee_torque],
            "com_compliance_m_per_N": self.com_compliance.tolist(),
            "roots": [{"group": r["group"], "label": r["label"],
                       "value": [r["value"].real, r["value"].imag]} for r in self.roots],
            "attitude_separation": self.loop_roots.separation,
            "warnings": list(self.warnings)})


def com_compliance(subject: CheckSubject) -> np.ndarray:
    """The CoM's static deflection per newton of push along the heading axes (m/N) under the
    paper's law, one-axis model (docs/control.md): ``(1 + (Lbar2 K_x + k_w D_x) / (k_R m))
    / K_x`` horizontally (the feed-forwards miss ``F / m``, and the attitude error this
    leaves holds the thrust short of the tilt ``f_d`` asks for; ``Lbar2`` of the axis the
    push tilts about: b2 for x, b1 for y) and ``1 / K_x`` along z (no tilt)."""
    g, m = subject.scenario.gains, subject.mass
    K, D, L = (np.asarray(g.K_x, float), np.asarray(g.D_x, float),
               np.asarray(g.Lambda2_bar, float))
    tilt = np.array([L[1], L[0]])
    horizontal = (1.0 + (tilt * K[:2] + g.k_w * D[:2]) / (g.k_R * m)) / K[:2]
    return np.array([horizontal[0], horizontal[1], 1.0 / K[2]])


def _say(stream: TextIO | None, text: str) -> None:
    if stream is not None:
        stream.write(text + "\n")
        stream.flush()


def check_robot(file: Path, scenario: str | None = None, stream: TextIO | None = None,
                *, torques: bool = True, directions: tuple[str, ...] | None = None
                ) -> RobotCheck:
    """The margins of ``robot check FILE [--scenario S]`` (module docstring); progress lines
    on ``stream``. ``torques``: also the end-effector torques (six more searches);
    ``directions``: the force and torque margins along these only (default: the six).

    Raises:
        OnboardingError: FILE or S missing, the hover point unreachable (exit status 2).
    """
    subject = load_subject(Path(file), scenario)
    loop = RestLoop(subject)
    rest = loop.limits_at(subject.q0)
    _say(stream, f"robot check: {subject.model.description.name} at the hover of "
                 f"{subject.scenario_source}; sigma_min(J_3) = {rest.sigma_min:.4g}")
    _say(stream, "reach along the heading axes ...")
    reaches = reach(subject)
    _say(stream, "push margins on the vehicle (an equilibrium per step) ...")
    push = direction_margins(loop, "vehicle push", stream, directions)
    _say(stream, "end-effector force margins ...")
    ee_force = direction_margins(loop, "end-effector force", stream, directions)
    ee_torque: list[Margin] = []
    if torques:
        _say(stream, "end-effector torque margins ...")
        ee_torque = direction_margins(loop, "end-effector torque", stream, directions)
    x = np.concatenate([subject.q0, np.zeros(subject.model.plant.num_velocities())])
    Lambda_z = loop.controller.solve(x, *subject.references).Lambda_z
    gains = subject.scenario.gains
    roots = predicted_eigenvalues(subject.mass, gains, Lambda_z)
    lr = loop_roots(subject.mass, gains.K_x, gains.D_x, gains.k_R, gains.k_w,
                    gains.Lambda2_bar)
    report = RobotCheck(subject=subject, rest=rest, reach=reaches, push=push,
                        ee_force=ee_force, ee_torque=ee_torque, roots=roots, loop_roots=lr,
                        com_compliance=com_compliance(subject), warnings=[])
    report.warnings.extend(check_warnings(report))
    return report


def check_warnings(report: RobotCheck) -> list[str]:
    """The warnings of the report: tight margins and slow or fast roots (the thresholds of
    this module)."""
    s = report.subject
    out = []
    if s.scenario.controller.type != "paper":
        out.append(f"the scenario's controller is '{s.scenario.controller.type}'; the margins "
                   "are the paper's law's")
    if not report.rest.ok:
        out.append("at the nominal posture itself: " + "; ".join(report.rest.violated))
    if report.rest.sigma_min < SIGMA_TIGHT_FACTOR * report.sigma_limit:
        out.append(f"sigma_min(J_3) = {report.rest.sigma_min:.3g} at the posture is within "
                   f"{SIGMA_TIGHT_FACTOR:g}x of the Assumption-1 limit {report.sigma_limit:g}")
    short = [r for r in report.reach if r.distance < report.workspace_radius]
    if short:
        out.append("reach below the workspace_radius "
                   f"{report.workspace_radius:g} m along "
                   + ", ".join(f"{r.direction} ({r.distance:.3g} m: {r.binding})"
                               for r in short))
    for margins, fraction, what in ((report.push, PUSH_TIGHT_WEIGHTS, "push on the vehicle"),
                                    (report.ee_force, EE_FORCE_TIGHT_WEIGHTS,
                                     "force at the end effector")):
        tight = [m for m in margins if m.largest < fraction * s.weight]
        if tight:
            out.append(f"the largest {what} is below {fraction:g} m g "
                       f"({fraction * s.weight:.3g} N) along "
                       + ", ".join(f"{m.direction} ({m.largest:.3g} N: {m.binding})"
                                   for m in tight))
    message = gain_design_message(report.loop_roots, "(gains.Lambda2_bar, by (16))")
    if message is not None:
        out.append(message)
    period = float(s.scenario.controller_period)
    if period > 0:
        fastest = max(report.roots, key=lambda r: abs(r["value"]))
        if abs(fastest["value"]) > FAST_ROOT_SAMPLING / period:
            fix = {"task_z": "lower that row's K_z", "task_y": "lower that row's K_y",
                   "attitude": "lower k_R and k_w, or raise Lambda2_bar",
                   "com": "lower K_x and D_x"}.get(fastest["group"], "lower its gains")
            out.append(f"the fastest closed-loop root, {fastest['label']} = "
                       f"{fastest['value'].real:.4g} 1/s, is beyond {FAST_ROOT_SAMPLING:g} / "
                       f"controller_period = {FAST_ROOT_SAMPLING / period:.4g} rad/s: {fix}")
    return out
