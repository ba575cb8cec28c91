"""The result files: strict JSON, atomic writes, the set's order, the folder lock, the run
folder's name; and the Python API's checks of its caller."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from aerial_drake.simulation import outputs as dut
from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import ScenarioError, checks, load_scenario
from aerial_drake.simulation.scenarios.checks import folder_name

DOC = Path(__file__).resolve().parents[2] / "docs" / "reliability.md"


def test_strict_json_writes_null_for_non_finite_figures():
    text = dut.strict_json({"a": math.nan, "b": [1.0, math.inf], "c": {"d": -math.inf}})
    assert json.loads(text) == {"a": None, "b": [1.0, None], "c": {"d": None}}


def test_strict_json_takes_numpy_arrays_scalars_and_eigenvalues():
    """What the analysis report holds: arrays with NaN/inf, numpy scalars, complex poles."""
    text = dut.strict_json({"x": np.array([[1.0, np.nan], [np.inf, 2.0]]),
                            "s": np.float64(np.nan), "n": np.int64(3), "ok": np.bool_(True),
                            "poles": np.array([-1.0 + 2.0j, complex(np.nan, 1.0)])})
    assert json.loads(text) == {"x": [[1.0, None], [None, 2.0]], "s": None, "n": 3,
                                "ok": True, "poles": [[-1.0, 2.0], [None, 1.0]]}


@pytest.mark.parametrize("name,folder", [
    ("nominal", "nominal"), ("../../x", "x"), ("/etc/passwd", "etc_passwd"),
    ("a b/c", "a_b_c"), ("..", ""), ("", ""), (".hidden", "hidden"),
])
def test_run_folder_names_never_leave_the_output_folder(name, folder):
    assert folder_name(name) == folder


def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path):
    target = tmp_path / "f.txt"
    target.write_text("old")

    def fail(f):
        f.write(b"half")
        raise OSError(28, "No space left on device")

    with pytest.raises(OSError):
        dut.write_atomically(target, fail)
    assert target.read_text() == "old" and list(tmp_path.iterdir()) == [target]


def test_a_failed_set_removes_what_it_wrote_and_the_old_marker(tmp_path):
    (tmp_path / "metrics.json").write_text("{}")

    def fail(f):
        raise OSError(28, "No space left on device")

    with pytest.raises(dut.ResultsNotWritten, match="nothing of this run was left"):
        dut.write_result_set(tmp_path, [("a", lambda f: f.write(b"1")), ("b", fail)],
                             ("metrics.json", lambda f: f.write(b"{}")))
    assert list(tmp_path.iterdir()) == []


def test_the_lock_is_exclusive_and_freed_on_release(tmp_path):
    first = dut.prepare_folder(tmp_path)
    with pytest.raises(dut.OutputError, match="in use by another run"):
        dut.prepare_folder(tmp_path)
    first.release()
    dut.prepare_folder(tmp_path).release()


@pytest.mark.parametrize("call,match", [
    (lambda: run_scenario("nominal"), r"scenario: expected a Scenario, got str"),
    (lambda: run_scenario(load_scenario("nominal"), out_dir=123), r"out_dir: expected"),
    (lambda: load_scenario("nominal", overrides={"duraton": 2}), r"overrides\['duraton'\]"),
    (lambda: load_scenario("nominal", overrides={"duration": True}),
     r"overrides\['duration'\]: expected a number, got true"),
    (lambda: load_scenario("nominal", overrides={"gains": {"k_R": 1}}),
     r"overrides\['gains'\]: expected a Gains"),
    (lambda: load_scenario(123), r"scenario: expected a shipped scenario's name"),
])
def test_the_python_api_checks_its_caller(call, match):
    with pytest.raises((ScenarioError, dut.OutputError), match=match):
        call()


def test_every_range_is_in_the_reliability_doc():
    doc = DOC.read_text()
    ranges = [v for v in vars(checks).values() if isinstance(v, checks.Range)]
    ranges += [r for _, r in checks.TRAJECTORY.values()]
    for r in ranges:
        assert f"| {r.text()} | {r.fix} |" in doc, r
