"""Study files: typed, validated with errors naming file and field, expanded into runs whose
identity is their resolved scenario."""

import subprocess
import sys
from pathlib import Path

import pytest

from aerial_drake.simulation.scenarios import ScenarioError
from aerial_drake.studies import spec as dut

SMALL = Path(__file__).resolve().parent / "small_study.yaml"


def test_runs_are_the_grid_times_the_draws_with_common_random_numbers():
    loaded = dut.load_study(SMALL)
    runs = dut.plan_runs(loaded)
    assert len(runs) == 2 * 3
    assert len({r.run_id for r in runs}) == 6
    by_point = {}
    for r in runs:
        by_point.setdefault(r.values["gains.k_R"], []).append(r)
    first, second = by_point[250.0], by_point[500.0]
    for a, b in zip(first, second):  # the same draw at both grid points
        assert a.draw == b.draw
        assert a.values["payload.mass"] == b.values["payload.mass"]
        assert a.values["model_mismatch.seed"] == b.values["model_mismatch.seed"]
    assert len({r.values["payload.mass"] for r in first}) == 3
    scenario = dut.scenario_from_text(second[0].scenario_text)
    assert scenario.gains.k_R == 500.0 and scenario.duration == 0.3
    assert scenario.model_mismatch.mass_error == 0.1  # the study's settings
    assert scenario.model_mismatch.seed == second[0].values["model_mismatch.seed"]
    # The same file plans the same runs.
    assert [r.run_id for r in dut.plan_runs(dut.load_study(SMALL))] == [r.run_id for r in runs]


def test_scale_mode_scales_every_entry():
    loaded = dut.load_study("gains")
    runs = dut.plan_runs(loaded)
    assert len(runs) == 25
    base = loaded.base.gains
    last = dut.scenario_from_text(runs[-1].scenario_text).gains
    assert last.K_y == [4.0 * k for k in base.K_y] and last.K_z == [4.0 * k for k in base.K_z]


def test_shipped_studies_load():
    # Each shipped study planned once (every planned run is validated: the costly part).
    # robustness_plus differs from robustness by its controller settings only (checked
    # below): its first 20 draws validate those, at a tenth of the cost.
    plans = {name: dut.plan_runs(dut.load_study(name),
                                 limit=20 if name == "robustness_plus" else None)
             for name in dut.shipped_studies()}
    sizes = {name: len(runs) for name, runs in plans.items()}
    assert sizes == {"robustness": 200, "gains": 25, "gains_attitude": 25, "directions": 200,
                     "directions_plus": 200, "robustness_plus": 20, "gains_plus": 25,
                     "gains_attitude_plus": 25,
                     "contact_robustness": 30, "contact_robustness_ur3e": 30,
                     "contact_robustness_ur3e_integral": 30}
    # The control draws the robustness study's directions, without its model error.
    robust, control = plans["robustness"], plans["directions"]
    for a, b in zip(robust, control):
        assert a.values["random_disturbances.seed"] == b.values["random_disturbances.seed"]
        assert b.values["payload.mass"] == 0.0
    # The _plus studies draw as their paper twins do, draw for draw, with paper_plus.
    for name in ("directions", "robustness", "gains", "gains_attitude"):
        for a, b in zip(plans[name], plans[name + "_plus"]):
            assert a.values == b.values
            plus = dut.scenario_from_text(b.scenario_text)
            assert plus.controller.type == "paper_plus"
            assert plus.controller.plus.wrench_compensation and plus.observer.enabled


def _write(tmp_path, text):
    path = tmp_path / "study.yaml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("text, words", [
    ("base: nominal\nparameters:\n  - {field: gains.k_Q, values: [1.0]}\n",
     "parameters[0].field"),
    ("base: nominal\nparameters:\n  - {field: gains.k_R, kind: sobol}\n", "parameters[0].kind"),
    ("base: nominal\nparameters:\n  - {field: gains.k_R}\n", "parameters[0].values"),
    ("base: nominal\nparameters:\n  - {field: gains.k_R, kind: uniform, low: 2.0, high: 1.0}\n",
     "parameters[0].low"),
    ("base: nominal\nparameters:\n  - {field: payload.mass, kind: seed}\n",
     "parameters[0].kind"),
    ("base: nominal\nmetrics: [phase*.nothing]\n", "metrics[0]"),
    ("base: nominal\ndraws: 0\n", "draws"),
    ("base: nominal\ndraws: 2\n", "the same scenario"),
    ("base: nominal\ndrawz: 2\n", "drawz"),
    ("base: nominal\nsettings:\n  payload: {mass: -1.0}\n", "payload.mass"),
    ("base: nowhere\n", "base"),
    ("base: nominal\nparameters:\n  - {field: gains.k_R, values: [-5.0]}\n", "gains.k_R"),
])
def test_bad_study_files_name_file_and_field(tmp_path, text, words):
    path = _write(tmp_path, text)
    with pytest.raises(ScenarioError) as err:
        dut.load_study(path)
    assert str(path) in str(err.value) and words in str(err.value)


def test_the_command_line_exits_2_on_a_bad_study(tmp_path):
    path = _write(tmp_path, "base: nominal\nparameters:\n  - {field: gains.k_Q, values: [1]}\n")
    done = subprocess.run([sys.executable, "-m", "aerial_drake.cli", "study", str(path)],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert "parameters[0].field" in done.stderr and str(path) in done.stderr
