"""Overlay figures of one scenario run with several controllers: the quantities of the paper's
Figs. 3-6, one line per controller (labelled by controller), the disturbance windows shaded.

Files (``.png`` and ``.pdf``): ``compare_fig3_end_effector`` (end-effector position per axis
and the error norm), ``compare_fig4_com`` (the CoM, likewise), ``compare_fig5_orientation_errors``
(base attitude and end-effector orientation errors), ``compare_fig6_inputs`` (each applied
input, limits dashed). Like :mod:`aerial_drake.viz.plots`, nothing is recomputed from a model.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from aerial_drake.simulation.metrics import INPUT_NAMES
from aerial_drake.viz.plots import (
    DESIRED_COLOR,
    FORMATS,
    Run,
    _draw_limit,
    _legend,
    _new_figure,
    _shade_windows,
)

COMPARE_FIGURE_NAMES = ("compare_fig3_end_effector", "compare_fig4_com",
                        "compare_fig5_orientation_errors", "compare_fig6_inputs")
#: Line colours by controller name; others cycle through ``_CYCLE``.
CONTROLLER_COLORS = {"paper": "black", "uncoupled": "tab:purple",
                     "static_compensation": "tab:blue"}
_CYCLE = ("tab:green", "tab:purple", "tab:brown", "tab:olive", "tab:cyan")


def _colors(names: list[str]) -> dict[str, str]:
    others = iter(_CYCLE * (1 + len(names)))
    return {n: CONTROLLER_COLORS.get(n) or next(others) for n in names}


def _handles(colors: dict[str, str], desired: bool) -> list:
    handles = [Line2D([], [], color=c, linewidth=1.4, label=n) for n, c in colors.items()]
    if desired:
        handles.insert(0, Line2D([], [], color=DESIRED_COLOR, linestyle="--", linewidth=1.2,
                                 label="desired"))
    return handles


def _t_end(runs: dict[str, Run]) -> float:
    return max(float(r.t[-1]) if len(r.t) else 0.0 for r in runs.values())


def _first(runs: dict[str, Run]) -> Run:
    return next(iter(runs.values()))


def _position_overlay(runs: dict[str, Run], which: str, title: str, symbol: str) -> Figure:
    colors = _colors(list(runs))
    fig, axes = _new_figure(4, 9.5)
    longest = max(runs.values(), key=lambda r: len(r.t))
    desired, _ = getattr(longest, which)()
    for i, ax in enumerate(axes[:3]):
        ax.plot(longest.t, desired[:, i], color=DESIRED_COLOR, linestyle="--", linewidth=1.0,
                zorder=3)
        ax.set_ylabel(f"{symbol} {'xyz'[i]} (m)")
    for name, run in runs.items():
        d, actual = getattr(run, which)()
        for i, ax in enumerate(axes[:3]):
            ax.plot(run.t, actual[:, i], color=colors[name], linewidth=1.1)
        error = 1e3 * np.linalg.norm(actual - d, axis=1)
        axes[3].semilogy(run.t, np.maximum(error, 1e-4), color=colors[name], linewidth=1.0)
    axes[3].set_ylabel("|error| (mm)")
    axes[3].set_ylim(bottom=1e-3)
    windows = _shade_windows(axes, _first(runs).scenario, _t_end(runs))
    fig.suptitle(title)
    _legend(fig, _handles(colors, desired=True) + windows)
    return fig


def figure_end_effector(runs: dict[str, Run], scenario_name: str = "") -> Figure:
    """End-effector position against p_ed, one line per controller (Fig. 3's quantity)."""
    return _position_overlay(runs, "end_effector",
                             f"End-effector position, {scenario_name} (Fig. 3)", "$p_E$")


def figure_com(runs: dict[str, Run], scenario_name: str = "") -> Figure:
    """Centre of mass against x_d, one line per controller (Fig. 4's quantity)."""
    return _position_overlay(runs, "com", f"Centre of mass, {scenario_name} (Fig. 4)", "$x_g$")


def figure_orientation_errors(runs: dict[str, Run], scenario_name: str = "") -> Figure:
    """Base attitude error (angle of R_d^T R_b, R_d each controller's own) and end-effector
    orientation error, one line per controller (Fig. 5's quantities)."""
    colors = _colors(list(runs))
    fig, axes = _new_figure(2, 6.0)
    for name, run in runs.items():
        axes[0].plot(run.t, run.diagnostic("base_attitude_error")[:, 0], color=colors[name],
                     linewidth=1.1)
        axes[1].plot(run.t, run.diagnostic("ee_orientation_error")[:, 0], color=colors[name],
                     linewidth=1.1)
    axes[0].set_ylabel("base attitude error\nangle of $R_d^T R_b$ (rad)")
    axes[1].set_ylabel("end-effector orientation error\nangle of $R_E R_{ed}^T$ (rad)")
    for ax in axes:
        ax.set_ylim(bottom=0.0)
    windows = _shade_windows(axes, _first(runs).scenario, _t_end(runs))
    fig.suptitle(f"Orientation errors, {scenario_name} (Fig. 5)")
    _legend(fig, _handles(colors, desired=False) + windows)
    return fig


def figure_inputs(runs: dict[str, Run], scenario_name: str = "") -> Figure:
    """Each applied input (thrust, body torques, joint torques), one line per controller,
    its limits dashed (Fig. 6's quantities)."""
    colors = _colors(list(runs))
    n_inputs = _first(runs).log["applied_command"].shape[1]
    names = list(INPUT_NAMES[:n_inputs])
    fig, axes = _new_figure(n_inputs, 1.3 * n_inputs + 1.5)
    limits = _first(runs).input_limits()
    for k, ax in enumerate(axes):
        for name, run in runs.items():
            ax.plot(run.t, run.log["applied_command"][:, k], color=colors[name], linewidth=0.9)
        for bound in limits.get(names[k], (None, None)):
            _draw_limit(ax, bound)
        unit = "N" if k == 0 else "N m"
        ax.set_ylabel(f"{names[k]} ({unit})", fontsize=8)
    windows = _shade_windows(axes, _first(runs).scenario, _t_end(runs))
    fig.suptitle(f"Inputs as applied, {scenario_name}; limits dashed (Fig. 6)")
    _legend(fig, _handles(colors, desired=False) + windows)
    return fig


def write_compare_figures(out_dir: str | Path, runs: dict[str, Run], scenario_name: str = "",
                          formats: tuple[str, ...] = FORMATS) -> list[Path]:
    """Write the four overlays of ``runs`` ({controller: run}) to ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    makers = (figure_end_effector, figure_com, figure_orientation_errors, figure_inputs)
    written = []
    for name, make in zip(COMPARE_FIGURE_NAMES, makers):
        fig = make(runs, scenario_name)
        for fmt in formats:
            path = out / f"{name}.{fmt}"
            fig.savefig(path, format=fmt)
            written.append(path)
    return written
