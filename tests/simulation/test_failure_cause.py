"""aerial_drake.simulation.failure_cause: each cause from a synthetic log, the decision order,
and the arm's stretch on the paper's robot."""

import numpy as np
import pytest

from aerial_drake.simulation import failure_cause as dut
from aerial_drake.simulation.metrics import input_names

NAMES = input_names(7)
UPPER = np.array([980.6, 200, 200, 200, 165, 165, 70, 70, 70, 30, 30], dtype=float)
LOWER = np.concatenate([[0.0], -UPPER[1:]])
A1 = "t = 3.0000 s: Assumption 1 violated: J_3 is singular, sigma_min(J_3) = 0.0009 (limit 0.001)"


def hover_log(duration=3.0, dt=1e-3):
    """A calm log: hover thrust, small slow torques (the reference's 0.5 Hz), sigma 0.2."""
    t = np.arange(0.0, duration, dt)
    command = np.zeros((t.size, 11))
    command[:, 0] = 540.0
    command[:, 1:] = np.sin(np.pi * t)[:, None] * np.linspace(1.0, 2.0, 10)
    return t, command, np.full(t.size, 0.2)


def classify(message, t, command, sigma=None, stretch=0.8):
    """The cause of a log whose inputs are ``command`` applied (clipped at the limits)."""
    return dut.classify_failure(
        message, t=t, applied=np.clip(command, LOWER, UPPER), lower=LOWER, upper=UPPER,
        names=NAMES, sigma_min_J3=sigma, sigma_limit=1e-3, stretch=stretch)


def test_a_completed_run_has_no_cause():
    t, command, sigma = hover_log()
    assert classify(None, t, command, sigma=sigma) is None


@pytest.mark.parametrize("message, cause, said", [
    ("interrupted (SIGINT) at t = 1.000 s", "interrupted", "signal"),
    ("t = 12.3456 s: joint limit: lwr_joint_4 at 2.1000 rad past its upper limit 2.0944 rad "
     "(joint_limits.positions: stop)", "joint_limit", "lwr_joint_4 at 2.1000 rad"),
    ("t = 0.3000 s: the control law's command became non-finite (first non-finite signal: "
     "'command'); likely cause: ...", "divergence", "non-finite"),
    ("t = 0.0000 s: the plant state is not finite (the simulation diverged before the "
     "controller could act)", "divergence", "non-finite"),
])
def test_causes_named_by_the_message(message, cause, said):
    t, command, sigma = hover_log()
    command[:, 2] += 100 * np.sin(2 * np.pi * 13 * t)  # evidence of another cause: ignored
    found = classify(message, t, command, sigma=sigma)
    assert found["cause"] == cause and said in found["detail"]


def test_an_assumption_stop_with_no_evidence_is_other():
    t, command, sigma = hover_log()
    found = classify(A1, t, command, sigma=sigma)
    assert found["cause"] == "other"
    assert found["saturated_inputs"] == [] and found["dominant_frequency_hz"] is None


def test_a_large_single_frequency_is_an_oscillation_naming_it():
    t, command, sigma = hover_log()
    command[:, 2] += 100 * np.sin(2 * np.pi * 13 * t)  # mu_y: RMS 71 N m, 0.35 of 200 N m
    found = classify(A1, t, command, sigma=sigma)
    assert found["cause"] == "oscillation" and found["time_s"] == 3.0
    assert found["dominant_frequency_hz"] == pytest.approx(13.0, abs=0.5)
    assert found["oscillation_input"] == "mu_y"
    assert found["oscillation_amplitude_ratio"] == pytest.approx(100 / np.sqrt(2) / 200,
                                                                 rel=0.05)
    assert "13.0 Hz" in found["detail"]


def test_a_small_oscillation_is_not_the_cause():
    t, command, sigma = hover_log()
    command[:, 2] += 5 * np.sin(2 * np.pi * 13 * t)  # 4 N m-like: an unperturbed level
    found = classify(A1, t, command, sigma=sigma)
    assert found["cause"] == "other"
    assert found["dominant_frequency_hz"] == pytest.approx(13.0, abs=0.5)


def test_broadband_noise_is_not_an_oscillation():
    t, command, sigma = hover_log()
    command[:, 2] += np.random.default_rng(0).normal(0.0, 150.0, t.size)
    assert classify(A1, t, command, sigma=sigma)["cause"] == "other"


def test_inputs_held_at_their_limits_are_a_saturation_naming_them():
    t, command, sigma = hover_log()
    late = t >= t[-1] - 0.4  # 80 % of the last 0.5 s
    command[late, 9] = 30.0
    command[late, 10] = -30.0
    command[t >= t[-1] - 0.1, 8] = 70.0  # tau_5: 20 %, not saturated
    found = classify(A1, t, command, sigma=sigma)
    assert found["cause"] == "torque_saturation"
    assert found["saturated_inputs"] == ["tau_6", "tau_7"]
    assert found["saturated_share"]["tau_5"] == pytest.approx(0.2, abs=0.01)
    assert "tau_6 80 %" in found["detail"]


