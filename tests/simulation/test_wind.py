"""Dryden turbulence has the standard's variances and correlation, is seeded, and its drag
acts in the body's axes."""

import dataclasses
import math

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource

from aerial_drake.robots.models import add_to_builder
from aerial_drake.simulation import wind as dut
from aerial_drake.simulation.scenarios.perturbations import Wind


def _wind(**kw):
    return dataclasses.replace(Wind(enabled=True), **kw)


def test_variances_are_the_intensities_squared():
    w = _wind(sigma=[1.0, 0.5, 0.8], length_scale=[10.0, 10.0, 5.0], airspeed=5.0, seed=11)
    _, gusts = dut.dryden_gusts(w, 4000.0)
    np.testing.assert_allclose(gusts.std(axis=0), [1.0, 0.5, 0.8], rtol=0.08)


def test_longitudinal_correlation_decays_as_exp_of_minus_v_tau_over_l():
    w = _wind(sigma=[1.0, 0.0, 0.0], length_scale=[10.0, 10.0, 5.0], airspeed=5.0, seed=2)
    times, gusts = dut.dryden_gusts(w, 4000.0)
    u = gusts[:, 0] - gusts[:, 0].mean()
    lag = int(round(2.0 / w.sample_period))  # tau = L / V = 2 s
    rho = np.dot(u[:-lag], u[lag:]) / np.dot(u, u)
    assert rho == pytest.approx(math.exp(-1.0), abs=0.06)


def test_seeded_and_mean_only_without_intensities():
    w = _wind(sigma=[1.0, 1.0, 1.0], seed=4)
    a = dut.wind_velocity(w, 2.0)[1]
    assert np.array_equal(a, dut.wind_velocity(w, 2.0)[1])
    assert not np.array_equal(a, dut.wind_velocity(dataclasses.replace(w, seed=5), 2.0)[1])
    calm = _wind(mean=[2.0, -1.0, 0.0])
    np.testing.assert_array_equal(dut.wind_velocity(calm, 1.0)[1],
                                  np.tile([2.0, -1.0, 0.0], (len(dut.wind_velocity(calm,
                                                                                   1.0)[0]), 1)))


def test_gust_axes_follow_the_mean_wind():
    R = dut.wind_axes([0.0, 3.0, 0.0])
    np.testing.assert_allclose(R[:, 0], [0.0, 1.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(R[:, 2], [0.0, 0.0, 1.0])
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-15)


@pytest.mark.parametrize("yaw", [0.0, math.pi / 2])
def test_drag_in_body_axes(yaw):
    builder = DiagramBuilder()
    sim = add_to_builder(builder, "rigid", time_step=0.0)
    linear, quadratic = [1.0, 2.0, 3.0], [0.5, 4.0, 1.0]
    drag = builder.AddSystem(dut.WindDrag(sim.base_body, linear, quadratic))
    source = builder.AddSystem(ConstantVectorSource([3.0, 0.0, 0.0]))
    builder.Connect(sim.plant.get_body_poses_output_port(), drag.GetInputPort("body_poses"))
    builder.Connect(sim.plant.get_body_spatial_velocities_output_port(),
                    drag.GetInputPort("body_spatial_velocities"))
    builder.Connect(source.get_output_port(), drag.GetInputPort("wind_velocity"))
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    plant_context = sim.plant.GetMyMutableContextFromRoot(context)
    sim.plant.SetFreeBodyPose(plant_context, sim.base_body,
                              RigidTransform(RollPitchYaw(0.0, 0.0, yaw), [0.0, 0.0, 1.0]))
    wrench = drag.GetOutputPort("wrench").Eval(drag.GetMyContextFromRoot(context))
    # At rest: 3 m/s along World x is body x at yaw 0, body -y at yaw 90 deg.
    axis = 0 if yaw == 0.0 else 1
    along = linear[axis] * 3.0 + quadratic[axis] * 9.0
    np.testing.assert_allclose(wrench, [0, 0, 0, along, 0, 0], atol=1e-12)
