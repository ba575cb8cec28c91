"""The analysis of issue 6: hover equilibria, Drake's Linearize of the closed loop against design
note 6, open-loop stabilisability, V(t) of (24)-(25), the region-of-attraction study, the CLI
and the AutoDiffXd controller it all rests on."""

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest
from pydrake.autodiffutils import AutoDiffXd, ExtractGradient, ExtractValue, InitializeAutoDiff

from aerial_drake import analysis as dut
from aerial_drake.analysis.report import format_lyapunov
from aerial_drake.control.controller import DecoupledController_, make_controller
from aerial_drake.dynamics.equilibrium import UnreachablePose
from aerial_drake.robots.description import shipped_robots
from aerial_drake.robots.models import make_plant
from aerial_drake.simulation.scenarios import load_scenario
from aerial_drake.trajectories.kinds import evaluate_reference
from aerial_drake.trajectories.params import TrajectoryParams


@pytest.fixture(scope="module")
def gains():
    return load_scenario("nominal").gains


#: One scenario per shipped robot: the equilibria, linearisations and the open loop are
#: checked on each.
ROBOT_CASES = ["nominal", "quadrotor_ur3e"]


def test_the_cases_cover_every_shipped_robot():
    assert {load_scenario(name).robot for name in ROBOT_CASES} == set(shipped_robots())


@pytest.fixture(scope="module", params=ROBOT_CASES)
def robot_case(request):
    """(scenario, its robot's rigid model with an rpy base)."""
    scenario = load_scenario(request.param)
    return scenario, scenario.controller_model(floating_base="rpy")


@pytest.fixture(scope="module")
def equilibria(robot_case):
    return dut.default_equilibria(robot_case[1])


@pytest.fixture(scope="module")
def linearizations(equilibria, robot_case):
    return {name: dut.linearize_closed_loop(eq, robot_case[0].gains)
            for name, eq in equilibria.items()}


def test_equilibria_differ(equilibria):
    a, b = equilibria["nominal"], equilibria["turned"]
    assert np.linalg.norm(a.p_WE - b.p_WE) > 0.1 and np.abs(a.q - b.q).max() > 0.1


@pytest.mark.parametrize("name", ["nominal", "turned"])
def test_hover_inputs_hold_the_equilibrium(equilibria, linearizations, name):
    eq, lin = equilibria[name], linearizations[name]
    m = eq.model.total_mass()
    # A level base: the thrust carries the whole weight and nothing pushes sideways.
    assert eq.thrust == pytest.approx(m * 9.81, rel=1e-12)
    assert eq.horizontal_force_residual < 1e-9
    # The closed loop is at rest there, and the controller's command at zero error is the
    # static balance F = g(q) (it applies exactly the hover inputs).
    assert lin.derivative_residual < 1e-9
    np.testing.assert_allclose(lin.command_at_equilibrium, eq.inputs, rtol=0, atol=1e-9)
    # The configuration realises the request.
    ctx = eq.model.plant.CreateDefaultContext()
    eq.model.plant.SetPositions(ctx, eq.q)
    np.testing.assert_allclose(eq.model.plant.CalcCenterOfMassPositionInWorld(ctx), eq.p_WG,
                               atol=1e-9)
    X_WE = eq.model.end_effector_frame.CalcPoseInWorld(ctx)
    np.testing.assert_allclose(X_WE.translation(), eq.p_WE, atol=1e-9)
    np.testing.assert_allclose(X_WE.rotation().matrix(), eq.R_WE, atol=1e-9)


def test_unreachable_hover_names_the_constraint():
    with pytest.raises(UnreachablePose, match=r"no hover equilibrium .*end-effector position"):
        dut.hover_equilibrium([0.0, 0.0, 2.0], [3.0, 0.0, 1.4], np.eye(3))


@pytest.mark.parametrize("name", ["nominal", "turned"])
def test_closed_loop_eigenvalues_match_design_note_6(linearizations, name):
    lin = linearizations[name]
    n = lin.equilibrium.model.n
    assert lin.A.shape == (2 * (6 + n),) * 2  # rpy base, no quaternion norm direction
    assert {r["group"] for r in lin.table} == {"com", "attitude", "task_y", "task_z"}
    assert len(lin.table) == 2 * (6 + n)
    assert lin.max_relative_mismatch < 1e-6
    assert np.all(lin.eigenvalues.real < 0)


