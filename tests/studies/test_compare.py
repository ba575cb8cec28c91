"""Tests of aerial_drake.studies.compare (``aerial-drake compare``): run folders as ``run``
writes them, the overlays, the side-by-side table, and bad controller lists; and compare on
the reliability layer (docs/reliability.md): signals, sanitised folders, exit statuses, strict
JSON written atomically, complete runs only."""

import dataclasses
import json
import math
import multiprocessing
import os
import signal
import threading
import time

import numpy as np
import pytest

from aerial_drake import cli
from aerial_drake.cli import errors as reporting
from aerial_drake.simulation import interrupts, outputs, runner
from aerial_drake.simulation.scenarios import Disturbance, ScenarioError, shipped_scenarios
from aerial_drake.studies import compare as dut
from aerial_drake.viz.compare import COMPARE_FIGURE_NAMES


@pytest.fixture(scope="module")
def short_compare(tmp_path_factory):
    out = tmp_path_factory.mktemp("compare")
    return dut.run_compare("nominal", ("paper", "uncoupled"), out, duration=0.3, jobs=1,
                           progress=False)


def test_each_controller_gets_a_run_folder_and_a_column(short_compare):
    result = short_compare
    assert result.completed and list(result.runs) == ["paper", "uncoupled"]
    for name in ("paper", "uncoupled"):
        folder = result.out_dir / name
        assert {"log.npz", "metrics.json", "scenario.yaml"} <= {p.name for p in
                                                                folder.iterdir()}
        assert result.runs[name].scenario.controller.type == name
    header = result.table.splitlines()[0].split()
    assert header == ["paper", "uncoupled"]
    assert (result.out_dir / "summary.txt").read_text().strip() == result.table.strip()
    summary = json.loads((result.out_dir / "comparison.json").read_text())
    assert set(summary) == {"paper", "uncoupled"}
    assert summary["paper"]["phases"][0]["ee_position_error_m"]["max"] == pytest.approx(
        result.runs["paper"].metrics["phases"][0]["ee_position_error_m"]["max"])
    for name in COMPARE_FIGURE_NAMES:
        for fmt in ("png", "pdf"):
            assert (result.out_dir / f"{name}.{fmt}").stat().st_size > 1000


def test_the_paper_column_is_the_paper_run(short_compare, tmp_path):
    """The compare's paper run is `run`'s, to the last bit."""
    from aerial_drake.simulation.runner import run_scenario
    from aerial_drake.simulation.scenarios import load_scenario

    alone = run_scenario(load_scenario("nominal", overrides={"duration": 0.3}),
                         progress=False)
    np.testing.assert_array_equal(short_compare.runs["paper"].log["plant_state"],
                                  alone.log["plant_state"])


def test_a_process_pool_gives_the_same_runs(short_compare, tmp_path):
    pooled = dut.run_compare("nominal", ("paper", "uncoupled"), tmp_path, duration=0.3,
                             jobs=2, progress=False)
    for name in ("paper", "uncoupled"):
        np.testing.assert_array_equal(pooled.runs[name].log["plant_state"],
                                      short_compare.runs[name].log["plant_state"])


def test_bad_controller_lists_are_refused_before_running(tmp_path, capsys):
    with pytest.raises(ScenarioError, match="named twice"):
        dut.run_compare("nominal", ("paper", "paper"), tmp_path)
    assert cli.main(["compare", "nominal", "--controllers", "paper,lqr", "--out",
                     str(tmp_path)]) == 2
    assert "controller.type: 'lqr'" in capsys.readouterr().err
    assert not (tmp_path / "compare").exists()


def test_undisturbed_reference_and_displacement(short_compare):
    scenario = dut._scenario_for("nominal", "uncoupled", 2.0, undisturbed=True)
    assert scenario.name == "nominal_undisturbed" and scenario.disturbances == []
    assert scenario.controller.type == "uncoupled" and scenario.duration == 2.0
    run = short_compare.runs["uncoupled"]
    rows = dut.disturbance_displacement(run, run, windows=((0.0, 0.1), (5.0, 6.0)))
    assert rows[0] == {"window_s": [0.0, 0.1], "ee_moved_max_m": 0.0, "com_moved_max_m": 0.0}
    assert rows[1]["ee_moved_max_m"] is None  # beyond the 0.3 s run
    # Against another run: the largest distance between the two end-effector errors.
    other = short_compare.runs["paper"]
    moved = dut.disturbance_displacement(run, other, windows=((0.0, 0.3),))[0]
    expected = np.linalg.norm(run.diagnostic("y_tilde")[:, :3]
                              - other.diagnostic("y_tilde")[:, :3], axis=1).max()
    assert moved["ee_moved_max_m"] == pytest.approx(expected)


