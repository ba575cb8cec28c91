"""The state sensor delays by whole samples and adds noise of the stated spread per group,
keeping the base's quaternion a unit quaternion."""

import dataclasses

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import LogVectorOutput, TrajectorySource
from pydrake.trajectories import PiecewisePolynomial

from aerial_drake.robots.models import make_plant
from aerial_drake.simulation import sensing as dut
from aerial_drake.simulation.scenarios.perturbations import Sensing

PERIOD = 1e-3


def _sensed(sensing, x_of_t, duration, period=PERIOD):
    """The sensor's output logged at each sample, for the input ``x_of_t`` (times, (n, nx))."""
    model = make_plant("rigid")
    builder = DiagramBuilder()
    times, values = x_of_t
    source = builder.AddSystem(TrajectorySource(PiecewisePolynomial.FirstOrderHold(
        times, values.T)))
    sensor = builder.AddSystem(dut.StateSensor(model, sensing, period, duration))
    builder.Connect(source.get_output_port(), sensor.GetInputPort("state"))
    logger = LogVectorOutput(sensor.GetOutputPort("measured_state"), builder, period)
    diagram = builder.Build()
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    sensor.prime(sensor.GetMyMutableContextFromRoot(context), values[0])
    simulator.AdvanceTo(duration)
    log = logger.FindLog(context)
    return model, log.sample_times(), log.data().T


def _ramp(model, duration):
    nx = model.plant.num_multibody_states()
    times = np.array([0.0, duration + 1.0])
    return times, np.outer(times, np.ones(nx)) + 1.0


@pytest.mark.parametrize("delay, period, steps", [
    (0.0, PERIOD, 0), (3 * PERIOD, PERIOD, 3),
    # 0.29 / 0.01 = 28.999999999999996 in floating point: 29 samples, not 28.
    (0.29, 0.01, 29),
    # Not a multiple of the period (the scenario refuses it; the sensor rounds): 2.6 -> 3.
    (2.6e-3, PERIOD, 3), (2.4e-3, PERIOD, 2)])
def test_delay_in_whole_samples_rounded(delay, period, steps):
    model = make_plant("rigid")
    duration = 0.05 if period == PERIOD else 0.4
    _, t, y = _sensed(Sensing(delay=delay), _ramp(model, duration), duration, period)
    k = np.arange(len(t))
    expected = 1.0 + np.maximum(k - steps, 0) * period
    np.testing.assert_allclose(y[:, -1], expected, atol=1e-12)


def test_noise_spread_per_group_and_unit_quaternion():
    model = make_plant("rigid")
    nx = model.plant.num_multibody_states()
    x0 = np.zeros(nx)
    q = model.base_position_indices
    x0[q[0]] = 1.0  # identity quaternion
    sensing = Sensing(base_position_std=0.01, base_attitude_std=0.02, joint_position_std=0.03,
                      base_angular_velocity_std=0.04, base_linear_velocity_std=0.05,
                      joint_velocity_std=0.06, seed=9)
    times = np.array([0.0, 3.0])
    _, _, y = _sensed(sensing, (times, np.vstack([x0, x0])), 2.0)
    nq = model.plant.num_positions()
    np.testing.assert_allclose(np.linalg.norm(y[:, q[:4]], axis=1), 1.0, atol=1e-12)
    spreads = {0.01: y[:, q[4:]], 0.03: y[:, model.arm_position_indices],
               0.04: y[:, nq + model.base_velocity_indices[:3]],
               0.05: y[:, nq + model.base_velocity_indices[3:]],
               0.06: y[:, nq + model.arm_velocity_indices]}
    for std, values in spreads.items():
        assert values.std() == pytest.approx(std, rel=0.05)
    # The attitude noise: a rotation of about std per axis (small angles: 2 * vector part).
    np.testing.assert_allclose((2 * y[:, q[1:4]]).std(axis=0), 0.02, rtol=0.08)
    again = _sensed(sensing, (times, np.vstack([x0, x0])), 2.0)[2]
    assert np.array_equal(y, again)
    other = _sensed(dataclasses.replace(sensing, seed=10), (times, np.vstack([x0, x0])), 2.0)[2]
    assert not np.array_equal(y, other)
