"""The runnable diagram scripts in diagrams/ build, draw and run their diagram."""

import subprocess
import sys
from pathlib import Path

import pytest

SCRIPTS = sorted((Path(__file__).resolve().parent.parent / "diagrams").glob("[!_]*.py"))


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
