"""The results table keeps every complete row, drops a cut-short line and the cluster's own
failures on reopening, refuses another study's columns, and pandas reads it."""

import pytest

from aerial_drake.simulation.outputs import OutputError
from aerial_drake.studies import table as dut

COLUMNS = [*dut.ID_COLUMNS, "param.x", *dut.OUTCOME_COLUMNS, "metric"]


def _row(i, kind="", value=0.1):
    return {"run_id": f"id{i}", "index": i, "draw": 0, "param.x": 1.5, "completed": not kind,
            "failure_kind": kind, "failure": "a, \"quoted\" reason" if kind else "",
            "failure_cause": "reach" if kind == "simulation" else "", "wall_time_s": 1.0,
            "worker": "host:1", "metric": value}


def test_rows_survive_reopening_and_a_cut_short_line_is_dropped(tmp_path):
    path = tmp_path / "results.csv"
    table = dut.ResultsTable.open(path, COLUMNS)
    table.append(_row(0, value=0.1 + 0.2))
    table.append(_row(1, kind="simulation"))
    with open(path, "a") as f:
        f.write("id2,2,0,1.5,tr")  # a crash in the middle of a line
    again = dut.ResultsTable.open(path, COLUMNS)
    assert again.done == {"id0", "id1"}
    assert not path.read_text().endswith("tr")
    rows = dut.read_table(path)
    assert float(rows[0]["metric"]) == 0.1 + 0.2  # written exactly
    assert rows[1]["failure"] == 'a, "quoted" reason' and rows[1]["failure_cause"] == "reach"


def test_the_clusters_failures_are_tried_again(tmp_path):
    path = tmp_path / "results.csv"
    table = dut.ResultsTable.open(path, COLUMNS)
    table.append(_row(0))
    table.append(_row(1, kind="worker"))
    assert dut.ResultsTable.open(path, COLUMNS).done == {"id0"}
    assert [r["run_id"] for r in dut.read_table(path)] == ["id0"]


def test_another_studys_table_is_refused(tmp_path):
    path = tmp_path / "results.csv"
    dut.ResultsTable.open(path, COLUMNS).append(_row(0))
    with pytest.raises(OutputError, match="other columns"):
        dut.ResultsTable.open(path, COLUMNS[:-1])


def test_failure_cause_follows_failure():
    assert dut.OUTCOME_COLUMNS.index("failure_cause") == dut.OUTCOME_COLUMNS.index("failure") + 1


def test_a_table_written_before_failure_cause_is_refused_naming_the_column(tmp_path):
    # The outcome columns of tables written before the failure cause existed: such a table
    # is refused (its rows lack the column), saying which column and how to start again.
    path = tmp_path / "results.csv"
    old = [c for c in COLUMNS if c != "failure_cause"]
    dut.ResultsTable.open(path, old).append(_row(0))
    with pytest.raises(OutputError, match=r"other columns \(missing: failure_cause: .*"
                                          r"before failure_cause\).*--restart"):
        dut.ResultsTable.open(path, COLUMNS)


def test_pandas_reads_it(tmp_path):
    pandas = pytest.importorskip("pandas")
    path = tmp_path / "results.csv"
    table = dut.ResultsTable.open(path, COLUMNS)
    for i in range(3):
        table.append(_row(i, value=i / 3))
    frame = pandas.read_csv(path)
    assert list(frame.columns) == COLUMNS
    assert frame["metric"].tolist() == [0.0, 1 / 3, 2 / 3]
    assert frame["completed"].tolist() == [True, True, True]


def test_provenance_is_strict_json(tmp_path):
    path = tmp_path / "provenance.json"
    dut.write_provenance(path, {"spec": {"duration": float("nan")}}, {"workers": 2})
    data = dut.read_provenance(path)
    assert data["study"]["spec"]["duration"] is None
    assert data["drake_version"] and data["aerial_drake_version"]
    assert "NaN" not in path.read_text()
