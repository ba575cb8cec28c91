"""The closed loop of Section III on the nominal plant (issue 3's claims, measured).

Integrators (scenario files): the sampled runs use Drake's runge_kutta3 with a fixed 1 ms step
(the controller's period, so each step sees one held command); the Lyapunov run uses continuous
feedback with the same integrator (its stages see the controller's continuous output).
"""

import json
from types import SimpleNamespace

import numpy as np
import pytest
from pydrake.systems.analysis import SimulatorConfig

from aerial_drake.control.law import diagnostics_slices
from aerial_drake.simulation.metrics import input_names
from aerial_drake.simulation.runner import SimulationFailed, run_scenario
from aerial_drake.simulation.scenarios import ScenarioError, load_scenario

N_TASK = 7  # the paper's task: end-effector pose and q3 (seven arm joints)
SL = diagnostics_slices(N_TASK)
INPUT_NAMES = input_names(N_TASK)
ERRORS = ("ee_position_error", "ee_orientation_error", "com_error", "base_attitude_error")
# Largest error after 5 s without disturbances (m, rad). The requirement is 1 mm / 1e-3 rad;
# the bounds sit 2-3x above what the law achieves (measured, drake 1.51.1 and 1.58.0 alike), so
# a law that still converges but worse (a wrong feed-forward, a lost coupling term) fails.
CONVERGED = {
    "ee_position_error": 1.5e-4,    # measured 5.61e-5 (2.7x)
    "ee_orientation_error": 1e-4,   # measured 3.35e-5 (3.0x)
    "com_error": 1e-3,              # measured 5.78e-4 (1.7x; the requirement)
    "base_attitude_error": 1e-3,    # measured 4.16e-4 (2.4x)
}
# The same on the orbit scenario (second trajectory; heading -0.15 rad/s since issue 31).
CONVERGED_ORBIT = {
    "ee_position_error": 1e-4,      # measured 2.93e-5 (3.4x)
    "ee_orientation_error": 3e-5,   # measured 8.78e-6 (3.4x)
    "com_error": 1e-3,              # measured 3.92e-4 (2.6x)
    "base_attitude_error": 8e-4,    # measured 2.71e-4 (3.0x)
}


def max_after(result, name, t0, t1=np.inf):
    t = result.log["t"]
    mask = (t >= t0) & (t <= t1)
    return float(result.log["diagnostics"][mask, SL[name]].max())


@pytest.fixture(scope="module")
def nominal(full_paper):
    """The paper's nominal scenario, 15 s, with both disturbance windows (from the shared
    paper run, conftest.py)."""
    run = full_paper.runs["nominal"]
    return SimpleNamespace(log=run.log, metrics=run.metrics,
                           out_dir=full_paper.out_dir / "nominal")


@pytest.fixture(scope="module")
def undisturbed():
    scenario = load_scenario("nominal", overrides={"duration": 10.0, "disturbances": []})
    return run_scenario(scenario, progress=False)


@pytest.mark.parametrize("error", ERRORS)
def test_nominal_converges_without_disturbances(undisturbed, error):
    assert max_after(undisturbed, error, 5.0) < CONVERGED[error]


def test_second_trajectory_converges():
    scenario = load_scenario("orbit", overrides={"duration": 10.0})
    result = run_scenario(scenario, progress=False)
    for error in ERRORS:
        assert max_after(result, error, 5.0) < CONVERGED_ORBIT[error], error
    # q3 is held at the orbit's joint target (q3d) 0.2 rad, not the paper's 0.
    assert scenario.trajectory.joint_targets == [0.2]
    t = result.log["t"]
    q3_error = result.log["diagnostics"][t >= 5.0, SL["y_tilde"]][:, 6]
    # Over the last 5 s, not at one sample (it oscillates through zero): measured 1.39e-5
    # (1.23e-5 at the former heading rate); held at the paper's 0 it would be 0.2.
    assert np.abs(q3_error).max() < 4e-5


