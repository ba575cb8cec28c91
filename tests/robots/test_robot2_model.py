"""Tests of the second robot's model files (quadrotor.sdf, ur3e.sdf,
quadrotor_arm_mount.dmd.yaml) and of every shipped SDF's physical validity.

The numbers asserted here are the sources' (written in the files' headers and in
docs/models.md, "Quadrotor with UR3e"); the conditioning margins are the documented ones.
"""

import numpy as np
import pytest
from pydrake.geometry import Box, Cylinder, SceneGraph
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
from pydrake.multibody.parsing import LoadModelDirectives, ProcessModelDirectives
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, MultibodyPlant
from pydrake.multibody.tree import BodyIndex, RevoluteJoint
from pydrake.systems.framework import DiagramBuilder

from aerial_drake.dynamics.decoupling import DecoupledDynamics
from aerial_drake.robots.models import make_parser
from aerial_drake.robots.resources import model_directory

ROBOT2_DIRECTIVES = "quadrotor_arm_mount.dmd.yaml"
ROBOT2_SDFS = ("quadrotor.sdf", "ur3e.sdf")
VEHICLE = "quadrotor"
ARM_JOINTS = [f"ur3e_joint_{i}" for i in range(1, 7)]

# Sources (file headers): Alta X MTOW 34.86 kg minus its 15.9 kg maximum payload; UR3e 11.2 kg.
VEHICLE_MASS = 34.86 - 15.9
VEHICLE_INERTIA = np.diag([1.3500, 1.3031, 2.2479])
ARM_MASS = 11.2
UR3E_LINK_MASSES = [1.98, 3.4445, 1.437, 0.871, 0.805, 0.261]
UR3E_EFFORT = [56.0, 56.0, 28.0, 12.0, 12.0, 12.0]
UR3E_SPEED = np.deg2rad([180, 180, 180, 360, 360, 360])
UR3E_RANGE = np.deg2rad([360, 360, 180, 360, 360, 360])
UR3E_A = [0, -0.24355, -0.2132, 0, 0, 0]
UR3E_D = [0.15185, 0, 0, 0.13105, 0.08535, 0.0921]
UR3E_ALPHA = np.array([1, 0, 0, 1, -1, 0]) * np.pi / 2
GRAVITY = 9.81
THRUST_LIMIT = 1.5 * 34.86 * GRAVITY  # N: 1.5 x the MTOW weight (quadrotor.sdf)
EE_FROM_COM = np.array([0.2, 0.0, -0.4])  # nominal, from the system CoM, quadrotor frame
# Documented conditioning of J_3 (docs/models.md): 0.117 nominal, 0.092 worst over the moves;
# the asserted margins leave about 10 %.
SIGMA_MIN_NOMINAL_MARGIN = 0.105
SIGMA_MIN_MOVES_MARGIN = 0.083
COND_NOMINAL_MAX = 17.0
COND_MOVES_MAX = 22.0
# The vehicle's lowest shape (the skids: 0.40 m below the rotor plane, radius 0.015 m, the
# rotor plane 0.0267 m below the CoM); the end effector must hang below it.
SKID_BOTTOM_Z = -0.40 - 0.015 - 0.026714135
# Bodies allowed to be massless: the LWR's base, welded to the helicopter (docs/models.md).
MASSLESS_ALLOWED = {"lwr_link_0"}


def robot2_plant() -> MultibodyPlant:
    plant = MultibodyPlant(0.0)
    parser = make_parser(plant)
    directives = LoadModelDirectives(str(model_directory() / ROBOT2_DIRECTIVES))
    ProcessModelDirectives(directives, plant, parser)
    plant.Finalize()
    return plant


@pytest.fixture(scope="module")
def plant():
    return robot2_plant()


def shipped_sdfs():
    return sorted(p.name for p in model_directory().glob("*.sdf"))


def test_robot2_files_are_shipped():
    names = shipped_sdfs()
    for name in ROBOT2_SDFS:
        assert name in names
    assert (model_directory() / ROBOT2_DIRECTIVES).is_file()


