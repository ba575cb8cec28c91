"""Tests of aerial_drake.simulation.actuators' PointWrenchApplier: the wrench it hands the plant
(at any pose of the body), and that it follows its input (time-varying sources, several
contexts)."""

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.math import SpatialForce
from pydrake.multibody.plant import ExternallyAppliedSpatialForce
from pydrake.systems.framework import DiagramBuilder

from aerial_drake.robots.models import make_plant
from aerial_drake.simulation import actuators as dut
from aerial_drake.simulation.disturbances import add_wrench_source
from aerial_drake.simulation.scenarios import Disturbance

P_BoQ_B = np.array([0.01, -0.02, 0.15])


@pytest.fixture(scope="module")
def model():
    return make_plant("rigid")


def make_applier(model):
    return dut.PointWrenchApplier(model.end_effector_body, P_BoQ_B, model.plant.num_bodies())


def applied(applier, context):
    """The applier's output as (body index, p_BoBq_B, [torque; force]) of the total wrench at
    its point: every force it outputs is at that point of that body."""
    forces = applier.get_output_port().Eval(context)
    total = np.zeros(6)
    for force in forces:
        assert force.body_index == forces[0].body_index
        np.testing.assert_array_equal(force.p_BoBq_B, forces[0].p_BoBq_B)
        F = force.F_Bq_W
        total += np.concatenate([F.rotational(), F.translational()])
    return forces[0].body_index, forces[0].p_BoBq_B, total


def test_output_is_the_input_wrench_at_the_point(model):
    applier = make_applier(model)
    context = applier.CreateDefaultContext()
    for wrench in (np.zeros(6), np.arange(1.0, 7.0), -np.pi * np.ones(6), np.arange(1.0, 7.0)):
        applier.get_input_port().FixValue(context, wrench)
        body, point, F = applied(applier, context)
        assert body == model.end_effector_body.index()
        np.testing.assert_array_equal(point, P_BoQ_B)
        np.testing.assert_array_equal(F, wrench)  # exact: the axes are written out


def test_plant_feels_the_world_wrench_at_any_pose(model):
    """The applier's World axes come from constant identity poses, not the body's: the plant's
    accelerations with it equal those with a single World force at the point, at a
    configuration where the body is far from World-aligned."""
    plant = model.plant
    context = plant.CreateDefaultContext()
    rng = np.random.default_rng(7)
    plant.SetFreeBodyPose(context, model.base_body, RigidTransform(
        RollPitchYaw(0.4, -0.7, 2.1), [0.3, -0.2, 1.5]))
    for joint in model.arm_joints:
        joint.set_angle(context, rng.uniform(-1.0, 1.0))
    arm = model.arm_actuators[0].model_instance()
    plant.get_actuation_input_port(arm).FixValue(context, np.zeros(len(model.arm_joints)))
    wrench = np.array([1.5, -2.0, 0.7, 30.0, -12.0, 45.0])
    applier = make_applier(model)
    applier_context = applier.CreateDefaultContext()
    applier.get_input_port().FixValue(applier_context, wrench)
    plant.get_applied_spatial_force_input_port().FixValue(
        context, applier.get_output_port().Eval(applier_context))
    vdot = plant.get_generalized_acceleration_output_port().Eval(context).copy()
    single = ExternallyAppliedSpatialForce()
    single.body_index = model.end_effector_body.index()
    single.p_BoBq_B = P_BoQ_B
    single.F_Bq_W = SpatialForce(wrench[:3], wrench[3:])
    plant.get_applied_spatial_force_input_port().FixValue(context, [single])
    expected = plant.get_generalized_acceleration_output_port().Eval(context)
    np.testing.assert_allclose(vdot, expected, rtol=1e-13, atol=1e-13)
    # And the wrench matters here (the comparison is not between two zero effects).
    plant.get_applied_spatial_force_input_port().FixValue(context, [])
    free = plant.get_generalized_acceleration_output_port().Eval(context)
    assert np.max(np.abs(free - expected)) > 0.1


def test_contexts_do_not_share_outputs(model):
    """Each context gets its own input's wrench, in any order of evaluation."""
    applier = make_applier(model)
    a, b = applier.CreateDefaultContext(), applier.CreateDefaultContext()
    applier.get_input_port().FixValue(a, np.ones(6))
    applier.get_input_port().FixValue(b, 2.0 * np.ones(6))
    for context, expected in ((a, 1.0), (b, 2.0), (a, 1.0), (b, 2.0)):
        np.testing.assert_array_equal(applied(applier, context)[2], expected * np.ones(6))


def test_follows_a_disturbance_window_in_time(model):
    """Driven by a disturbance source, the output is the window's wrench on [start, stop) and
    zero outside, evaluated at any time (as the integrator's stages do)."""
    window = Disturbance(target="end_effector", start=9.0, stop=10.0, force=[40.0, 41.0, 42.0],
                         torque=[20.0, 21.0, 22.0])
    builder = DiagramBuilder()
    source = add_wrench_source(builder, [window], "end_effector")
    applier = builder.AddSystem(make_applier(model))
    builder.Connect(source.get_output_port(), applier.get_input_port())
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    applier_context = applier.GetMyContextFromRoot(context)
    on = np.array([20.0, 21.0, 22.0, 40.0, 41.0, 42.0])
    for t, expected in ((8.9995, 0 * on), (9.0, on), (9.0005, on), (9.9995, on), (10.0, 0 * on),
                        (9.5, on), (3.0, 0 * on)):
        context.SetTime(t)
        np.testing.assert_array_equal(applied(applier, applier_context)[2], expected,
                                      err_msg=f"t = {t}")
