"""aerial_drake.simulation.metrics on synthetic logs with hand-computed answers, and the
workspace check (aerial_drake.simulation.feasibility.check_workspace) on both sides of its radius
(issue 22, item 3).

Every expected number below is computed by hand in the comment beside it, not by the code under
test. Signals are chosen so that the usual slips give different numbers: an RMS taken as a mean
(1 and 7 alternating: RMS 5, mean 4), a phase taken closed on both ends (the boundary samples
carry values of their own), a response window not cut at the tail or at the next window (a
larger peak just outside), a sign flipped in the workspace check's World-to-heading transform
(offsets whose size depends on that sign at a turned heading).
"""

import math

import numpy as np
import pytest

from aerial_drake.control.law import diagnostics_layout, diagnostics_size, diagnostics_slices
from aerial_drake.robots.models import make_plant, nominal_end_effector_offset
from aerial_drake.simulation import metrics as dut
from aerial_drake.simulation.feasibility import check_workspace
from aerial_drake.simulation.scenarios import ScenarioError, load_scenario
from aerial_drake.simulation.tracking import entries

N_TASK = 7  # the paper's task: end-effector pose and q3 (seven arm joints)
SL = diagnostics_slices(N_TASK)
DIAGNOSTICS_SIZE = diagnostics_size(N_TASK)
INPUT_NAMES = dut.input_names(N_TASK)
DT = 0.1


def named(d):
    """The synthetic log ``d`` (the paper law's diagnostics layout) by entry name: what the
    runner gives the metrics (its tracking errors and the controller's entries)."""
    return entries(d, diagnostics_layout(N_TASK))


def test_input_names_of_the_papers_robot():
    assert INPUT_NAMES == ("thrust", "mu_x", "mu_y", "mu_z", "tau_1", "tau_2", "tau_3",
                           "tau_4", "tau_5", "tau_6", "tau_7")


# --- phase_edges ------------------------------------------------------------------------------
@pytest.mark.parametrize("windows, duration, expected", [
    ([(4.0, 5.0), (9.0, 10.0)], 15.0, [0.0, 4.0, 5.0, 9.0, 10.0, 15.0]),  # the paper's
    ([(9.0, 10.0), (4.0, 5.0), (5.0, 6.0)], 15.0, [0.0, 4.0, 5.0, 6.0, 9.0, 10.0, 15.0]),
    ([(-1.0, 2.0), (14.0, 20.0)], 15.0, [0.0, 2.0, 14.0, 15.0]),  # edges outside dropped
    ([(0.0, 15.0)], 15.0, [0.0, 15.0]),  # edges on the run's ends are not inner edges
    ([], 3.0, [0.0, 3.0]),
])
def test_phase_edges(windows, duration, expected):
    assert dut.phase_edges(windows, duration) == expected


# --- compute_metrics --------------------------------------------------------------------------
@pytest.fixture
def synthetic():
    """21 samples at 0.1 s over [0, 2] s, two phases [0, 1) (10 samples: 0.0 .. 0.9) and
    [1, 2] (11 samples: 1.0 .. 2.0, the last phase is closed)."""
    t = np.round(np.arange(21) * DT, 12)
    d = np.zeros((t.size, DIAGNOSTICS_SIZE))
    first, second = t < 1.0, t >= 1.0
    ee = np.where(np.arange(t.size) % 2 == 0, 1.0, 7.0)  # 1, 7, 1, 7, ... in phase 1
    ee[second] = 0.0
    ee[15] = 6.0  # phase 2: one 6 among 11 samples
    d[:, SL["ee_position_error"]] = ee[:, None]
    d[:, SL["ee_orientation_error"]] = 0.25
    d[:, SL["com_error"]] = np.where(first, 2.0, 3.0)[:, None]
    # Base attitude error 3 at t = 1.0 only: the first sample of phase 2, not of phase 1.
    d[10, SL["base_attitude_error"]] = 3.0
    d[:, SL["sigma_min_J3"]] = 0.5
    d[4, SL["sigma_min_J3"]] = 0.3
    d[18, SL["sigma_min_J3"]] = 0.2
    d[:, SL["f_d_norm"]] = 500.0
    d[2, SL["f_d_norm"]] = 400.0
    d[20, SL["f_d_norm"]] = 350.0  # the last sample belongs to the last phase

    effort = np.array([165.0, 165.0, 70.0, 70.0, 70.0, 30.0, 30.0])
    lower = np.concatenate([[0.0, -200.0, -200.0, -200.0], -effort])
    upper = np.concatenate([[980.6, 200.0, 200.0, 200.0], effort])
    applied = np.zeros((t.size, 11))
    applied[:, 0] = 500.0
    applied[[0, 1, 2, 15], 0] = 980.6  # thrust at its limit at t = 0, 0.1, 0.2 and 1.5
    applied[[6, 7], 1] = -200.0  # mu_x at its lower limit at t = 0.6, 0.7 (after the grace)
    applied[12, 4] = 165.0 - 1e-12  # tau_1 within the tolerance (1e-9 * 980.6) of its limit
    applied[13, 4] = 165.0 - 1e-3  # tau_1 1 mN m short of it: not saturated
    applied[14, 10] = -30.0 - 5.0  # tau_7 beyond its lower limit (a lagged input may overshoot)
    return t, d, applied, lower, upper


