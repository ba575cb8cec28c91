"""``aerial-drake study FILE`` (a study's runs on Dask: :func:`aerial_drake.studies.study.
run_study`) and ``aerial-drake study-plot TABLE`` (:func:`aerial_drake.viz.study_plots.
write_study_plots`)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from aerial_drake.cli.errors import report_error


def shipped_study_names() -> list[str]:
    """The shipped studies' names (their files' folder read directly: nothing heavy is
    imported to build the parser)."""
    import aerial_drake.studies
    folder = Path(aerial_drake.studies.__file__).resolve().parent / "files"
    return sorted(p.stem for p in folder.glob("*.yaml"))


def cmd_study(args: argparse.Namespace) -> int:
    """``aerial-drake study FILE [--workers N | --scheduler ADDRESS] [--out DIR]
    [--duration S] [--draws N] [--restart] [--quiet] [--json]``."""
    from aerial_drake.simulation.outputs import OutputError, strict_json
    from aerial_drake.simulation.scenarios import ScenarioError
    from aerial_drake.studies.executor import ClusterError
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
                           progress=not args.quiet, stream=sys.stderr,
                           restart=args.restart)
    except (OutputError, ClusterError) as err:
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
    run``: a single run reproduces it exactly. Its description is the study's (the run's
    text carries the base's, which its id hashes), with the run's number and values."""
    import dataclasses

    from aerial_drake.studies.spec import plan_runs, scenario_from_text, scenario_text
    for run in plan_runs(loaded):
        if args.show_run in (run.run_id, str(run.index)):
            values = ", ".join(f"{k} = {v:g}" for k, v in run.values.items())
            about = (f"Run {run.index} (run_id {run.run_id}, draw {run.draw}"
                     f"{': ' + values if values else ''}) of study '{loaded.study.name}'. "
                     f"{loaded.study.description}").strip()
            shown = dataclasses.replace(scenario_from_text(run.scenario_text),
                                        description=about)
            sys.stdout.write(scenario_text(shown))
            return 0
    return report_error(args, 2, f"--show-run: no run {args.show_run!r} in study "
                        f"'{loaded.study.name}' (give a run_id or an index from its table)")


def cmd_study_plot(args: argparse.Namespace) -> int:
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