def test_task_poles_depend_on_the_equilibrium(linearizations):
    # -Lambda_z^-1 K_z changes with the configuration, the rest does not: the two equilibria
    # exercise different predictions.
    z = {n: sorted(r["predicted"][0] for r in lin.table if r["group"] == "task_z")
         for n, lin in linearizations.items()}
    assert np.abs(np.subtract(z["nominal"], z["turned"])).max() > 0.1


@pytest.mark.parametrize("name", ["nominal", "turned"])
def test_open_loop_is_stabilizable(equilibria, name):
    eq = equilibria[name]
    system = dut.linearize_open_loop(eq)
    report = dut.controllability(system)
    assert report["IsStabilizable"]
    assert report["IsControllable_time_scaled"]
    assert report["pbh_max_rank_deficiency"] == 0
    # Underactuation: 4 + n inputs for 6 + n velocities (the paper's: 11 for 13); the missing
    # directions are reached through the attitude (two more integrations).
    n = eq.model.n
    assert report["rank_B"] == 4 + n
    assert report["controllability_rank_growth"] == [4 + n, 8 + 2 * n, 10 + 2 * n, 12 + 2 * n]
    # The forces the inputs cannot produce: horizontal forces on the base (World x, y).
    missing = dut.unactuated_directions(eq, system)
    assert missing.shape == (2, 6 + n)
    np.testing.assert_allclose(missing[:, 3:5] @ missing[:, 3:5].T, np.eye(2), atol=1e-9)


def test_lee_conditions_bounds_are_where_W2_turns_singular(gains):
    m = make_plant("rigid").total_mass()
    lee = dut.lee_conditions(gains, m, accel_bound=m * 9.81)
    bound = lee["gamma2_bounds"]["4 k_w k_R l_min^2 / (k_w^2 l_max + 4 k_R l_min^2)"]
    g = dataclasses.replace(gains, lyapunov_gamma2=bound)
    assert abs(dut.lee_conditions(g, m, accel_bound=m * 9.81)["lambda_min_W2"]) < 1e-9
    assert lee["gamma1_ok"]


def test_lyapunov_function_decreases_without_disturbances():
    # Continuous feedback, no saturation, runge_kutta3 with error control at accuracy 1e-8.
    result = dut.lyapunov_study("nominal", duration=0.3, accuracy=1e-8)
    s = result.summary()
    assert s["integrator"] == {"scheme": "runge_kutta3", "accuracy": 1e-8,
                               "use_error_control": True, "max_step_size_s": 1e-3}
    assert len(result.t) == 301
    for name in ("V", "V_task"):
        x = getattr(result, name)
        assert x[-1] < 0.7 * x[0]
        assert s[name]["max_increase"] <= 1e-9 * x[0], name
    np.testing.assert_allclose(result.V, result.V1 + result.V_task, rtol=1e-12)
    assert s["started_on_reference"] is False
    assert "V never increased along the run" in format_lyapunov(s)


def test_a_run_started_on_its_reference_is_reported_as_round_off():
    """No initial offset from a reference at rest: V(0) is round-off (about 1e-28), and the
    report says the check shows nothing instead of judging V's rises of 1e-30 (issue 27)."""
    nominal = load_scenario("nominal")
    hover = dataclasses.replace(nominal.trajectory, kind="hover")  # at rest: starts on it
    base = dataclasses.replace(nominal, trajectory=hover, initial=dataclasses.replace(
        nominal.initial, base_position_offset=[0.0, 0.0, 0.0],
        base_rpy_offset=[0.0, 0.0, 0.0], arm_offset=[]))
    s = dut.lyapunov_study(base, duration=0.05, accuracy=1e-8).summary()
    assert s["started_on_reference"] is True and s["V"]["initial"] < 1e-20
    assert math.isnan(s["V"]["max_increase_relative"])
    line = format_lyapunov(s)
    assert "round-off" in line and "started on its reference" in line
    assert "initial.base_position_offset" in line and "never increased" not in line