def test_task_lyapunov_function_never_increases_with_continuous_feedback():
    """(24), (26): with continuous feedback, no saturation and no disturbance,
    V_task = 1/2 z~^T Lambda_z z~ + y~^T K_y K_z y~ is non-increasing."""
    scenario = load_scenario("nominal", overrides={
        "duration": 3.0, "controller_period": 0.0, "disturbances": [],
        "simulator": SimulatorConfig(integration_scheme="runge_kutta3", max_step_size=1e-3,
                                     use_error_control=False)})
    scenario.actuation.saturate = False
    result = run_scenario(scenario, progress=False)
    V = result.log["diagnostics"][:, SL["V_task"]][:, 0]
    assert V[-1] < 3e-4 * V[0]  # measured 1.14e-4 V[0] after 3 s (2.6x)
    # Integrator accuracy: RK3 at 1 ms has a local error ~1e-9 relative on these dynamics.
    assert np.diff(V).max() <= 1e-9 * V[0]


def test_disturbances_stay_bounded_and_reconverge(nominal):
    m = nominal.metrics
    phases = {(p["start_s"], p["end_s"]): p for p in m["phases"]}
    assert set(phases) == {(0.0, 4.0), (4.0, 5.0), (5.0, 9.0), (9.0, 10.0), (10.0, 15.0)}
    # Bounded during the windows (measured values beside each bound).
    assert phases[(4.0, 5.0)]["com_position_error_m"]["max"] < 0.44   # 0.220 m
    assert phases[(4.0, 5.0)]["ee_position_error_m"]["max"] < 4e-3    # 1.66e-3 m
    assert phases[(9.0, 10.0)]["ee_position_error_m"]["max"] < 0.2    # 0.137 m
    assert phases[(9.0, 10.0)]["ee_orientation_error_rad"]["max"] < 0.3  # 0.127 rad
    # Re-converged by the end of the following phase (4 s, or 5 s after the second window):
    # the last 0.5 s below this fraction of the window's peak. The CoM and attitude recover
    # with Table II's slowest closed-loop mode, k_R / k_w = 1.25 1/s (docs/analysis.md).
    recovered = {  # (window, metric): bound on tail / peak (measured)
        ((4.0, 5.0), "ee_position_error_m"): 0.035,       # 0.0142
        ((4.0, 5.0), "com_position_error_m"): 0.05,       # 0.0306
        ((4.0, 5.0), "base_attitude_error_rad"): 0.03,    # 0.0124
        ((9.0, 10.0), "ee_position_error_m"): 0.009,      # 0.00355
        ((9.0, 10.0), "com_position_error_m"): 0.024,     # 0.00948
        ((9.0, 10.0), "base_attitude_error_rad"): 0.009,  # 0.00355
    }
    diag_of = {"ee_position_error_m": "ee_position_error", "com_position_error_m": "com_error",
               "base_attitude_error_rad": "base_attitude_error"}
    ends = {(4.0, 5.0): 9.0, (9.0, 10.0): 15.0}
    for (window, key), bound in recovered.items():
        peak = phases[window][key]["max"]
        end = ends[window]
        assert max_after(nominal, diag_of[key], end - 0.5, end) < bound * peak, (window, key)


def test_metrics_file(nominal):
    m = json.loads((nominal.out_dir / "metrics.json").read_text())
    assert m["completed"] is True and m["failure"] is None and m["failure_cause"] is None
    assert len(m["phases"]) == 5
    log = np.load(nominal.out_dir / "log.npz")
    t = log["t"]
    for i, phase in enumerate(m["phases"]):
        # The phase's samples: [start, end), the last phase closed at the run's end.
        last = i == len(m["phases"]) - 1
        mask = (t >= phase["start_s"]) & ((t <= phase["end_s"]) if last else
                                          (t < phase["end_s"]))
        assert phase["samples"] == int(mask.sum())
        for key, diag in (("ee_position_error_m", "ee_position_error"),
                          ("ee_orientation_error_rad", "ee_orientation_error"),
                          ("com_position_error_m", "com_error"),
                          ("base_attitude_error_rad", "base_attitude_error")):
            assert set(phase[key]) == {"rms", "max"}
            e = log["diagnostics"][mask, SL[diag]][:, 0]
            # Recomputed from the log: an RMS that is a mean, or a max over the wrong
            # samples, fails here.
            assert phase[key]["rms"] == pytest.approx(np.sqrt(np.mean(e ** 2)), rel=1e-12)
            assert phase[key]["max"] == pytest.approx(e.max(), rel=1e-12)
        assert phase["min_sigma_min_J3"] > 0.05   # measured 0.0987 (9-10 s), 2.0x
        assert phase["min_f_d_norm_N"] > 250.0    # measured 517.7 N (9-10 s), 2.1x
        assert set(phase["saturated_s"]) == set(INPUT_NAMES)
    # That inputs saturate only in the first 0.5 s: tests/studies/test_paper.py.
    assert m["wall_time_s"] > 0
    assert m["real_time_factor"] == pytest.approx(m["simulated_time_s"] / m["wall_time_s"],
                                                  rel=1e-9)
    assert m["controller_evaluations"] == pytest.approx(15001, abs=2)
    for key in ("t", "plant_state", "command", "applied_command", "diagnostics",
                "com_reference", "task_reference", "heading_reference"):
        assert len(log[key]) == len(log["t"])


