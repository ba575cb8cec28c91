"""The analysis's figures (matplotlib's object API: no pyplot state, no display needed)."""

from __future__ import annotations

import numpy as np

from aerial_drake.analysis.linearization import ClosedLoopLinearization
from aerial_drake.analysis.lyapunov import LyapunovResult
from aerial_drake.analysis.region_of_attraction import ROA_UNIT, RegionOfAttraction

# --- Figures (matplotlib's object API: no pyplot state, no display needed) ------------------
_GROUP_STYLE = {"com": ("tab:blue", "CoM"), "attitude": ("tab:orange", "attitude"),
                "task_y": ("tab:green", "task, -K_y"),
                "task_z": ("tab:red", "task, eig(-Lambda_z^-1 K_z)"),
                "unpredicted": ("k", "not predicted")}


def figure_eigenvalues(linearizations: dict[str, ClosedLoopLinearization]):
    """Computed (crosses) and predicted (circles) closed-loop eigenvalues, one panel per
    equilibrium, against -Re(s) on a log axis (all are real and negative)."""
    from matplotlib.figure import Figure
    fig = Figure(figsize=(8, 2.2 * len(linearizations) + 0.6), layout="constrained")
    axes = fig.subplots(len(linearizations), 1, squeeze=False)[:, 0]
    for ax, (name, lin) in zip(axes, linearizations.items()):
        for k, group in enumerate(_GROUP_STYLE):
            rows = [r for r in lin.table if r["group"] == group]
            if not rows:
                continue
            color, label = _GROUP_STYLE[group]
            pred = np.array([r["predicted"] for r in rows if r["predicted"] is not None])
            comp = np.array([r["computed"] for r in rows if r["computed"] is not None])
            if len(pred):
                ax.scatter(-pred[:, 0], np.full(len(pred), k), s=70, facecolors="none",
                           edgecolors=color, label=f"{label} (predicted)")
            if len(comp):
                ax.scatter(-comp[:, 0], np.full(len(comp), k), marker="x", color=color)
        ax.set_xscale("log")
        ax.set_yticks(range(len(_GROUP_STYLE) - 1),
                      [v[1] for k, v in _GROUP_STYLE.items() if k != "unpredicted"])
        ax.set_ylim(-0.6, len(_GROUP_STYLE) - 1.4)
        ax.set_title(f"hover '{name}': {lin.A.shape[0]} eigenvalues, max relative mismatch "
                     f"{lin.max_relative_mismatch:.1e} (o predicted, x Linearize)", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
    axes[-1].set_xlabel("-Re(s) (1/s)")
    return fig


def figure_lyapunov(result: LyapunovResult):
    """V, V1 and V_task of (24)-(25) against time (log scale)."""
    from matplotlib.figure import Figure
    fig = Figure(figsize=(8, 3.6), layout="constrained")
    ax = fig.subplots()
    for name, style in (("V", "k-"), ("V1", "C0--"), ("V_task", "C3:")):
        ax.semilogy(result.t, getattr(result, name), style, label=name)
    s = result.summary()
    ax.set_title(f"(24)-(25) along the nominal trajectory, no disturbances, continuous "
                 f"feedback;\nmax increase of V: {s['V']['max_increase']:.2e}, of V_task: "
                 f"{s['V_task']['max_increase']:.2e}", fontsize=9)
    ax.set_xlabel("t (s)")
    ax.legend()
    ax.grid(True, which="both", alpha=0.3)
    return fig


def figure_region_of_attraction(result: RegionOfAttraction):
    """Fraction of converged runs against the size of the initial offsets."""
    from matplotlib.figure import Figure
    fig = Figure(figsize=(6, 3.6), layout="constrained")
    ax = fig.subplots()
    ax.plot(result.scales, result.fractions, "o-")
    ax.set_ylim(-0.05, 1.05)
    ax.set_xlabel(f"offset size s: base {ROA_UNIT['base_position_offset']:g} s m, attitude "
                  f"{ROA_UNIT['base_rpy_offset']:g} s rad, joints {ROA_UNIT['arm_offset']:g} s rad")
    ax.set_ylabel("fraction converged")
    ax.set_title(f"{len(result.runs)} runs of {result.duration:g} s; converged: completed "
                 f"and V(T) <= exp(-{result.min_decay_rate:g} T) V(0)", fontsize=9)
    ax.grid(True, alpha=0.3)
    return fig