# --- On the reliability layer -----------------------------------------------------------------
def _strict(text):
    return json.loads(text, parse_constant=lambda c: pytest.fail(f"{c} in JSON"))


def _signal_self(signum):
    os.kill(os.getpid(), signum)


def test_a_signal_stops_compare_before_the_next_controller(tmp_path, capsys, monkeypatch):
    """SIGTERM in the first controller's run: its logs are written, the second controller is
    not started, nothing is drawn, the exit is 128 + 15 with a JSON error on stdout; a stale
    log without its metrics.json is never loaded as a run."""
    def report(self, t):  # the first progress pause, at t = 1 s
        _signal_self(signal.SIGTERM)

    monkeypatch.setattr(runner._Progress, "report", report)
    stale = tmp_path / "compare" / "nominal" / "uncoupled"
    stale.mkdir(parents=True)
    (stale / "log.npz").write_bytes(b"not a log")  # a previous run's, without metrics.json
    status = cli.main(["compare", "nominal", "--controllers", "paper,uncoupled", "--jobs", "1",
                       "--duration", "1.5", "--quiet", "--json", "--out", str(tmp_path)])
    out, err = capsys.readouterr()
    assert status == 128 + signal.SIGTERM, err
    error = _strict(out)["error"]
    assert error["exit_status"] == 128 + signal.SIGTERM
    assert "interrupted (SIGTERM)" in err and "'uncoupled' not started" in err
    assert "Traceback" not in err and "unexpected" not in err
    folder = tmp_path / "compare" / "nominal"
    metrics = json.loads((folder / "paper" / "metrics.json").read_text())
    assert metrics["completed"] is False and metrics["failure"].startswith("interrupted (")
    assert not (stale / "metrics.json").exists() and not (stale / ".lock").exists()
    assert not list(folder.glob("compare_fig*")) and not (folder / "summary.txt").exists()


def test_a_signal_stops_the_process_pool(tmp_path):
    """With --jobs 2 and three controllers: SIGTERM in this process once a worker runs
    cancels the third run and terminates the workers; nothing is left running."""
    folder = tmp_path / "nominal"
    started = [folder / n / ".lock" for n in ("uncoupled", "static_compensation")]

    def signal_once_a_baseline_started():
        # As soon as the first run holds its folder: the third (paper) can start only after
        # a 15 s baseline run has finished, so it is certainly queued whatever the machine's
        # speed. (The deadline only keeps a broken pool from hanging the suite.)
        deadline = time.monotonic() + 900
        while not any(p.exists() for p in started) and time.monotonic() < deadline:
            time.sleep(0.02)
        _signal_self(signal.SIGTERM)

    threading.Thread(target=signal_once_a_baseline_started, daemon=True).start()
    with interrupts.handling():  # as the command line: SIGTERM raises, not ends pytest
        try:
            result = dut.run_compare("nominal", ("uncoupled", "static_compensation", "paper"),
                                     tmp_path, duration=15.0, jobs=2, progress=False)
        except KeyboardInterrupt:
            pytest.fail("the interruption escaped run_compare")
    assert result.interrupted == signal.SIGTERM and not result.completed
    # The third run never completes: it is cancelled in the queue ("not started") or, when a
    # worker had already taken it from the pool's queue as the stop arrived, interrupted there.
    paper = result.failures["paper"]
    assert "not started" in paper or "interrupted (SIGTERM)" in paper, paper
    if (folder / "paper" / "metrics.json").exists():
        assert not result.runs["paper"].metrics["completed"]
    assert multiprocessing.active_children() == []
    for name in ("uncoupled", "static_compensation"):
        if (folder / name / "metrics.json").exists():  # the worker wrote its logs on SIGTERM
            assert not result.runs[name].metrics["completed"]
    assert not list(folder.glob("compare_fig*")) and not (folder / "comparison.json").exists()


def test_folders_come_from_sanitised_names_and_json_is_alone_and_strict(tmp_path, capsys,
                                                                       monkeypatch):
    """A scenario named '../../x' writes into OUT/compare/x, nothing outside OUT; with --json
    stdout is one JSON document; comparison.json is strict JSON (a NaN becomes null)."""
    source = tmp_path / "in" / "escape.yaml"
    source.parent.mkdir()
    source.write_text(shipped_scenarios()["nominal"].read_text().replace(
        "name: nominal", 'name: "../../x"', 1))
    summary = dut.comparison_summary
    monkeypatch.setattr(dut, "comparison_summary",
                        lambda metrics: {**summary(metrics), "nan_check": math.nan})
    out = tmp_path / "a" / "b"
    status = cli.main(["compare", str(source), "--controllers", "paper", "--duration", "0.3",
                       "--quiet", "--json", "--out", str(out)])
    stdout, err = capsys.readouterr()
    assert status == 0, err
    printed = _strict(stdout)
    assert printed["nan_check"] is None and printed["paper"]["completed"] is True
    folder = out / "compare" / "x"
    assert (folder / "paper" / "metrics.json").is_file()
    assert _strict((folder / "comparison.json").read_text())["nan_check"] is None
    assert "wrote " in err and (folder / "summary.txt").is_file()
    outside = [p for p in tmp_path.rglob("*") if p.is_file()
               and not p.is_relative_to(out) and p != source]
    assert outside == []
    assert not list(folder.glob(".*.tmp"))


