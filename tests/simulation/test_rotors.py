"""The disturbed case's plant (Section IV; docs/models.md, Helicopter with rotors): the spinning
rotors, the drive that holds their speed, the actuator lag and the saturation, each against
physics or a closed-form answer."""

import math

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.systems.analysis import ApplySimulatorConfig, Simulator, SimulatorConfig
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource

from aerial_drake.robots import models
from aerial_drake.simulation.actuators import lag_time_constant
from aerial_drake.simulation.diagram import _add_rotor_drive, build_closed_loop
from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import load_scenario

#: Spin directions of the rotors (left, right): the "rotors" variant's in the description.
ROTOR_DIRECTIONS = models.make_plant("rotors").rotor_directions
ROTOR_SPEEDS = 26.0 * np.pi * np.array(ROTOR_DIRECTIONS)  # Table I: +-26 pi rad/s


def arm_instance(manip):
    """The LWR's model instance (the arm's actuators are all of it)."""
    return manip.plant.GetModelInstanceByName("lwr")


def test_rotors_counter_rotate():
    assert ROTOR_DIRECTIONS == (1.0, -1.0)

SPEED = 26.0 * math.pi  # Table I
TILT = math.radians(12.5)  # docs/models.md
# docs/models.md: 2 I_s (26 pi) sin(12.5 deg) along +y_B, I_s = 0.12 kg m^2.
NET_MOMENTUM = 2 * 0.12 * SPEED * math.sin(TILT)


def _random_configuration(manip, context, rng):
    """Random base pose, arm angles and (for "rotors") rotor angles."""
    plant = manip.plant
    X_WB = RigidTransform(RollPitchYaw(rng.uniform(-0.5, 0.5, 3)), rng.uniform(-1, 1, 3))
    plant.SetFreeBodyPose(context, manip.base_body, X_WB)
    for joint, q in zip(manip.arm_joints, rng.uniform(-1.0, 1.0, 7)):
        joint.set_angle(context, q)
    for joint in manip.rotor_joints:
        joint.set_angle(context, rng.uniform(-math.pi, math.pi))
    return X_WB


def test_disturbed_scenario_speed_is_table_i():
    scenario = load_scenario("disturbed")
    assert scenario.plant_variant == "rotors"
    assert scenario.rotors.speed == pytest.approx(SPEED, rel=1e-15)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_rotors_at_rest_change_nothing_the_controller_sees(seed):
    """Composite spatial inertia of helicopter + rotors about B_o equals the rigid helicopter's
    at any rotor angle, and so do the mass matrix (rigid coordinates), the CoM and the mass."""
    rng = np.random.default_rng(seed)
    rigid, rotors = models.make_plant("rigid"), models.make_plant("rotors")
    c_rigid, c_rotors = rigid.plant.CreateDefaultContext(), rotors.plant.CreateDefaultContext()
    X_WB = _random_configuration(rotors, c_rotors, rng)
    rigid.plant.SetFreeBodyPose(c_rigid, rigid.base_body, X_WB)
    for j_rigid, j_rotors in zip(rigid.arm_joints, rotors.arm_joints):
        j_rigid.set_angle(c_rigid, j_rotors.get_angle(c_rotors))

    heli_bodies = rotors.plant.GetBodyIndices(rotors.vehicle)
    assert len(heli_bodies) == 3  # fuselage and two rotors
    M_rotors = rotors.plant.CalcSpatialInertia(c_rotors, rotors.base_body.body_frame(),
                                               heli_bodies)
    M_rigid = rigid.base_body.CalcSpatialInertiaInBodyFrame(c_rigid)
    assert M_rotors.get_mass() == pytest.approx(37.6, rel=1e-14)
    np.testing.assert_allclose(M_rotors.CopyToFullMatrix6(), M_rigid.CopyToFullMatrix6(),
                               atol=1e-12)
    np.testing.assert_allclose(M_rigid.CalcRotationalInertia().CopyToFullMatrix3(),
                               np.diag([1.46, 0.36, 1.46]), atol=1e-12)

    # What the controller's model sees: M, CoM and mass on the rigid coordinates.
    H_rotors = rotors.plant.CalcMassMatrix(c_rotors)
    H_rigid = rigid.plant.CalcMassMatrix(c_rigid)
    v_idx = np.concatenate([rotors.base_velocity_indices, rotors.arm_velocity_indices])
    np.testing.assert_allclose(H_rotors[np.ix_(v_idx, v_idx)], H_rigid, atol=1e-10)
    np.testing.assert_allclose(rotors.plant.CalcCenterOfMassPositionInWorld(c_rotors),
                               rigid.plant.CalcCenterOfMassPositionInWorld(c_rigid), atol=1e-13)
    assert rotors.plant.CalcTotalMass(c_rotors) == pytest.approx(
        rigid.plant.CalcTotalMass(c_rigid), rel=1e-14)