def steady_fall(t, sigma):
    """sigma_min(J_3) falling steadily from 0.2 to the limit over the last 0.4 s."""
    late = t >= t[-1] - 0.4
    sigma = sigma.copy()
    sigma[late] = np.linspace(0.2, 1.1e-3, late.sum())
    return sigma


def test_a_stretched_arm_with_a_steady_fall_is_reach():
    t, command, sigma = hover_log()
    found = classify(A1, t, command, sigma=steady_fall(t, sigma), stretch=0.9999)
    assert found["cause"] == "reach"
    assert found["sigma_steady_share"] == 1.0 and found["arm_stretch"] == 0.9999


def test_reach_needs_the_arm_stretched_and_the_fall_steady():
    t, command, sigma = hover_log()
    assert classify(A1, t, command, sigma=steady_fall(t, sigma), stretch=0.95)["cause"] == \
        "other"
    shaken = steady_fall(t, sigma) + 0.02 * np.sin(2 * np.pi * 13 * t)
    found = classify(A1, t, command, sigma=shaken, stretch=0.9999)
    assert found["cause"] == "other" and found["sigma_steady_share"] < dut.STEADY_SHARE
    # A baseline's singular task Jacobian is read as Assumption 1 is.
    baseline = ("t = 3.0000 s: the arm's fixed-base task Jacobian is singular, sigma_min = "
                "0.0009 (limit 0.001)")
    assert classify(baseline, t, command, sigma=steady_fall(t, sigma), stretch=0.9999)[
        "cause"] == "reach"
    # Not an Assumption 1 stop: the stretch is not its cause.
    a2 = "t = 3.0000 s: Assumption 2 violated: the desired thrust vanishes, |f_d| = 0.5 N"
    assert classify(a2, t, command, sigma=steady_fall(t, sigma), stretch=0.9999)["cause"] == \
        "other"


def test_decision_order_reach_then_oscillation_then_saturation():
    t, command, sigma = hover_log()
    command[:, 2] += 400 * np.sin(2 * np.pi * 13 * t)
    found = classify(A1, t, command, sigma=sigma)  # mu_y clipped 60 % of the time
    assert found["saturated_inputs"] == ["mu_y"] and found["cause"] == "oscillation"
    found = classify(A1, t, command, sigma=steady_fall(t, sigma), stretch=0.9999)
    assert found["cause"] == "reach" and found["oscillation_input"] == "mu_y"


def test_a_log_too_short_for_the_spectrum_has_no_frequency():
    t, command, sigma = hover_log(duration=1.0)
    command[:, 2] += 100 * np.sin(2 * np.pi * 13 * t)
    found = classify(A1, t, command, sigma=sigma)
    assert found["dominant_frequency_hz"] is None and found["cause"] == "other"


def test_an_empty_log_is_classified_by_its_message():
    empty = np.zeros((0, 11))
    found = classify("t = 0.0000 s: joint limit: lwr_joint_2 ...", np.zeros(0), empty,
                     sigma=np.zeros(0))
    assert found["cause"] == "joint_limit" and found["time_s"] == 0.0
    assert classify("a reason without a time", np.zeros(0), empty)["time_s"] is None
    assert classify(A1, np.zeros(0), empty, sigma=np.zeros(0))["cause"] == "other"


@pytest.fixture(scope="module", params=["nominal", "quadrotor_ur3e"])
def arm(request):
    """The controller's model of a shipped scenario's robot at its nominal posture, and the
    index of its elbow joint (the LWR's joint 4, the UR3e's joint 3)."""
    from aerial_drake.robots.models import set_nominal_posture
    from aerial_drake.simulation.diagram import build_simulation
    from aerial_drake.simulation.scenarios import load_scenario
    _, loop, _ = build_simulation(load_scenario(request.param))
    model = loop.controller_model
    context = model.plant.CreateDefaultContext()
    set_nominal_posture(model, context)
    elbow = {"nominal": 3, "quadrotor_ur3e": 2}[request.param]
    return model, model.plant.GetPositions(context), elbow


def test_arm_stretch_is_the_elbows(arm):
    model, q, elbow = arm
    assert dut.arm_stretch(model, q) < 0.7  # the hover posture: elbow bent
    for joint in range(model.n):
        bent = q.copy()
        bent[model.arm_position_indices[joint]] = 0.0
        stretch = dut.arm_stretch(model, bent)
        if joint == elbow:  # straightened: as stretched as it goes
            assert stretch == pytest.approx(1.0, abs=1e-9)
        else:  # another joint (the shoulder, the wrist) leaves the elbow as it was
            assert stretch == pytest.approx(dut.arm_stretch(model, q), abs=1e-9)
    # Bent 20 degrees: below the threshold (the span cos 10 deg = 0.985 of its largest for
    # equal links); 5 degrees: above it (cos 2.5 deg = 0.999).
    for degrees, stretched in ((20.0, False), (5.0, True)):
        near = q.copy()
        near[model.arm_position_indices[elbow]] = np.radians(degrees)
        assert (dut.arm_stretch(model, near) >= dut.STRETCHED) is stretched