@pytest.mark.parametrize("sdf", shipped_sdfs())
def test_every_body_of_every_shipped_sdf_is_physically_valid(sdf):
    plant = MultibodyPlant(0.0)
    make_parser(plant).AddModels(str(model_directory() / sdf))
    plant.Finalize()
    checked = 0
    for index in range(1, plant.num_bodies()):  # 0 is World
        body = plant.get_body(BodyIndex(index))
        m = body.default_mass()
        M = body.default_spatial_inertia()
        if body.name() in MASSLESS_ALLOWED:
            assert m == 0.0
            continue
        assert m > 0.0, f"{sdf}: {body.name()} has mass {m}"
        # Rotational inertia about the body's own centre of mass.
        I_cm = M.Shift(M.get_com()).CalcRotationalInertia().CopyToFullMatrix3()
        np.testing.assert_allclose(I_cm, I_cm.T, atol=1e-15)
        ev = np.linalg.eigvalsh(I_cm)
        assert ev[0] > 0.0, f"{sdf}: {body.name()} inertia not positive definite: {ev}"
        assert ev[0] + ev[1] >= ev[2] * (1 + 1e-12), f"{sdf}: {body.name()} triangle: {ev}"
        checked += 1
    assert checked >= 1


def _inside(shape, X_BG: RigidTransform, p_B: np.ndarray) -> bool:
    p = X_BG.inverse().multiply(p_B)
    if isinstance(shape, Cylinder):
        return (np.hypot(p[0], p[1]) <= shape.radius() + 1e-12
                and abs(p[2]) <= shape.length() / 2 + 1e-12)
    if isinstance(shape, Box):
        return bool(np.all(np.abs(p) <= np.array([shape.width(), shape.depth(),
                                                  shape.height()]) / 2 + 1e-12))
    return False


@pytest.mark.parametrize("sdf", ROBOT2_SDFS)
def test_every_centre_of_mass_is_inside_its_links_shapes(sdf):
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, 0.0)
    make_parser(plant).AddModels(str(model_directory() / sdf))
    plant.Finalize()
    inspector = scene_graph.model_inspector()
    bodies = [plant.get_body(i) for i in plant.GetBodyIndices(plant.GetModelInstanceByName(
        sdf.removesuffix(".sdf")))]
    assert bodies
    for body in bodies:
        com = body.default_com()
        geometries = plant.GetVisualGeometriesForBody(body)
        assert geometries, body.name()
        assert any(_inside(inspector.GetShape(g), inspector.GetPoseInFrame(g), com)
                   for g in geometries), f"{sdf}: {body.name()}'s CoM {com} is outside its shapes"


def test_masses_inertia_and_thrust_to_weight(plant):
    context = plant.CreateDefaultContext()
    vehicle = plant.GetModelInstanceByName(VEHICLE)
    arm = plant.GetModelInstanceByName("ur3e")
    assert plant.CalcTotalMass(context, [vehicle]) == pytest.approx(VEHICLE_MASS, abs=1e-12)
    assert plant.CalcTotalMass(context, [arm]) == pytest.approx(ARM_MASS, abs=1e-12)
    links = [plant.GetBodyByName(f"ur3e_link_{i}").default_mass() for i in range(1, 7)]
    np.testing.assert_allclose(links, UR3E_LINK_MASSES, atol=0)
    total = plant.CalcTotalMass(context)
    assert total == pytest.approx(30.16, abs=1e-12)
    # The vehicle's body frame is at its CoM, with the fitted inertia about it.
    body = plant.GetBodyByName(VEHICLE)
    M = body.default_spatial_inertia()
    np.testing.assert_allclose(M.get_com(), np.zeros(3), atol=0)
    np.testing.assert_allclose(M.CalcRotationalInertia().CopyToFullMatrix3(), VEHICLE_INERTIA,
                               atol=0)
    gravity = -plant.gravity_field().gravity_vector()[2]
    assert gravity == pytest.approx(GRAVITY)
    thrust_to_weight = THRUST_LIMIT / (total * gravity)
    assert thrust_to_weight >= 1.5
    assert thrust_to_weight == pytest.approx(1.734, abs=1e-3)


