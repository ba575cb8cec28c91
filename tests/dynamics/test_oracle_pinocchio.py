"""Section II against an independent rigid-body library (issue 22, item 1).

Pinocchio (``pin`` on PyPI, in the ``test`` extra) computes M (CRBA), the Christoffel-consistent
Coriolis matrix (``computeCoriolisMatrix``), the CoM Jacobian and frame Jacobians with their time
variation, on a Pinocchio model built from the Drake plant's kinematic and inertial parameters
(tests/paper_oracles.py: Pinocchio's pip wheel does not parse SDF, so the joint frames, axes,
welds, spatial inertias and reflected inertias are read from the Drake plant; the algorithms are
Pinocchio's). Pinocchio's free-flyer velocity [v_B; w_B] (base frame) is mapped to Drake's
[w_WB; v_WBo] (World) by v_drake = S v_pin (C picks up -M S_dot S^-1).

Held against it, on every shipped model (the helicopter + KUKA LWR, plant variants "rigid" and
"rotors"), at random states: both implementations of Section II
(aerial_drake.dynamics.decoupling, numpy; aerial_drake.control.compiled.decompose, numba),
then T, Lambda, Gamma of (3)-(6) built here from Pinocchio's M, C, J_g by the paper's formulas,
and the task Jacobians J1, J2, J3 of (17) and Lambda_z, Gamma_z of (19) against the law's
(aerial_drake.control via the controller's ``solve``).

Measured on correct code (relative, worst state): M 1.2e-15, C 1.3e-14, J_g 7e-16, J_g_dot v
3e-14, end-effector J 9e-16 and J_dot 8e-16; T 8e-15, Lambda 2e-15, Gamma 2.3e-10 (T_dot by a
fourth-order central difference); J3 8e-16, Lambda_z 3e-15, Gamma_z 3.5e-11. The tolerances
below sit 30x to 1000x above; a wrong Coriolis factorization or a sign error in a block is off
by O(1e-2..1).
"""

import numpy as np
import pytest

pin = pytest.importorskip(
    "pinocchio", reason="Pinocchio (pip package 'pin', in the test extra) is not installed: "
    "the independent rigid-body oracle cannot run")

from aerial_drake.control import compiled  # noqa: E402
from aerial_drake.control.controller import make_controller  # noqa: E402
from aerial_drake.dynamics.decoupling import DecoupledDynamics  # noqa: E402
from aerial_drake.dynamics.kinematic_tree import KinematicTree  # noqa: E402
from aerial_drake.robots.description import (  # noqa: E402
    default_robot,
    load_robot_description,
    shipped_robots,
)
from aerial_drake.robots.models import make_plant  # noqa: E402
from aerial_drake.simulation.runner import reference_configuration  # noqa: E402
from aerial_drake.simulation.scenarios import load_scenario  # noqa: E402
from aerial_drake.trajectories.kinds import evaluate_reference  # noqa: E402
from paper_oracles import (  # noqa: E402
    ChristoffelFromMassMatrix,
    PinocchioModel,
    decoupling_transform,
    directional_derivative,
    task_space_mobility,
)


def rel(a, b):
    return float(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300))


#: The plant variants of the paper's robot description.
PLANT_VARIANTS = default_robot().variant_names()
#: Every plant of every shipped robot: (robot, variant).
SHIPPED_PLANTS = [(name, variant) for name in sorted(shipped_robots())
                  for variant in load_robot_description(name).variant_names()]


def random_states(plant, seed, count=6):
    """Random attitudes and positions, arm (and rotor) joints within +-2 rad, velocities up to
    1 (odd k) or 10 (even k) rad/s or m/s."""
    rng = np.random.default_rng(seed)
    ctx = plant.CreateDefaultContext()
    q0 = plant.GetPositions(ctx)
    for k in range(count):
        q = q0.copy()
        quat = rng.normal(size=4)
        q[:4] = quat / np.linalg.norm(quat)
        q[4:7] = rng.normal(size=3)
        q[7:] += rng.uniform(-2.0, 2.0, q.size - 7)
        scale = 1.0 if k % 2 else 10.0
        yield q, rng.uniform(-scale, scale, plant.num_velocities())