def test_compute_metrics_per_phase(synthetic):
    t, d, applied, lower, upper = synthetic
    m = dut.compute_metrics(t, named(d), applied, lower, upper, [0.0, 1.0, 2.0], DT)
    p1, p2 = m["phases"]
    assert (p1["start_s"], p1["end_s"], p1["samples"]) == (0.0, 1.0, 10)
    assert (p2["start_s"], p2["end_s"], p2["samples"]) == (1.0, 2.0, 11)
    # Phase 1, 1 and 7 five times each: RMS sqrt((5 * 1 + 5 * 49) / 10) = 5 (a mean gives 4).
    assert p1["ee_position_error_m"]["rms"] == pytest.approx(5.0, rel=1e-12)
    assert p1["ee_position_error_m"]["max"] == 7.0
    # Phase 2: one 6 in 11 samples: RMS sqrt(36 / 11) = 1.80907 (a mean: 0.545).
    assert p2["ee_position_error_m"]["rms"] == pytest.approx(math.sqrt(36.0 / 11.0), rel=1e-12)
    assert p2["ee_position_error_m"]["max"] == 6.0
    for p in (p1, p2):
        assert p["ee_orientation_error_rad"] == pytest.approx({"rms": 0.25, "max": 0.25})
    assert p1["com_position_error_m"] == pytest.approx({"rms": 2.0, "max": 2.0})
    assert p2["com_position_error_m"] == pytest.approx({"rms": 3.0, "max": 3.0})
    # The sample at t = 1.0 is phase 2's: phase 1 sees no base attitude error; phase 2's RMS is
    # sqrt(9 / 11) = 0.904534.
    assert p1["base_attitude_error_rad"] == {"rms": 0.0, "max": 0.0}
    assert p2["base_attitude_error_rad"]["rms"] == pytest.approx(math.sqrt(9.0 / 11.0),
                                                                 rel=1e-12)
    assert p2["base_attitude_error_rad"]["max"] == 3.0
    assert (p1["min_sigma_min_J3"], p2["min_sigma_min_J3"]) == (0.3, 0.2)
    assert (p1["min_f_d_norm_N"], p2["min_f_d_norm_N"]) == (400.0, 350.0)
    assert m["min_sigma_min_J3"] == 0.2 and m["min_f_d_norm_N"] == 350.0


def test_saturated_time(synthetic):
    t, d, applied, lower, upper = synthetic
    m = dut.compute_metrics(t, named(d), applied, lower, upper, [0.0, 1.0, 2.0], DT)
    p1, p2 = m["phases"]
    after = m[dut.saturated_after_key()]
    assert dut.saturated_after_key() == "saturated_s_after_0.5s"
    zero = {name: 0.0 for name in INPUT_NAMES}
    # thrust: 3 samples (0.3 s) in phase 1, 1 (0.1 s) in phase 2; after 0.5 s only t = 1.5.
    # mu_x: t = 0.6, 0.7 (0.2 s), both after the grace. tau_1: t = 1.2 only. tau_7: t = 1.4.
    assert p1["saturated_s"] == pytest.approx({**zero, "thrust": 0.3, "mu_x": 0.2})
    assert p2["saturated_s"] == pytest.approx({**zero, "thrust": 0.1, "tau_1": 0.1,
                                               "tau_7": 0.1})
    assert m["saturated_s_total"] == pytest.approx({**zero, "thrust": 0.4, "mu_x": 0.2,
                                                    "tau_1": 0.1, "tau_7": 0.1})
    assert after == pytest.approx({**zero, "thrust": 0.1, "mu_x": 0.2, "tau_1": 0.1,
                                   "tau_7": 0.1})
    # Another grace: after 0.65 s, mu_x keeps t = 0.7 only.
    later = dut.compute_metrics(t, named(d), applied, lower, upper, [0.0, 2.0], DT,
                                saturation_grace=0.65)
    assert later["saturated_s_after_0.65s"]["mu_x"] == pytest.approx(0.1)
    # Without limits (a scenario that does not saturate) nothing is saturated.
    inf = np.full(11, np.inf)
    free = dut.compute_metrics(t, named(d), applied, -inf, inf, [0.0, 2.0], DT)
    assert free["saturated_s_total"] == zero


