"""Model mismatch, payload and random windows: in the simulated plant's context only, seeded,
off by default, validated with errors that name the field."""

import dataclasses

import numpy as np
import pytest

from aerial_drake.simulation import disturbances
from aerial_drake.simulation import perturbations as dut
from aerial_drake.simulation.diagram import build_simulation
from aerial_drake.simulation.runner import run_scenario, set_initial_state
from aerial_drake.simulation.scenarios import ScenarioError, load_scenario

R = dataclasses.replace


def _built(scenario):
    builder, loop, _ = build_simulation(scenario)
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    plant_context = loop.simulated_plant.plant.GetMyMutableContextFromRoot(context)
    set_initial_state(scenario, loop, plant_context)
    dut.start_perturbations(scenario, loop, context)
    return diagram, loop, plant_context


def _inertias(plant, context):
    return [(b.name(), b.get_mass(context), b.CalcCenterOfMassInBodyFrame(context).copy(),
             b.CalcSpatialInertiaInBodyFrame(context).CalcRotationalInertia()
             .CopyToFullMatrix3()) for b in dut.massive_bodies(plant, context)]


@pytest.fixture(scope="module")
def nominal():
    return load_scenario("nominal", overrides={"duration": 0.2})


def test_off_by_default_adds_no_system_and_touches_no_parameter(nominal):
    diagram, loop, ctx = _built(nominal)
    names = {s.get_name() for s in diagram.GetSystems()}
    assert not names & {"wind_drag", "wind_velocity", "state_sensor"}
    assert loop.sensor is None
    plant = loop.simulated_plant.plant
    defaults = _inertias(plant, plant.CreateDefaultContext())
    for (name, m, c, I), (_, m0, c0, I0) in zip(_inertias(plant, ctx), defaults):
        assert m == m0 and np.array_equal(c, c0) and np.array_equal(I, I0), name


def test_mismatch_draws_within_bounds_in_the_simulated_plant_only(nominal):
    scenario = R(nominal, model_mismatch=R(nominal.model_mismatch, mass_error=0.1,
                                           inertia_error=0.1, com_error=0.1, seed=5))
    _, loop, ctx = _built(scenario)
    plant = loop.simulated_plant.plant
    nominal_ctx = plant.CreateDefaultContext()
    changed = 0
    for (name, m, c, _), (_, m0, c0, _) in zip(_inertias(plant, ctx),
                                               _inertias(plant, nominal_ctx)):
        assert 0.9 * m0 <= m <= 1.1 * m0, name
        changed += m != m0
    assert changed == len(dut.massive_bodies(plant, ctx))
    # The controller's model keeps its nominal inertias.
    model = loop.controller_model.plant
    model_ctx = model.CreateDefaultContext()
    assert model.CalcTotalMass(model_ctx) == pytest.approx(
        model.CalcTotalMass(model.CreateDefaultContext()))
    # Same seed, same draws; another seed, others.
    again = dut.apply_model_mismatch(scenario.model_mismatch, plant, plant.CreateDefaultContext())
    other = dut.apply_model_mismatch(R(scenario.model_mismatch, seed=6), plant,
                                     plant.CreateDefaultContext())
    first = dut.apply_model_mismatch(scenario.model_mismatch, plant, plant.CreateDefaultContext())
    assert again == first and other != first


def test_scaled_inertia_about_the_com_and_shifted_com():
    from pydrake.multibody.tree import RotationalInertia, SpatialInertia
    M = SpatialInertia.MakeFromCentralInertia(2.0, np.array([0.1, 0.0, 0.0]),
                                              RotationalInertia(0.3, 0.4, 0.5))
    out = dut.perturbed_inertia(M, 1.1, 0.8, np.array([0.0, 0.02, 0.0]))
    assert out.get_mass() == pytest.approx(2.2)
    np.testing.assert_allclose(out.get_com(), [0.1, 0.02, 0.0])
    central = out.Shift(out.get_com()).CalcRotationalInertia().CopyToFullMatrix3()
    np.testing.assert_allclose(np.diag(central), 0.8 * np.array([0.3, 0.4, 0.5]))


def test_payload_adds_its_mass_at_its_point(nominal):
    scenario = R(nominal, payload=R(nominal.payload, mass=0.7, inertia=[1e-3] * 3,
                                    offset=[0.0, 0.0, 0.05]))
    _, loop, ctx = _built(scenario)
    sim = loop.simulated_plant
    plant = sim.plant
    before = plant.CreateDefaultContext()
    plant.SetPositionsAndVelocities(before, plant.GetPositionsAndVelocities(ctx))
    assert plant.CalcTotalMass(ctx) == pytest.approx(plant.CalcTotalMass(before) + 0.7)
    # The composite CoM moves toward the payload's point by m_p / m_total of the way.
    p_WP = sim.end_effector_frame.CalcPoseInWorld(ctx) @ np.array([0.0, 0.0, 0.05])
    c0 = plant.CalcCenterOfMassPositionInWorld(before)
    c1 = plant.CalcCenterOfMassPositionInWorld(ctx)
    np.testing.assert_allclose(c1, c0 + 0.7 / plant.CalcTotalMass(ctx) * (p_WP - c0),
                               atol=1e-12)