@pytest.fixture(scope="module", params=SHIPPED_PLANTS, ids="-".join)
def model(request):
    robot, variant = request.param
    m = make_plant(variant, robot=load_robot_description(robot))
    pm = PinocchioModel(m.plant, m.base_body)
    ee = pm.add_frame("end_effector", m.end_effector_body,
                      m.end_effector_frame.GetFixedPoseInBodyFrame())
    return m, pm, ee


def test_every_shipped_model_is_covered():
    # A robot or variant added is held against Pinocchio by the fixture above; this names
    # the ones the oracle was written for, so a renamed one is noticed.
    assert set(PLANT_VARIANTS) == {"rigid", "rotors"}
    assert set(SHIPPED_PLANTS) == {("helicopter_lwr", "rigid"), ("helicopter_lwr", "rotors"),
                                   ("quadrotor_ur3e", "rigid")}


def test_section_ii_quantities_match_pinocchio(model):
    """M, C, J_g, J_g_dot v, p_WG and the end-effector Jacobian [v_WE; w_WE] with its time
    derivative, from both implementations, against Pinocchio."""
    m, pm, ee = model
    plant = m.plant
    dd = DecoupledDynamics(plant)
    tree = KinematicTree.from_plant(plant, dd.base_body)
    ctx = plant.CreateDefaultContext()
    worst = {}
    for q, v in random_states(plant, seed=11):
        plant.SetPositions(ctx, q)
        plant.SetVelocities(ctx, v)
        d = dd.compute(ctx)
        c = compiled.decompose(tree, q, v)
        o = pm.drake_quantities(q, v, [ee])
        J_E, J_E_dot = dd.frame_jacobian(d, m.end_effector_frame)
        J_p, J_p_dot, p_WE, R_WE = o["frames"][ee]
        X_WE = m.end_effector_frame.CalcPoseInWorld(ctx)
        checks = {
            # measured (worst of 6 states, both variants) -> tolerance
            "M": (d.M, c["M"], o["M"], 1e-12),  # 1.2e-15
            "C": (d.C, c["C"], o["C"], 1e-11),  # 1.3e-14
            "J_g": (d.J_g, c["J_g"], o["J_g"], 1e-12),  # 7e-16
            "J_g_dot v": (d.J_g_dot @ v, c["J_g_dot"] @ v, o["J_g_dot_v"], 1e-11),  # 3e-14
            "p_WG": (d.p_WG, c["p_WG"], o["p_WG"], 1e-12),  # 5e-16
        }
        for name, (numpy_value, compiled_value, expected, tol) in checks.items():
            for which, value in (("numpy", numpy_value), ("compiled", compiled_value)):
                err = rel(value, expected)
                worst[name] = max(worst.get(name, 0.0), err)
                assert err < tol, (m.variant, which, name, err)
        assert rel(J_E, J_p) < 1e-12, rel(J_E, J_p)  # 9e-16
        assert rel(J_E_dot, J_p_dot) < 1e-12, rel(J_E_dot, J_p_dot)  # 8e-16
        assert rel(X_WE.translation(), p_WE) < 1e-12
        assert rel(X_WE.rotation().matrix(), R_WE) < 1e-12
    print(m.variant, {k: f"{v:.1e}" for k, v in worst.items()})