@pytest.mark.parametrize("seed", [0, 1])
def test_spinning_rotors_angular_momentum_is_documented_value(seed):
    """+-26 pi rad/s with the base at rest: the rotors' angular momentum is 4.24 N m s along
    +y of the body frame (docs/models.md), about any point (the rotors' CoMs do not move), and
    so is the whole plant's about its CoM (the arm at rest adds nothing)."""
    rng = np.random.default_rng(seed)
    manip = models.make_plant("rotors")
    plant = manip.plant
    context = plant.CreateDefaultContext()
    X_WB = _random_configuration(manip, context, rng)
    v = np.zeros(plant.num_velocities())
    v[manip.rotor_velocity_indices] = ROTOR_SPEEDS
    plant.SetVelocities(context, v)
    R_BW = X_WB.rotation().inverse()
    for point in (X_WB.translation(), rng.uniform(-3, 3, 3)):
        h = plant.CalcSpatialMomentumInWorldAboutPoint(context, [manip.vehicle], point)
        np.testing.assert_allclose(R_BW @ h.rotational(), [0.0, NET_MOMENTUM, 0.0], atol=1e-12)
        np.testing.assert_allclose(h.translational(), np.zeros(3), atol=1e-12)
    h = plant.CalcSpatialMomentumInWorldAboutPoint(
        context, plant.CalcCenterOfMassPositionInWorld(context))
    np.testing.assert_allclose(R_BW @ h.rotational(), [0.0, NET_MOMENTUM, 0.0], atol=1e-12)
    np.testing.assert_allclose(h.translational(), np.zeros(3), atol=1e-12)
    # Each rotor alone: 0.12 * 26 pi = 9.80 N m s along its mast, tilted 12.5 deg outward.
    for joint, speed, side in zip(manip.rotor_joints, ROTOR_SPEEDS, (1, -1)):
        rotor = joint.child_body()
        X_WR = rotor.EvalPoseInWorld(context)
        M_RRo_W = rotor.CalcSpatialInertiaInBodyFrame(context).ReExpress(X_WR.rotation())
        L = (M_RRo_W * rotor.EvalSpatialVelocityInWorld(context)).rotational()
        mast_B = np.array([0.0, side * math.sin(TILT), math.cos(TILT)])
        np.testing.assert_allclose(R_BW @ L, 0.12 * speed * mast_B, atol=1e-12)
    assert NET_MOMENTUM == pytest.approx(4.24, abs=5e-3)
    assert NET_MOMENTUM == pytest.approx(4.243, abs=1e-3)


