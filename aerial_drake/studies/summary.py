"""Run metrics as text: one run's summary (:func:`format_summary`, printed by ``aerial-drake
run SCENARIO``) and several runs side by side (:func:`format_table`: ``run paper``'s and
``compare``'s table, also written as their ``summary.txt``). Plain functions of the metrics
dictionaries (metrics.json's content); nothing is printed here."""

from __future__ import annotations

from aerial_drake.simulation.metrics import saturated_after_key
from aerial_drake.trajectories.com_planning import plan_summary


def _table(header: list[str], rows: list[list[str]]) -> str:
    """Columns right-aligned under ``header`` (the first column left-aligned)."""
    widths = [max(len(r[k]) for r in [header, *rows]) for k in range(len(header))]
    lines = ["  ".join(c.ljust(w) if k == 0 else c.rjust(w)
                       for k, (c, w) in enumerate(zip(row, widths))).rstrip()
             for row in [header, *rows]]
    return "\n".join(lines)


def format_summary(m: dict) -> str:
    """One run's metrics as text: the run, the largest errors per phase, the assumptions'
    margins and the saturated time per input, as tables at meaningful precision."""
    lines = [f"scenario '{m['scenario']}': simulated {m['simulated_time_s']:.2f} s in "
             f"{m['wall_time_s']:.2f} s wall (real-time factor {m['real_time_factor']:.1f}x)"]
    rows = [[f"{p['start_s']:g}-{p['end_s']:g}",
             f"{1e3 * p['ee_position_error_m']['max']:.3f}",
             f"{1e3 * p['ee_orientation_error_rad']['max']:.3f}",
             f"{1e3 * p['com_position_error_m']['max']:.3f}",
             f"{1e3 * p['base_attitude_error_rad']['max']:.3f}"]
            for p in m["phases"] if p["samples"] > 0]
    lines.append(_table(["phase (s)", "EE pos max (mm)", "EE rot max (mrad)", "CoM max (mm)",
                         "base att max (mrad)"], rows))
    lines.append(f"min sigma_min(J_3) = {m['min_sigma_min_J3']:.4f} (Assumption 1: > 0); "
                 f"min |f_d| = {m['min_f_d_norm_N']:.1f} N (Assumption 2: > 0)")
    for r in m.get("disturbance_response", []):
        if r.get("partial"):
            lines.append(f"disturbance on {r['target']} {r['window_s'][0]:g}-"
                         f"{r['window_s'][1]:g} s: response partial (the log ends at "
                         f"{r['log_end_s']:g} s, before {r['evaluated_s'][1]:g} s); its peaks "
                         "are those of the part logged")
    if m.get("com_planning"):  # trajectory.com_planning: the plan's margins, once
        lines.append(plan_summary(m["com_planning"]))
    late = next((k for k in m if k.startswith("saturated_s_after")), None)
    sat = [k for k, v in m["saturated_s_total"].items() if v > 0]
    if not sat:
        lines.append("saturated time: none (no input reached a limit)")
    else:
        after = late.removeprefix("saturated_s_after_") if late else ""
        header = ["input at a limit", "whole run (s)"] + ([f"after {after} (s)"] if late else [])
        lines.append(_table(header, [
            [k, f"{m['saturated_s_total'][k]:.3f}"] + ([f"{m[late][k]:.3f}"] if late else [])
            for k in sat]))
    return "\n".join(lines)


def _phase_rows(metrics: dict[str, dict]) -> list[tuple[str, list[str]]]:
    names = list(metrics)
    rows = []
    quantities = (("EE position", "ee_position_error_m", 1e3, "mm"),
                  ("CoM position", "com_position_error_m", 1e3, "mm"),
                  ("base attitude", "base_attitude_error_rad", 1e3, "mrad"),
                  ("EE orientation", "ee_orientation_error_rad", 1e3, "mrad"))
    phases = metrics[names[0]]["phases"]
    for label, key, scale, unit in quantities:
        rows.append((f"max {label} error ({unit})", [""] * len(names)))
        for k, phase in enumerate(phases):
            cells = []
            for n in names:
                ph = metrics[n]["phases"][k] if k < len(metrics[n]["phases"]) else {}
                cells.append(f"{scale * ph[key]['max']:.2f}" if key in ph else "-")
            rows.append((f"  {phase['start_s']:g}-{phase['end_s']:g} s", cells))
    return rows