def test_metrics_of_an_empty_log():
    d = np.zeros((0, DIAGNOSTICS_SIZE))
    m = dut.compute_metrics(np.zeros(0), named(d), np.zeros((0, 11)), np.zeros(11), np.ones(11),
                            [0.0, 1.0], DT)
    assert m["phases"] == [{"start_s": 0.0, "end_s": 1.0, "samples": 0}]
    assert m["min_sigma_min_J3"] is None and m["min_f_d_norm_N"] is None


def test_metrics_of_a_controller_without_its_own_entries(synthetic):
    """A controller that reports neither base_attitude_error nor f_d_norm: those metrics are
    None, the errors and sigma_min (the tracking errors') as before; no KeyError."""
    t, d, applied, lower, upper = synthetic
    tracking = {k: v for k, v in named(d).items()
                if k not in ("base_attitude_error", "f_d_norm", "V", "e_R")}
    tracking["heading_error"] = np.full((t.size, 1), 0.5)
    tracking["heading_error"][7] = 2.0
    m = dut.compute_metrics(t, tracking, applied, lower, upper, [0.0, 1.0, 2.0], DT)
    p1, p2 = m["phases"]
    assert p1["base_attitude_error_rad"] is None and p1["min_f_d_norm_N"] is None
    assert m["min_f_d_norm_N"] is None and m["min_sigma_min_J3"] == 0.2
    assert p1["ee_position_error_m"]["max"] == 7.0 and p2["min_sigma_min_J3"] == 0.2
    # Over the run: twenty 0.5 and one 2: RMS sqrt((20 * 0.25 + 4) / 21) = sqrt(9 / 21).
    assert m["heading_error_rad"]["rms"] == pytest.approx(math.sqrt(9.0 / 21.0), rel=1e-12)
    assert m["heading_error_rad"]["max"] == 2.0
    assert dut.compute_metrics(t, named(d), applied, lower, upper, [0.0, 2.0],
                               DT)["heading_error_rad"] is None  # (not in the log)


# --- disturbance_response ---------------------------------------------------------------------
def response_log(peaks_ee, peaks_com, duration=15.0, dt=0.01):
    t = np.round(np.arange(int(round(duration / dt)) + 1) * dt, 12)
    d = np.zeros((t.size, DIAGNOSTICS_SIZE))
    for name, peaks in (("ee_position_error", peaks_ee), ("com_error", peaks_com)):
        for time, value in peaks.items():
            d[int(round(time / dt)), SL[name]] = value
    return t, d


def test_disturbance_response_windows_and_ratio():
    t, d = response_log(
        peaks_ee={4.5: 0.002, 5.9: 0.003, 6.1: 0.5, 10.8: 0.2, 11.2: 0.9},
        peaks_com={3.9: 0.4, 5.2: 0.1, 9.5: 0.05, 12.0: 1.0})
    out = dut.disturbance_response(t, named(d), [("helicopter", 4.0, 5.0),
                                                 ("end_effector", 9.0, 10.0)])
    heli, ee = out
    # Helicopter: [4, 5 + 1] s: ee peaks 0.002 (4.5), 0.003 (5.9); 0.5 at 6.1 is outside.
    # CoM: 0.1 (5.2); 0.4 at 3.9 is before the window. Ratio 0.003 / 0.1 = 0.03.
    assert heli["target"] == "helicopter" and heli["window_s"] == [4.0, 5.0]
    assert heli["evaluated_s"] == [4.0, 6.0]
    assert heli["ee_position_error_peak_m"] == 0.003
    assert heli["com_error_peak_m"] == 0.1
    assert heli["ee_to_com_peak_ratio"] == pytest.approx(0.03, rel=1e-12)
    # End effector: [9, 11] s: ee 0.2 (10.8), 0.9 at 11.2 outside; CoM 0.05. Ratio 4.
    assert ee["evaluated_s"] == [9.0, 11.0]
    assert ee["ee_position_error_peak_m"] == 0.2 and ee["com_error_peak_m"] == 0.05
    assert ee["ee_to_com_peak_ratio"] == pytest.approx(4.0, rel=1e-12)


