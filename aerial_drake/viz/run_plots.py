"""Figures for the daily loop: one run's own Figs. 3-6, and any runs overlaid.

- :func:`write_run_figures`: what ``aerial-drake run SCENARIO`` writes into the run's folder
  after the simulation (``--no-plots`` skips it): Figs. 3-6 of that run alone, its arm
  joints against their limits (:func:`figure_joint_limits`), and with an environment its
  contact (:mod:`aerial_drake.viz.contact_plots`), as PNG.
- :func:`write_overlay`: ``aerial-drake plot RUN_DIR [RUN_DIR ...]``: Figs. 3-5 with every
  run overlaid, each labelled by its run name (the scenario's name; the folder is added when
  two runs share a name) and each distinct reference drawn dashed with its own legend entry;
  Fig. 6 once per run (``fig6_inputs_<label>``).

The figures themselves are :mod:`aerial_drake.viz.plots`'s; nothing here changes a run's
logs or metrics (the figures are drawn from the files the run wrote).
"""

from __future__ import annotations

import re
from pathlib import Path

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from aerial_drake.simulation.joint_limits import scenario_arm_limits
from aerial_drake.viz.contact_plots import CONTACT_FIGURE, figure_contact
from aerial_drake.viz.plots import (
    DPI,
    FIGURE_NAMES,
    Run,
    figure_com,
    figure_end_effector,
    figure_inputs,
    figure_orientation_errors,
    load_run,
    save_figure,
    series,
)

#: Formats of the figures a run writes for itself (PNG: quick to write and to open).
RUN_FORMATS = ("png",)


#: The run's figure of its arm joints against their limits (:func:`figure_joint_limits`).
JOINT_LIMITS_FIGURE = "joint_limits"


def write_run_figures(run_dir: str | Path, formats: tuple[str, ...] = RUN_FORMATS,
                      ) -> list[Path]:
    """Figs. 3-6 of the run in ``run_dir`` and its joints against their limits
    (``joint_limits``), written into that folder; returns the files."""
    folder = Path(run_dir)
    run = load_run(folder)
    runs = series([run])
    figures = dict(zip(FIGURE_NAMES, (figure_end_effector(runs), figure_com(runs),
                                      figure_orientation_errors(runs), figure_inputs(run))))
    figures[JOINT_LIMITS_FIGURE] = figure_joint_limits(run)
    if "contact_wrench" in run.log:  # an environment (docs/contact.md)
        figures[CONTACT_FIGURE] = figure_contact(run)
    return [p for name, fig in figures.items() for p in save_figure(fig, folder, name, formats)]


def figure_joint_limits(run: Run) -> Figure:
    """Each arm joint's position over its limit (+1 at the upper, -1 at the lower; the ratio
    of metrics.json's ``joint_limits``, signed) and its speed over its limit, over time; the
    dashed lines at +-1 are the limits (past them: outside the arm's range)."""
    limits = scenario_arm_limits(run.scenario)
    x = run.log["plant_state"]
    fig = Figure(figsize=(10.0, 5.6), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 1, sharex=True)
    for ax, ratios, label in ((axes[0], limits.position_ratios(x, signed=True), "q / limit"),
                              (axes[1], limits.velocity_ratios(x, signed=True),
                               "v / v_max")):
        ax.grid(True, color="0.88", linewidth=0.6)
        for i, name in enumerate(limits.names):
            ax.plot(run.t, ratios[:, i], linewidth=1.0, label=name)
        for bound in (-1.0, 1.0):
            ax.axhline(bound, color="0.3", linestyle="--", linewidth=0.9)
        ax.set_ylabel(label)
    axes[0].set_title(f"{run.name}: arm joints against their limits (the model files')")
    axes[0].legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize="small")
    axes[1].set_xlabel("t (s)")
    return fig


def run_labels(runs: list[Run], folders: list[Path]) -> list[str]:
    """Each run's legend label: its name, with its folder where two runs share a name."""
    names = [run.name for run in runs]
    return [name if names.count(name) == 1 else f"{name} ({folder})"
            for name, folder in zip(names, folders)]


def _file_label(label: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", label).strip("_")


def write_overlay(run_dirs: list[str | Path], out_dir: str | Path,
                  formats: tuple[str, ...] = RUN_FORMATS) -> list[Path]:
    """Figs. 3-5 of all runs overlaid and Fig. 6 of each, into ``out_dir``; returns the
    files. Raises FileNotFoundError naming a folder that is not a complete run folder."""
    folders = [Path(d) for d in run_dirs]
    runs = [load_run(folder) for folder in folders]
    labels = run_labels(runs, folders)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    overlaid = series(runs, labels)
    written = []
    for name, figure in zip(FIGURE_NAMES[:3], (figure_end_effector, figure_com,
                                               figure_orientation_errors)):
        written += save_figure(figure(overlaid), out, name, formats)
    for run, label in zip(runs, labels):
        written += save_figure(figure_inputs(run), out, f"{FIGURE_NAMES[3]}_{_file_label(label)}",
                         formats)
    return written
