"""The paper's Figs. 3-6 from the run folders written by :mod:`aerial_drake.simulation.runner`.

A run folder holds ``log.npz`` (the logged ports), ``metrics.json`` and ``scenario.yaml`` (the
scenario as run); :func:`aerial_drake.simulation.run_folder.load_run` reads it (without
matplotlib; :class:`Run` and :func:`load_run` are re-exported here). From a nominal and,
optionally, a disturbed run this module writes

- ``fig3_end_effector``: end-effector position, desired and actual, x/y/z, and the error norm;
- ``fig4_com``: centre of mass position, desired and actual, x/y/z, and the error norm;
- ``fig5_orientation_errors``: base attitude error (top) and end-effector orientation error
  (bottom), as rotation angles;
- ``fig6_inputs``: thrust, body torques and each joint torque that reached the nominal plant,
  each with its own limits dashed, over the whole run and over its first 50 ms;

each as ``.png`` and ``.pdf``. As in the paper: nominal black, disturbed grey (each labelled
by its run's name), the disturbance on the helicopter shaded green and the one at the end
effector orange (the windows of every run's scenario, each once; with several runs each
window's legend entry names the runs whose window it is). :func:`series` colours and
labels any number of runs for Figs. 3-5 (``aerial-drake plot``, :mod:`aerial_drake.viz.run_plots`).

Nothing is recomputed from the model: the actual CoM and end-effector positions are the
reference plus the logged tracking errors (``x_tilde = x_g - x_d``, ``y_tilde[:3] = p_E -
p_ed``, :mod:`aerial_drake.simulation.tracking`; :class:`~aerial_drake.simulation.run_folder.Run`),
which is exact, and the orientation errors are the logged angles: the end effector's from the
tracking errors, the base's (against the attitude the controller commands) from the
controller's diagnostics, drawn for the runs whose controller reports it. Rendering uses
Matplotlib's Agg canvas directly (no pyplot, no global backend switch), so it works without a
display.

Command line: ``python -m aerial_drake.viz.plots NOMINAL_DIR [DISTURBED_DIR] [--out DIR]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from aerial_drake.simulation.metrics import input_names
from aerial_drake.simulation.run_folder import Run, load_run
from aerial_drake.simulation.scenarios import Scenario

FIGURE_NAMES = ("fig3_end_effector", "fig4_com", "fig5_orientation_errors", "fig6_inputs")
FORMATS = ("png", "pdf")

# The paper's colours (Section IV-B, Figs. 3-6).
NOMINAL_COLOR = "black"
DISTURBED_COLOR = "0.6"
DESIRED_COLOR = "tab:red"
WINDOW_COLORS = {"vehicle": ("tab:green", 0.18), "end_effector": ("tab:orange", 0.22)}
WINDOW_LABELS = {"vehicle": "force on the vehicle",
                 "end_effector": "wrench at the end effector"}
JOINT_COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown",
                "tab:pink")
DPI = 120


# --- Figure helpers -------------------------------------------------------------------------
def _new_figure(rows: int, height: float) -> tuple[Figure, list]:
    fig = Figure(figsize=(9.0, height), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(rows, 1, sharex=True, squeeze=False)[:, 0]
    for ax in axes:
        ax.grid(True, color="0.88", linewidth=0.6)
        ax.margins(x=0)
    axes[-1].set_xlabel("time t (s)")
    return fig, list(axes)


def _shade_windows(axes, scenario: Scenario, t_end: float,
                   owners: dict[tuple, list[str]] | None = None) -> list:
    """Shade the disturbance windows that start before ``t_end``, limit the time axis to
    [0, t_end]; return legend handles, one per window (one per target beyond
    :data:`LEGEND_WINDOWS` of it). ``owners``: the labels of the runs each window ``(target,
    start, stop)`` belongs to, named in its legend entry."""
    axes[0].set_xlim(0.0, max(t_end, 1e-3))
    shown: dict[str, list] = {}
    for d in scenario.disturbances:
        if d.start >= t_end:
            continue
        color, alpha = WINDOW_COLORS.get(d.target, ("tab:gray", 0.2))
        for ax in axes:
            ax.axvspan(d.start, d.stop, color=color, alpha=alpha, linewidth=0, zorder=0)
        shown.setdefault(d.target, []).append(d)
    handles = []
    for target, windows in shown.items():
        color, alpha = WINDOW_COLORS.get(target, ("tab:gray", 0.2))
        name = WINDOW_LABELS.get(target, target)
        if len(windows) > LEGEND_WINDOWS:  # many windows: one entry, not a legend of hundreds
            whose = sorted({o for d in windows for o in (owners or {}).get(
                (d.target, d.start, d.stop), [])})
            labels = [f"{name} ({len(windows)} windows, {min(d.start for d in windows):g}-"
                      f"{max(d.stop for d in windows):g} s)"
                      + (f" of {', '.join(whose)}" if whose else "")]
        else:
            labels = [f"{name} ({d.start:g}-{d.stop:g} s)"
                      + (f" of {', '.join(owners[(d.target, d.start, d.stop)])}" if owners
                         else "") for d in windows]
        handles += [Patch(color=color, alpha=alpha + 0.1, label=label) for label in labels]
    return handles


#: Windows of one target named one by one in a legend; more share one entry.
LEGEND_WINDOWS = 6


#: Colours of the runs in order: the paper's black and grey first, then Matplotlib's.
RUN_COLORS = (NOMINAL_COLOR, DISTURBED_COLOR, "tab:blue", "tab:purple", "tab:olive",
              "tab:cyan", "tab:brown")
#: Colours of the distinct references, in order (dashed).
DESIRED_COLORS = (DESIRED_COLOR, "tab:pink", "darkgoldenrod", "tab:gray")

#: One curve set of a figure: the run, its colour and its legend label.
Series = tuple[Run, str, str]


def series(runs: list[Run], labels: list[str] | None = None,
           colors: list[str] | None = None) -> list[Series]:
    """Colour and label each of ``runs`` (labels default to the runs' names, colours to
    :data:`RUN_COLORS` in order)."""
    labels = labels if labels is not None else [run.name for run in runs]
    colors = colors if colors is not None else [RUN_COLORS[k % len(RUN_COLORS)]
                                                for k in range(len(runs))]
    return list(zip(runs, colors, labels))


def _runs(nominal: Run, disturbed: Run | None) -> list[Series]:
    """The paper's pair, black and grey, each labelled by its run's name (the paper run's are
    "nominal" and "disturbed"); "nominal"/"disturbed" if the two share a name."""
    runs = [nominal] + ([disturbed] if disturbed is not None else [])
    names = [run.name for run in runs]
    return series(runs, None if len(set(names)) == len(names) else
                  ["nominal", "disturbed"][:len(runs)])


def _as_series(first, second) -> list[Series]:
    """The figures take (nominal, disturbed) runs, or a list of :data:`Series`."""
    return first if isinstance(first, list) else _runs(first, second)


def _t_end(runs) -> float:
    return max(float(run.t[-1]) for run, _, _ in runs)


def _shade_all(axes, runs: list[Series]) -> list:
    """Shade every run's disturbance windows once (the union), see :func:`_shade_windows`;
    with several runs each window's legend entry names the runs it belongs to."""
    owners: dict[tuple, list[str]] = {}
    windows = []
    for run, _, label in runs:
        for d in run.scenario.disturbances:
            key = (d.target, d.start, d.stop)
            if key not in owners:
                owners[key] = []
                windows.append(d)
            if label not in owners[key]:
                owners[key].append(label)
    union = dataclasses.replace(runs[0][0].scenario, disturbances=windows)
    return _shade_windows(axes, union, _t_end(runs), owners if len(runs) > 1 else None)


