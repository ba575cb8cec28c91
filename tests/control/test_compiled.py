"""The compiled decomposition and law (aerial_drake.control.compiled) against the numpy reference
implementation fed by Drake's kinematics (aerial_drake.dynamics.decoupling,
aerial_drake.control.law)."""

import dataclasses

import numpy as np
import pytest

from aerial_drake.control import compiled as dut
from aerial_drake.control.compiled.linalg import _min_eigenvalue_sym
from aerial_drake.control.controller import make_controller
from aerial_drake.control.law import AssumptionViolation, diagnostics_size, diagnostics_slices
from aerial_drake.dynamics.decoupling import DecoupledDynamics
from aerial_drake.dynamics.kinematic_tree import KinematicTree, UnsupportedTree
from aerial_drake.robots.description import shipped_robots
from aerial_drake.robots.models import make_plant
from aerial_drake.simulation.diagram import build_closed_loop
from aerial_drake.simulation.runner import reference_configuration
from aerial_drake.simulation.scenarios import load_scenario
from aerial_drake.trajectories.kinds import evaluate_reference
from chain_plant import KERNEL_TEST_PLANTS, kernel_test_plant
from states import at_state, random_states, rel, symmetric_cases

N_TASK = 7  # the paper's task: end-effector pose and q3
DIAGNOSTICS_SIZE = diagnostics_size(N_TASK)
FIELDS = ("M", "C", "g", "J_g", "J_g_dot", "p_WG", "N", "N_dot", "T", "T_dot", "T_inv",
          "Lambda", "Gamma", "xi", "R")


@pytest.mark.parametrize("which", KERNEL_TEST_PLANTS)
def test_decomposition_matches_reference(which):
    """Every quantity, per body Jacobians and their derivatives included, to ~1e-14: on our
    model, on the rotors variant (a tree: rotors and arm both hang from the base), on the
    second shipped robot and on a random chain (arbitrary joint axes and offsets)."""
    plant = kernel_test_plant(which)
    dd = DecoupledDynamics(plant)
    tree = KinematicTree.from_plant(plant, dd.base_body)
    bodies = [tree.index_of(b) for b in dd.bodies]
    for k, (q, v) in enumerate(random_states(plant, seed=3)):
        if k == 1:
            q[:4] *= 1.0 + 1e-7  # the integrator's quaternions are not exactly unit
        d = at_state(plant, dd, q, v)[1]
        c = dut.decompose(tree, q, v)
        for name in FIELDS:
            assert rel(c[name], getattr(d, name)) < 1e-12, (which, k, name)
        assert rel(c["body_J"][bodies], d.body_J) < 1e-12
        assert rel(c["body_J_dot"][bodies], d.body_J_dot) < 1e-12
        assert c["m"] == pytest.approx(d.m, rel=1e-15)


@pytest.fixture(scope="module")
def nominal():
    scenario = load_scenario("nominal")
    return scenario, build_closed_loop(scenario).controller


def law_inputs(scenario, seed):
    """States near the reference (its configuration moved by up to 5 cm / 0.1 rad, moving at
    up to 1 m/s or rad/s) with the reference at random times of the scenario's trajectory."""
    rng = np.random.default_rng(seed)
    model = scenario.controller_model()
    for t in rng.uniform(0.0, scenario.duration, 8):
        q = reference_configuration(scenario, model, t)
        q[4:7] += rng.uniform(-0.05, 0.05, 3)
        q[7:] += rng.uniform(-0.1, 0.1, q.size - 7)
        v = rng.uniform(-1.0, 1.0, model.plant.num_velocities())
        refs = evaluate_reference(scenario.trajectory, t, model.task_joint_nominal())
        yield np.concatenate([q, v]), refs.to_vectors()


#: One scenario per shipped robot.
ROBOT_CASES = ["nominal", "quadrotor_ur3e"]


def test_the_law_cases_cover_every_shipped_robot():
    assert {load_scenario(name).robot for name in ROBOT_CASES} == set(shipped_robots())


@pytest.fixture(scope="module", params=ROBOT_CASES)
def robot_case(request):
    """The controller of one scenario per shipped robot."""
    scenario = load_scenario(request.param)
    return scenario, build_closed_loop(scenario).controller