def test_disturbance_response_is_cut_at_the_next_window():
    t, d = response_log(peaks_ee={1.5: 0.1, 2.6: 0.7}, peaks_com={1.2: 0.2, 2.7: 0.9},
                        duration=5.0)
    a, b = dut.disturbance_response(t, named(d), [("end_effector", 2.5, 3.0),
                                                  ("helicopter", 1.0, 2.0)])
    # Window (1, 2) s ends at min(2 + 1, 2.5) = 2.5 s: the peaks at 2.6 / 2.7 are b's only.
    assert b["evaluated_s"] == [1.0, 2.5]
    assert (b["ee_position_error_peak_m"], b["com_error_peak_m"]) == (0.1, 0.2)
    assert a["evaluated_s"] == [2.5, 4.0]
    assert (a["ee_position_error_peak_m"], a["com_error_peak_m"]) == (0.7, 0.9)
    assert a["ee_to_com_peak_ratio"] == pytest.approx(0.7 / 0.9, rel=1e-12)


def test_disturbance_response_beyond_the_log():
    t, d = response_log(peaks_ee={}, peaks_com={}, duration=3.0)
    (r,) = dut.disturbance_response(t, named(d), [("helicopter", 4.0, 5.0)])
    assert r["ee_position_error_peak_m"] is None and r["com_error_peak_m"] is None
    assert r["ee_to_com_peak_ratio"] is None
    # A window with no CoM error gives no ratio (not a division by zero).
    t, d = response_log(peaks_ee={1.5: 0.1}, peaks_com={}, duration=3.0)
    (r,) = dut.disturbance_response(t, named(d), [("helicopter", 1.0, 2.0)])
    assert r["ee_position_error_peak_m"] == 0.1 and r["ee_to_com_peak_ratio"] is None


# --- rotor_metrics ------------------------------------------------------------------------------
def test_rotor_metrics():
    speeds = np.array([[81.0, -82.0], [82.5, -81.5], [81.5, -81.9], [81.7, -81.6]])
    torque = np.array([[1.0, -2.0], [7.0, 2.0], [1.0, -2.0], [7.0, 2.0]])
    out = dut.rotor_metrics(speeds, torque, np.array([81.68, -81.68]))
    left, right = out["left"], out["right"]
    assert (left["speed_min_rad_s"], left["speed_max_rad_s"]) == (81.0, 82.5)
    # |81 - 81.68| = 0.68, |82.5 - 81.68| = 0.82.
    assert left["speed_max_deviation_rad_s"] == pytest.approx(0.82, rel=1e-12)
    assert right["speed_max_deviation_rad_s"] == pytest.approx(0.32, rel=1e-12)
    # RMS of 1, 7, 1, 7 is 5 (a mean: 4); of -2, 2, -2, 2 it is 2 (a mean: 0).
    assert left["drive_torque_rms_N_m"] == pytest.approx(5.0, rel=1e-12)
    assert right["drive_torque_rms_N_m"] == pytest.approx(2.0, rel=1e-12)
    assert (left["drive_torque_max_abs_N_m"], right["drive_torque_max_abs_N_m"]) == (7.0, 2.0)
    assert dut.rotor_metrics(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(2)) == {}


def test_limits_by_input():
    lower = np.concatenate([[0.0], -np.full(10, np.inf)])
    upper = np.concatenate([[980.6], np.full(10, 200.0)])
    out = dut.limits_by_input(lower, upper)
    assert out["thrust"] == [0.0, 980.6] and out["tau_7"] == [None, 200.0]
    assert list(out) == list(INPUT_NAMES)