def test_region_of_attraction_small_offsets_converge():
    roa = dut.region_of_attraction("nominal", scales=(0.5,), samples=1, duration=0.4)
    (run,) = roa.runs
    assert run["completed"] and run["converged"], run
    assert roa.fractions == [1.0]
    assert np.linalg.norm(run["base_rpy_offset"]) == pytest.approx(0.05)


def test_autodiff_controller_matches_double(gains):
    model = make_plant("rigid")
    ctrl = make_controller(model, gains)
    ad = ctrl.ToAutoDiffXd()
    assert isinstance(ad, DecoupledController_[AutoDiffXd])
    q = model.plant.GetPositions(model.plant.CreateDefaultContext())
    q[4:7] = [0.1, -0.2, 2.0]
    x = np.concatenate([q, np.random.default_rng(3).normal(scale=0.2, size=13)])
    refs = evaluate_reference(TrajectoryParams(), 0.4).to_vectors()
    out = ctrl.solve(x, *refs)
    out_ad = ad.solve(InitializeAutoDiff(x).ravel(), *refs)
    u = np.concatenate([[out.f], out.mu, out.tau])
    u_ad = np.concatenate([[out_ad.f], out_ad.mu, out_ad.tau])
    np.testing.assert_allclose(ExtractValue(u_ad).ravel(), u, rtol=1e-10, atol=1e-9)
    # The gradient Linearize uses: d u / d x against central differences of the double law.
    gradient = ExtractGradient(u_ad)
    assert gradient.shape == (11, x.size)
    h = 1e-6
    fd = np.empty_like(gradient)
    for k in range(x.size):
        step = np.zeros_like(x)
        step[k] = h
        hi, lo = ctrl.solve(x + step, *refs), ctrl.solve(x - step, *refs)
        fd[:, k] = (np.concatenate([[hi.f], hi.mu, hi.tau])
                    - np.concatenate([[lo.f], lo.mu, lo.tau])) / (2 * h)
    scale = np.abs(fd).max()
    assert scale > 1.0  # the inputs do depend on the state
    # measured 1.9e-11 * scale; central differences at h = 1e-6 are good to ~1e-10 here
    np.testing.assert_allclose(gradient, fd, rtol=0, atol=1e-8 * scale)


def test_cli_analyze_fast(tmp_path, capsys):
    from aerial_drake.cli import main
    assert main(["analyze", "--fast", "--quiet", "--out", str(tmp_path)]) == 0
    report = json.loads((tmp_path / "analysis.json").read_text())
    for name in ("nominal", "turned"):
        assert report["equilibria"][name]["closed_loop"]["max_relative_mismatch"] < 1e-6
        assert report["equilibria"][name]["open_loop"]["IsStabilizable"]
    assert report["lyapunov"]["V"]["max_increase"] <= 1e-9 * report["lyapunov"]["V"]["initial"]
    assert {p.name for p in tmp_path.glob("*.png")} == {
        "eigenvalues.png", "lyapunov.png", "region_of_attraction.png"}
    assert "max relative eigenvalue mismatch" in capsys.readouterr().out


NOTEBOOKS = Path(__file__).resolve().parents[2] / "notebooks"


@pytest.mark.parametrize("name", ["paper_reproduction", "stability_analysis"])
def test_notebook_runs_top_to_bottom(name, tmp_path, monkeypatch):
    # nbformat and nbclient come with the "test" extra (pip install -e ".[test]").
    import nbclient
    import nbformat

    monkeypatch.setenv("AERIAL_DRAKE_FAST", "1")  # the notebooks shorten their runs
    monkeypatch.setenv("AERIAL_DRAKE_OUT", str(tmp_path))
    notebook = nbformat.read(NOTEBOOKS / f"{name}.ipynb", as_version=4)
    nbclient.NotebookClient(notebook, timeout=900, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()
    errors = [o for c in notebook.cells if c.cell_type == "code" for o in c.get("outputs", [])
              if o.get("output_type") == "error"]
    assert not errors
