"""Summarise a study's results table as Markdown (what docs/studies.md quotes).

    python tools/study_report.py OUT/studies/NAME/results.csv [--study NAME]

Prints the success rate, the failure reasons, the failures counted by cause (the table's
``failure_cause`` column, where it has one), the per-phase distributions (median, 90th
percentile, max) of the end-effector and CoM errors of completed runs, the worst runs with
their seeds (and the command that reproduces each), and for a two-parameter grid the maps of
stability and peak errors as tables. With ``--study`` (a study with ``random_disturbances``
seeds), also the success rate against the direction of each disturbance window's force,
re-drawn from each row's seed exactly as the run drew it.
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import re
import sys
from pathlib import Path

import numpy as np

from aerial_drake.studies.table import read_table


def _f(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        return float("nan")


def _phases(columns, quantity):
    found = [(int(m.group(1)), c) for c in columns
             if (m := re.match(rf"phase(\d+)\.{quantity}\.max$", c))]
    return [c for _, c in sorted(found)]


def _worst(row, columns):
    return max(_f(row[c]) for c in columns)


def report(path: Path, study: str | None) -> str:
    rows = read_table(path)
    columns = list(rows[0])
    done = [r for r in rows if r["completed"] == "true"]
    lines = [f"{len(done)} of {len(rows)} runs completed ({100 * len(done) / len(rows):.0f} %).",
             ""]
    reasons = collections.Counter(re.sub(r"[-\d.]+", "#", r["failure"].split(": ", 1)[-1])
                                  for r in rows if r["completed"] != "true")
    for reason, n in reasons.most_common(5):
        lines.append(f"- {n} x {reason}")
    failed_at = collections.Counter(
        int(_f(r["simulated_time_s"])) for r in rows if r["completed"] != "true")
    if failed_at:
        lines.append("- failure times (s, whole seconds: runs): " + ", ".join(
            f"{t}: {n}" for t, n in sorted(failed_at.items())))
    lines += ["", *_causes(rows)]
    ee, com = _phases(columns, "ee_position_error_m"), _phases(columns, "com_position_error_m")
    lines += ["| phase | EE max error (mm): median / p90 / max | CoM max error (mm): median / "
              "p90 / max | runs |", "|---|---|---|---|"]
    for k, (a, b) in enumerate(zip(ee, com)):
        e = np.array([_f(r[a]) for r in done if np.isfinite(_f(r[a]))]) * 1e3
        c = np.array([_f(r[b]) for r in done if np.isfinite(_f(r[b]))]) * 1e3
        if len(e):
            lines.append(f"| {k} | {np.median(e):.1f} / {np.percentile(e, 90):.1f} / "
                         f"{e.max():.1f} | {np.median(c):.1f} / {np.percentile(c, 90):.1f} / "
                         f"{c.max():.1f} | {len(e)} |")
    params = [c for c in columns if c.startswith("param.")]
    lines += ["", "Worst completed runs (largest EE error over the run):", "",
              "| index | run_id | " + " | ".join(p.removeprefix("param.") for p in params)
              + " | EE max (mm) | CoM max (mm) |", "|---" * (len(params) + 4) + "|"]
    for r in sorted(done, key=lambda r: -_worst(r, ee))[:5]:
        lines.append(f"| {r['index']} | {r['run_id']} | " + " | ".join(r[p] for p in params)
                     + f" | {1e3 * _worst(r, ee):.1f} | {1e3 * _worst(r, com):.1f} |")
    failed = [r for r in rows if r["completed"] != "true"]
    if failed:
        lines += ["", "Earliest failures:", "",
                  "| index | run_id | " + " | ".join(p.removeprefix("param.") for p in params)
                  + " | failed at (s) |", "|---" * (len(params) + 3) + "|"]
        for r in sorted(failed, key=lambda r: _f(r["simulated_time_s"]))[:5]:
            lines.append(f"| {r['index']} | {r['run_id']} | " + " | ".join(r[p] for p in params)
                         + f" | {_f(r['simulated_time_s']):.3f} |")
    grid = [p for p in params if 1 < len({r[p] for r in rows}) <= 20]
    if len(grid) == 2 and len(params) == 2:
        lines += ["", *_map(rows, grid, ee)]
    if study is not None and "param.random_disturbances.seed" in params:
        lines += ["", *_by_direction(rows, study)]
    return "\n".join(lines)


def _causes(rows):
    """The failed runs counted by ``failure_cause`` (none for a table written before it)."""
    failed = [r for r in rows if r["completed"] != "true"]
    if not failed or "failure_cause" not in rows[0]:
        return []
    by_cause = collections.defaultdict(list)
    for r in failed:
        by_cause[r["failure_cause"] or f"({r['failure_kind'] or 'unknown'})"].append(
            _f(r["simulated_time_s"]))
    out = ["Failures by cause (aerial_drake.simulation.failure_cause):", "",
           "| cause | runs | failed at (s): min / median / max |", "|---|---|---|"]
    for cause, times in sorted(by_cause.items(), key=lambda item: -len(item[1])):
        t = np.array([x for x in times if np.isfinite(x)])
        when = f"{t.min():.2f} / {np.median(t):.2f} / {t.max():.2f}" if t.size else ""
        out.append(f"| {cause} | {len(times)} | {when} |")
    return [*out, ""]


def _map(rows, grid, ee):
    a, b = grid
    xs = sorted({_f(r[a]) for r in rows})
    ys = sorted({_f(r[b]) for r in rows})
    cell = {(_f(r[a]), _f(r[b])): r for r in rows}
    out = [f"Largest EE error over the run (mm), or the failure time; rows {b}, columns {a}:",
           "", f"| {b} \\ {a} | " + " | ".join(f"{x:g}" for x in xs) + " |",
           "|---" * (len(xs) + 1) + "|"]
    for y in ys:
        cells = []
        for x in xs:
            r = cell.get((x, y))
            if r is None:
                cells.append("")
            elif r["completed"] == "true":
                cells.append(f"{1e3 * _worst(r, ee):.1f}")
            else:
                cells.append(f"fails at {_f(r['simulated_time_s']):.2f} s")
        out.append(f"| {y:g} | " + " | ".join(cells) + " |")
    return out


def _by_direction(rows, study):
    from aerial_drake.simulation.disturbances import random_windows
    from aerial_drake.studies.spec import load_study
    base = load_study(study).base
    counts: dict = collections.defaultdict(lambda: [0, 0])
    for r in rows:
        section = dataclasses.replace(base.random_disturbances,
                                      seed=int(r["param.random_disturbances.seed"]))
        window = random_windows(dataclasses.replace(base, random_disturbances=section))[0]
        f = np.asarray(window.force) / np.linalg.norm(window.force)
        axis = int(np.argmax(np.abs(f)))
        key = f"{'+' if f[axis] > 0 else '-'}{'xyz'[axis]}"
        counts[key][0] += r["completed"] == "true"
        counts[key][1] += 1
    first = base.disturbances[0]
    out = [f"Completed runs by the main World axis of window 0's force ({first.target}, "
           f"{np.linalg.norm(first.force):g} N):", "",
           "| main axis | completed / runs |", "|---|---|"]
    out += [f"| {k} | {c} / {n} |" for k, (c, n) in sorted(counts.items())]
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("table")
    parser.add_argument("--study", default=None)
    args = parser.parse_args()
    sys.stdout.write(report(Path(args.table), args.study) + "\n")


if __name__ == "__main__":
    main()