def _legend(fig: Figure, handles: list) -> None:
    if not handles:
        return
    fig.legend(handles=handles, loc="outside lower center", ncol=min(len(handles), 3),
               fontsize=9, frameon=False)


def _run_handles(runs, desired: list | None = None) -> list:
    """Legend entries: the references drawn (``desired``), then one per run."""
    handles = [Line2D([], [], color=c, linewidth=1.4, label=label) for _, c, label in runs]
    return list(desired or []) + handles


def _position_figure(runs: list[Series], which: str, title: str, symbol: str) -> Figure:
    """Figs. 3 and 4: desired and actual positions per axis, then the error norm (log).

    Each distinct reference is drawn once, dashed, in its own colour; its legend entry names
    the runs that track it ("desired" alone when every run tracks the same one)."""
    fig, axes = _new_figure(4, 9.5)
    references: list[tuple[np.ndarray, list[str], str]] = []  # (desired, labels, colour)
    for run, color, label in runs:
        desired, actual = getattr(run, which)()
        for i, ax in enumerate(axes[:3]):
            ax.plot(run.t, actual[:, i], color=color, linewidth=1.2)
        error = 1e3 * np.linalg.norm(actual - desired, axis=1)
        axes[3].semilogy(run.t, np.maximum(error, 1e-4), color=color, linewidth=1.0)
        same = next((r for r in references
                     if len(r[0]) == len(desired) and np.allclose(r[0], desired)), None)
        if same is not None:
            same[1].append(label)
            continue
        ref_color = DESIRED_COLORS[len(references) % len(DESIRED_COLORS)]
        for i, ax in enumerate(axes[:3]):
            ax.plot(run.t, desired[:, i], color=ref_color, linestyle="--", linewidth=1.0,
                    zorder=3)
        references.append((desired, [label], ref_color))
    for i, ax in enumerate(axes[:3]):
        ax.set_ylabel(f"{symbol} {'xyz'[i]} (m)")
    axes[3].set_ylabel("|error| (mm)")
    axes[3].set_ylim(bottom=1e-3)
    windows = _shade_all(axes, runs)
    fig.suptitle(title)
    desired_handles = [
        Line2D([], [], color=c, linestyle="--", linewidth=1.2,
               label="desired" if len(references) == 1 else f"desired ({', '.join(labels)})")
        for _, labels, c in references]
    _legend(fig, _run_handles(runs, desired_handles) + windows)
    return fig


