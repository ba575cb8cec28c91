"""The command line's study commands: ``aerial-drake study FILE`` and ``aerial-drake
study-plot TABLE`` (parsers here, so that ``aerial_drake.cli`` only adds them)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from aerial_drake.studies.reporting import report_error


def cli_study(args: argparse.Namespace) -> int:
    """``aerial-drake study FILE [--workers N | --scheduler ADDRESS] [--out DIR]
    [--duration S] [--draws N] [--quiet] [--json]``."""
    from aerial_drake.simulation.outputs import OutputError, strict_json
    from aerial_drake.simulation.scenarios import ScenarioError
    from aerial_drake.studies.spec import load_study
    from aerial_drake.studies.study import run_study

    if args.workers is not None and args.scheduler is not None:
        return report_error(args, 2, "--workers starts a local cluster and --scheduler uses "
                            "an existing one: give one of them")
    if args.workers is not None and args.workers < 1:
        return report_error(args, 2, f"--workers must be >= 1; got {args.workers}")
    if args.draws is not None and args.draws < 1:
        return report_error(args, 2, f"--draws must be >= 1; got {args.draws}")
    try:
        loaded = load_study(args.file, duration=args.duration, draws=args.draws)
    except ScenarioError as err:
        return report_error(args, 2, err)
    if args.show_run is not None:
        return _show_run(args, loaded)
    out = Path(args.out) if args.out else Path("out/studies") / loaded.study.name
    say = sys.stderr if args.json else sys.stdout
    where = args.scheduler or f"a local cluster of {args.workers or 'one worker per CPU'}"
    print(f"study '{loaded.study.name}' on {where} -> {out / 'results.csv'}", file=say,
          flush=True)
    try:
        result = run_study(loaded, out, workers=args.workers, scheduler=args.scheduler,
                           progress=not args.quiet, stream=sys.stderr)
    except OutputError as err:
        return report_error(args, 2, err)
    summary = {"planned": result.planned, "skipped_done_before": result.skipped,
               "ran": result.ran, "failed": result.failed, "table": str(result.table),
               "provenance": str(result.provenance), "complete": result.complete}
    if result.interrupted is not None:
        return report_error(args, 128 + result.interrupted,
                            f"study interrupted after {result.ran} runs this time",
                            f"the rows written are kept in {result.table}; run the same "
                            "command again to resume")
    print(f"{result.planned} runs: {result.skipped} done before, {result.ran} run now; "
          f"{result.failed} failed (reasons in the table's 'failure' column)", file=say)
    print(f"wrote {result.table} and {result.provenance}; plot with 'aerial-drake study-plot "
          f"{result.table}'", file=say)
    if args.json:
        print(strict_json(summary))
    return 0


def _show_run(args: argparse.Namespace, loaded: Any) -> int:
    """Print one run's resolved scenario (by run id or index) as YAML, for ``aerial-drake
    run``: a single run reproduces it exactly."""
    from aerial_drake.studies.spec import plan_runs
    for run in plan_runs(loaded):
        if args.show_run in (run.run_id, str(run.index)):
            sys.stdout.write(run.scenario_text)
            return 0
    return report_error(args, 2, f"--show-run: no run {args.show_run!r} in study "
                        f"'{loaded.study.name}' (give a run_id or an index from its table)")


def cli_study_plot(args: argparse.Namespace) -> int:
    """``aerial-drake study-plot TABLE [--out DIR] [--formats png svg]``."""
    from aerial_drake.viz.study_plots import write_study_plots
    out = Path(args.out) if args.out else Path(args.table).parent / "plots"
    try:
        written = write_study_plots(args.table, out, formats=tuple(args.formats))
    except (FileNotFoundError, ValueError) as err:
        return report_error(args, 2, err)
    for path in written:
        print(f"wrote {path}")
    return 0


def add_study_parsers(sub: Any, common: argparse.ArgumentParser) -> None:
    """Add ``study`` and ``study-plot`` to the command line's subparsers."""
    study = sub.add_parser(
        "study", parents=[common], help="run a study (parameter grid, Monte Carlo draws) on "
        "Dask; one row per run in OUT/results.csv (docs/studies.md)",
        description="Run a study file's runs on a local Dask cluster (default: one worker "
        "process per CPU) or on an existing cluster (--scheduler). Rows are written as runs "
        "finish; run the same command again to resume an interrupted study.")
    study.add_argument("file", help="a shipped study's name (robustness, gains, "
                       "gains_attitude) or a study YAML file")
    study.add_argument("--workers", type=int, default=None,
                       help="worker processes of the local cluster (default: one per CPU)")
    study.add_argument("--scheduler", default=None,
                       help="address of an existing Dask scheduler (e.g. tcp://host:8786)")
    study.add_argument("--out", default=None,
                       help="output folder (default: out/studies/NAME)")
    study.add_argument("--duration", type=float, default=None,
                       help="override every run's duration (s)")
    study.add_argument("--draws", type=int, default=None, help="override the number of draws")
    study.add_argument("--show-run", default=None, metavar="RUN",
                       help="print the scenario of one run (its run_id or index in the "
                            "table) as YAML, to reproduce it with 'aerial-drake run FILE.yaml'; "
                            "runs nothing")
    study.add_argument("--quiet", action="store_true", help="no progress bar")
    study.add_argument("--json", action="store_true", help="also print a JSON summary")
    study.set_defaults(func=cli_study)
    plot = sub.add_parser(
        "study-plot", parents=[common], help="histograms, box plots per phase and maps of a "
        "study's results table")
    plot.add_argument("table", help="a study's results.csv")
    plot.add_argument("--out", default=None, help="where to write (default: TABLE's folder/"
                      "plots)")
    plot.add_argument("--formats", nargs="+", default=["png", "svg"], choices=["png", "svg",
                                                                                "pdf"])
    plot.set_defaults(func=cli_study_plot)
