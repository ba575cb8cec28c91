"""Figures of a study's results table (``results.csv``, aerial_drake.studies.table):
histograms of the largest errors, box plots of the errors per phase, and for a two-parameter
grid, maps of stability and peak errors. Errors are of completed runs; a map marks failed
runs."""

from __future__ import annotations

import csv
import math
import re
from pathlib import Path

import numpy as np

QUANTITIES = (("ee_position_error_m", "end-effector position error", 1e3, "mm"),
              ("com_position_error_m", "CoM position error", 1e3, "mm"))


def _read(path: Path) -> tuple[list[str], list[dict[str, str]]]:
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as err:
        raise ValueError(f"{path} is not a study's results table (not UTF-8 text: byte "
                         f"{err.object[err.start]:#04x} at offset {err.start}): give the "
                         "results.csv that 'aerial-drake study' wrote") from None
    if not text.endswith("\n"):  # a cut-short last line (an interrupted study)
        text = text[:text.rfind("\n") + 1]
    reader = csv.DictReader(text.splitlines())
    rows = [r for r in reader if None not in r and None not in r.values()]
    return list(reader.fieldnames or []), rows


def _float(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        return math.nan


def _phases(columns: list[str], quantity: str) -> list[str]:
    pattern = re.compile(rf"phase(\d+)\.{quantity}\.max$")
    found = [(int(m.group(1)), c) for c in columns if (m := pattern.match(c))]
    return [c for _, c in sorted(found)]


def _save(fig, out: Path, stem: str, formats: tuple[str, ...]) -> list[Path]:
    written = []
    for fmt in formats:
        path = out / f"{stem}.{fmt}"
        fig.savefig(path, dpi=120)
        written.append(path)
    return written


def _grid_parameters(columns: list[str], rows: list[dict[str, str]]) -> list[str]:
    """The varied parameters that take few values (a grid's), at most two."""
    params = [c for c in columns if c.startswith("param.")]
    grid = [c for c in params if 1 < len({r[c] for r in rows}) <= 20]
    return grid if len(grid) == 2 and len(grid) == len(params) else []


def write_study_plots(table: str | Path, out: str | Path,
                      formats: tuple[str, ...] = ("png", "svg")) -> list[Path]:
    """Write the figures of ``table`` into ``out``; returns the files. ValueError (before
    any figure) for a table that is not UTF-8, has no rows, no error columns or no completed
    run (its errors are what the figures show)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = Path(table)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such results table (a study's results.csv)")
    columns, rows = _read(path)
    if not rows:
        raise ValueError(f"{path}: no complete row to plot")
    phase_columns = {q: _phases(columns, q) for q, *_ in QUANTITIES}
    if not any(phase_columns.values()):
        raise ValueError(f"{path}: no per-phase error columns (phase*.ee_position_error_m.max"
                         " or phase*.com_position_error_m.max) to plot")
    done = [r for r in rows if r.get("completed") == "true"]
    if not done:
        reasons = sorted({r.get("failure", "")[:120] for r in rows} - {""})
        raise ValueError(f"{path}: none of its {len(rows)} runs completed, so there is no "
                         "error to plot; the failures (its 'failure' column) include: "
                         f"{'; '.join(reasons[:3]) or 'none given'}. Fix the study (see "
                         "'aerial-drake study FILE --show-run 0') and run it again")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    shown = [(q, label, scale, unit) for q, label, scale, unit in QUANTITIES
             if phase_columns[q]]

    fig, axes = plt.subplots(1, len(shown), figsize=(5 * len(shown), 3.6), squeeze=False)
    for ax, (q, label, scale, unit) in zip(axes[0], shown):
        worst = [scale * max(_float(r[c]) for c in phase_columns[q]) for r in done]
        ax.hist([w for w in worst if math.isfinite(w)], bins=30, color="tab:blue")
        ax.set_xlabel(f"largest {label} over the run ({unit})")
        ax.set_ylabel("runs")
    fig.suptitle(f"{path.parent.name}: {len(done)} of {len(rows)} runs completed")
    fig.tight_layout()
    written += _save(fig, out, "histograms", formats)
    plt.close(fig)

    fig, axes = plt.subplots(1, len(shown), figsize=(5 * len(shown), 3.6), squeeze=False)
    for ax, (q, label, scale, unit) in zip(axes[0], shown):
        data = [[scale * _float(r[c]) for r in done if math.isfinite(_float(r[c]))]
                for c in phase_columns[q]]
        ax.boxplot(data)
        ax.set_xticks(range(1, len(data) + 1), [f"phase {k}" for k in range(len(data))])
        if any(x > 0 for column in data for x in column):  # (else nothing to log-scale)
            ax.set_yscale("log")
        ax.set_ylabel(f"max {label} ({unit})")
    fig.tight_layout()
    written += _save(fig, out, "box_per_phase", formats)
    plt.close(fig)

    grid = _grid_parameters(columns, rows)
    if grid:
        written += _write_maps(plt, rows, grid, shown, phase_columns, out, formats)
    return written


def _write_maps(plt, rows, grid, shown, phase_columns, out: Path,
                formats: tuple[str, ...]) -> list[Path]:
    """Stability and each quantity's largest error over the grid of two parameters."""
    a, b = grid
    xs = sorted({_float(r[a]) for r in rows})
    ys = sorted({_float(r[b]) for r in rows})
    panels = [("completed (1) or failed (0)", None, 1.0)] + [
        (f"largest {label} ({unit}), log10", q, scale) for q, label, scale, unit in shown]
    fig, axes = plt.subplots(1, len(panels), figsize=(4.6 * len(panels), 3.8), squeeze=False)
    for ax, (title, q, scale) in zip(axes[0], panels):
        grid_values = np.full((len(ys), len(xs)), np.nan)
        for r in rows:
            i, j = ys.index(_float(r[b])), xs.index(_float(r[a]))
            if q is None:
                grid_values[i, j] = 1.0 if r["completed"] == "true" else 0.0
            elif r["completed"] == "true":
                worst = scale * max(_float(r[c]) for c in phase_columns[q])
                grid_values[i, j] = math.log10(worst) if worst > 0 else np.nan
        image = ax.imshow(grid_values, origin="lower", cmap="RdYlGn" if q is None
                          else "viridis", aspect="auto")
        ax.set_xticks(range(len(xs)), [f"{x:g}" for x in xs])
        ax.set_yticks(range(len(ys)), [f"{y:g}" for y in ys])
        ax.set_xlabel(a.removeprefix("param."))
        ax.set_ylabel(b.removeprefix("param."))
        ax.set_title(title, fontsize=9)
        fig.colorbar(image, ax=ax)
    fig.tight_layout()
    written = _save(fig, out, "maps", formats)
    plt.close(fig)
    return written
