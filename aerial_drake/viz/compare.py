"""Overlay figures of one scenario run with several controllers: the quantities of the paper's
Figs. 3-6, one line per controller (labelled by controller), the disturbance windows shaded.

Files (``.png`` and ``.pdf``): ``compare_fig3_end_effector`` (end-effector position per axis
and the error norm), ``compare_fig4_com`` (the CoM, likewise), ``compare_fig5_orientation_errors``
(base attitude and end-effector orientation errors): :mod:`aerial_drake.viz.plots`' overlays
of Figs. 3-5, in each controller's colour; ``compare_fig6_inputs`` (each applied input, one
line per controller, limits dashed), the one figure of its own. Like
:mod:`aerial_drake.viz.plots`, nothing is recomputed from a model.
"""

from __future__ import annotations

from pathlib import Path

from matplotlib.figure import Figure

from aerial_drake.simulation.metrics import input_names
from aerial_drake.viz import plots
from aerial_drake.viz.plots import FORMATS, Run, Series

COMPARE_FIGURE_NAMES = ("compare_fig3_end_effector", "compare_fig4_com",
                        "compare_fig5_orientation_errors", "compare_fig6_inputs")
#: Line colours by controller name; others cycle through ``_CYCLE``.
CONTROLLER_COLORS = {"paper": "black", "uncoupled": "tab:purple",
                     "static_compensation": "tab:blue"}
_CYCLE = ("tab:green", "tab:purple", "tab:brown", "tab:olive", "tab:cyan")


def controller_series(runs: dict[str, Run]) -> list[Series]:
    """``runs`` ({controller: run}) as :func:`aerial_drake.viz.plots.series`, labelled by
    controller, coloured by :data:`CONTROLLER_COLORS` (others cycle through ``_CYCLE``)."""
    others = iter(_CYCLE * (1 + len(runs)))
    colors = [CONTROLLER_COLORS.get(n) or next(others) for n in runs]
    return plots.series(list(runs.values()), list(runs), colors)


def _titled(fig: Figure, title: str) -> Figure:
    fig.suptitle(title)
    return fig


def figure_end_effector(runs: dict[str, Run], scenario_name: str = "") -> Figure:
    """End-effector position against p_ed, one line per controller (Fig. 3's quantity)."""
    return _titled(plots.figure_end_effector(controller_series(runs)),
                   f"End-effector position, {scenario_name} (Fig. 3)")


def figure_com(runs: dict[str, Run], scenario_name: str = "") -> Figure:
    """Centre of mass against x_d, one line per controller (Fig. 4's quantity)."""
    return _titled(plots.figure_com(controller_series(runs)),
                   f"Centre of mass, {scenario_name} (Fig. 4)")


def figure_orientation_errors(runs: dict[str, Run], scenario_name: str = "") -> Figure:
    """Base attitude error (angle of R_d^T R_b, R_d each controller's own) and end-effector
    orientation error, one line per controller (Fig. 5's quantities)."""
    return _titled(plots.figure_orientation_errors(controller_series(runs)),
                   f"Orientation errors, {scenario_name} (Fig. 5)")


def figure_inputs(runs: dict[str, Run], scenario_name: str = "") -> Figure:
    """Each applied input (thrust, body torques, joint torques), one line per controller,
    its limits dashed (Fig. 6's quantities)."""
    overlaid = controller_series(runs)
    first = overlaid[0][0]
    n_inputs = first.log["applied_command"].shape[1]
    names = list(input_names(n_inputs - 4))
    fig, axes = plots._new_figure(n_inputs, 1.3 * n_inputs + 1.5)
    limits = first.input_limits()
    for k, ax in enumerate(axes):
        for run, color, _ in overlaid:
            ax.plot(run.t, run.log["applied_command"][:, k], color=color, linewidth=0.9)
        for bound in limits.get(names[k], (None, None)):
            plots._draw_limit(ax, bound)
        unit = "N" if k == 0 else "N m"
        ax.set_ylabel(f"{names[k]} ({unit})", fontsize=8)
    windows = plots._shade_all(axes, overlaid)
    fig.suptitle(f"Inputs as applied, {scenario_name}; limits dashed (Fig. 6)")
    plots._legend(fig, plots._run_handles(overlaid) + windows)
    return fig


def write_compare_figures(out_dir: str | Path, runs: dict[str, Run], scenario_name: str = "",
                          formats: tuple[str, ...] = FORMATS) -> list[Path]:
    """Write the four overlays of ``runs`` ({controller: run}) to ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    makers = (figure_end_effector, figure_com, figure_orientation_errors, figure_inputs)
    return [path for name, make in zip(COMPARE_FIGURE_NAMES, makers)
            for path in plots.save_figure(make(runs, scenario_name), out, name, formats)]
