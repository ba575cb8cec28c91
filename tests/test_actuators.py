"""Tests of aerial_drake.actuators' PointWrenchApplier: the wrench it hands the plant, and that
it follows its input (time-varying sources, several contexts)."""

import numpy as np
import pytest
from pydrake.systems.framework import DiagramBuilder

from aerial_drake import actuators as dut
from aerial_drake.disturbances import add_wrench_source
from aerial_drake.models import make_plant
from aerial_drake.scenarios import Disturbance

P_BoQ_B = np.array([0.01, -0.02, 0.15])


@pytest.fixture(scope="module")
def model():
    return make_plant("rigid")


def applied(applier, context):
    """The applier's output as (body index, p_BoBq_B, [torque; force]) of its single force."""
    forces = applier.get_output_port().Eval(context)
    assert len(forces) == 1
    F = forces[0].F_Bq_W
    return (forces[0].body_index, forces[0].p_BoBq_B,
            np.concatenate([F.rotational(), F.translational()]))


def test_output_is_the_input_wrench_at_the_point(model):
    applier = dut.PointWrenchApplier(model.end_effector_body, P_BoQ_B)
    context = applier.CreateDefaultContext()
    for wrench in (np.zeros(6), np.arange(1.0, 7.0), -np.pi * np.ones(6), np.arange(1.0, 7.0)):
        applier.get_input_port().FixValue(context, wrench)
        body, point, F = applied(applier, context)
        assert body == model.end_effector_body.index()
        np.testing.assert_array_equal(point, P_BoQ_B)
        np.testing.assert_array_equal(F, wrench)


def test_contexts_do_not_share_outputs(model):
    """The applier keeps its last force list on the system: each context still gets its own
    input's wrench, in any order of evaluation."""
    applier = dut.PointWrenchApplier(model.end_effector_body, P_BoQ_B)
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
    applier = builder.AddSystem(dut.PointWrenchApplier(model.end_effector_body, P_BoQ_B))
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
