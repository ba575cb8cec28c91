"""Tests of aerial_drake.studies.compare (``aerial-drake compare``): run folders as ``run``
writes them, the overlays, the side-by-side table, and bad controller lists."""

import json

import numpy as np
import pytest

from aerial_drake import cli
from aerial_drake.simulation.scenarios import ScenarioError
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
