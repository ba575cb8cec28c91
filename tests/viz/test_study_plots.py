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


def test_a_table_where_every_run_failed_is_refused_before_any_figure(tmp_path):
    rows = [{**_row(i, completed=False, **{"param.a": i}), "failure": "diverged at t = 0.1"}
            for i in range(4)]
    rows = [{k: ("" if k in ERRORS else v) for k, v in r.items()} for r in rows]
    with pytest.raises(ValueError, match="none of its 4 runs completed.*diverged at t = 0.1"):
        dut.write_study_plots(_table(tmp_path, ["param.a"], rows), tmp_path / "p")
    assert not (tmp_path / "p").exists()


def test_runs_whose_errors_are_all_zero_still_plot(tmp_path):
    rows = [{**_row(i, **{"param.a": i}), **{c: 0.0 for c in ERRORS}} for i in range(3)]
    written = dut.write_study_plots(_table(tmp_path, ["param.a"], rows), tmp_path / "p",
                                    formats=("png",))
    assert {p.name for p in written} == {"histograms.png", "box_per_phase.png"}


def test_the_command_line_exits_2_on_a_failed_study_or_a_table_not_utf8(tmp_path, capsys):
    from aerial_drake import cli
    rows = [_row(i, completed=False, **{"param.a": i}) for i in range(2)]
    table = _table(tmp_path, ["param.a"], rows)
    assert cli.main(["study-plot", str(table)]) == 2
    assert "none of its 2 runs completed" in capsys.readouterr().err
    table.write_bytes(b"run_id,completed\n\xe9t\xe9,true\n")
    assert cli.main(["study-plot", str(table)]) == 2
    err = capsys.readouterr().err
    assert str(table) in err and "not UTF-8" in err and "unexpected" not in err
