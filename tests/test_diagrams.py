"""The runnable diagram scripts in diagrams/ build, draw and run their diagram; the custom
controller example is one short subclass of the controller base, run through ``compare``
beside the paper's controller."""

import ast
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

DIAGRAMS = Path(__file__).resolve().parent.parent / "diagrams"
SCRIPTS = sorted(DIAGRAMS.glob("[!_]*.py"))


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.stem)
def test_diagram_script_runs(script, tmp_path):
    done = subprocess.run([sys.executable, str(script), "--duration", "0.05", "--out",
                           str(tmp_path)], cwd=script.parent, capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr
    dot = next(tmp_path.glob("*_closed_loop.dot")).read_text()
    for block in ("plant", "controller", "reference", "end_effector_wrench", "base_actuator"):
        assert block in dot
    assert next(tmp_path.glob("**/metrics.json")).is_file()
    if script.stem == "custom_controller":
        _check_the_comparison(tmp_path)


def _check_the_comparison(out: Path):
    """``compare`` ran the example beside the paper: a column each, and the example's log
    holds its own diagnostics by name and the errors measured from the state."""
    compared = out / "nominal"
    assert (compared / "summary.txt").read_text().split()[:2] == ["paper", "joint_hold"]
    for name in ("paper", "joint_hold"):
        metrics = json.loads((compared / name / "metrics.json").read_text())
        assert metrics["completed"], name
        assert metrics["phases"][0]["ee_position_error_m"]["max"] > 0.0, name
    log = np.load(compared / "joint_hold" / "log.npz")
    layout = json.loads(str(log["layout"]))
    assert layout["diagnostics"] == [["e_R", 3], ["w_tilde", 3],
                                     ["base_attitude_error", 1], ["f_d_norm", 1]]
    assert np.all(np.isfinite(log["diagnostics"]))
    assert np.all(np.isfinite(log["tracking"]))


def test_custom_controller_is_one_short_subclass():
    """The example's controller: a ControllerBase subclass of at most 60 lines, with no port,
    state or cache declaration of its own (the base owns them)."""
    source = (DIAGRAMS / "custom_controller.py").read_text()
    classes = [node for node in ast.parse(source).body if isinstance(node, ast.ClassDef)]
    assert [c.name for c in classes] == ["JointHoldController"]
    (cls,) = classes
    assert [ast.unparse(b) for b in cls.bases] == ["ControllerBase"]
    assert cls.end_lineno - cls.lineno + 1 <= 60
    body = ast.get_source_segment(source, cls)
    assert "Declare" not in body
