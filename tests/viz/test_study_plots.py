"""study-plot draws its figures from a results table, maps for a two-parameter grid, in every
format asked for, and refuses a table it cannot plot."""

import pytest

from aerial_drake.studies.table import ID_COLUMNS, OUTCOME_COLUMNS, ResultsTable
from aerial_drake.viz import study_plots as dut

ERRORS = [f"phase{k}.{q}.max" for k in range(2)
          for q in ("ee_position_error_m", "com_position_error_m")]


def _table(tmp_path, params, rows):
    path = tmp_path / "results.csv"
    table = ResultsTable.open(path, [*ID_COLUMNS, *params, *OUTCOME_COLUMNS,
                                     "simulated_time_s", *ERRORS])
    for row in rows:
        table.append(row)
    return path


def _row(i, completed=True, **params):
    return {"run_id": f"r{i}", "index": i, "draw": 0, "completed": completed,
            "failure_kind": "" if completed else "simulation", "simulated_time_s": 1.0,
            **params, **{c: 0.01 * (i + 1) for c in ERRORS}}


def test_a_grid_gets_maps_in_every_format(tmp_path):
    rows = [_row(3 * a + b, completed=(a, b) != (2, 2), **{"param.a": a, "param.b": 10 * b})
            for a in range(3) for b in range(3)]
    written = dut.write_study_plots(_table(tmp_path, ["param.a", "param.b"], rows),
                                    tmp_path / "plots", formats=("png", "svg"))
    names = {p.name for p in written}
    assert names == {f"{stem}.{fmt}" for stem in ("histograms", "box_per_phase", "maps")
                     for fmt in ("png", "svg")}
    assert all(p.stat().st_size > 0 for p in written)


def test_draws_get_no_map(tmp_path):
    rows = [_row(i, **{"param.mass": 0.1 * i}) for i in range(30)]
    written = dut.write_study_plots(_table(tmp_path, ["param.mass"], rows), tmp_path / "p",
                                    formats=("png",))
    assert {p.name for p in written} == {"histograms.png", "box_per_phase.png"}


def test_a_table_without_error_columns_is_refused(tmp_path):
    path = tmp_path / "results.csv"
    ResultsTable.open(path, [*ID_COLUMNS, *OUTCOME_COLUMNS]).append(
        {"run_id": "x", "index": 0, "draw": 0, "completed": True})
    with pytest.raises(ValueError, match="no per-phase error columns"):
        dut.write_study_plots(path, tmp_path / "p")