def format_table(metrics: dict[str, dict]) -> str:
    """The runs' main metrics side by side (columns: runs), as plain text."""
    if not metrics:
        return "no run produced a log"
    names = list(metrics)
    rows: list[tuple[str, list[str]]] = []

    def row(label, fn):
        cells = []
        for n in names:
            try:
                cells.append(fn(metrics[n]))
            except (KeyError, IndexError, TypeError):
                cells.append("-")
        rows.append((label, cells))

    row("completed", lambda m: "yes" if m.get("completed") else f"NO: {m.get('failure')}")
    row("simulated time (s)", lambda m: f"{m['simulated_time_s']:.2f}")
    row("wall time (s)", lambda m: f"{m['wall_time_s']:.1f}")
    rows += _phase_rows(metrics)
    n_windows = max(len(m.get("disturbance_response", [])) for m in metrics.values())
    for w in range(n_windows):
        responses = [m["disturbance_response"][w] for m in metrics.values()
                     if len(m.get("disturbance_response", [])) > w]
        if all(r.get("ee_position_error_peak_m") is None for r in responses):
            continue  # after every run's end (or before its log): nothing to show
        first = responses[0]
        a, b = first["evaluated_s"]
        start, stop = first["window_s"]
        rows.append((f"disturbance on {first['target']} {start:g}-{stop:g} s, peaks over "
                     f"{a:g}-{b:g} s", [""] * len(names)))
        if any(r.get("partial") for r in responses):  # a run's log ends inside the response
            row("  partial: the log ends at",
                lambda m: f"{m['disturbance_response'][w]['log_end_s']:g} s"
                if m["disturbance_response"][w].get("partial") else "no")
        row("  EE position error peak (mm)",
            lambda m: f"{1e3 * m['disturbance_response'][w]['ee_position_error_peak_m']:.2f}")
        row("  CoM error peak (mm)",
            lambda m: f"{1e3 * m['disturbance_response'][w]['com_error_peak_m']:.2f}")
        row("  ratio EE / CoM",
            lambda m: f"{m['disturbance_response'][w]['ee_to_com_peak_ratio']:.4f}")
    # Saturated time: one row per input that sat at a limit in any run.
    late = saturated_after_key()
    saturated = [k for k in dict.fromkeys(k for m in metrics.values()
                                          for k in m.get("saturated_s_total", {}))
                 if any(m.get("saturated_s_total", {}).get(k, 0) > 0 for m in metrics.values())]
    rows.append(("saturated time (s): whole run / after 0.5 s",
                 [""] * len(names) if saturated else ["none"] * len(names)))
    for key in saturated:
        row(f"  {key}", lambda m, k=key: f"{m['saturated_s_total'][k]:.3f} / "
                                         f"{m[late][k]:.3f}")
    row("min sigma_min(J_3)", lambda m: f"{m['min_sigma_min_J3']:.4f}")
    row("min |f_d| (N)", lambda m: f"{m['min_f_d_norm_N']:.1f}")
    for side in [s for s in ("left", "right")
                 if any(s in m.get("rotors", {}) for m in metrics.values())]:
        row(f"rotor {side} speed min..max (rad/s)",
            lambda m, s=side: f"{m['rotors'][s]['speed_min_rad_s']:.3f}.."
                              f"{m['rotors'][s]['speed_max_rad_s']:.3f}")
        row(f"rotor {side} drive torque RMS / max (N m)",
            lambda m, s=side: f"{m['rotors'][s]['drive_torque_rms_N_m']:.2f} / "
                              f"{m['rotors'][s]['drive_torque_max_abs_N_m']:.2f}")
    width = max(len(label) for label, _ in rows) + 2
    col = max([12] + [len(c) + 2 for _, cells in rows for c in cells]
              + [len(n) + 2 for n in names])
    lines = [" " * width + "".join(f"{n:>{col}}" for n in names)]
    lines += [f"{label:<{width}}" + "".join(f"{c:>{col}}" for c in cells)
              for label, cells in rows]
    return "\n".join(lines)
