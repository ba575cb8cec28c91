"""tools/study_report.py counts a study's failures by cause (the table's failure_cause)."""

import importlib.util
from pathlib import Path

from aerial_drake.studies.table import ID_COLUMNS, OUTCOME_COLUMNS, ResultsTable

TOOL = Path(__file__).resolve().parents[2] / "tools" / "study_report.py"


def _report_module():
    spec = importlib.util.spec_from_file_location("study_report", TOOL)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _table(path, columns, rows):
    errors = ("phase0.ee_position_error_m.max", "phase0.com_position_error_m.max")
    table = ResultsTable.open(path, [*ID_COLUMNS, *columns, "simulated_time_s", *errors])
    for i, (completed, cause, t) in enumerate(rows):
        table.append({"run_id": f"id{i}", "index": i, "draw": i, "completed": completed,
                      "failure_kind": "" if completed else "simulation",
                      "failure": "" if completed else f"t = {t} s: Assumption 1 violated",
                      "failure_cause": cause, "simulated_time_s": t,
                      **dict.fromkeys(errors, 0.01)})


def test_failures_are_counted_by_cause(tmp_path):
    path = tmp_path / "results.csv"
    _table(path, OUTCOME_COLUMNS, [(True, "", 15.0), (False, "reach", 5.2),
                                   (False, "reach", 5.4), (False, "oscillation", 2.6)])
    text = _report_module().report(path, None)
    assert "| reach | 2 | 5.20 / 5.30 / 5.40 |" in text
    assert "| oscillation | 1 | 2.60 / 2.60 / 2.60 |" in text
    assert text.index("| reach |") < text.index("| oscillation |")  # most frequent first


def test_a_table_without_the_column_has_no_causes_table(tmp_path):
    path = tmp_path / "results.csv"
    _table(path, [c for c in OUTCOME_COLUMNS if c != "failure_cause"],
           [(True, "", 15.0), (False, "", 5.2)])
    assert "Failures by cause" not in _report_module().report(path, None)
