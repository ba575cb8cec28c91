"""The command line of the daily loop: a run draws its own figures, ``plot`` overlays runs,
``scenarios`` lists and prints the shipped ones, summaries and ``analyze`` read plainly."""

import contextlib
import io
import json

import numpy as np
import pytest
from pydrake.common.yaml import yaml_dump_typed

from aerial_drake.analysis.report import format_lee, format_open_loop
from aerial_drake.cli import build_parser
from aerial_drake.cli import main as dut
from aerial_drake.simulation.metrics import input_names
from aerial_drake.simulation.scenarios import load_scenario, shipped_scenarios
from aerial_drake.studies.summary import format_summary
from aerial_drake.viz import plots
from aerial_drake.viz.run_plots import run_labels

SHORT = "0.1"  # s: every run here is this long
FIGURES = {f"{name}.png" for name in plots.FIGURE_NAMES}


def run_cli(*argv: str) -> tuple[int, str]:
    """``aerial-drake ARGV`` in this process: (exit status, stdout)."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        status = dut(list(argv))
    return status, out.getvalue()


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Short runs of two scenarios with different references, and one without figures."""
    out = tmp_path_factory.mktemp("runs")
    for name in ("nominal", "orbit"):
        status, _ = run_cli("run", name, "--duration", SHORT, "--out", str(out), "--quiet")
        assert status == 0
    bare = tmp_path_factory.mktemp("bare")
    status, _ = run_cli("run", "nominal", "--duration", SHORT, "--out", str(bare), "--quiet",
                        "--no-plots")
    assert status == 0
    return out, bare