def test_law_matches_reference(robot_case):
    scenario, controller = robot_case
    assert controller.compiled
    slices = diagnostics_slices(scenario.controller_model().n)
    for x, refs in law_inputs(scenario, seed=0):
        out = controller.solve(x, *refs)
        command, diagnostics = controller.evaluate(x, *refs)
        expected = np.concatenate([[out.f], out.mu, out.tau])
        assert rel(command, expected) < 1e-12
        for name, s in slices.items():
            if name == "thrust_residual":  # zero up to rounding in both
                assert np.max(np.abs(diagnostics[s])) < 1e-9 * abs(out.f)
                continue
            # Angles near zero come from arccos of a trace: rounding of 1e-16 in the trace
            # moves them by ~1e-16 / angle.
            tol = 1e-12 + (2e-15 / max(float(out.diagnostics[s][0]), 1e-9)
                           if name.endswith("_error") else 0.0)
            assert rel(diagnostics[s], out.diagnostics[s]) < max(tol, 1e-12), name


def test_law_checks_assumptions_and_state(nominal):
    """The compiled law raises as the reference one does, before any output is used."""
    scenario, controller = nominal
    x, refs = next(law_inputs(scenario, seed=1))
    for limits, match in (({"sigma_min_J3_limit": 100.0}, "Assumption 1"),
                          ({"f_d_limit": 1e6}, "Assumption 2")):
        strict = build_closed_loop(dataclasses.replace(scenario, **limits)).controller
        with pytest.raises(AssumptionViolation, match=match):
            strict.solve(x, *refs)
        with pytest.raises(AssumptionViolation, match=match):
            strict.evaluate(x, *refs)
    bad = x.copy()
    bad[20] = np.nan
    with pytest.raises(FloatingPointError, match="not finite"):
        controller.evaluate(bad, *refs)


def test_unsupported_plants_fall_back_to_the_reference_path(nominal):
    """An RPY floating base is not in the kernels: KinematicTree refuses it with a reason and
    the controller evaluates the numpy law instead, with the same result."""
    scenario, controller = nominal
    rpy = make_plant("rigid", floating_base="rpy")
    with pytest.raises(UnsupportedTree, match="rpy_floating joint"):
        KinematicTree.from_plant(rpy.plant, rpy.plant.GetBodyByName("helicopter"))
    fallback = make_controller(rpy, scenario.gains)
    assert not fallback.compiled
    x, refs = next(law_inputs(scenario, seed=2))
    command, _ = fallback.evaluate(_to_rpy_state(rpy, x), *refs)
    assert rel(command, controller.evaluate(x, *refs)[0]) < 1e-9


def _to_rpy_state(rpy, x):
    """The quaternion-base state x as the RPY plant's state (same velocities)."""
    from pydrake.common.eigen_geometry import Quaternion
    from pydrake.math import RollPitchYaw
    w = x[:4] / np.linalg.norm(x[:4])
    rpy_angles = RollPitchYaw(Quaternion(w)).vector()
    q = np.concatenate([rpy_angles, x[4:14]])
    return np.concatenate([q, x[14:]])


def test_law_does_not_depend_on_earlier_calls(nominal):
    """The law keeps its buffers between calls (and writes the body Jacobians only where they
    are not zero): the same state gives the same outputs, to the bit, whatever was evaluated
    before it (non-finite states in between included)."""
    scenario, controller = nominal
    law = controller._compiled
    inputs = list(law_inputs(scenario, seed=3))
    bad = inputs[0][0].copy()
    bad[17] = np.inf
    outputs = {}
    for order in (inputs, inputs[::-1]):
        for x, refs in order:
            command, diagnostics = np.full(11, np.nan), np.full(DIAGNOSTICS_SIZE, np.nan)
            status = law(x, *refs, command, diagnostics)
            assert law(bad, *refs, np.empty(11), np.empty(DIAGNOSTICS_SIZE))[0] == \
                dut.NONFINITE
            key = x.tobytes()
            if key in outputs:
                assert outputs[key][0] == status
                np.testing.assert_array_equal(outputs[key][1], command)
                np.testing.assert_array_equal(outputs[key][2], diagnostics)
            outputs[key] = (status, command, diagnostics)
    assert len(outputs) == len(inputs)


def test_min_eigenvalue_matches_numpy():
    """sigma_min(J3) comes from the smallest eigenvalue by tridiagonal reduction and Newton's
    method: as accurate as LAPACK's (a few rounding units of the norm) on symmetric matrices
    with a spread, a double or a zero smallest eigenvalue, and on indefinite ones; nan when
    the matrix is not finite."""
    work = np.empty((4, 7))
    for k, S in symmetric_cases():
        expected = np.linalg.eigvalsh(S)[0]
        got = _min_eigenvalue_sym(S.copy(), work)
        assert abs(got - expected) <= 1e-14 * np.linalg.norm(S, 2), k
    S = np.eye(7)
    S[2, 3] = S[3, 2] = np.nan
    assert np.isnan(_min_eigenvalue_sym(S, work))