def test_floating_vehicle_and_arm_joints(plant):
    body = plant.GetBodyByName(VEHICLE)
    assert plant.GetFloatingBaseBodies() == {body.index()}
    assert plant.num_velocities() == 6 + 6
    joints = [plant.GetJointByName(n) for n in ARM_JOINTS]
    assert all(isinstance(j, RevoluteJoint) for j in joints)
    assert [plant.get_joint_actuator(a).joint().name()
            for a in plant.GetJointActuatorIndices()] == ARM_JOINTS
    np.testing.assert_allclose([plant.get_joint_actuator(a).effort_limit()
                                for a in plant.GetJointActuatorIndices()], UR3E_EFFORT)
    np.testing.assert_allclose([j.velocity_upper_limits()[0] for j in joints], UR3E_SPEED)
    np.testing.assert_allclose([j.position_upper_limits()[0] for j in joints], UR3E_RANGE)
    np.testing.assert_allclose([j.position_lower_limits()[0] for j in joints], -UR3E_RANGE)
    # A chain: each joint's child is the next joint's parent, the first hangs off the base.
    assert joints[0].parent_body().name() == "ur3e_link_0"
    for a, b in zip(joints, joints[1:]):
        assert a.child_body().index() == b.parent_body().index()
    assert plant.GetFrameByName("end_effector").body().name() == "ur3e_link_6"


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_arm_kinematics_is_standard_dh(seed):
    plant = MultibodyPlant(0.0)
    make_parser(plant).AddModels(str(model_directory() / "ur3e.sdf"))
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("ur3e_link_0"))
    plant.Finalize()
    context = plant.CreateDefaultContext()
    q = np.random.default_rng(seed).uniform(-np.pi, np.pi, 6)
    plant.SetPositions(context, q)
    X = RigidTransform()
    for qi, a, d, alpha in zip(q, UR3E_A, UR3E_D, UR3E_ALPHA):
        X = X.multiply(RigidTransform(RotationMatrix.MakeZRotation(qi), [0, 0, d]))
        X = X.multiply(RigidTransform(RotationMatrix.MakeXRotation(alpha), [a, 0, 0]))
    X_W6 = plant.GetFrameByName("ur3e_link_6").CalcPoseInWorld(context)
    np.testing.assert_allclose(X_W6.GetAsMatrix4(), X.GetAsMatrix4(), atol=1e-12)


def _ee_relative(plant, context):
    """End-effector position from the system CoM and its orientation, in the vehicle frame."""
    X_WB = plant.GetBodyByName(VEHICLE).EvalPoseInWorld(context)
    X_WE = plant.GetFrameByName("end_effector").CalcPoseInWorld(context)
    p_G = plant.CalcCenterOfMassPositionInWorld(context)
    R_BW = X_WB.rotation().inverse()
    return R_BW.multiply(X_WE.translation() - p_G), R_BW.multiply(X_WE.rotation())


def _sigma_cond(plant, dynamics, context):
    d = dynamics.compute(context)
    J_y, _ = dynamics.frame_jacobian(d, plant.GetFrameByName("end_effector"))
    J3 = (J_y @ d.T_inv)[:, 6:]
    s = np.linalg.svd(J3, compute_uv=False)
    return s[-1], s[0] / s[-1]


def test_nominal_posture(plant):
    context = plant.CreateDefaultContext()  # the directives' default joint positions
    p, R = _ee_relative(plant, context)
    np.testing.assert_allclose(p, EE_FROM_COM, atol=1e-8)
    np.testing.assert_allclose(R.matrix(), np.eye(3), atol=1e-8)
    sigma_min, cond = _sigma_cond(plant, DecoupledDynamics(plant), context)
    assert sigma_min > SIGMA_MIN_NOMINAL_MARGIN
    assert cond < COND_NOMINAL_MAX
    # The whole arm and the end effector hang below the vehicle, between its skids.
    X_WB = plant.GetBodyByName(VEHICLE).EvalPoseInWorld(context)
    for i in range(1, 7):
        p_B = X_WB.inverse().multiply(
            plant.GetFrameByName(f"ur3e_link_{i}").CalcPoseInWorld(context).translation())
        assert p_B[2] < -0.2 and abs(p_B[1]) < 0.3 - 0.05, (i, p_B)
    p_BE = X_WB.inverse().multiply(
        plant.GetFrameByName("end_effector").CalcPoseInWorld(context).translation())
    assert p_BE[2] < SKID_BOTTOM_Z
    assert np.hypot(p_BE[0], p_BE[1]) < 0.65  # inside the rotors' circle, under the vehicle
    # The system's CoM is near the thrust axis (hover trim torque 3.2 N m, docs/models.md).
    p_BG = X_WB.inverse().multiply(plant.CalcCenterOfMassPositionInWorld(context))
    assert np.hypot(p_BG[0], p_BG[1]) < 0.015


