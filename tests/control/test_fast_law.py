"""The fast kernel of the compiled law (aerial_drake.control.compiled.fast_law, chosen by
``controller.kernel: fast``) against the exact kernel: the same command and diagnostics to
round-off, on the states runs of both shipped robots and of a URDF robot of the user's
visited; its Section II pieces against the exact ones and numpy; the option's validation, and
the default staying the exact kernel."""

import dataclasses

import numpy as np
import pytest

from aerial_drake.control import compiled
from aerial_drake.control.compiled.fast_section2 import (
    _cholesky_into,
    _cholesky_solve,
    _lu_factor,
    _lu_solve,
    _min_eigenvalue_laguerre,
    _structured_inverse,
)
from aerial_drake.control.compiled.kernels import _law
from aerial_drake.control.compiled.law import LAW_KERNEL_NAMES
from aerial_drake.control.controller import DecoupledController, make_controller
from aerial_drake.control.law import SingularityRobust, diagnostics_slices
from aerial_drake.control.registry import LAW_KERNEL_CHOICES
from aerial_drake.dynamics.decoupling import DecoupledDynamics
from aerial_drake.dynamics.kinematic_tree import KinematicTree
from aerial_drake.robots.models import make_plant
from aerial_drake.simulation.diagram import build_closed_loop
from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import ScenarioError, load_scenario
from own_robot import write_robot
from states import random_states, rel, symmetric_cases

#: The agreement asked of the fast kernel: round-off of the reordered sums and solves
#: (measured about 1e-14 to 1e-13), far below any effect on a run.
TOL = 1e-10


def _recorded_inputs(scenario, rows=12):
    """(state, com, task, heading) rows a short run of ``scenario`` visited."""
    scenario = dataclasses.replace(scenario, duration=0.3)
    log = run_scenario(scenario, progress=False).log
    loop = build_closed_loop(scenario)
    idx = loop.simulated_plant.rigid_state_indices
    picks = np.linspace(0, len(log["t"]) - 1, rows).astype(int)
    return [(np.ascontiguousarray(log["plant_state"][k][idx]), log["com_reference"][k],
             log["task_reference"][k], log["heading_reference"][k]) for k in picks]


def _assert_agree(exact, fast, inputs, n):
    """The two controllers' commands and every diagnostic agree to TOL on ``inputs``."""
    slices = diagnostics_slices(n)
    for x, com, task, heading in inputs:
        c_exact, d_exact = exact.evaluate(x, com, task, heading)
        c_fast, d_fast = fast.evaluate(x, com, task, heading)
        assert rel(c_fast, c_exact) < TOL
        for name, s in slices.items():
            if name == "thrust_residual":  # zero up to rounding in both
                assert np.max(np.abs(d_fast[s])) < 1e-9 * abs(c_exact[0])
                continue
            # Angles near zero come from arccos of a trace: rounding of 1e-16 in the trace
            # moves them by ~1e-16 / angle.
            tol = TOL + (2e-15 / max(float(d_exact[s][0]), 1e-9)
                         if name.endswith("_error") else 0.0)
            assert rel(d_fast[s], d_exact[s]) < tol, name


@pytest.fixture(params=["nominal", "quadrotor_ur3e", "urdf"])
def scenario(request, tmp_path):
    if request.param == "urdf":
        return load_scenario(write_robot(tmp_path)[1])
    return load_scenario(request.param)


def test_fast_kernel_agrees_with_exact_on_recorded_states(scenario):
    model = scenario.controller_model()
    exact, fast = (make_controller(model, scenario.gains, period=scenario.controller_period,
                                   kernel=kernel) for kernel in ("exact", "fast"))
    assert exact.compiled and fast.compiled
    assert exact._compiled._kernel is _law
    assert fast._compiled._kernel is LAW_KERNEL_NAMES["fast"]
    _assert_agree(exact, fast, _recorded_inputs(scenario), model.n)


def test_fast_kernel_agrees_with_exact_under_the_damped_inverse():
    """paper_plus's damped inverse of J_3 (formed as in the exact kernel) on the fast path:
    a threshold above every state's sigma_min keeps the damping on throughout."""
    scenario = load_scenario("nominal")
    model = scenario.controller_model()
    damped = SingularityRobust(damping=0.05, threshold=10.0, lost_error=1e3)
    exact, fast = (DecoupledController(model.plant, model.end_effector_frame, model.task,
                                       scenario.gains, period=scenario.controller_period,
                                       singularity=damped, kernel=kernel)
                   for kernel in ("exact", "fast"))
    _assert_agree(exact, fast, _recorded_inputs(scenario, rows=4), model.n)