def figure_end_effector(nominal: Run | list[Series], disturbed: Run | None = None) -> Figure:
    """Fig. 3: end-effector position p_E against p_ed (World); ``nominal`` may be a list of
    :data:`Series` (any runs, see :func:`series`)."""
    return _position_figure(_as_series(nominal, disturbed), "end_effector",
                            "End-effector position (Fig. 3)", "$p_E$")


def figure_com(nominal: Run | list[Series], disturbed: Run | None = None) -> Figure:
    """Fig. 4: centre of mass x_g against x_d (World); runs as in :func:`figure_end_effector`."""
    return _position_figure(_as_series(nominal, disturbed), "com",
                            "Centre of mass position (Fig. 4)", "$x_g$")


def figure_orientation_errors(nominal: Run | list[Series],
                              disturbed: Run | None = None) -> Figure:
    """Fig. 5: angle of R_d^T R_b (top) and of R_E R_ed^T (bottom); runs as in
    :func:`figure_end_effector`."""
    runs = _as_series(nominal, disturbed)
    fig, axes = _new_figure(2, 6.0)
    for run, color, _ in runs:
        base = run.diagnostic("base_attitude_error")  # the controller's (None: not reported)
        if base is not None:
            axes[0].plot(run.t, base[:, 0], color=color, linewidth=1.2)
        axes[1].plot(run.t, run.tracking("ee_orientation_error")[:, 0], color=color,
                     linewidth=1.2)
    axes[0].set_ylabel("base attitude error\nangle of $R_d^T R_b$ (rad)")
    axes[1].set_ylabel("end-effector orientation error\nangle of $R_E R_{ed}^T$ (rad)")
    for ax in axes:
        ax.set_ylim(bottom=0.0)
    windows = _shade_all(axes, runs)
    fig.suptitle("Orientation errors (Fig. 5)")
    _legend(fig, _run_handles(runs) + windows)
    return fig


def _draw_limit(ax, value, color="0.35", text=None) -> None:
    if value is None:
        return
    ax.axhline(value, color=color, linestyle="--", linewidth=0.9, zorder=1)
    if text:
        ax.annotate(text, (1.0, value), xycoords=("axes fraction", "data"), xytext=(3, 0),
                    textcoords="offset points", va="center", fontsize=8, color=color)


def input_rows(n: int) -> tuple[tuple[str, ...], ...]:
    """Fig. 6's rows for a robot with ``n`` arm joints: the inputs drawn on each (names of
    :func:`aerial_drake.simulation.metrics.input_names`)."""
    return (("thrust",), ("mu_x", "mu_y", "mu_z")) + tuple((f"tau_{j}",) for j in range(1, n + 1))


#: Fig. 6's right column: the first ZOOM_S seconds, where the start saturates some inputs.
ZOOM_S = 0.05
_ROW_LABELS = {"thrust": "$f$ (N)", "mu_x": "$\\mu$ (N m)"}
_MU_COLORS = ("tab:blue", "tab:orange", "tab:green")


