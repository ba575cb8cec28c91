"""The momentum observer's pure parts (aerial_drake.dynamics.momentum_observer): the split of
a generalized force into the vehicle's and the end effector's wrenches on the paper's robot,
the discrete filter's step response, and the actuation's generalized force."""

import numpy as np
import pytest
from pydrake.math import RollPitchYaw
from pydrake.multibody.tree import JacobianWrtVariable

from aerial_drake.dynamics import momentum_observer as dut
from aerial_drake.robots.models import make_plant


@pytest.fixture(scope="module")
def posture():
    """The paper's robot at a random bent posture and attitude: its end-effector Jacobian
    (World, [w; v] rows) and E's position from the base origin (World)."""
    model = make_plant("rigid")
    plant = model.plant
    ctx = plant.CreateDefaultContext()
    rng = np.random.default_rng(7)
    q = plant.GetPositions(ctx)
    q[:4] = RollPitchYaw(rng.uniform(-0.3, 0.3, 3)).ToQuaternion().wxyz()
    q[4:7] = [0.2, -0.1, 1.5]
    q[7:] += rng.uniform(-0.5, 0.5, q.size - 7)
    q[7 + 3] += 1.2  # the elbow bent, away from the stretched arm's singularity
    plant.SetPositions(ctx, q)
    world = plant.world_frame()
    J_E = plant.CalcJacobianSpatialVelocity(ctx, JacobianWrtVariable.kV,
                                            model.end_effector_frame, np.zeros(3), world, world)
    p_BE = (model.end_effector_frame.CalcPoseInWorld(ctx).translation()
            - plant.EvalBodyPoseInWorld(ctx, model.base_body).translation())
    return J_E, p_BE


def test_split_recovers_a_vehicle_and_an_end_effector_wrench(posture):
    """tau = [w_B; 0] + J_E^T w_E (the closed loop's two disturbance ports' generalized
    forces) splits back into w_B and w_E, to round-off, and each alone into itself and zero."""
    J_E, p_BE = posture
    w_B = np.array([5.0, -3.0, 2.0, 10.0, 50.0, -20.0])
    w_E = np.array([20.0, 20.0, 20.0, 40.0, 40.0, 40.0])
    tau_B = np.zeros(J_E.shape[1])
    tau_B[:6] = w_B
    np.testing.assert_allclose(dut.split_wrenches(tau_B + J_E.T @ w_E, J_E),
                               np.concatenate([w_B, w_E]), atol=1e-9)
    np.testing.assert_allclose(dut.split_wrenches(tau_B, J_E),
                               np.concatenate([w_B, np.zeros(6)]), atol=1e-12)
    np.testing.assert_allclose(dut.split_wrenches(J_E.T @ w_E, J_E),
                               np.concatenate([np.zeros(6), w_E]), atol=1e-9)
    # The base rows of J_E^T move w_E to the base origin: [torque + p_BE x force; force].
    torque, force = w_E[:3], w_E[3:]
    np.testing.assert_allclose(J_E[:, :6].T @ w_E,
                               np.concatenate([torque + np.cross(p_BE, force), force]),
                               atol=1e-12)


def _sample(M, v, J_E, bias, g):
    return dut.ObserverSample(M=M, v=v, bias=bias, g=g, R_WB=np.eye(3), J_E=J_E)


def test_a_constant_external_force_is_followed_as_one_minus_exp(posture):
    """A constant M, bias and gravity, and a constant command: the velocity grows by
    h M^-1 (tau_act - C v - g + tau_ext) per sample, and the estimate after k samples is
    (1 - exp(-K_O k h)) tau_ext to round-off (the filter's exact discretization; explicit
    Euler's 1 - (1 - K_O h)^k is 1 % off at k = 3), the wrenches likewise."""
    J_E, _ = posture
    nv = J_E.shape[1]
    rng = np.random.default_rng(3)
    A = rng.normal(size=(nv, nv))
    M = A @ A.T + nv * np.eye(nv)
    bias, g = rng.normal(size=nv), rng.normal(size=nv)
    command = rng.normal(size=nv - 2)
    w_B, w_E = rng.normal(size=6) * 10, rng.normal(size=6) * 10
    tau_ext = J_E.T @ w_E
    tau_ext[:6] += w_B
    K, h = 20.0, 1e-3
    state = dut.ObserverState(np.zeros(dut.ObserverState.size(nv)), nv)
    v = rng.normal(size=nv)
    dut.start(state, _sample(M, v, J_E, bias, g))
    force = dut.actuation_force(np.eye(3), command) - bias - g + tau_ext
    pole = dut.filter_pole(K, h)
    for k in range(1, 201):
        v = v + h * np.linalg.solve(M, force)
        dut.step(state, _sample(M, v, J_E, bias, g), command, h, pole)
        scale = 1.0 - np.exp(-K * k * h)
        np.testing.assert_allclose(state.r, scale * tau_ext, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(state.wrenches, scale * np.concatenate([w_B, w_E]),
                                   rtol=1e-9, atol=1e-9)


def test_the_actuation_is_thrust_along_body_z_and_torques_at_the_base():
    R = RollPitchYaw(0.3, -0.2, 1.0).ToRotationMatrix().matrix()
    command = np.array([500.0, 1.0, 2.0, 3.0, 4.0, 5.0])
    tau = dut.actuation_force(R, command)
    np.testing.assert_allclose(tau[:3], R @ [1.0, 2.0, 3.0])
    np.testing.assert_allclose(tau[3:6], 500.0 * R[:, 2])
    np.testing.assert_array_equal(tau[6:], [4.0, 5.0])


@pytest.mark.parametrize("bandwidth,period", [(0.0, 1e-3), (-1.0, 1e-3), (np.inf, 1e-3),
                                              (20.0, 0.0)])
def test_a_bad_bandwidth_or_period_is_refused(bandwidth, period):
    with pytest.raises(ValueError, match="observer"):
        dut.filter_pole(bandwidth, period)
