"""Section II identities on every shipped robot (and on a random chain), at many random
states."""

import numpy as np
import pytest
from pydrake.multibody.tree import JacobianWrtVariable

from aerial_drake.dynamics.decoupling import DecoupledDynamics, decompose, hat, vee
from aerial_drake.robots.description import load_robot_description, shipped_robots
from aerial_drake.robots.models import make_plant
from chain_plant import make_random_chain
from states import at_state, random_states, rel


@pytest.fixture(scope="module", params=[*sorted(shipped_robots()), "chain"])
def dut(request):
    if request.param == "chain":
        plant = make_random_chain(3)
    else:
        plant = make_plant(robot=load_robot_description(request.param)).plant
    return plant, DecoupledDynamics(plant)


def decompositions(plant, dd, seed):
    """The decomposition at each of ``random_states(plant, seed)``."""
    for q, v in random_states(plant, seed=seed):
        yield at_state(plant, dd, q, v)[1]


def central_difference(plant, dd, q, v, attr, h=1e-6):
    """d/dt of a Decomposition field along q_dot = N(q) v (v held)."""
    ctx = plant.CreateDefaultContext()
    plant.SetPositions(ctx, q)
    qdot = plant.MapVelocityToQDot(ctx, v)
    vals = []
    for s in (1.0, -1.0):
        qs = q + s * h * qdot
        _, d = at_state(plant, dd, qs, v)
        vals.append(getattr(d, attr))
    return (vals[0] - vals[1]) / (2 * h)




def test_coriolis_matches_bias_term(dut):
    plant, dd = dut
    for q, v in random_states(plant):
        ctx, d = at_state(plant, dd, q, v)
        assert rel(d.C @ v, plant.CalcBiasTerm(ctx)) < 1e-10


def test_passivity_M_dot_equals_C_plus_CT(dut):
    plant, dd = dut
    for q, v in random_states(plant, seed=1):
        _, d = at_state(plant, dd, q, v)
        M_dot = central_difference(plant, dd, q, v, "M")
        assert rel(d.C + d.C.T, M_dot) < 1e-6


def test_coriolis_is_linear_in_v(dut):
    plant, dd = dut
    rng = np.random.default_rng(2)
    for q, v in random_states(plant, seed=2):
        v2 = rng.normal(size=v.size)
        a, b = 2.5, -0.7
        C1 = at_state(plant, dd, q, v)[1].C
        C2 = at_state(plant, dd, q, v2)[1].C
        C12 = at_state(plant, dd, q, a * v + b * v2)[1].C
        assert rel(C12, a * C1 + b * C2) < 1e-12


def test_jacobian_derivatives_match_central_difference(dut):
    plant, dd = dut
    for q, v in random_states(plant, seed=3):
        _, d = at_state(plant, dd, q, v)
        assert rel(d.body_J_dot, central_difference(plant, dd, q, v, "body_J")) < 1e-6
        assert rel(d.T_dot, central_difference(plant, dd, q, v, "T")) < 1e-6


def test_com_jacobian_matches_drake(dut):
    plant, dd = dut
    for q, v in random_states(plant, seed=4):
        ctx, d = at_state(plant, dd, q, v)
        J_g = plant.CalcJacobianCenterOfMassTranslationalVelocity(
            ctx, JacobianWrtVariable.kV, plant.world_frame(), plant.world_frame())
        np.testing.assert_allclose(d.J_g, J_g, atol=1e-12)
        np.testing.assert_allclose(d.p_WG, plant.CalcCenterOfMassPositionInWorld(ctx),
                                   atol=1e-12)


def test_lambda_block_diagonal_and_com_block(dut):
    plant, dd = dut
    for d in decompositions(plant, dd, seed=5):
        L = d.Lambda
        norm = np.linalg.norm(L)
        for i, j in ((1, 2), (1, 3), (2, 3)):
            assert np.linalg.norm(d.Lambda_block(i, j)) / norm < 1e-9
            assert np.linalg.norm(d.Lambda_block(j, i)) / norm < 1e-9
        np.testing.assert_allclose(d.Lambda_block(1, 1), d.m * np.eye(3), rtol=0,
                                   atol=1e-9 * d.m)
        cond = np.linalg.cond(d.T)
        print(f"cond(T) = {cond:.3g}")
        assert np.isfinite(cond) and cond < 1e8
        np.testing.assert_allclose(d.T_inv @ d.T, np.eye(d.T.shape[0]), atol=1e-10)


def test_gamma_structure_and_passivity(dut):
    plant, dd = dut
    for q, v in random_states(plant, seed=6):
        _, d = at_state(plant, dd, q, v)
        G = d.Gamma
        scale = np.linalg.norm(G)
        assert np.abs(G[:3]).max() < 1e-10 * scale, "Gamma's first three rows must vanish"
        assert np.abs(G[:, :3]).max() < 1e-10 * scale, "Gamma's first three columns must vanish"
        assert rel(d.Gamma_block(3, 2), -d.Gamma_block(2, 3).T) < 1e-10
        Lambda_dot = central_difference(plant, dd, q, v, "Lambda")
        assert rel(G + G.T, Lambda_dot) < 1e-6


def test_input_map_and_transformed_gravity(dut):
    plant, dd = dut
    for d in decompositions(plant, dd, seed=7):
        top = d.input_map[:3]
        expected = np.hstack([d.R, np.zeros((3, 3 + d.n))])
        np.testing.assert_allclose(top, expected, atol=1e-10)
        g = plant.gravity_field().gravity_vector()
        expected_g = np.zeros(6 + d.n)
        expected_g[2] = -d.m * g[2]
        np.testing.assert_allclose(d.transformed_gravity, expected_g, atol=1e-9 * d.m * 9.81)


def test_null_space_and_xi(dut):
    plant, dd = dut
    for d in decompositions(plant, dd, seed=8):
        v = d.v  # the state's velocity
        np.testing.assert_allclose(d.Z @ np.vstack([d.J_g, d.J_bw]).T, 0, atol=1e-12)
        Minv = np.linalg.inv(d.M)
        np.testing.assert_allclose(d.N @ Minv @ np.vstack([d.J_g, d.J_bw]).T, 0, atol=1e-9)
        np.testing.assert_allclose(d.xi[3:6], d.R.T @ v[:3], atol=1e-12)
        np.testing.assert_allclose(d.J_b @ v, np.concatenate([d.R.T @ v[3:6], d.R.T @ v[:3]]),
                                   atol=1e-12)
        np.testing.assert_allclose(d.Q @ v, v[6:], atol=0)


def test_decompose_convenience_and_errors():
    plant = make_plant("rigid").plant
    ctx = plant.CreateDefaultContext()
    d = decompose(plant, ctx)
    assert d.M.shape == (13, 13) and d.n == 7
    from pydrake.multibody.plant import MultibodyPlant
    with pytest.raises(ValueError, match="finalized"):
        DecoupledDynamics(MultibodyPlant(0.0))


def test_hat_vee_roundtrip():
    a = np.array([0.3, -1.2, 2.0])
    np.testing.assert_allclose(vee(hat(a)), a)
    np.testing.assert_allclose(hat(a) @ np.array([1.0, 2.0, 3.0]), np.cross(a, [1.0, 2.0, 3.0]))