def _input_limit_lines(ax, names: tuple[str, ...], colors: list[str], limits: dict,
                       annotate: bool) -> None:
    """Dashed lines at the limits of the inputs ``names`` drawn on ``ax``: once in grey when
    they share their limits, else each in its input's colour."""
    pairs = [limits.get(n, (None, None)) for n in names]
    shared = all(p == pairs[0] for p in pairs)
    for k, (lower, upper) in enumerate(pairs[:1] if shared else pairs):
        color = "0.35" if shared else colors[k]
        for bound in (lower, upper):
            text = f"{bound:g}" if annotate and bound is not None else None
            _draw_limit(ax, bound, color=color, text=text)


def figure_inputs(run: Run) -> Figure:
    """Fig. 6: the inputs that reached the plant (after saturation, and lag if any) of one
    run, each with its own limits dashed: thrust, the three body torques (one panel), then
    each joint torque on its own panel. Left the whole run, right its first
    :data:`ZOOM_S` s (the start saturates some inputs for a few milliseconds)."""
    u = run.log["applied_command"]
    t = run.t
    limits = run.input_limits()
    index = {name: k for k, name in enumerate(input_names(u.shape[1] - 4))}
    rows = list(input_rows(u.shape[1] - 4))
    fig = Figure(figsize=(10.0, 1.35 * len(rows) + 1.2), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(rows), 2, sharex="col", squeeze=False,
                        gridspec_kw={"width_ratios": [3.2, 1.0]})
    zoom = t <= ZOOM_S + 1e-12
    for (full, near), names in zip(axes, rows):
        colors = list(_MU_COLORS) if len(names) > 1 else [NOMINAL_COLOR]
        for ax, mask in ((full, slice(None)), (near, zoom)):
            ax.grid(True, color="0.88", linewidth=0.6)
            for name, color in zip(names, colors):
                label = name.replace("mu_", "$\\mu_") + "$" if name.startswith("mu") else None
                ax.plot(t[mask], u[mask, index[name]], color=color, linewidth=1.0,
                        label=label)
            _input_limit_lines(ax, names, colors, limits, annotate=ax is near)
        full.set_ylabel(_ROW_LABELS.get(names[0], f"$\\tau_{names[0][-1]}$ (N m)"))
        if len(names) > 1:
            full.legend(loc="upper right", fontsize=8, ncol=3, framealpha=0.85)
    axes[0][0].set_xlim(0.0, max(float(t[-1]), 1e-3))
    axes[0][1].set_xlim(0.0, ZOOM_S)
    axes[0][1].set_title(f"first {1e3 * ZOOM_S:g} ms", fontsize=9)
    axes[-1][0].set_xlabel("time t (s)")
    axes[-1][1].set_xlabel("time t (s)")
    windows = _shade_windows([a for a, _ in axes], run.scenario, float(t[-1]))
    fig.suptitle(f"Inputs of the {run.name} run, as applied; each input's limits dashed "
                 "(Fig. 6)")
    _legend(fig, windows)
    return fig


def write_figures(out_dir: str | Path, nominal: Run, disturbed: Run | None = None,
                  formats: tuple[str, ...] = FORMATS) -> list[Path]:
    """Write Figs. 3-6 (Fig. 6 from ``nominal``) to ``out_dir``; returns the files written."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    figures = {
        "fig3_end_effector": figure_end_effector(nominal, disturbed),
        "fig4_com": figure_com(nominal, disturbed),
        "fig5_orientation_errors": figure_orientation_errors(nominal, disturbed),
        "fig6_inputs": figure_inputs(nominal),
    }
    return [p for name, fig in figures.items() for p in save_figure(fig, out, name, formats)]


def save_figure(fig: Figure, out: Path, name: str, formats: tuple[str, ...]) -> list[Path]:
    """Write ``fig`` as ``out/name.<format>`` for each of ``formats``; returns the files."""
    written = []
    for fmt in formats:
        path = out / f"{name}.{fmt}"
        fig.savefig(path, format=fmt)
        written.append(path)
    return written


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m aerial_drake.viz.plots",
        description="Write the paper's Figs. 3-6 from run folders (log.npz, metrics.json, "
                    "scenario.yaml).")
    parser.add_argument("nominal", help="the nominal run's folder (e.g. out/paper/nominal)")
    parser.add_argument("disturbed", nargs="?", default=None,
                        help="the disturbed run's folder (optional)")
    parser.add_argument("--out", default=None,
                        help="where to write the figures (default: the nominal folder's parent)")
    args = parser.parse_args(argv)
    try:
        nominal = load_run(args.nominal)
        disturbed = load_run(args.disturbed) if args.disturbed else None
    except (FileNotFoundError, ValueError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    out = Path(args.out) if args.out else Path(args.nominal).resolve().parent
    for path in write_figures(out, nominal, disturbed):
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
