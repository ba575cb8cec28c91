"""Runs, plots, compare and the Python API under bad input and faults (issue 27): plotting a
run without its user code, the names of ``extra_files``, a truncated or corrupt run folder,
too many or round-off disturbance windows, numpy arrays in vector fields, Ctrl-C while a
compiled module loads, ``compare --jobs 0``, a controller factory that is not callable, a
disturbance response cut short, compare's progress and table, the overlays' window labels.
Each exit status is checked on a real process (docs/reliability.md, "Exit statuses")."""

import dataclasses
import io
import json
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from aerial_drake.control import registry
from aerial_drake.simulation import metrics as metrics_module
from aerial_drake.simulation.outputs import OutputError
from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import (
    Disturbance,
    ScenarioError,
    load_scenario,
    shipped_scenarios,
)
from aerial_drake.studies.summary import format_summary, format_table
from tests.trajectories.test_kinds import _python_scenario

SHORT = 0.05


def cli(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    """``aerial-drake ARGS`` in a process of its own (its exit status is the one a shell sees)."""
    return subprocess.run([sys.executable, "-m", "aerial_drake", *args], capture_output=True,
                          text=True, timeout=300, cwd=cwd)


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory) -> Path:
    """One short nominal run's folder (read-only for the tests: they copy it)."""
    out = tmp_path_factory.mktemp("nominal_run")
    run_scenario(load_scenario("nominal", overrides={"duration": SHORT}), out_dir=out,
                 progress=False)
    return out


# --- plot: only the run's files, never the user's code -------------------------------------
USER_MODULE = """
import numpy as np
from aerial_drake.trajectories.reference import ReferenceSample

def still(t):
    # The paper's start: the end effector at (0.6, 0, 1.3) m, the CoM at the offset (33).
    com = np.zeros((5, 3))
    com[0] = [0.3, 0.0, 1.9]
    zero = np.zeros(3)
    return ReferenceSample(com=com, p_ed=np.array([0.6, 0.0, 1.3]), v_ed=zero, a_ed=zero,
                           R_ed=np.eye(3), w_ed=zero, dw_ed=zero, q_jd=np.zeros(1),
                           q_jd_dot=np.zeros(1), q_jd_ddot=np.zeros(1),
                           b1d=np.array([[1.0, 0, 0], [0, 0, 0], [0, 0, 0]]))
"""


def test_plot_of_a_python_run_needs_no_user_module(tmp_path):
    code = tmp_path / "code"
    code.mkdir()
    (code / "user_still.py").write_text(textwrap.dedent(USER_MODULE))
    scenario = _python_scenario(code, "user_still:still")
    ran = cli("run", str(scenario), "--out", str(tmp_path / "out"), "--duration", "0.1",
              "--quiet", "--no-plots")
    assert ran.returncode == 0, ran.stderr
    run = tmp_path / "out" / "nominal"  # (the scenario's name: the nominal file's)
    assert (run / "metrics.json").is_file()
    shutil.rmtree(code)  # the module moved away after the run
    plotted = cli("plot", str(run), "--out", str(tmp_path / "figs"))
    assert plotted.returncode == 0, plotted.stderr
    assert (tmp_path / "figs" / "fig3_end_effector.png").is_file()


# --- extra_files: plain names in the run's folder only -------------------------------------
@pytest.mark.parametrize("name", ["../outside.txt", "/tmp/absolute.txt", "sub/inner.txt",
                                  "..", "metrics.json", ".lock"])
def test_extra_files_names_that_leave_the_folder_are_refused_before_writing(tmp_path, name):
    scenario = load_scenario("nominal", overrides={"duration": SHORT})
    folder = tmp_path / "run"
    with pytest.raises(OutputError) as err:
        run_scenario(scenario, out_dir=folder, progress=False,
                     extra_files=lambda: {"replay.html": "ok", name: "x"})
    assert repr(name) in str(err.value) and "nothing was written" in str(err.value)
    assert sorted(p.name for p in folder.iterdir()) == [".lock"]  # nothing else written
    assert not (tmp_path / "outside.txt").exists()


