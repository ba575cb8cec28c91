"""The fast kernel's rigid-body part (aerial_drake.control.compiled.fast_rigid_body: the
recursions for M, the Christoffel-consistent C, J_g, J_g_dot and the CoM, and World-aligned
point Jacobians from the motion columns) against the exact kernel's sums over bodies, on the
shipped robots, the rotors variant (a tree: the rotors and the arm both hang from the base) and
a random chain."""

import numpy as np
import pytest

from aerial_drake.control import compiled
from aerial_drake.control.compiled.fast_rigid_body import fast_rigid_body
from aerial_drake.dynamics.decoupling import DecoupledDynamics
from aerial_drake.dynamics.kinematic_tree import KinematicTree
from chain_plant import KERNEL_TEST_PLANTS, kernel_test_plant
from states import random_states, rel

#: Round-off of the reordered sums (measured about 1e-15 to 5e-15).
TOL = 1e-12


@pytest.mark.parametrize("which", KERNEL_TEST_PLANTS)
def test_recursions_match_the_sums_over_bodies(which):
    """M, C, J_g, J_g_dot, the CoM and every body's point Jacobian to round-off, at random
    (half of them fast) states."""
    plant = kernel_test_plant(which)
    dd = DecoupledDynamics(plant)
    tree = KinematicTree.from_plant(plant, dd.base_body)
    for k, (q, v) in enumerate(random_states(plant, seed=11)):
        if k == 1:
            q[:4] *= 1.0 + 1e-7  # the integrator's quaternions are not exactly unit
        exact = compiled.decompose(tree, q, v)
        fast = fast_rigid_body(tree, q, v)
        assert fast["m"] == pytest.approx(exact["m"], rel=1e-15)
        assert np.array_equal(exact["R_all"][fast["base"]], exact["R"])
        for name in ("M", "C", "J_g", "J_g_dot", "p_WG"):
            assert rel(fast[name], exact[name]) < TOL, (which, k, name)
        # Every body origin's World-aligned Jacobian [v; w] and its derivative, against the
        # exact kernel's body-frame [w; v]: R J and d/dt (R J) = R (hat(w_B) J + J_dot) (all
        # bodies at once: the base's derivative is zero but for rounding).
        expected = np.empty_like(fast["J6"])
        for b in range(tree.parent.size):
            R, J, J_dot = exact["R_all"][b], exact["body_J"][b], exact["body_J_dot"][b]
            w_B = J[:3] @ v
            hat = np.array([[0.0, -w_B[2], w_B[1]], [w_B[2], 0.0, -w_B[0]],
                            [-w_B[1], w_B[0], 0.0]])
            expected[b, 0] = np.vstack([R @ J[3:], R @ J[:3]])
            expected[b, 1] = np.vstack([R @ (hat @ J[3:] + J_dot[3:]),
                                        R @ (hat @ J[:3] + J_dot[:3])])
        assert rel(fast["J6"][:, 0], expected[:, 0]) < TOL, (which, k)
        assert rel(fast["J6"][:, 1], expected[:, 1]) < TOL, (which, k)
