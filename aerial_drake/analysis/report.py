"""All of the analysis, written to a folder (:func:`analyze`: ``analysis.json`` and plots),
and its text report (:func:`format_report`); ``aerial-drake analyze`` (:mod:`aerial_drake.cli.
analyze`) calls and prints them."""

from __future__ import annotations

from pathlib import Path
from typing import TextIO

import numpy as np

from aerial_drake.analysis.controllability import (
    controllability,
    linearize_open_loop,
    unactuated_directions,
)
from aerial_drake.analysis.equilibria import default_equilibria
from aerial_drake.analysis.figures import (
    figure_eigenvalues,
    figure_lyapunov,
    figure_region_of_attraction,
)
from aerial_drake.analysis.linearization import linearize_closed_loop
from aerial_drake.analysis.lyapunov import (
    V_ROUND_OFF,
    lee_conditions,
    lyapunov_study,
    trajectory_accel_bound,
)
from aerial_drake.analysis.region_of_attraction import region_of_attraction
from aerial_drake.analysis.settings import FULL_SETTINGS, AnalysisSettings
from aerial_drake.simulation.outputs import strict_json, write_text_atomically
from aerial_drake.simulation.scenarios import ScenarioError, load_scenario


# --- Everything, to a folder ----------------------------------------------------------------
def analyze(out_dir: str | Path = "out/analysis", *, scenario: str = "nominal",
            settings: AnalysisSettings = FULL_SETTINGS, seed: int = 0,
            stream: TextIO | None = None) -> dict:
    """Equilibria, linearisations, eigenvalue tables, open-loop controllability, Lee's
    conditions, the Lyapunov study and the region-of-attraction study (``settings``) of
    ``scenario``'s gains;
    writes ``analysis.json``, ``eigenvalues.png``, ``lyapunov.png`` and
    ``region_of_attraction.png`` to ``out_dir`` and returns the JSON content."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)

    def say(msg):
        if stream is not None:
            stream.write(msg + "\n")
            stream.flush()

    sc = load_scenario(scenario)
    if sc.controller.type != "paper":
        # Everything here is the paper controller's theory (its eigenvalues, its Lyapunov
        # function); analysing the gains of another controller's scenario would mislead.
        raise ScenarioError(f"analyze studies the paper's controller; '{sc.name}' chooses "
                            f"controller.type '{sc.controller.type}' (docs/baselines.md)")
    report: dict = {"scenario": sc.name, "equilibria": {}}
    lins = {}
    model = sc.controller_model(floating_base="rpy")
    for name, eq in default_equilibria(model).items():
        say(f"linearising the closed loop at hover '{name}'")
        lin = linearize_closed_loop(eq, sc.gains)
        lins[name] = lin
        open_loop = linearize_open_loop(eq)
        report["equilibria"][name] = {
            "closed_loop": lin.summary(),
            "open_loop": {**controllability(open_loop), "unactuated_generalized_forces":
                          unactuated_directions(eq, open_loop).round(12).tolist()}}
        say(f"  max relative eigenvalue mismatch {lin.max_relative_mismatch:.2e}")
    m = model.total_mass()
    report["lee_conditions"] = lee_conditions(sc.gains, m,
                                              accel_bound=trajectory_accel_bound(sc, m))
    st = settings
    say(f"Lyapunov study: {st.lyapunov_duration:g} s, continuous feedback, runge_kutta3 "
        f"{st.lyapunov_accuracy:g}")
    lyap = lyapunov_study(sc, duration=st.lyapunov_duration, accuracy=st.lyapunov_accuracy)
    report["lyapunov"] = lyap.summary()
    say(f"region of attraction: {len(st.roa_scales)} sizes x {st.roa_samples} runs of "
        f"{st.roa_duration:g} s")
    roa = region_of_attraction(sc, scales=st.roa_scales, samples=st.roa_samples,
                               duration=st.roa_duration, seed=seed)
    report["region_of_attraction"] = roa.summary()
    figures = {"eigenvalues.png": figure_eigenvalues(lins), "lyapunov.png": figure_lyapunov(lyap),
               "region_of_attraction.png": figure_region_of_attraction(roa)}
    report["figures"] = []
    for name, fig in figures.items():
        fig.savefig(out / name, dpi=120)
        report["figures"].append(name)
    # JSON has no NaN: undefined numbers are written as null.
    write_text_atomically(out / "analysis.json", strict_json(report))
    say(f"wrote {out / 'analysis.json'} and {', '.join(figures)}")
    return report


# --- Command line ---------------------------------------------------------------------------


def format_eigenvalue_table(rows: list[dict]) -> str:
    """A :func:`compare_eigenvalues` table as text, slowest first."""
    lines = [f"{'eigenvalue':<46}{'predicted':>14}{'Linearize':>14}{'rel. err':>10}"]
    for r in sorted(rows, key=lambda r: -r["computed"][0] if r["predicted"] is None
                    else -r["predicted"][0]):
        p = "-" if r["predicted"] is None else f"{r['predicted'][0]:.6f}"
        c = "-" if r["computed"] is None else f"{r['computed'][0]:.6f}"
        lines.append(f"{r['label']:<46}{p:>14}{c:>14}{r['relative_mismatch']:10.1e}")
    return "\n".join(lines)


def format_open_loop(ol: dict) -> list[str]:
    """The open loop's controllability verdict, worded so it reads right without the docs."""
    scaled, raw = ol["IsControllable_time_scaled"], ol["IsControllable"]
    pbh = ol.get("pbh_max_rank_deficiency", 0)
    verdict = ("controllable" if scaled and pbh == 0 else
               "NOT controllable" if not scaled and pbh > 0 else "undecided (tests disagree)")
    lines = [f"open loop (the plant alone, linearised at hover): {verdict}; "
             f"{'stabilisable' if ol['IsStabilizable'] else 'NOT stabilisable'} "
             "(what the controller needs)"]
    lines.append(f"  evidence: PBH rank deficiency {pbh} at every eigenvalue; rank of "
                 f"[B, AB, ..., A^k B] for k = 0, 1, ...: {ol['controllability_rank_growth']} "
                 f"(full: {ol['states']}); rank B = {ol['rank_B']} of {ol['states'] // 2} "
                 "velocities (underactuated: thrust acts along the body z only)")
    if not raw and scaled and ol["controllability_matrix_conditioning"] < 1e-14:
        lines.append(f"  Drake's IsControllable(A, B) says {raw} only because Kalman's matrix "
                     f"is numerically singular (sigma_min/sigma_max "
                     f"{ol['controllability_matrix_conditioning']:.1e}, below double "
                     "precision): its columns grow like |A|^k. The time-scaled system "
                     "(A, B)/|A| has the same controllability and a well-conditioned matrix "
                     f"(ratio {ol.get('time_scaled_conditioning', float('nan')):.1e}); on it "
                     f"IsControllable says {scaled}.")
    else:
        lines.append(f"  Drake's IsControllable: {raw} on (A, B), {scaled} on the time-scaled "
                     f"(A, B)/|A| (Kalman matrix sigma_min/sigma_max "
                     f"{ol['controllability_matrix_conditioning']:.1e})")
    return lines