def test_a_run_writes_its_own_figures(runs):
    out, bare = runs
    for name in ("nominal", "orbit"):
        assert FIGURES <= {p.name for p in (out / name).glob("*.png")}, name
        for png in FIGURES:
            assert (out / name / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list((bare / "nominal").glob("*.png"))  # --no-plots


def test_plotting_leaves_the_metrics_unchanged(runs):
    """The figures come after the metrics, from the files: a run with them and one without
    have the same metrics but for the wall clock."""
    out, bare = runs
    clock = {"wall_time_s", "real_time_factor"}
    with_plots, without = (json.loads((d / "nominal" / "metrics.json").read_text())
                           for d in (out, bare))
    assert {k: v for k, v in with_plots.items() if k not in clock} == \
        {k: v for k, v in without.items() if k not in clock}
    assert np.array_equal(np.load(out / "nominal" / "log.npz")["applied_command"],
                          np.load(bare / "nominal" / "log.npz")["applied_command"])


def test_plot_overlays_two_scenarios_each_with_its_reference(runs, tmp_path):
    out, _ = runs
    status, text = run_cli("plot", str(out / "nominal"), str(out / "orbit"), "--out",
                           str(tmp_path))
    assert status == 0
    assert {p.name for p in tmp_path.glob("*.png")} == {
        "fig3_end_effector.png", "fig4_com.png", "fig5_orientation_errors.png",
        "fig6_inputs_nominal.png", "fig6_inputs_orbit.png"}
    assert "wrote" in text
    loaded = [plots.load_run(out / n) for n in ("nominal", "orbit")]
    for figure, which in ((plots.figure_end_effector, "end_effector"),
                          (plots.figure_com, "com")):
        fig = figure(plots.series(loaded))
        labels = [t.get_text() for legend in fig.legends for t in legend.get_texts()]
        assert {"nominal", "orbit", "desired (nominal)", "desired (orbit)"} <= set(labels)
        curves = [np.asarray(line.get_ydata()) for line in fig.axes[0].get_lines()]
        for run in loaded:  # both references drawn, each in full
            desired = getattr(run, which)()[0][:, 0]
            assert any(len(y) == len(desired) and np.allclose(y, desired) for y in curves)
    status, _ = run_cli("plot", str(tmp_path / "no_such_run"))
    assert status == 2


def test_runs_sharing_a_name_are_told_apart_by_folder(runs):
    out, bare = runs
    loaded = [plots.load_run(d / "nominal") for d in (out, bare)]
    labels = run_labels(loaded, [out / "nominal", bare / "nominal"])
    assert len(set(labels)) == 2 and all(label.startswith("nominal (") for label in labels)


def test_fig6_zooms_on_the_start_and_draws_each_inputs_limits(runs):
    out, _ = runs
    run = plots.load_run(out / "nominal")
    fig = plots.figure_inputs(run)
    u = run.log["applied_command"]
    limits = run.input_limits()
    index = {n: k for k, n in enumerate(input_names(7))}  # the paper's seven arm joints
    for row, names in enumerate(plots.input_rows(7)):
        full, zoom = fig.axes[2 * row], fig.axes[2 * row + 1]
        data = [line for line in full.get_lines() if len(line.get_xdata()) > 2]
        assert [list(line.get_ydata()) for line in data] == [list(u[:, index[n]])
                                                            for n in names]
        assert zoom.get_xlim() == pytest.approx((0.0, plots.ZOOM_S))
        drawn = {round(float(line.get_ydata()[0]), 9) for line in full.get_lines()
                 if len(line.get_xdata()) == 2}
        expected = {round(float(b), 9) for n in names for b in limits[n] if b is not None}
        assert drawn == expected, names
    assert 45.0 not in {abs(float(line.get_ydata()[0])) for line in fig.axes[2 * 8].get_lines()
                        if len(line.get_xdata()) == 2}  # tau_7's panel: q7's limit only


def test_scenarios_lists_every_shipped_one_with_its_description():
    status, text = run_cli("scenarios")
    assert status == 0
    lines = text.splitlines()
    for name in shipped_scenarios():
        line = next(line for line in lines if line.startswith(name + " "))
        assert load_scenario(name).description.split(":")[0] in line


@pytest.mark.parametrize("name", sorted(shipped_scenarios()))
def test_scenarios_show_prints_a_file_that_loads_as_the_shipped_one(name, tmp_path):
    status, text = run_cli("scenarios", "show", name)
    assert status == 0
    saved = tmp_path / "edited.yaml"
    saved.write_text(text)
    assert yaml_dump_typed(load_scenario(saved)) == yaml_dump_typed(load_scenario(name))


def test_scenarios_show_names_the_valid_ones():
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        assert run_cli("scenarios", "show", "nominall")[0] == 2
    assert "Valid names are" in err.getvalue() and "'nominal'" in err.getvalue()


def _metrics() -> dict:
    phase = {"start_s": 0.0, "end_s": 4.0, "samples": 10,
             **{k: {"rms": 0.001, "max": 0.0012345678}
                for k in ("ee_position_error_m", "ee_orientation_error_rad",
                          "com_position_error_m", "base_attitude_error_rad")}}
    return {"scenario": "nominal", "simulated_time_s": 15.0, "wall_time_s": 3.2,
            "real_time_factor": 4.6875, "phases": [phase], "min_sigma_min_J3": 0.123456,
            "min_f_d_norm_N": 369.6123,
            "saturated_s_total": {"thrust": 0.0, "mu_y": 0.018000000000000002},
            "saturated_s_after_0.5s": {"thrust": 0.0, "mu_y": 0.0}}


def test_summary_is_a_rounded_table():
    text = format_summary(_metrics())
    assert "0.018000000000000002" not in text and "{" not in text
    row = next(line for line in text.splitlines() if line.startswith("mu_y"))
    assert row.split() == ["mu_y", "0.018", "0.000"]
    assert "thrust" not in text.split("input at a limit")[1]  # only inputs that saturated
    assert "1.235" in text  # 1.2345678 mm at three decimals


def test_analyze_help_describes_and_shows_defaults():
    parser = build_parser()
    analyze = parser._subparsers._group_actions[0].choices["analyze"]
    help_text = analyze.format_help()
    assert "Lyapunov" in help_text and "region of attraction" in help_text
    assert "(default: nominal)" in help_text and "(default: out/analysis)" in help_text
    assert "(default: 0)" in help_text


def test_open_loop_verdict_reads_without_the_docs():
    ol = {"IsControllable": False, "IsControllable_time_scaled": True, "IsStabilizable": True,
          "pbh_max_rank_deficiency": 0, "controllability_matrix_conditioning": 5.2e-17,
          "time_scaled_conditioning": 7.6e-5, "controllability_rank_growth": [11, 22, 24, 26],
          "states": 26, "rank_B": 11}
    text = "\n".join(format_open_loop(ol))
    assert ": controllable;" in text and "stabilisable" in text
    assert "numerically singular" in text and "time-scaled" in text
    ol.update(IsControllable_time_scaled=False, pbh_max_rank_deficiency=2, IsStabilizable=False)
    assert "NOT controllable" in format_open_loop(ol)[0]


def test_a_sufficient_condition_not_met_is_not_called_instability():
    lee = {"gamma1": 20.0, "gamma1_bounds": {"a": 82.1}, "gamma1_ok": True, "gamma2": 0.4,
           "gamma2_bounds": {"b": 0.443}, "gamma2_ok": True, "gamma2_per_axis_bounds": [1.78],
           "gamma2_per_axis_ok": True, "coupling_ok": False,
           "coupling_possible_for_some_gammas": np.False_}
    text = "\n".join(format_lee(lee))
    assert "sufficient, not necessary" in text and "not a sign of instability" in text
    assert "VIOLATED" not in text


def test_a_run_without_plots_never_imports_matplotlib(tmp_path):
    """Plotting is the only reason a run imports Matplotlib (``-X importtime`` lists every
    module imported)."""
    import subprocess
    import sys

    def imported(*flags: str) -> str:
        done = subprocess.run(
            [sys.executable, "-X", "importtime", "-m", "aerial_drake", "run", "nominal",
             "--duration", "0.05", "--quiet", "--out", str(tmp_path), *flags],
            capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stderr[-2000:]
        return done.stderr

    assert "matplotlib" not in imported("--no-plots")
    assert "matplotlib" in imported()


@pytest.mark.parametrize("flag", [["--hold"], ["--no-wait"], ["--wait-timeout", "5"]])
def test_live_view_options_need_meshcat(flag, capsys):
    assert dut(["run", "nominal", "--duration", SHORT, *flag]) == 2
    assert "add --meshcat" in capsys.readouterr().err
