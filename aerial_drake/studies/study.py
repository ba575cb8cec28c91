"""``aerial-drake study FILE`` (or :func:`run_study`): a study's runs on Dask, one row each in
``OUT/results.csv`` as they finish, ``OUT/provenance.json`` beside it.

Run again, a study skips the runs that have a row (a run's identity is the hash of its
resolved scenario), so an interrupted study resumes where it stopped: no run twice, none
missing. One study at a time per folder (its lock, as a run folder's); a folder whose
rows were run from another spec is refused (:mod:`aerial_drake.studies.identity`), or,
with ``restart``, its results are discarded first. A signal (Ctrl-C, SIGTERM, SIGHUP)
cancels the runs in flight, keeps every row written, closes the cluster and exits 128 + the
signal's number.
"""

from __future__ import annotations

import dataclasses
import fnmatch
import signal
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

from aerial_drake.simulation.interrupts import handling
from aerial_drake.simulation.outputs import prepare_folder
from aerial_drake.studies.executor import execute, study_client
from aerial_drake.studies.identity import check_same_study
from aerial_drake.studies.metrics_table import metric_names
from aerial_drake.studies.progress import StudyProgress
from aerial_drake.studies.spec import LoadedStudy, PlannedRun, plan_runs, scenario_text
from aerial_drake.studies.table import (
    ID_COLUMNS,
    OUTCOME_COLUMNS,
    ResultsTable,
    write_provenance,
)

TABLE_NAME = "results.csv"
PROVENANCE_NAME = "provenance.json"


@dataclass
class StudyResult:
    """What :func:`run_study` did: the files, the planned runs, those skipped (a row from
    before), those run now, how many of all failed, and the signal that stopped it, if any."""

    out_dir: Path
    table: Path
    provenance: Path
    planned: int
    skipped: int = 0
    ran: int = 0
    failed: int = 0
    interrupted: int | None = None

    @property
    def complete(self) -> bool:
        return self.interrupted is None and self.skipped + self.ran == self.planned


def table_columns(loaded: LoadedStudy) -> list[str]:
    """The results table's columns: identity, the varied fields, the outcome, the metrics
    the study keeps (in the metrics' own order)."""
    study = loaded.study
    names = metric_names(loaded.base)
    kept = [n for n in names if any(fnmatch.fnmatchcase(n, p) for p in study.metrics)]
    return [*ID_COLUMNS, *(p.column for p in study.parameters), *OUTCOME_COLUMNS, *kept]


def _row(run: PlannedRun, outcome: dict[str, Any], loaded: LoadedStudy) -> dict[str, Any]:
    row: dict[str, Any] = {"run_id": run.run_id, "index": run.index, "draw": run.draw}
    row.update({p.column: run.values[p.field] for p in loaded.study.parameters})
    row.update(outcome)
    return row


def _provenance(loaded: LoadedStudy, planned: int) -> dict[str, Any]:
    return {"file": str(loaded.path), "spec": dataclasses.asdict(loaded.study),
            "settings": loaded.settings, "runs": planned,
            "base_scenario": scenario_text(loaded.base)}


def run_study(loaded: LoadedStudy, out_dir: str | Path, *, workers: int | None = None,
              scheduler: str | None = None, progress: bool = True,
              stream: TextIO | None = None, restart: bool = False) -> StudyResult:
    """Run the study's runs that have no row yet in ``out_dir/results.csv`` (module
    docstring) on a local cluster of ``workers`` processes, or on the cluster at
    ``scheduler``; with ``restart``, the folder's results are discarded first. OutputError
    (before any run) if another study holds the folder's lock, or the folder holds another
    study's table or rows run from another spec (StudyChanged); ClusterError if the
    scheduler cannot be reached."""
    out = Path(out_dir)
    runs = plan_runs(loaded)
    lock = prepare_folder(out)
    try:
        return _run_locked(loaded, out, runs, workers, scheduler, progress, stream, restart)
    finally:
        lock.release()


def _run_locked(loaded: LoadedStudy, out: Path, runs: list[PlannedRun], workers: int | None,
                scheduler: str | None, progress: bool, stream: TextIO | None,
                restart: bool) -> StudyResult:
    if restart:
        for name in (TABLE_NAME, PROVENANCE_NAME):
            (out / name).unlink(missing_ok=True)
    check_same_study(out / TABLE_NAME, out / PROVENANCE_NAME, _provenance(loaded, len(runs)))
    table = ResultsTable.open(out / TABLE_NAME, table_columns(loaded))
    planned_ids = {r.run_id for r in runs}
    done = table.done & planned_ids
    todo = [r for r in runs if r.run_id not in done]
    failed = sum(1 for row in table.rows
                 if row["run_id"] in planned_ids and row["completed"] != "true")
    result = StudyResult(out_dir=out, table=table.path, provenance=out / PROVENANCE_NAME,
                         planned=len(runs), skipped=len(done), failed=failed)
    bar = StudyProgress(len(runs), len(done), failed, stream if progress else None)

    def on_row(run: PlannedRun, outcome: dict[str, Any]) -> None:
        table.append(_row(run, outcome, loaded))
        result.ran += 1
        result.failed += 0 if outcome["completed"] else 1
        bar.update(bool(outcome["completed"]))

    try:
        with handling():
            cluster: dict[str, Any] = {"scheduler": scheduler or "local", "workers": workers}
            write_provenance(result.provenance, _provenance(loaded, len(runs)), cluster)
            if todo:
                with study_client(workers, scheduler) as (client, info):
                    write_provenance(result.provenance, _provenance(loaded, len(runs)), info)
                    bar.update()
                    execute(client, todo, on_row)
    except KeyboardInterrupt as err:
        result.interrupted = getattr(err, "signum", signal.SIGINT)
    finally:
        bar.close()
    return result