def test_angular_momentum_conserved_with_rotors_spinning_and_body_tumbling():
    """No gravity, no inputs: the rotors plant's total angular momentum about its CoM (and its
    linear momentum) stays constant while the body tumbles, the rotors spin and the arm
    swings (reflected drive inertia acts as equal and opposite joint torques)."""
    manip = models.make_plant("rotors")
    plant = manip.plant
    plant.mutable_gravity_field().set_gravity_vector(np.zeros(3))
    context = plant.CreateDefaultContext()
    rng = np.random.default_rng(4)
    _random_configuration(manip, context, rng)
    v = np.zeros(plant.num_velocities())
    v[manip.base_velocity_indices] = [0.8, -0.6, 1.1, 0.3, -0.1, 0.2]  # tumbling
    v[manip.rotor_velocity_indices] = ROTOR_SPEEDS
    v[manip.arm_velocity_indices] = rng.uniform(-0.5, 0.5, 7)
    plant.SetVelocities(context, v)
    for port in (plant.get_actuation_input_port(manip.vehicle),
                 plant.get_actuation_input_port(arm_instance(manip))):
        port.FixValue(context, np.zeros(port.size()))

    def momentum(ctx):
        h = plant.CalcSpatialMomentumInWorldAboutPoint(
            ctx, plant.CalcCenterOfMassPositionInWorld(ctx))
        return h.rotational(), h.translational()

    L0, p0 = momentum(context)
    assert np.linalg.norm(L0) > 1.0  # rotors (4.24 N m s along y_B) plus the tumbling
    simulator = Simulator(plant, context)
    ApplySimulatorConfig(SimulatorConfig(integration_scheme="runge_kutta5", accuracy=1e-12,
                                         max_step_size=1e-3, use_error_control=True),
                         simulator)
    w0 = v[manip.base_velocity_indices[:3]]
    worst = 0.0
    for t in np.linspace(0.05, 0.5, 10):
        simulator.AdvanceTo(t)
        L, p = momentum(context)
        worst = max(worst, np.linalg.norm(L - L0) / np.linalg.norm(L0))
        np.testing.assert_allclose(p, p0, atol=1e-9)
    assert worst < 1e-6
    # Momentum moved between the parts: the check is not trivially satisfied.
    w = plant.GetVelocities(context)[manip.base_velocity_indices[:3]]
    assert np.linalg.norm(w - w0) > 0.05


def test_rotor_drive_spins_the_rotors_up_to_speed():
    """The drive of the closed loop (damping towards the speed, an AffineSystem) returns each rotor
    to its own speed, with the right sign and actuator ordering."""
    scenario = load_scenario("disturbed")
    builder = DiagramBuilder()
    manip = models.add_to_builder(builder, "rotors")
    plant = manip.plant
    plant.mutable_gravity_field().set_gravity_vector(np.zeros(3))
    _add_rotor_drive(builder, manip, scenario)
    arm = builder.AddSystem(ConstantVectorSource(np.zeros(7)))
    builder.Connect(arm.get_output_port(), plant.get_actuation_input_port(arm_instance(manip)))
    diagram = builder.Build()
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    plant_context = plant.GetMyMutableContextFromRoot(context)
    models.set_nominal_posture(manip, plant_context, p_WB=(0, 0, 2))
    for joint, w in zip(manip.rotor_joints, (0.98 * SPEED, -1.01 * SPEED)):
        joint.set_angular_rate(plant_context, w)
    torque = diagram.GetSubsystemByName("rotor_drive").get_output_port()
    tau0 = torque.Eval(diagram.GetSubsystemByName("rotor_drive").GetMyContextFromRoot(context))
    gain = scenario.rotors.drive_gain
    np.testing.assert_allclose(tau0, gain * SPEED * np.array([0.02, 0.01]), rtol=1e-9)
    simulator.get_mutable_integrator().set_target_accuracy(1e-8)
    simulator.AdvanceTo(0.2)  # about 80 time constants I_s / gain = 2.4 ms
    w = plant.GetVelocities(plant_context)[manip.rotor_velocity_indices]
    np.testing.assert_allclose(w, [SPEED, -SPEED], atol=1e-3)


