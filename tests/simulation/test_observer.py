"""The external wrench observer in a run (scenario section ``observer``;
aerial_drake.control.wrench_observer): its estimate of known constant wrenches on the vehicle
and at the end effector, its log, and that it adds nothing when off."""

import dataclasses

import numpy as np
import pytest

from aerial_drake.control.wrench_observer import WrenchObserver
from aerial_drake.simulation.diagram import build_simulation
from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import ScenarioError, load_scenario
from aerial_drake.simulation.scenarios.schema import Disturbance, Observer

BANDWIDTH = 20.0
#: [torque; force] (N m, N), World axes: on the vehicle (its frame's origin) over 0.1-0.9 s,
#: the paper's end-effector wrench over 1.0-1.9 s.
VEHICLE = np.array([5.0, 0.0, -3.0, 0.0, 50.0, 0.0])
END_EFFECTOR = np.array([20.0, 20.0, 20.0, 40.0, 40.0, 40.0])
WINDOWS = {"vehicle": (0.1, 0.9), "end_effector": (1.0, 1.9)}


def _hover(observer: Observer, duration: float = 2.0):
    """The nominal plant (rigid, no lag, no rotors) on a hover reference, starting at rest on
    it, with the two windows."""
    nominal = load_scenario("nominal")
    windows = [Disturbance(target=target, start=a, stop=b, torque=w[:3].tolist(),
                           force=w[3:].tolist())
               for (target, (a, b)), w in zip(WINDOWS.items(), (VEHICLE, END_EFFECTOR))]
    return dataclasses.replace(
        nominal, name="observer_hover", duration=duration, observer=observer,
        trajectory=dataclasses.replace(nominal.trajectory, kind="hover"),
        initial=dataclasses.replace(nominal.initial, base_position_offset=[0.0] * 3,
                                    base_rpy_offset=[0.0] * 3),
        disturbances=windows)


@pytest.fixture(scope="module")
def run():
    return run_scenario(_hover(Observer(enabled=True, bandwidth=BANDWIDTH)), progress=False)


def test_the_estimate_of_a_constant_wrench_is_within_2_percent(run):
    """After 5 / bandwidth (the filter's transient down to exp(-5) = 0.7 %) and to each
    window's end, the estimate of each window's wrench, the other's estimate zero, is within
    2 % of its magnitude (measured: at most 0.69 % for both, just after the transient; at
    the windows' ends 0.0007 % on the vehicle and 0.05 % at the end effector); before the
    first window the estimate is zero to 1e-6 N."""
    assert run.completed, run.failure
    t, w = run.log["t"], run.log["external_wrench_estimate"]
    truth = {"vehicle": np.concatenate([VEHICLE, np.zeros(6)]),
             "end_effector": np.concatenate([np.zeros(6), END_EFFECTOR])}
    for target, (start, stop) in WINDOWS.items():
        after = (t >= start + 5.0 / BANDWIDTH) & (t < stop)
        error = np.linalg.norm(w[after] - truth[target], axis=1) / np.linalg.norm(
            truth[target])
        assert after.sum() > 300 and error.max() < 0.02, (target, error.max())
        assert error[-1] < 1e-3, (target, error[-1])
    assert np.abs(w[t < WINDOWS["vehicle"][0]]).max() < 1e-6


def test_the_log_names_the_estimates(run):
    n = 7
    assert run.layouts["external_wrench_estimate"] == (
        ("vehicle_torque", 3), ("vehicle_force", 3), ("end_effector_torque", 3),
        ("end_effector_force", 3))
    assert run.log["external_wrench_estimate"].shape[1] == 12
    assert run.log["generalized_force_estimate"].shape[1] == 6 + n
    # On the vehicle alone, the raw estimate's base rows are its wrench.
    t, r = run.log["t"], run.log["generalized_force_estimate"]
    k = np.searchsorted(t, WINDOWS["vehicle"][1]) - 1
    np.testing.assert_allclose(r[k, :6], VEHICLE, atol=0.01)
    np.testing.assert_allclose(r[k, 6:], 0.0, atol=0.01)


def test_off_by_default_adds_nothing():
    scenario = _hover(Observer(), duration=0.1)
    assert scenario.observer.enabled is False
    builder, loop, loggers = build_simulation(scenario)
    assert not any(isinstance(s, WrenchObserver) for s in builder.GetSystems())
    assert "external_wrench_estimate" not in loggers
    assert "external_wrench_estimate" not in loop.outputs


@pytest.mark.parametrize("override,needle", [
    ({"observer.bandwidth": 0.0}, "observer.bandwidth"),
    ({"observer.enabled": True, "controller_period": 0.0}, "observer.enabled"),
])
def test_bad_observer_settings_are_refused(override, needle):
    with pytest.raises(ScenarioError, match=needle):
        load_scenario("nominal", overrides=override)