def test_a_file_as_out_is_bad_input_not_a_bug(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("")
    status = cli.main(["compare", "nominal", "--controllers", "paper", "--out", str(blocker),
                       "--json"])
    stdout, err = capsys.readouterr()
    assert status == 2, err
    error = _strict(stdout)["error"]
    assert error["kind"] == "OutputError" and error["exit_status"] == 2
    assert "unexpected" not in err and "choose another --out" in err


def test_results_not_written_exits_3(tmp_path, capsys, monkeypatch):
    def full_disk(folder, files, last):
        raise outputs.ResultsNotWritten(f"could not write the results into {folder} (disk "
                                        "full)")

    monkeypatch.setattr(runner, "write_result_set", full_disk)
    status = cli.main(["compare", "nominal", "--controllers", "paper,uncoupled", "--jobs", "1",
                       "--duration", "0.3", "--quiet", "--out", str(tmp_path)])
    err = capsys.readouterr().err
    assert status == 3, err
    assert "disk full" in err and "unexpected" not in err
    assert not (tmp_path / "compare" / "nominal" / "uncoupled").exists()  # stopped there


def test_exit_status_for_maps_each_error():
    from aerial_drake.dynamics.equilibrium import UnreachablePose

    expected = {ScenarioError("x"): 2, UnreachablePose("x"): 2, outputs.OutputError("x"): 2,
                outputs.ResultsNotWritten("x"): 3, runner.SimulationFailed("x"): 1,
                runner.SimulationInterrupted("x", signal.SIGHUP): 128 + signal.SIGHUP,
                interrupts.Interrupted(signal.SIGTERM): 128 + signal.SIGTERM,
                KeyboardInterrupt(): 130, OSError("x"): None, RuntimeError("x"): None}
    for err, status in expected.items():
        assert reporting.exit_status_for(err) == status, err


def test_displacement_windows_come_from_the_scenario(short_compare):
    run = short_compare.runs["uncoupled"]
    pushed = dataclasses.replace(run, scenario=dataclasses.replace(run.scenario, disturbances=[
        Disturbance(target="end_effector", start=0.15, stop=0.2),
        Disturbance(target="vehicle", start=0.05, stop=0.1)]))
    rows = dut.disturbance_displacement(pushed, run)
    assert [r["window_s"] for r in rows] == [[0.05, 0.1], [0.1, 0.15], [0.15, 0.2],
                                             [0.2, 1.2]]
    assert rows[0]["ee_moved_max_m"] == 0.0 and rows[-1]["ee_moved_max_m"] == 0.0
    assert dut.displacement_windows(run.scenario) == [(4.0, 5.0), (5.0, 6.0), (9.0, 10.0),
                                                      (10.0, 11.0)]


def test_the_overlays_shade_every_runs_windows_in_the_controllers_colours(short_compare):
    """The compare figures are viz.plots' overlays: every run's disturbance windows shaded
    (the union, not the first run's alone), each controller in its colour."""
    from aerial_drake.viz import compare as figures

    paper, uncoupled = short_compare.runs["paper"], short_compare.runs["uncoupled"]
    pushed = dataclasses.replace(uncoupled, scenario=dataclasses.replace(
        uncoupled.scenario, disturbances=[Disturbance(start=0.1, stop=0.2)]))
    runs = {"paper": dataclasses.replace(paper, scenario=dataclasses.replace(
        paper.scenario, disturbances=[])), "uncoupled": pushed}
    for make in (figures.figure_end_effector, figures.figure_orientation_errors,
                 figures.figure_inputs):
        fig = make(runs, "nominal")
        for ax in fig.axes:
            spans = [(round(p.get_x(), 9), round(p.get_x() + p.get_width(), 9))
                     for p in ax.patches]
            assert spans == [(0.1, 0.2)], make.__name__
        colors = {line.get_color() for line in fig.axes[0].lines}
        assert {"black", "tab:purple"} <= colors, make.__name__
        assert "nominal" in fig._suptitle.get_text()