def test_random_windows_redirect_keeps_magnitudes_and_timing(nominal):
    section = R(nominal.random_disturbances, redirect=True, count=2, start=[1.0, 2.0],
                length=[0.5, 1.0], force=[10.0, 20.0], torque=[0.0, 5.0], seed=3)
    scenario = R(nominal, random_disturbances=section)
    resolved = disturbances.resolve_random_disturbances(scenario)
    old, new = resolved.disturbances[:2], resolved.disturbances[2:]
    for a, b in zip(nominal.disturbances, old):
        assert (a.start, a.stop, a.target) == (b.start, b.stop, b.target)
        assert np.linalg.norm(b.force) == pytest.approx(np.linalg.norm(a.force))
        assert not np.allclose(a.force, b.force)
    assert len(new) == 2
    for d in new:
        assert 1.0 <= d.start <= 2.0 and 0.5 <= d.stop - d.start <= 1.0
        assert 10.0 <= np.linalg.norm(d.force) <= 20.0
    assert disturbances.resolve_random_disturbances(resolved) is resolved
    assert disturbances.resolve_random_disturbances(scenario) == resolved


def test_a_run_with_every_perturbation_completes_and_differs(nominal):
    base = run_scenario(nominal, progress=False)
    scenario = R(
        nominal,
        model_mismatch=R(nominal.model_mismatch, mass_error=0.1, com_error=0.1, seed=1),
        payload=R(nominal.payload, mass=0.5, inertia=[1e-3] * 3),
        wind=R(nominal.wind, enabled=True, mean=[3.0, 0.0, 0.0], sigma=[1.0, 1.0, 0.5]),
        sensing=R(nominal.sensing, delay=0.002, base_position_std=1e-4),
        random_disturbances=R(nominal.random_disturbances, count=1, start=[0.05, 0.1],
                              length=[0.05, 0.05], force=[20.0, 20.0])).validate()
    result = run_scenario(scenario, progress=False)
    assert result.completed
    assert len(result.scenario.disturbances) == len(nominal.disturbances) + 1
    e0 = base.metrics["phases"][0]["com_position_error_m"]["max"]
    e1 = result.metrics["phases"][0]["com_position_error_m"]["max"]
    assert e0 != e1


@pytest.mark.parametrize("section, field, value, words", [
    ("model_mismatch", "mass_error", 2.0, "model_mismatch.mass_error"),
    ("model_mismatch", "seed", -1, "model_mismatch.seed"),
    ("payload", "inertia", [1.0, 0.1, 0.1], "triangle"),
    ("wind", "sigma", [1.0, 1.0], "wind.sigma"),
    ("sensing", "delay", 0.0015, "multiple of controller_period"),
    ("random_disturbances", "force", [5.0, 1.0], "low <= high"),
    ("random_disturbances", "target", "tail", "random_disturbances.target"),
])
def test_bad_values_name_the_field(nominal, section, field, value, words):
    bad = R(nominal, **{section: R(getattr(nominal, section), **{field: value})})
    with pytest.raises(ScenarioError, match=words.replace(".", r"\.")):
        bad.validate()


def test_a_misspelt_key_in_a_section_is_named(tmp_path):
    from aerial_drake.simulation.scenarios import shipped_scenarios
    path = tmp_path / "s.yaml"
    path.write_text(shipped_scenarios()["nominal"].read_text() + "\nwind:\n  enabeld: true\n")
    with pytest.raises(ScenarioError, match="wind.enabeld"):
        load_scenario(path)


def test_payload_offset_is_from_the_end_effector_frame_not_its_bodys_origin(tmp_path):
    """A robot whose end-effector frame is 6 cm and a rotation away from its body's origin
    (both shipped robots have it at the origin): the payload's mass sits at X_BE @ offset,
    its inertia turned with R_BE (issue 27)."""
    from pydrake.math import RigidTransform, RollPitchYaw

    from aerial_drake.robots.description import load_robot_description
    from aerial_drake.robots.models import make_plant
    from aerial_drake.simulation.scenarios.perturbations import Payload
    from own_robot import write_robot

    description, _ = write_robot(tmp_path)
    text = description.read_text().replace("offset_xyz: [0, 0, -0.06]",
                                           "offset_xyz: [0.01, 0.02, -0.06], "
                                           "offset_rpy: [0.3, -0.2, 0.5]")
    description.write_text(text)
    model = make_plant(robot=load_robot_description(description))
    X_BE = model.end_effector_frame.GetFixedPoseInBodyFrame()
    assert np.linalg.norm(X_BE.translation()) > 0.05
    payload = Payload(mass=0.7, inertia=[1e-3, 2e-3, 3e-3], offset=[0.02, -0.01, 0.05])
    # The inertia alone: its CoM at X_BE @ offset in the body, its central inertia R I R^T.
    X = RigidTransform(RollPitchYaw(0.3, -0.2, 0.5), [0.01, 0.02, -0.06])
    M = dut.payload_inertia(payload, X)
    np.testing.assert_allclose(M.get_com(), X @ np.array(payload.offset), atol=1e-15)
    R = X.rotation().matrix()
    central = M.Shift(M.get_com()).CalcRotationalInertia().CopyToFullMatrix3()
    np.testing.assert_allclose(central, R @ np.diag(payload.inertia) @ R.T, atol=1e-15)
    # On the plant: the composite CoM moves toward the payload's point in World.
    plant = model.plant
    context = plant.CreateDefaultContext()
    c0, m0 = plant.CalcCenterOfMassPositionInWorld(context), plant.CalcTotalMass(context)
    dut.apply_payload(payload, model, context)
    p_WP = model.end_effector_frame.CalcPoseInWorld(context) @ np.array(payload.offset)
    np.testing.assert_allclose(plant.CalcCenterOfMassPositionInWorld(context),
                               c0 + 0.7 / (m0 + 0.7) * (p_WP - c0), atol=1e-12)