def test_assumption_violation_stops_with_time_and_value(tmp_path, monkeypatch):
    # A threshold the start meets (sigma_min(J_3) = 0.203) and the state stops meeting at
    # about 0.135 s: the run must stop there, naming Assumption 1, the time and the value,
    # and still write what it logged. The check of the whole reference would refuse this
    # limit before simulating (its margin is 3 x the limit); it is bypassed to reach the
    # in-run stop, which guards the states no check of the reference foresees (a
    # disturbance, a model error).
    monkeypatch.setattr("aerial_drake.simulation.runner.check_reference", lambda *a: None)
    scenario = load_scenario("nominal", overrides={"duration": 0.2, "sigma_min_J3_limit": 0.2})
    with pytest.raises(SimulationFailed, match=r"t = 0\.1\d+ s: Assumption 1 violated: J_3 is "
                                               r"singular, sigma_min\(J_3\) = 0\.\d+"):
        run_scenario(scenario, out_dir=tmp_path, progress=False)
    m = json.loads((tmp_path / "metrics.json").read_text())
    assert m["completed"] is False and "Assumption 1" in m["failure"]
    assert 0.1 < m["simulated_time_s"] < 0.2
    # Its cause from the log: none of the physical ones (the threshold was raised to stop it
    # in a calm run), the arm far from stretched, the time the message's.
    cause = m["failure_cause"]
    assert cause["cause"] == "other" and cause["time_s"] == pytest.approx(m["simulated_time_s"])
    assert cause["arm_stretch"] < 0.9 and cause["saturated_inputs"] == []
    assert cause["sigma_min_J3"] == pytest.approx(0.2, abs=1e-3)


def test_singular_start_posture_is_rejected_before_simulating(tmp_path, monkeypatch):
    # A threshold no state meets: refused before anything is simulated or written, naming
    # the field to change: by the check of the whole reference, and (that check bypassed) at
    # the start posture.
    scenario = load_scenario("nominal", overrides={"duration": 0.2, "sigma_min_J3_limit": 5.0})
    with pytest.raises(ScenarioError, match=r"trajectory: Assumption 1 fails along the "
                                            r"reference at t = 0\.\d+ s"):
        run_scenario(scenario, out_dir=tmp_path, progress=False)
    monkeypatch.setattr("aerial_drake.simulation.runner.check_reference", lambda *a: None)
    with pytest.raises(ScenarioError, match=r"initial: Assumption 1 fails at the start posture "
                                            r"\(t = 0\): J_3 is singular, sigma_min\(J_3\) = "
                                            r"0\.\d+ \(limit sigma_min_J3_limit = 5\)"):
        run_scenario(scenario, out_dir=tmp_path, progress=False)
    assert not (tmp_path / "metrics.json").exists() and not (tmp_path / "log.npz").exists()


def test_trajectory_outside_the_workspace_is_rejected_before_simulating():
    scenario = load_scenario("nominal")
    scenario.trajectory.agile_amplitude = 0.4
    with pytest.raises(ScenarioError, match="trajectory: .*leaves the arm's workspace"):
        run_scenario(scenario, progress=False)
