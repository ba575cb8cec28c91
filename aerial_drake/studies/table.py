"""A study's results on disk: ``results.csv``, one row per run, appended as rows arrive, and
``provenance.json`` beside it.

The table is CSV (pandas reads it: ``pandas.read_csv(path)``; so does the standard library).
Each row is written whole, flushed and synced before the next, so an interrupted study keeps
every row it finished; at most the last line is cut short by a crash, and opening the table
again drops such a line (the file is rewritten atomically without it). A row's ``run_id`` is
its identity (the hash of the resolved scenario): a study run again skips the runs with a row.
Rows whose failure is the cluster's (``failure_kind`` "worker": its worker died twice) are not
results: opening the table again drops them so the runs are tried anew.
"""

from __future__ import annotations

import csv
import io
import json
import os
import platform
import subprocess
import sys
import time
from importlib import metadata
from pathlib import Path
from typing import Any

from aerial_drake.simulation.outputs import OutputError, strict_json, write_text_atomically

#: The columns every table starts with; then ``param.*``, then the run's outcome, then metrics.
ID_COLUMNS = ("run_id", "index", "draw")
#: ``failure_cause``: metrics.json's ``failure_cause.cause`` (simulation.failure_cause) of a
#: run that failed in simulation, empty otherwise.
OUTCOME_COLUMNS = ("completed", "failure_kind", "failure", "failure_cause", "wall_time_s",
                   "worker")
#: Failures of the cluster, not of the run: tried again when the study is resumed.
RETRIED_KINDS = ("worker",)


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)  # the shortest text that reads back as the same double
    return str(value)


class ResultsTable:
    """``results.csv`` with fixed ``columns``: :meth:`open` it, :meth:`append` rows."""

    def __init__(self, path: Path, columns: list[str]) -> None:
        self.path = path
        self.columns = columns
        self.rows: list[dict[str, str]] = []

    @classmethod
    def open(cls, path: Path, columns: list[str]) -> ResultsTable:
        """The table at ``path`` with its complete rows (module docstring), or a new one;
        OutputError if it holds another study's columns."""
        table = cls(path, columns)
        path.parent.mkdir(parents=True, exist_ok=True)
        if not path.exists() or path.stat().st_size == 0:
            write_text_atomically(path, table._line(columns))
            return table
        text = read_table_text(path, "give another --out, or --restart to start over")
        complete = text if text.endswith("\n") else text[:text.rfind("\n") + 1]
        reader = csv.reader(io.StringIO(complete))
        header = next(reader, None)
        if header != columns:
            raise OutputError(f"{path} holds the results of a study with other columns "
                              f"({_column_change(header or [], columns)}: its parameters or "
                              "metrics differ, or it was written by a version with other "
                              "outcome columns, e.g. before failure_cause): give another "
                              "--out, or --restart (or remove the file) to start again")
        found = list(reader)
        rows = [dict(zip(columns, cells)) for cells in found if len(cells) == len(columns)]
        table.rows = [row for row in rows if row["failure_kind"] not in RETRIED_KINDS]
        if complete != text or len(table.rows) != len(found):  # drop what is not kept
            body = "".join(table._line([r[c] for c in columns]) for r in table.rows)
            write_text_atomically(path, table._line(columns) + body)
        return table

    @property
    def done(self) -> set[str]:
        """The run ids with a row."""
        return {row["run_id"] for row in self.rows}

    def _line(self, cells: list[Any]) -> str:
        buffer = io.StringIO()
        csv.writer(buffer, lineterminator="\n").writerow([_cell(c) for c in cells])
        return buffer.getvalue()

    def append(self, row: dict[str, Any]) -> None:
        """Write one row (missing columns empty, others ignored), synced to disk."""
        line = self._line([row.get(c) for c in self.columns])
        with open(self.path, "a", encoding="utf-8") as f:
            f.write(line)
            f.flush()
            os.fsync(f.fileno())
        self.rows.append(dict(zip(self.columns, next(csv.reader([line])))))


def _column_change(header: list[str], columns: list[str]) -> str:
    """What differs between a table's ``header`` and the ``columns`` expected, in a phrase."""
    missing = [c for c in columns if c not in header]
    extra = [c for c in header if c not in columns]
    said = [f"{label}: {', '.join(names[:5])}{', ...' if len(names) > 5 else ''}"
            for label, names in (("missing", missing), ("not expected", extra)) if names]
    return "; ".join(said) or "the same columns in another order"


def read_table_text(path: Path, fix: str) -> str:
    """The text of the table at ``path``; OutputError naming it and ``fix`` if it is not
    UTF-8 text (not a study's table: they are written as UTF-8)."""
    try:
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError as err:
        raise OutputError(f"{path} is not a study's results table (not UTF-8 text: byte "
                          f"{err.object[err.start]:#04x} at offset {err.start}): {fix}"
                          ) from None


def read_table(path: str | Path) -> list[dict[str, str]]:
    """A results table's complete rows as dicts of text (a cut-short last line left out)."""
    text = read_table_text(Path(path), "give a study's results.csv")
    if not text.endswith("\n"):
        text = text[:text.rfind("\n") + 1]
    reader = csv.DictReader(io.StringIO(text))
    return [row for row in reader if None not in row.values() and None not in row]


def _git_commit() -> str | None:
    """The commit of the package's checkout (with "+dirty" if it has changes), if any."""
    folder = Path(__file__).resolve().parent
    try:
        commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=folder, capture_output=True,
                                text=True, timeout=10)
        if commit.returncode != 0:
            return None
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"],
                               cwd=folder, capture_output=True, text=True, timeout=10)
        return commit.stdout.strip() + ("+dirty" if dirty.stdout.strip() else "")
    except (OSError, subprocess.SubprocessError):
        return None


def _version(package: str) -> str | None:
    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return None


def write_provenance(path: Path, study: dict[str, Any], cluster: dict[str, Any]) -> None:
    """``provenance.json``: versions (package, drake, dask, numpy, Python), the git commit if
    any, the host, the time, the cluster, and the resolved study."""
    import aerial_drake
    data = {
        "aerial_drake_version": aerial_drake.__version__,
        "drake_version": _version("drake"),
        "dask_version": _version("dask"),
        "distributed_version": _version("distributed"),
        "numpy_version": _version("numpy"),
        "python_version": sys.version.split()[0],
        "platform": platform.platform(),
        "host": platform.node(),
        "git_commit": _git_commit(),
        "written_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "cluster": cluster,
        "study": study,
    }
    write_text_atomically(path, strict_json(data) + "\n")


def read_provenance(path: Path) -> dict[str, Any]:
    return json.loads(path.read_text(encoding="utf-8"))
