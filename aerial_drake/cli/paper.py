"""``aerial-drake run paper``: Section IV's two runs, Figs. 3-6 and the metrics table
(:func:`aerial_drake.studies.paper.run_paper`), printed."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from aerial_drake.cli.errors import report_error, report_exception


def cmd_paper(args: argparse.Namespace, overrides: dict | None = None) -> int:
    """``aerial-drake run paper [--duration S] [--out DIR] [--seed N] [--quiet] [--json]``;
    ``overrides``: the scenario fields the command line sets
    (:func:`aerial_drake.cli.overrides.scenario_overrides`)."""
    from aerial_drake.dynamics.equilibrium import UnreachablePose
    from aerial_drake.simulation.outputs import OutputError, strict_json
    from aerial_drake.simulation.scenarios import ScenarioError
    from aerial_drake.studies.paper import PAPER_SCENARIOS, run_paper

    out = Path(args.out) / "paper"
    say = sys.stderr if args.json else sys.stdout  # with --json, stdout holds the JSON alone
    print(f"running the paper's scenarios {PAPER_SCENARIOS} -> {out}", file=say, flush=True)
    try:
        result = run_paper(out, seed=args.seed, progress=not args.quiet, stream=sys.stderr,
                           overrides=overrides)
    except (ScenarioError, UnreachablePose, OutputError) as err:  # ResultsNotWritten: 3
        return report_exception(args, err)
    if result.interrupted is not None:
        reasons = "; ".join(result.failures.values())
        return report_error(args, 128 + result.interrupted, reasons,
                            f"logs up to the interruption are in {out}")
    print(result.table, file=say)
    for path in result.figures:
        if path.suffix == ".png":
            print(f"wrote {path} (and .pdf)", file=say)
    folders = ", ".join(str(out / n) for n in result.runs)
    print(f"wrote {out / 'summary.txt'}; run folders {folders}", file=say)
    if args.json:
        print(strict_json({n: r.metrics for n, r in result.runs.items()}))
    for name, reason in result.failures.items():
        print(f"error: {reason}", file=sys.stderr)
    return 0 if result.completed else 1