def test_structured_inverse_is_the_inverse_of_T():
    """T^-1 from T's blocks equals the exact kernel's Gaussian elimination on T, at random
    (fast) states, and inverts T."""
    plant = make_plant("rigid").plant
    dd = DecoupledDynamics(plant)
    tree = KinematicTree.from_plant(plant, dd.base_body)
    for q, v in random_states(plant, seed=5):
        d = compiled.decompose(tree, q, v)
        nv = v.size
        T_inv = np.empty((nv, nv))
        _structured_inverse(d["R"], d["J_g"], d["N"], np.empty((nv - 6, nv)), T_inv)
        assert rel(T_inv, d["T_inv"]) < 1e-13
        assert np.max(np.abs(d["T"] @ T_inv - np.eye(nv))) < 1e-12


def test_small_solvers_match_numpy():
    rng = np.random.default_rng(0)
    for n in (1, 3, 7):
        A = rng.normal(size=(n, n))
        b = rng.normal(size=n)
        LU, piv, out = A.copy(), np.empty(n), np.empty(n)
        _lu_factor(LU, piv)
        _lu_solve(LU, piv, b, out)
        assert rel(out, np.linalg.solve(A, b)) < 1e-12
        S = A @ A.T + n * np.eye(n)
        L = np.zeros((n, n))
        _cholesky_into(S, L)
        B = rng.normal(size=(n, 4))
        X = B.copy()
        _cholesky_solve(L, X)
        assert rel(X, np.linalg.solve(S, B)) < 1e-12


def test_the_default_kernel_is_exact_and_the_option_reaches_the_law():
    scenario = load_scenario("nominal")
    assert scenario.controller.kernel == "exact"
    assert tuple(LAW_KERNEL_NAMES) == LAW_KERNEL_CHOICES
    assert build_closed_loop(scenario).controller._compiled._kernel is _law
    fast = load_scenario("nominal", overrides={"controller.kernel": "fast"})
    assert build_closed_loop(fast).controller._compiled.kernel == "fast"
    plus = load_scenario("nominal", overrides={"controller.kernel": "fast",
                                               "controller.type": "paper_plus"})
    assert build_closed_loop(plus).controller._law._compiled.kernel == "fast"
    # Built, the fast kernel is in numba's cache; the cold check counts it only when asked.
    assert not compiled.law_cache_is_cold(("fast",))
    assert len(compiled.law.LAW_KERNELS) + 1 == len(compiled.law._law_kernels(("fast",)))


@pytest.mark.parametrize("overrides, match", [
    ({"controller.kernel": "quick"},
     r"controller.kernel: 'quick' is not one of exact, fast .*write e.g. controller.kernel: "
     r"exact"),
    ({"controller.kernel": "fast", "controller.type": "uncoupled"},
     r"controller.kernel: fast .* controller.type uncoupled does not run: remove "
     r"controller.kernel \(or set it to exact\)"),
])
def test_a_bad_kernel_is_refused_naming_the_field_and_the_fix(overrides, match):
    with pytest.raises(ScenarioError, match=match) as err:
        load_scenario("nominal", overrides=overrides)
    assert err.value.field == "controller.kernel"


def test_laguerre_min_eigenvalue_matches_numpy():
    """The fast kernel's smallest eigenvalue (Laguerre's iteration) on the exact kernel's test
    cases (tests/control/test_compiled.py): a spread, a tiny, a double or a zero smallest
    eigenvalue, indefinite matrices; a few rounding units of the norm; nan when not finite."""
    work = np.empty((4, 7))
    for k, S in symmetric_cases():
        expected = np.linalg.eigvalsh(S)[0]
        got = _min_eigenvalue_laguerre(S.copy(), work)
        assert abs(got - expected) <= 1e-14 * np.linalg.norm(S, 2), k
    assert _min_eigenvalue_laguerre(np.array([[2.5]]), work) == 2.5
    S = np.eye(7)
    S[2, 3] = S[3, 2] = np.nan
    assert np.isnan(_min_eigenvalue_laguerre(S, work))
