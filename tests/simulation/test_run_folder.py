"""Reading a run folder (aerial_drake.simulation.run_folder): the files as written, and without
matplotlib, which only the figures import."""

import json
import subprocess
import sys

import numpy as np
import pytest

from aerial_drake.simulation import run_folder as dut
from aerial_drake.simulation.scenarios import shipped_scenarios


def _write_folder(folder, metrics=None):
    """A run folder with the shipped nominal scenario, a two-sample log and metrics."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "scenario.yaml").write_text(shipped_scenarios()["nominal"].read_text())
    np.savez(folder / "log.npz", t=np.array([0.0, 0.01]), state=np.zeros((2, 3)))
    (folder / "metrics.json").write_text(json.dumps(metrics or {"completed": True}))
    return folder


def test_load_run_reads_the_three_files(tmp_path):
    run = dut.load_run(_write_folder(tmp_path / "run", {"completed": True,
                                                        "input_limits": {"f": [0, 10]}}))
    assert run.name == "nominal" and run.scenario.name == "nominal"
    np.testing.assert_array_equal(run.t, [0.0, 0.01])
    assert run.metrics["completed"] is True
    assert run.input_limits() == {"f": (0, 10)}


def test_an_incomplete_folder_names_what_is_missing(tmp_path):
    folder = _write_folder(tmp_path / "run")
    (folder / "metrics.json").unlink()
    with pytest.raises(FileNotFoundError, match=r"missing \['metrics.json'\].*aerial-drake run"):
        dut.load_run(folder)


# In a fresh process: read a run through every path that reads runs (the library's batch and
# reports, the command line's modules), then say whether matplotlib was imported.
_READ_WITHOUT_FIGURES = """
import sys
import aerial_drake.cli.run, aerial_drake.cli.paper, aerial_drake.cli.compare
import aerial_drake.studies.batch, aerial_drake.studies.compare, aerial_drake.studies.paper
import aerial_drake.studies.summary
from aerial_drake.simulation.run_folder import load_run
run = load_run(sys.argv[1])
if len(sys.argv) > 2:
    import aerial_drake.viz.plots  # the figures: the check's own control
print("matplotlib" in sys.modules)
"""


@pytest.mark.parametrize("figures", [False, True])
def test_reading_a_run_imports_no_matplotlib(tmp_path, figures):
    folder = _write_folder(tmp_path / "run")
    argv = [sys.executable, "-c", _READ_WITHOUT_FIGURES, str(folder)] + (["x"] if figures else [])
    done = subprocess.run(argv, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    # Without figures no matplotlib; the control (viz.plots imported) shows the check sees it.
    assert done.stdout.strip().splitlines()[-1] == str(figures)
