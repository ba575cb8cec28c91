"""The text of ``robot check``'s report (:func:`format_check`): units, the binding limit per
direction, the warnings last."""

from __future__ import annotations

import numpy as np

from aerial_drake.analysis.onboarding.check import RobotCheck
from aerial_drake.analysis.onboarding.margins import Margin


def _margins(title: str, margins: list[Margin], show_deflection: bool) -> list[str]:
    if not margins:
        return []
    lines = [title]
    for m in margins:
        size = f"{'>= ' if m.capped else ''}{m.largest:.4g} {m.unit}"
        extra = ""
        if show_deflection:
            extra = (f", CoM moved {1000 * np.linalg.norm(m.com_deflection):.1f} mm, end "
                     f"effector {1000 * np.linalg.norm(m.ee_displacement):.1f} mm")
        near = ""
        if m.state is not None:
            name, usage = m.state.nearest
            near = f"; nearest there: {name} at {100 * usage:.0f} %"
        binding = "nothing up to the search's cap" if m.capped else m.binding
        lines.append(f"  {m.direction}: {size}{extra}; past it: {binding}{near}")
    return lines


def format_check(report: RobotCheck) -> str:
    """The readable report of :func:`~aerial_drake.analysis.onboarding.check.check_robot`."""
    s, model = report.subject, report.subject.model
    names = [j.name() for j in model.arm_joints]
    q_arm = s.q0[model.arm_position_indices]
    lines = [
        f"robot check: {model.description.name} ({s.file}), gains and hover from "
        f"{s.scenario_source}",
        f"  mass {s.mass:.4g} kg, weight {s.weight:.4g} N; task "
        f"{list(model.task.components) if model.task else []}; directions in the heading "
        "frame [b1d, e3 x b1d, e3]",
        "nominal posture: " + ", ".join(f"{n} {v:.3f}" for n, v in zip(names, q_arm))
        + " rad",
        f"  sigma_min(J_3) = {report.rest.sigma_min:.4g} (Assumption-1 limit "
        f"{report.sigma_limit:g}: {report.rest.sigma_min / report.sigma_limit:.3g}x)",
        f"  command at rest: thrust {report.rest.command[0]:.4g} N, body torques "
        f"{np.round(report.rest.command[1:4], 3).tolist()} N m, joint torques "
        f"{np.round(report.rest.command[4:], 3).tolist()} N m",
        f"reach of the end effector, CoM held (workspace_radius {report.workspace_radius:g} m):",
    ]
    for r in report.reach:
        lines.append(f"  {r.direction}: {'>= ' if r.capped else ''}{1000 * r.distance:.0f} mm"
                     f"; then {r.binding or 'the search cap'}")
    c = report.com_compliance
    lines += _margins(
        "largest static push on the vehicle (the CoM settles at about "
        f"[{1000 * c[0]:.3g}, {1000 * c[1]:.3g}, {1000 * c[2]:.3g}] mm/N along x, y, z):",
        report.push, True)
    lines += _margins("largest force held at the end effector:", report.ee_force, True)
    lines += _margins("largest torque held at the end effector:", report.ee_torque, False)
    lr = report.loop_roots
    lines.append("closed-loop roots at the hover (predicted, docs/analysis.md):")
    for group in ("com", "attitude", "task_y", "task_z"):
        values = [r["value"] for r in report.roots if r["group"] == group]
        shown = ", ".join(f"{v.real:.4g}" if abs(v.imag) < 1e-9 else
                          f"{v.real:.4g}{v.imag:+.4g}j" for v in values)
        lines.append(f"  {group}: {shown}")
    lines.append(f"  slowest attitude root {lr.slowest_attitude.real:.4g} 1/s, slowest CoM "
                 f"root {lr.slowest_com.real:.4g} 1/s: separation {lr.separation:.2f}x")
    if report.warnings:
        lines.append("warnings:")
        lines += [f"  - {w}" for w in report.warnings]
    else:
        lines.append("no warnings")
    return "\n".join(lines)
