"""The figure of a run that touched its environment (``contact.png``; docs/contact.md): the
pressing force against the desired one, the path across the push with the contact points
(their travel: the slip), the error across the push with the friction ratio, and what the
coupling does (the vehicle's tilt, the CoM's error along the push).

Drawn from the run's files only: the log's true contact wrench (``contact_wrench``), the
sensor's reading (``measured_contact_force``), the tracking errors and the scenario's force
task (``controller.force``; without one, the contact force's size alone).
"""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from aerial_drake.simulation.contact import contact_slices
from aerial_drake.simulation.contact_metrics import FORCE_EVALUATION_S
from aerial_drake.simulation.run_folder import Run
from aerial_drake.viz.plots import DPI

#: The figure's file name (without extension) in a run's folder.
CONTACT_FIGURE = "contact"
_AXIS = "xyz"


def _grid(ax: Axes) -> None:
    ax.grid(True, color="0.88", linewidth=0.6)


def _tangent_axes(d: np.ndarray) -> tuple[int, int]:
    """The two World axes most across the push direction ``d`` (for a wall along x: y and
    z; for a table: x and y)."""
    order = np.argsort(np.abs(d))
    return tuple(sorted(int(i) for i in order[:2]))  # type: ignore[return-value]


def _shade(ax: Axes, task) -> None:
    h0, h1 = task.hold()
    ax.axvspan(task.start, task.stop, color="0.93", zorder=0)
    ax.axvspan(max(h0, h1 - FORCE_EVALUATION_S), h1, color="#dfe9f5", zorder=0)


def figure_contact(run: Run) -> Figure:
    """The contact figure of ``run`` (module docstring)."""
    s = contact_slices()
    t, wrench = run.t, run.log["contact_wrench"]
    force = wrench[:, s["force"]]
    task = run.scenario.controller.force if run.scenario.controller.type == "paper_force" \
        else None
    fig = Figure(figsize=(11.0, 8.0), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    if task is None:
        ax = fig.subplots(1, 1)
        _grid(ax)
        ax.plot(t, np.linalg.norm(force, axis=1), linewidth=1.0)
        ax.set_ylabel("|contact force| (N)")
        ax.set_xlabel("t (s)")
        ax.set_title(f"{run.name}: the contact force on the end effector")
        return fig
    d = np.asarray(task.unit_direction(), float)
    pressing = -force @ d
    axes = fig.subplots(2, 2)
    # The force: true and measured against the desired one, the goal's +-5 % band.
    ax = axes[0, 0]
    _grid(ax)
    _shade(ax, task)
    desired = run.diagnostic("force_desired")
    if desired is not None:
        ax.plot(t, desired[:, 0], "k--", linewidth=1.0, label="desired")
    if "measured_contact_force" in run.log:
        ax.plot(t, -run.log["measured_contact_force"] @ d, color="0.6", linewidth=0.6,
                label="sensor")
    ax.plot(t, pressing, color="C0", linewidth=1.2, label="true (Drake's contact)")
    for k in (0.95, 1.05):
        ax.axhline(k * task.force, color="C3", linestyle=":", linewidth=0.8)
    ax.set_ylabel(f"pressing force along {np.round(d, 2).tolist()} (N)")
    ax.set_xlabel("t (s)")
    ax.set_title("force (shaded: the window; blue: its judged last 3 s; dotted: +-5 %)")
    ax.legend(loc="upper right", fontsize="small")
    # The path across the push: desired and actual.
    ax = axes[0, 1]
    _grid(ax)
    i, j = _tangent_axes(d)
    p_d, p = run.end_effector()
    ax.plot(p_d[:, i], p_d[:, j], "k--", linewidth=1.0, label="desired")
    ax.plot(p[:, i], p[:, j], color="C0", linewidth=1.2, label="end effector")
    touching = wrench[:, s["contacts"]][:, 0] > 0
    if touching.any():
        pts = wrench[touching][:, s["point"]]
        ax.plot(pts[:, i], pts[:, j], ".", color="C1", markersize=1.5, label="contact point")
    ax.set_xlabel(f"{_AXIS[i]} (m)")
    ax.set_ylabel(f"{_AXIS[j]} (m)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_title("the path across the push (World)")
    ax.legend(loc="best", fontsize="small")
    # The error across the push over time (the slip: the path panel's contact points);
    # the friction ratio.
    ax = axes[1, 0]
    _grid(ax)
    _shade(ax, task)
    across = np.eye(3) - np.outer(d, d)
    error = (p - p_d) @ across
    ax.plot(t, 1e3 * np.linalg.norm(error, axis=1), color="C0", linewidth=1.0,
            label="end effector's error across the push")
    ax.set_ylabel("error across the push (mm)")
    ax.set_xlabel("t (s)")
    ax.set_title("tracking across the push; friction (green)")
    ax.legend(loc="upper left", fontsize="small")
    twin = ax.twinx()
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(touching & (pressing > 0.05 * task.force),
                         np.linalg.norm(force @ across, axis=1) / pressing, np.nan)
    twin.plot(t, ratio, color="C2", linewidth=0.8, alpha=0.7)
    twin.set_ylabel("|F_t| / F_n (green)")
    # The coupling: the vehicle leans against the push.
    ax = axes[1, 1]
    _grid(ax)
    _shade(ax, task)
    ax.plot(t, np.degrees(run.tracking("base_tilt")[:, 0]), color="C4", linewidth=1.0,
            label="vehicle's tilt (deg)")
    x_d, x = run.com()
    ax.plot(t, 1e3 * ((x - x_d) @ d), color="C5", linewidth=1.0,
            label="CoM error along the push (mm)")
    ax.set_xlabel("t (s)")
    ax.set_title("the coupling: the vehicle holds the push")
    ax.legend(loc="upper left", fontsize="small")
    fig.suptitle(f"{run.name}: force task ({task.force:g} N along "
                 f"{np.round(d, 2).tolist()})")
    return fig

