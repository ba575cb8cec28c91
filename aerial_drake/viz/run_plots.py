"""Figures for the daily loop: one run's own Figs. 3-6, and any runs overlaid.

- :func:`write_run_figures`: what ``aerial-drake run SCENARIO`` writes into the run's folder
  after the simulation (``--no-plots`` skips it): Figs. 3-6 of that run alone, as PNG.
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

from aerial_drake.viz.plots import (
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


def write_run_figures(run_dir: str | Path, formats: tuple[str, ...] = RUN_FORMATS,
                      ) -> list[Path]:
    """Figs. 3-6 of the run in ``run_dir``, written into that folder; returns the files."""
    folder = Path(run_dir)
    run = load_run(folder)
    runs = series([run])
    figures = dict(zip(FIGURE_NAMES, (figure_end_effector(runs), figure_com(runs),
                                      figure_orientation_errors(runs), figure_inputs(run))))
    return [p for name, fig in figures.items() for p in save_figure(fig, folder, name, formats)]


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