def test_christoffel_from_mass_matrix_matches_pinocchio(model):
    """The closed-loop oracle's Coriolis matrix (central differences of Drake's M in
    roll-pitch-yaw coordinates, tests/paper_oracles.py) is Pinocchio's: measured 1.1e-11
    relative (the differences' truncation and round-off); tolerance 1e-9. A form that only
    reproduces C v (e.g. 1/2 d(Cv)/dv) is off by O(1) (math.md, section 3)."""
    m, pm, _ = model
    oracle = ChristoffelFromMassMatrix(
        make_plant(m.variant, floating_base="rpy", robot=m.description).plant)
    for q, v in random_states(m.plant, seed=5, count=3):
        q[1:4] *= 0.3  # keep the pitch away from roll-pitch-yaw's singularity at +-90 deg
        q[:4] /= np.linalg.norm(q[:4])
        C = pm.drake_quantities(q, v)["C"]
        assert rel(oracle(q, v), C) < 1e-9, rel(oracle(q, v), C)


def _pinocchio_decomposition(pm, plant, q, v, h=1e-4):
    """T, T^-1, T_dot, Lambda, Gamma of (3)-(6) from Pinocchio's M, C, J_g, with T_dot a
    fourth-order central difference of T along q_dot = N(q) v (Drake's map; the quaternion is
    normalised at each point, which moves it along itself only)."""
    ctx = plant.CreateDefaultContext()
    plant.SetPositions(ctx, q)
    qdot = plant.MapVelocityToQDot(ctx, v)

    def at(qs):
        o = pm.drake_quantities(qs, v)
        return o, decoupling_transform(o["M"], o["J_g"], o["R"])

    o, d = at(q)
    T_dot = directional_derivative(lambda qs: at(qs)[1]["T"], q, qdot, h)
    T_inv = d["T_inv"]
    d["T_dot"] = T_dot
    d["Gamma"] = T_inv.T @ (o["C"] - o["M"] @ T_inv @ T_dot) @ T_inv
    return o, d


def test_lambda_and_gamma_match_pinocchio(model):
    """Lambda and Gamma of (5)-(6) from Pinocchio's M and C against both implementations,
    and the paper's structure on the oracle itself: Lambda block diagonal with
    Lambda_11 = m E3, Gamma's first three rows and columns zero, Gamma_32 = -Gamma_23^T."""
    m, pm, _ = model
    plant = m.plant
    dd = DecoupledDynamics(plant)
    tree = KinematicTree.from_plant(plant, dd.base_body)
    ctx = plant.CreateDefaultContext()
    mass = plant.CalcTotalMass(ctx)
    for q, v in random_states(plant, seed=7, count=4):
        plant.SetPositions(ctx, q)
        plant.SetVelocities(ctx, v)
        d = dd.compute(ctx)
        c = compiled.decompose(tree, q, v)
        o, p = _pinocchio_decomposition(pm, plant, q, v)
        L, G = p["Lambda"], p["Gamma"]
        scale_G = np.abs(G).max()
        # The oracle's own structure (round-off for Lambda: measured 9e-16; the difference's
        # error for Gamma: first rows/columns 2.3e-10, Gamma_32 + Gamma_23^T 9e-12).
        assert np.abs(L[:3, :3] - mass * np.eye(3)).max() < 1e-12 * mass
        assert np.abs(L[:3, 3:]).max() < 1e-12 * np.abs(L).max()
        assert np.abs(L[3:6, 6:]).max() < 1e-12 * np.abs(L).max()
        assert np.abs(G[:3]).max() < 1e-8 * scale_G and np.abs(G[:, :3]).max() < 1e-8 * scale_G
        assert np.abs(G[6:, 3:6] + G[3:6, 6:].T).max() < 1e-9 * scale_G
        for which, value in (("numpy", d), ("compiled", c)):
            get = (lambda k: getattr(value, k)) if which == "numpy" else value.__getitem__
            assert rel(get("T"), p["T"]) < 1e-12, (which, rel(get("T"), p["T"]))  # 8e-15
            assert rel(get("Lambda"), L) < 1e-12, (which, rel(get("Lambda"), L))  # 2e-15
            # Gamma: measured 2.3e-10 (T_dot by a fourth-order difference, h = 1e-4); a
            # Coriolis matrix that only matched C v would be off by O(1).
            assert rel(get("Gamma"), G) < 1e-8, (which, rel(get("Gamma"), G))