# --- a damaged run folder given to plot: exit 2 naming the file ----------------------------
@pytest.mark.parametrize("damage, words", [
    ("truncate-log", ["log.npz", "truncated or corrupt"]),
    ("corrupt-metrics", ["metrics.json", "corrupt"]),
])
def test_plot_of_a_damaged_run_folder_exits_2_naming_the_file(run_folder, tmp_path, damage,
                                                               words):
    folder = tmp_path / "run"
    shutil.copytree(run_folder, folder)
    if damage == "truncate-log":
        data = (folder / "log.npz").read_bytes()
        (folder / "log.npz").write_bytes(data[:len(data) // 2])
    else:
        (folder / "metrics.json").write_text('{"scenario": "nominal", "phases": [')
    done = cli("plot", str(folder), "--out", str(tmp_path / "figs"))
    assert done.returncode == 2, done.stderr
    assert all(w in done.stderr for w in words), done.stderr
    assert "unexpected" not in done.stderr and "Traceback" not in done.stderr


# --- disturbance windows: too many, or edges apart by round-off ----------------------------
def _windows(n: int) -> str:
    return "".join(f"  - target: vehicle\n    start: {0.002 * k:.3f}\n    stop: "
                   f"{0.002 * k + 0.001:.4f}\n    force: [0.0, 5.0, 0.0]\n"
                   "    torque: [0.0, 0.0, 0.0]\n" for k in range(n))


def test_too_many_windows_exit_2_through_a_file_and_are_refused_by_the_api(tmp_path):
    nominal = shipped_scenarios()["nominal"].read_text()
    head = nominal[:nominal.index("disturbances:")]
    path = tmp_path / "many.yaml"
    path.write_text(head + "disturbances:\n" + _windows(1001))
    done = cli("run", str(path), "--out", str(tmp_path / "out"), "--quiet", "--no-plots")
    assert done.returncode == 2, done.stderr
    assert "disturbances" in done.stderr and "1000" in done.stderr, done.stderr
    assert not (tmp_path / "out").exists()
    # Fifty windows (many, but a scenario's worth) run, plot and read back.
    path.write_text(head + "disturbances:\n" + _windows(50))
    done = cli("run", str(path), "--out", str(tmp_path / "out"), "--quiet", "--duration", "0.2")
    assert done.returncode == 0, done.stderr
    scenario = load_scenario(path)
    with pytest.raises(ScenarioError, match="random_disturbances.count"):
        dataclasses.replace(scenario, random_disturbances=dataclasses.replace(
            scenario.random_disturbances, count=951)).validate()


def test_window_edges_apart_by_round_off_are_refused_naming_both():
    scenario = load_scenario("nominal")
    windows = [Disturbance(target="vehicle", start=0.1, stop=0.1 + 0.2),
               Disturbance(target="end_effector", start=0.3, stop=0.4)]
    with pytest.raises(ScenarioError) as err:
        dataclasses.replace(scenario, disturbances=windows).validate()
    assert "disturbances[1].start" in str(err.value) and "disturbances[0].stop" in str(err.value)
    # Equal edges (one window ends where the next begins) are fine.
    windows[0] = Disturbance(target="vehicle", start=0.1, stop=0.3)
    dataclasses.replace(scenario, disturbances=windows).validate()


# --- numpy arrays in vector fields through the API -----------------------------------------
def test_numpy_arrays_in_vector_fields_run_as_lists_and_validate_names_them(tmp_path):
    scenario = load_scenario("nominal", overrides={"duration": SHORT})
    arrays = dataclasses.replace(
        scenario, initial=dataclasses.replace(scenario.initial, arm_offset=np.zeros(7)),
        disturbances=[Disturbance(target="vehicle", start=0.01, stop=0.02,
                                  force=np.array([1.0, 2.0, 3.0]), torque=np.zeros(3))])
    with pytest.raises(ScenarioError) as err:
        arrays.validate()
    assert "initial.arm_offset is a numpy array" in str(err.value)
    assert err.value.field == "initial.arm_offset"
    result = run_scenario(arrays, out_dir=tmp_path, progress=False)
    assert result.scenario.disturbances[0].force == [1.0, 2.0, 3.0]
    assert isinstance(arrays.disturbances[0].force, np.ndarray)  # the caller's left alone
    written = load_scenario(tmp_path / "scenario.yaml")
    assert written.initial.arm_offset == [0.0] * 7


# --- Ctrl-C while a compiled module initialises ---------------------------------------------
INTERRUPTED_IMPORT = """
import sys
class Interrupting:
    # As pybind11 reports a KeyboardInterrupt during a module's initialisation.
    def find_spec(self, name, path=None, target=None):
        if name == "aerial_drake.dynamics.equilibrium":
            try:
                raise KeyboardInterrupt
            except KeyboardInterrupt as err:
                raise ImportError("initialization failed") from err
        return None
sys.meta_path.insert(0, Interrupting())
sys.argv = ["aerial-drake", "run", "nominal", "--out", sys.argv[1], "--quiet"]
from aerial_drake.cli import main
sys.exit(main())
"""


def test_ctrl_c_inside_a_module_import_exits_130(tmp_path):
    done = subprocess.run([sys.executable, "-c", INTERRUPTED_IMPORT, str(tmp_path / "out")],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 130, done.stderr
    assert "interrupted (Ctrl-C)" in done.stderr and "unexpected" not in done.stderr


# --- nonsense refused at once ---------------------------------------------------------------
def test_compare_jobs_0_exits_2_naming_the_option_and_range(tmp_path):
    done = cli("compare", "nominal", "--jobs", "0", "--out", str(tmp_path))
    assert done.returncode == 2
    assert "--jobs" in done.stderr and "1 to" in done.stderr and "got 0" in done.stderr
    assert not any(tmp_path.iterdir())


def test_compare_refuses_jobs_0_through_the_api(tmp_path):
    from aerial_drake.studies.compare import run_compare
    with pytest.raises(ScenarioError, match="jobs must be an integer, 1 to"):
        run_compare("nominal", ("paper",), tmp_path, jobs=0)


def test_register_controller_refuses_a_factory_that_is_not_callable():
    with pytest.raises(TypeError) as err:
        registry.register_controller("x", 42)
    assert "factory must be callable" in str(err.value) and "int 42" in str(err.value)
    assert "x" not in registry.controller_types()


# --- a response cut short is marked partial -------------------------------------------------
def test_a_disturbance_response_cut_short_is_partial_and_the_summary_says_so():
    t = np.linspace(0.0, 4.5, 4501)
    entries = {"ee_position_error": np.full((len(t), 1), 0.01),
               "com_error": np.full((len(t), 1), 0.02)}
    windows = [("vehicle", 4.0, 5.0), ("end_effector", 9.0, 10.0)]
    cut, after = metrics_module.disturbance_response(t, entries, windows)
    assert cut["partial"] is True and cut["log_end_s"] == 4.5
    assert after["ee_position_error_peak_m"] is None and "partial" not in after
    whole = metrics_module.disturbance_response(np.linspace(0, 15, 1501),
                                                {k: np.full((1501, 1), 0.01) for k in entries},
                                                windows)
    assert all("partial" not in r for r in whole)  # a complete response: as before
    m = {"scenario": "s", "simulated_time_s": 4.5, "wall_time_s": 1.0, "real_time_factor": 4.5,
         "phases": [], "min_sigma_min_J3": 0.2, "min_f_d_norm_N": 500.0,
         "saturated_s_total": {}, "disturbance_response": [cut, after], "completed": False}
    summary = format_summary(m)
    assert "response partial (the log ends at 4.5 s, before 6 s)" in summary
    table = format_table({"a": m})
    assert "partial: the log ends at" in table and "4.5 s" in table
    assert "9-10 s" not in table  # the window after the run's end has no rows
    assert "rotor" not in table  # a plant without rotors has no rotor rows


# --- compare: progress per finished run; overlays name whose windows ----------------------
def test_compare_prints_a_line_per_finished_run(tmp_path):
    from aerial_drake.studies.compare import run_compare
    stream = io.StringIO()
    result = run_compare("nominal", ("paper", "uncoupled"), tmp_path, duration=SHORT,
                         jobs=1, progress=True, stream=stream)
    assert result.completed
    text = stream.getvalue()
    assert "[1/2] 'nominal' with controller 'paper': done" in text
    assert "[2/2] 'nominal' with controller 'uncoupled': done" in text


def test_overlay_legend_names_the_runs_each_window_belongs_to(run_folder, tmp_path):
    from aerial_drake.viz import plots
    nominal = plots.load_run(run_folder)
    other = dataclasses.replace(nominal, scenario=dataclasses.replace(
        nominal.scenario, disturbances=[Disturbance(target="vehicle", start=0.01, stop=0.02)]))
    fig = plots.figure_com(plots.series([nominal, other], ["first", "second"]))
    labels = [t.get_text() for legend in fig.legends for t in legend.get_texts()]
    assert "force on the vehicle (0.01-0.02 s) of second" in labels, labels
    many = dataclasses.replace(nominal, scenario=dataclasses.replace(
        nominal.scenario, disturbances=[Disturbance(target="vehicle", start=0.004 * k,
                                                    stop=0.004 * k + 0.002)
                                        for k in range(10)]))
    fig = plots.figure_com(plots.series([many, other], ["first", "second"]))
    labels = [t.get_text() for legend in fig.legends for t in legend.get_texts()]
    windows = [label for label in labels if label.startswith("force on the vehicle")]
    assert windows == ["force on the vehicle (11 windows, 0-0.038 s) of first, second"], labels


def test_nominal_and_disturbed_descriptions_say_the_difference():
    nominal, disturbed = (load_scenario(n).description for n in ("nominal", "disturbed"))
    assert "rigid" in nominal and "rotors" in nominal and "lag" in nominal
    assert "rotors" in disturbed and "lag" in disturbed and "rigid model" in disturbed


def test_metrics_json_of_a_run_has_no_partial_key_when_complete(run_folder):
    metrics = json.loads((run_folder / "metrics.json").read_text())
    assert all("partial" not in r for r in metrics["disturbance_response"])