def format_lee(lee: dict) -> list[str]:
    """Lee et al.'s conditions: sufficient for the Lyapunov decrease, so one not met is no
    verdict on stability."""

    def state(ok: bool) -> str:
        return "met" if ok else "NOT met"

    lines = ["Lee et al.'s conditions on the Lyapunov constants gamma1, gamma2 (sufficient, not "
             "necessary: one not met proves nothing about stability, it only leaves the proof "
             "to the paper's local argument; the Lyapunov and region-of-attraction runs below "
             "test it):",
             f"  CoM: gamma1 = {lee['gamma1']:g} < {min(lee['gamma1_bounds'].values()):.3g}: "
             f"{state(lee['gamma1_ok'])}",
             f"  attitude: gamma2 = {lee['gamma2']:g} < "
             f"{min(lee['gamma2_bounds'].values()):.3g}: {state(lee['gamma2_ok'])} (one axis "
             f"at a time, < {min(lee['gamma2_per_axis_bounds']):.3g}: "
             f"{state(lee['gamma2_per_axis_ok'])})"]
    coupling = f"  coupling between CoM and attitude: {state(lee['coupling_ok'])}"
    if not lee["coupling_ok"]:
        possible = lee.get("coupling_possible_for_some_gammas")
        coupling += ("; no gamma1, gamma2 could meet it with these gains, so this is a limit "
                     "of the sufficient condition, not a sign of instability"
                     if possible is not None and not possible
                     else "; other gamma1, gamma2 may meet it")
    lines.append(coupling)
    return lines


def format_report(report: dict) -> str:
    """The terminal summary of :func:`analyze`'s result."""
    lines = []
    for name, e in report["equilibria"].items():
        cl, ol = e["closed_loop"], e["open_loop"]
        eq = cl["equilibrium"]
        lines.append(f"hover '{name}': CoM {(np.round(eq['p_WG_m'], 3) + 0.0).tolist()} m, yaw "
                     f"{eq['yaw_rad']:g} rad, end effector "
                     f"{(np.round(eq['p_WE_m'], 3) + 0.0).tolist()} m, task joints "
                     f"{np.round(eq['task_joints_rad'], 4).tolist()} rad; "
                     f"thrust {eq['thrust_N']:.1f} N")
        lines.append(f"  closed loop: {cl['states']} states, |x_dot| at equilibrium "
                     f"{cl['derivative_residual']:.1e}, max relative eigenvalue mismatch "
                     f"{cl['max_relative_mismatch']:.1e}")
        lines += ["  " + line for line in format_eigenvalue_table(cl["eigenvalues"]).split("\n")]
        lines += ["  " + line for line in format_open_loop(ol)]
    lines += format_lee(report["lee_conditions"])
    lines.append(format_lyapunov(report["lyapunov"]))
    roa = report["region_of_attraction"]
    lines.append("region of attraction: fraction of sampled starts that converged ("
                 + roa["criterion"] + "), per size s of the initial offsets: " + ", ".join(
                     f"s = {s:g}: {f:.2f}"
                     for s, f in zip(roa["scales"], roa["converged_fraction"])))
    return "\n".join(lines)


def format_lyapunov(ly: dict) -> str:
    """The Lyapunov line of the report from :meth:`LyapunovResult.summary`: a run started on
    its reference (V(0) round-off) is said to show nothing, not to decrease or increase."""
    head = (f"Lyapunov ({ly['duration_s']:g} s, {ly['integrator']['scheme']} accuracy "
            f"{ly['integrator']['accuracy']:g}): V {ly['V']['initial']:.4g} -> "
            f"{ly['V']['final']:.4g}")
    if ly.get("started_on_reference"):
        return (head + f": round-off (V(0) < {V_ROUND_OFF:g}): the run started on its "
                "reference, so V's decrease shows nothing. Give the scenario an initial offset "
                "(initial.base_position_offset, base_rpy_offset) to test it")
    return (head + f", largest increase between samples {ly['V']['max_increase']:.2e}; "
            f"V_task's {ly['V_task']['max_increase']:.2e} ("
            + ("V never increased along the run" if ly['V']['max_increase'] <= 0
               else "V increased somewhere: see lyapunov.png") + ")")