def law_states(scenario, seed, count=4):
    """States near the reference at random times of the trajectory (so Assumption 1 holds),
    moving at up to 1 m/s or rad/s, with the reference at those times."""
    rng = np.random.default_rng(seed)
    model = make_plant("rigid")
    for t in rng.uniform(0.0, 15.0, count):
        q = reference_configuration(scenario, model, t)
        q[4:7] += rng.uniform(-0.05, 0.05, 3)
        q[7:] += rng.uniform(-0.1, 0.1, q.size - 7)
        v = rng.uniform(-1.0, 1.0, model.plant.num_velocities())
        yield q, v, evaluate_reference(scenario.trajectory, t).to_vectors()


def test_task_jacobians_and_task_inertia_match_pinocchio():
    """(17)-(19) on the controller's model: J = J_y T^-1 = [J1 J2 J3] with J_y from
    Pinocchio's end-effector Jacobian and the q3 row, Lambda_z = J3^-T Lambda_33 J3^-1 and
    Gamma_z = J3^-T (Gamma_33 - Lambda_33 J3^-1 J3_dot) J3^-1 (J3_dot a central difference of
    J3 along the motion), against the law's J3, Lambda_z, Gamma_z; and Lambda_z against the
    T^-1-free formula the closed-loop oracle uses (paper_oracles.task_space_mobility)."""
    scenario = load_scenario("nominal")
    m = make_plant("rigid")
    plant = m.plant
    pm = PinocchioModel(plant, m.base_body)
    ee = pm.add_frame("end_effector", m.end_effector_body,
                      m.end_effector_frame.GetFixedPoseInBodyFrame())
    controller = make_controller(m, scenario.gains)
    q3_v = m.arm_joints[2].velocity_start()
    ctx = plant.CreateDefaultContext()
    h = 1e-4

    def task_J(qs, v):
        o = pm.drake_quantities(qs, v, [ee])
        J_y = np.vstack([o["frames"][ee][0], np.eye(plant.num_velocities())[q3_v]])
        return o, J_y, J_y @ decoupling_transform(o["M"], o["J_g"], o["R"])["T_inv"]

    for q, v, refs in law_states(scenario, seed=2):
        out = controller.solve(np.concatenate([q, v]), *refs)
        plant.SetPositions(ctx, q)
        qdot = plant.MapVelocityToQDot(ctx, v)
        o, p = _pinocchio_decomposition(pm, plant, q, v)
        _, J_y, J = task_J(q, v)
        J_dot = directional_derivative(lambda qs: task_J(qs, v)[2], q, qdot, h)
        J3, J3_dot = J[:, 6:], J_dot[:, 6:]
        J3_inv = np.linalg.inv(J3)
        L33, G33 = p["Lambda"][6:, 6:], p["Gamma"][6:, 6:]
        Lambda_z = J3_inv.T @ L33 @ J3_inv
        Gamma_z = J3_inv.T @ (G33 - L33 @ J3_inv @ J3_dot) @ J3_inv
        assert rel(out.J3, J3) < 1e-12, rel(out.J3, J3)  # measured 8e-16
        assert rel(out.Lambda_z, Lambda_z) < 1e-12, rel(out.Lambda_z, Lambda_z)  # 3e-15
        assert rel(out.Gamma_z, Gamma_z) < 1e-9, rel(out.Gamma_z, Gamma_z)  # 3.5e-11
        # The closed-loop oracle's Lambda_z (no T^-1) is the same matrix (1e-15).
        _, Lambda_z_2, _ = task_space_mobility(o["M"], o["J_g"], o["R"], J_y)
        assert rel(Lambda_z_2, Lambda_z) < 1e-12, rel(Lambda_z_2, Lambda_z)