def _solve_pose(plant, context, q0, p_t, R_t):
    """Damped Gauss-Newton on the arm's positions for an end-effector pose relative to the
    system CoM in the vehicle frame (the vehicle held at the identity)."""
    arm = slice(7, 13)

    def residual(q):
        x = plant.GetPositions(context).copy()
        x[arm] = q
        plant.SetPositions(context, x)
        p, R = _ee_relative(plant, context)
        E = R_t.T @ R.matrix()
        return np.concatenate([p - p_t, 0.5 * np.array([E[2, 1] - E[1, 2], E[0, 2] - E[2, 0],
                                                        E[1, 0] - E[0, 1]])])

    q, f, lam = np.array(q0, float), residual(q0), 1e-4
    for _ in range(100):
        if np.linalg.norm(f) < 1e-11:
            break
        J = np.column_stack([(residual(q + 1e-7 * e) - f) / 1e-7 for e in np.eye(6)])
        step = np.linalg.solve(J.T @ J + lam * np.eye(6), -J.T @ f)
        step *= min(1.0, 0.2 / max(np.linalg.norm(step), 1e-300))
        f_new = residual(q + step)
        if np.linalg.norm(f_new) < np.linalg.norm(f):
            q, f, lam = q + step, f_new, max(lam / 3, 1e-9)
        else:
            lam *= 10
    residual(q)
    return q, np.linalg.norm(f)


def test_conditioning_over_moves_of_the_end_effector(plant):
    """J_3 stays well conditioned with the end effector 0.1 m away along each axis or tilted
    0.3 rad about each axis (relative to the system CoM, vehicle level)."""
    context = plant.CreateDefaultContext()
    dynamics = DecoupledDynamics(plant)
    q_nominal = plant.GetPositions(context)[7:].copy()
    moves = [(s * 0.1 * e, np.eye(3)) for e in np.eye(3) for s in (1, -1)]
    moves += [(np.zeros(3), mk(s * 0.3).matrix()) for mk in (
        RotationMatrix.MakeXRotation, RotationMatrix.MakeYRotation,
        RotationMatrix.MakeZRotation) for s in (1, -1)]
    worst_sigma, worst_cond = np.inf, 0.0
    for dp, R_t in moves:
        q, err = _solve_pose(plant, context, q_nominal, EE_FROM_COM + dp, R_t)
        assert err < 1e-9
        assert np.max(np.abs(q - q_nominal)) < 1.0  # the same branch, a nearby posture
        sigma_min, cond = _sigma_cond(plant, dynamics, context)
        worst_sigma, worst_cond = min(worst_sigma, sigma_min), max(worst_cond, cond)
    assert worst_sigma > SIGMA_MIN_MOVES_MARGIN
    assert worst_cond < COND_MOVES_MAX


def test_mount_pose(plant):
    context = plant.CreateDefaultContext()
    X_WB = plant.GetBodyByName(VEHICLE).EvalPoseInWorld(context)
    X_W0 = plant.GetBodyByName("ur3e_link_0").EvalPoseInWorld(context)
    X_B0 = X_WB.inverse().multiply(X_W0)
    np.testing.assert_allclose(X_B0.translation(), [-0.05, 0.0, -0.13], atol=1e-12)
    expected = RollPitchYaw(np.deg2rad([180.0, 30.0, 0.0])).ToRotationMatrix()
    np.testing.assert_allclose(X_B0.rotation().matrix(), expected.matrix(), atol=1e-12)
    z0 = X_B0.rotation().matrix()[:, 2]
    np.testing.assert_allclose(z0, [-0.5, 0.0, -np.sqrt(3) / 2], atol=1e-12)


def test_scene_graph_loads_robot2():
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, 0.0)
    assert isinstance(scene_graph, SceneGraph)
    ProcessModelDirectives(LoadModelDirectives(str(model_directory() / ROBOT2_DIRECTIVES)),
                           plant, make_parser(plant))
    plant.Finalize()
    assert plant.GetVisualGeometriesForBody(plant.GetBodyByName(VEHICLE))