# --- Lag and saturation ---------------------------------------------------------------------
def test_lag_step_response_has_the_rise_time_of_the_scenario():
    """The lag system of the disturbed closed loop: first order with time constant
    rise / ln 9, so a unit step's 10-90 % rise time is the scenario's 0.1 s."""
    scenario = load_scenario("disturbed")
    rise = scenario.actuation.lag_rise_time
    assert rise == 0.1
    loop = build_closed_loop(scenario)
    assert loop.lag is not None
    tau = lag_time_constant(rise)
    assert loop.lag.time_constant == pytest.approx(tau, rel=1e-15)
    # The same system, alone: a unit step from rest (Drake keeps a reference only).
    lag = loop.lag
    context = lag.CreateDefaultContext()
    step = np.array([1.0, 2.0, -3.0, 0.5])
    torques = np.linspace(-3.0, 3.0, loop.n_arm)  # the arm's torques pass through, unlagged
    lag.get_input_port().FixValue(context, np.concatenate([step, torques]))
    lag.set_initial_output_value(context, np.zeros(4))
    simulator = Simulator(lag, context)
    simulator.get_mutable_integrator().set_target_accuracy(1e-10)
    times = np.arange(0.0, 0.3, 1e-4)
    y = []
    for t in times:
        simulator.AdvanceTo(t)
        y.append(lag.get_output_port().Eval(context).copy())
    y = np.array(y)
    np.testing.assert_array_equal(y[:, 4:], np.tile(torques, (len(times), 1)))
    y = y[:, :4] / step
    expected = 1.0 - np.exp(-times / tau)
    np.testing.assert_allclose(y, np.column_stack([expected] * 4), atol=1e-8)
    for k in range(4):
        t10 = np.interp(0.1, y[:, k], times)
        t90 = np.interp(0.9, y[:, k], times)
        assert t90 - t10 == pytest.approx(rise, abs=2e-4)


def _limits(metrics):
    """(lower, upper) from metrics.json's input_limits (None = unbounded)."""
    pairs = np.array([[-np.inf if lo is None else lo, np.inf if hi is None else hi]
                      for lo, hi in metrics["input_limits"].values()])
    return pairs[:, 0], pairs[:, 1]


@pytest.fixture(scope="module")
def short_runs():
    """0.3 s of each paper scenario (the initial transient saturates several inputs)."""
    out = {}
    for name in ("nominal", "disturbed"):
        scenario = load_scenario(name, overrides={"duration": 0.3})
        result = run_scenario(scenario, progress=False)
        out[name] = (scenario, result, _limits(result.metrics))
    return out


def test_saturation_limits_are_table_i_and_lwr_sdf(short_runs):
    _, _, (lower, upper) = short_runs["nominal"]
    np.testing.assert_array_equal(lower, [0, -200, -200, -200, -165, -165, -70, -70, -70, -30,
                                          -30])
    np.testing.assert_array_equal(upper, [980.6, 200, 200, 200, 165, 165, 70, 70, 70, 30, 30])


def test_nominal_applied_inputs_are_the_saturated_commands(short_runs):
    _, result, (lower, upper) = short_runs["nominal"]
    command, applied = result.log["command"], result.log["applied_command"]
    np.testing.assert_allclose(applied, np.clip(command, lower, upper), rtol=0, atol=1e-9)
    clipped = (command < lower) | (command > upper)
    # The start saturates mu_y and several joints; the check above is not vacuous.
    assert clipped[:, 2].any() and clipped[:, 4:].any()


def test_disturbed_applied_inputs_are_lagged_then_saturated(short_runs):
    """applied = saturate(lag(command)) on [f, mu]; saturate(command) on the joints. The lag
    starts at the first command (no step at t = 0). The logged command at t_k is the value the
    hold kept over [t_{k-1}, t_k) (loggers publish before the hold's update at t_k), so the
    exact discrete solution of the lag is y_k = a y_{k-1} + (1 - a) c_k, a = exp(-h / tau)."""
    scenario, result, (lower, upper) = short_runs["disturbed"]
    t, command, applied = result.log["t"], result.log["command"], result.log["applied_command"]
    np.testing.assert_allclose(applied[0], np.clip(command[0], lower, upper), atol=1e-12)
    a = math.exp(-scenario.controller_period / lag_time_constant(0.1))
    y = np.empty((len(t), 4))
    y[0] = command[0, :4]
    for k in range(1, len(t)):
        y[k] = a * y[k - 1] + (1 - a) * command[k, :4]
    np.testing.assert_allclose(applied[:, :4], np.clip(y, lower[:4], upper[:4]), atol=1e-3)
    np.testing.assert_allclose(applied[:, 4:], np.clip(command[:, 4:], lower[4:], upper[4:]),
                               atol=1e-9)
    # The lag matters here: the unlagged command differs from what was applied by far more.
    assert np.abs(np.clip(command[:, :4], lower[:4], upper[:4]) - applied[:, :4]).max() > 1.0