# --- The workspace check ----------------------------------------------------------------------
#: The documented radius (the robot description's workspace_radius, docs/models.md): 0.2 m
#: about the nominal end-effector offset from the CoM, in the heading frame.
RADIUS = 0.2


@pytest.fixture(scope="module")
def model():
    return make_plant("rigid")


def test_workspace_radius_is_the_descriptions(model):
    assert model.description.workspace_radius == RADIUS


def workspace_scenario(model, deviation, heading, agile=0.0, heading_rate=0.0):
    """The paper's trajectory with its agile part ``agile`` (m) and a constant heading, and
    the CoM offset r_o chosen so that the desired end effector sits at ``deviation`` (heading
    frame, m) from the model's nominal offset: by (28) and (33), p_ed - x_d = x_a -
    R3(phi4) r_o, so in the heading frame R3^T x_a - r_o, and r_o = -(nominal + deviation)
    gives nominal + deviation + R3^T x_a."""
    nominal = nominal_end_effector_offset(model)
    scenario = load_scenario("nominal", overrides={"duration": 2.0})
    tr = scenario.trajectory
    tr.agile_amplitude = agile
    tr.heading_initial = heading
    tr.heading_rate = heading_rate
    tr.com_offset = list(-(nominal + np.asarray(deviation, dtype=float)))
    return scenario


@pytest.mark.parametrize("heading", [0.0, 0.7, -2.0])
@pytest.mark.parametrize("direction", [[1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1],
                                       [0.6, -0.8, 0.0]])
def test_workspace_radius_borderline(model, heading, direction):
    """1 mm inside the radius passes, 1 mm outside fails, in every direction of the heading
    frame and at turned headings."""
    u = np.asarray(direction, dtype=float)
    check_workspace(workspace_scenario(model, (RADIUS - 1e-3) * u, heading), model)
    with pytest.raises(ScenarioError, match=r"leaves the arm's workspace.* 0\.201 m from"):
        check_workspace(workspace_scenario(model, (RADIUS + 1e-3) * u, heading), model)


def test_workspace_is_judged_in_the_heading_frame(model):
    """Offsets whose size depends on the World-to-heading rotation's sign. With the heading
    at phi, a flipped sign of the transform's y row turns the heading-frame offset (a, b) into
    (a, a sin 2phi + b cos 2phi): the nominal offset's a = 0.3 m alone gives 0.3 sin 2phi."""
    a = nominal_end_effector_offset(model)[0]
    assert a == pytest.approx(0.3, abs=0.01)
    # On the nominal offset at heading 0.7 rad: deviation 0 (passes). Flipped: 0.30 m.
    check_workspace(workspace_scenario(model, [0.0, 0.0, 0.0], 0.7), model)
    # Heading rotating over the run (0.5 rad/s for 2 s): still deviation 0 at every sample.
    check_workspace(workspace_scenario(model, [0.0, 0.0, 0.0], 0.3, heading_rate=0.5), model)
    # 0.201 m to the right at phi = 0.5 atan(0.201 / a) (= 0.295 rad): fails; the flipped
    # transform gives a sin 2phi - 0.201 cos 2phi = 0 and would pass it.
    phi = 0.5 * math.atan2(0.201, a)
    with pytest.raises(ScenarioError, match="leaves the arm's workspace"):
        check_workspace(workspace_scenario(model, [0.0, -0.201, 0.0], phi), model)


def test_workspace_with_the_agile_motion(model):
    """On the nominal offset, the agile part x_a = A [sin 3t, cos 3t, cos 3t] (World) is, in
    the heading frame, a rotation of it: deviation A sqrt(sin^2 3t + 2 cos^2 3t), largest at
    t = 0 (a sample): A sqrt(2)."""
    inside, outside = (RADIUS - 1e-3) / math.sqrt(2), (RADIUS + 1e-3) / math.sqrt(2)
    check_workspace(workspace_scenario(model, [0, 0, 0], 0.7, agile=inside), model)
    with pytest.raises(ScenarioError, match=r"at t = 0\.00 s: it is 0\.201 m"):
        check_workspace(workspace_scenario(model, [0, 0, 0], 0.7, agile=outside), model)
    # The paper's own trajectory is inside (0.1 sqrt(2) = 0.141 m).
    check_workspace(load_scenario("nominal"), model)
