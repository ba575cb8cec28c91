"""``aerial-drake compare SCENARIO``: one scenario under several controllers
(:func:`aerial_drake.studies.compare.run_compare`), its table and files printed."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from aerial_drake.cli.errors import report_error, report_exception
from aerial_drake.cli.overrides import scenario_overrides
from aerial_drake.cli.restart import compile_first

#: The most worker processes ``--jobs`` may ask for (aerial_drake.studies.compare.MAX_JOBS).
MAX_JOBS = 256


def cmd_compare(args: argparse.Namespace) -> int:
    """``aerial-drake compare SCENARIO [--controllers A,B] [--jobs N] [--duration S]
    [--out DIR] [--quiet] [--json]``. Exit statuses as ``run``'s (docs/reliability.md): 2 bad
    input or output folder, 3 results not written, 128 + n stopped by signal n, 1 a run
    failed. With ``--json`` stdout holds only JSON (comparison.json's content, or an error
    object); the table and the "wrote" lines go to stderr."""
    from aerial_drake.simulation.scenarios import ScenarioError, load_scenario
    if args.jobs is not None and not 1 <= args.jobs <= MAX_JOBS:
        return report_error(args, 2, ScenarioError(
            f"--jobs must be 1 to {MAX_JOBS} (1 runs the controllers one after the other); "
            f"got {args.jobs}", "--jobs"))
    try:  # a misspelt scenario or override fails at once, not after the first-run compile
        overrides = scenario_overrides(args)
        load_scenario(args.scenario, overrides=overrides)
    except ScenarioError as err:
        return report_error(args, 2, err)
    compile_first(args.restartable)
    from aerial_drake.simulation.outputs import strict_json
    from aerial_drake.studies.compare import comparison_summary, run_compare

    controllers = tuple(c.strip() for c in args.controllers.split(",") if c.strip())
    jobs = args.jobs if args.jobs is not None else min(len(controllers), os.cpu_count() or 1)
    try:
        result = run_compare(args.scenario, controllers, Path(args.out) / "compare",
                             jobs=jobs, progress=not args.quiet, stream=sys.stderr,
                             undisturbed=args.undisturbed, overrides=overrides)
    except Exception as err:  # the foreseen ones get their status; a bug is raised again
        return report_exception(args, err)
    if result.interrupted is not None:
        return report_error(args, 128 + result.interrupted, "; ".join(result.failures.values()),
                            f"logs up to the interruption are in {result.out_dir}")
    human = sys.stderr if args.json else sys.stdout
    print(result.table, file=human)
    for path in result.figures:
        if path.suffix == ".png":
            print(f"wrote {path} (and .pdf)", file=human)
    print(f"wrote {result.out_dir / 'summary.txt'} and {result.out_dir / 'comparison.json'}",
          file=human)
    if args.json:
        print(strict_json(comparison_summary({n: r.metrics for n, r in result.runs.items()})))
    for name, reason in result.failures.items():
        print(f"error: {name}: {reason}", file=sys.stderr)
    return 0 if result.completed else 1
