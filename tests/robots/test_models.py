"""Tests of the aerial manipulator's models (aerial_drake.robots.models and models/sdf/)."""

import importlib.util
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.parsing import LoadModelDirectives
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import JacobianWrtVariable
from pydrake.systems.framework import DiagramBuilder

import aerial_drake
from aerial_drake.robots import models as dut
from aerial_drake.robots.description import default_robot
from aerial_drake.robots.resources import model_directory

CHECKOUT = Path(__file__).resolve().parents[2]
TABLE_I_HELICOPTER_MASS = 37.6  # kg
TABLE_I_HELICOPTER_INERTIA = np.diag([1.46, 0.36, 1.46])  # kg m^2
TABLE_I_ARM_MASS = 17.2  # kg
TABLE_I_ARM_EFFORT = np.array([165, 165, 70, 70, 70, 30, 30])  # N m
ARM_LIMITS = np.deg2rad([170, 120, 170, 120, 170, 120, 170])
DH_D = np.array([0.3105, 0, 0.4, 0, 0.39, 0, 0.078])
DH_ALPHA = np.array([1, -1, -1, 1, 1, -1, 0]) * np.pi / 2
EE_OFFSET_NOMINAL = np.array([0.3, 0.0, -0.6])  # from the system CoM, helicopter frame
#: The plant variants of the paper's robot description.
PLANT_VARIANTS = default_robot().variant_names()
ARM_MOUNT_FILE = "arm_mount.dmd.yaml"
ARM_MODEL_NAME = "lwr"


def arm_instance(manip):
    """The LWR's model instance (added by arm_mount.dmd.yaml)."""
    return manip.plant.GetModelInstanceByName(ARM_MODEL_NAME)


def dmd_nominal_arm_posture():
    """q_nominal [rad] as arm_mount.dmd.yaml writes it (the arm's default joint positions)."""
    directives = LoadModelDirectives(str(model_directory() / ARM_MOUNT_FILE))
    for directive in directives.directives:
        model = directive.add_model
        if model is not None and model.name == ARM_MODEL_NAME:
            positions = model.default_joint_positions
            return np.array([positions[f"lwr_joint_{i}"][0] for i in range(1, 8)])
    raise AssertionError(f"{ARM_MOUNT_FILE} adds no model named '{ARM_MODEL_NAME}'.")


def test_plant_variants_of_the_paper_robot():
    assert PLANT_VARIANTS == ("rigid", "rotors")


@pytest.fixture(scope="module", params=PLANT_VARIANTS)
def manip(request):
    return dut.make_plant(request.param)


def helicopter_spatial_inertia(manip, context):
    """Composite spatial inertia of the helicopter's bodies about Bo, expressed in B."""
    plant = manip.plant
    return plant.CalcSpatialInertia(
        context, manip.base_body.body_frame(), plant.GetBodyIndices(manip.vehicle)
    )


def dh_transform(q):
    """Standard DH product T_07(q) = prod Rz(q_i) Tz(d_i) Rx(alpha_i)."""
    X = RigidTransform()
    for qi, d, alpha in zip(q, DH_D, DH_ALPHA):
        X = X.multiply(RigidTransform(RotationMatrix.MakeZRotation(qi), [0, 0, d]))
        X = X.multiply(RigidTransform(RotationMatrix.MakeXRotation(alpha), [0, 0, 0]))
    return X


def test_total_and_arm_mass(manip):
    plant = manip.plant
    context = plant.CreateDefaultContext()
    assert plant.CalcTotalMass(context) == pytest.approx(54.8, abs=1e-12)
    assert manip.total_mass() == pytest.approx(54.8, abs=1e-12)
    moving = [j.child_body().index() for j in manip.arm_joints]
    assert plant.CalcTotalMass(context, [arm_instance(manip)]) == pytest.approx(
        TABLE_I_ARM_MASS, abs=1e-12
    )
    assert sum(plant.get_body(i).default_mass() for i in moving) == pytest.approx(
        TABLE_I_ARM_MASS, abs=1e-12
    )
    assert plant.GetBodyByName("lwr_link_0").default_mass() == 0.0


def test_helicopter_composite_matches_table_i(manip):
    plant = manip.plant
    context = plant.CreateDefaultContext()
    rng = np.random.default_rng(7)
    angles = [np.zeros(2)] + [rng.uniform(-np.pi, np.pi, 2) for _ in range(3)]
    for rotor_angles in angles if manip.rotor_joints else angles[:1]:
        for joint, angle in zip(manip.rotor_joints, rotor_angles):
            joint.set_angle(context, angle)
        M = helicopter_spatial_inertia(manip, context)
        assert M.get_mass() == pytest.approx(TABLE_I_HELICOPTER_MASS, abs=1e-12)
        np.testing.assert_allclose(M.get_com(), np.zeros(3), atol=1e-12)
        I_BBo = M.CalcRotationalInertia().CopyToFullMatrix3()
        np.testing.assert_allclose(I_BBo, TABLE_I_HELICOPTER_INERTIA, atol=1e-12)


def test_every_body_is_physically_valid(manip):
    plant = manip.plant
    for model in (manip.vehicle, arm_instance(manip)):
        for index in plant.GetBodyIndices(model):
            body = plant.get_body(index)
            assert body.default_spatial_inertia().IsPhysicallyValid(), body.name()


def test_arm_joints_and_actuators(manip):
    assert [j.name() for j in manip.arm_joints] == [f"lwr_joint_{i}" for i in range(1, 8)]
    assert [a.joint().name() for a in manip.arm_actuators] == [j.name() for j in manip.arm_joints]
    np.testing.assert_array_equal(manip.arm_effort_limits(), TABLE_I_ARM_EFFORT)
    lower, upper = manip.arm_position_limits()
    np.testing.assert_allclose(upper, ARM_LIMITS, rtol=1e-15)
    np.testing.assert_allclose(lower, -ARM_LIMITS, rtol=1e-15)
    speeds = manip.arm_velocity_limits()
    assert np.all(speeds > 0) and np.all(np.isfinite(speeds))


def test_rotors():
    manip = dut.make_plant("rotors")
    assert [j.name() for j in manip.rotor_joints] == ["rotor_left_joint", "rotor_right_joint"]
    assert [a.effort_limit() for a in manip.rotor_actuators] == [100.0, 100.0]
    for joint in manip.rotor_joints:
        rotor = joint.child_body()
        assert rotor.default_mass() == 1.3
        # Axisymmetric about the spin axis, centre of mass on it: the composite is constant.
        M = rotor.default_spatial_inertia()
        np.testing.assert_allclose(M.get_com(), np.zeros(3), atol=1e-15)
        I = M.CalcRotationalInertia().CopyToFullMatrix3()
        np.testing.assert_allclose(I, np.diag([0.061, 0.061, 0.12]), atol=1e-15)
        np.testing.assert_allclose(joint.revolute_axis(), [0, 0, 1])
    # Their angular momentum when spinning: tests/simulation/test_rotors.py.


@pytest.mark.parametrize("variant", PLANT_VARIANTS)
@pytest.mark.parametrize("floating_base", dut.FLOATING_BASES)
def test_coordinate_order(variant, floating_base):
    manip = dut.make_plant(variant, floating_base=floating_base)
    plant = manip.plant
    nq_base = 7 if floating_base == "quaternion" else 6
    n_rotor = len(manip.rotor_joints)
    np.testing.assert_array_equal(manip.base_velocity_indices, np.arange(6))
    np.testing.assert_array_equal(manip.base_position_indices, np.arange(nq_base))
    np.testing.assert_array_equal(manip.rotor_velocity_indices, 6 + np.arange(n_rotor))
    np.testing.assert_array_equal(manip.arm_velocity_indices, 6 + n_rotor + np.arange(7))
    np.testing.assert_array_equal(manip.arm_position_indices, nq_base + n_rotor + np.arange(7))
    assert plant.num_positions() == nq_base + n_rotor + 7
    assert plant.num_velocities() == 6 + n_rotor + 7
    # v = [w_WB (World), v_WBo (World), ...], checked at a rotated base.
    context = plant.CreateDefaultContext()
    dut.set_nominal_posture(manip, context, p_WB=(1.0, -2.0, 3.0), yaw=0.8)
    v = np.zeros(plant.num_velocities())
    v[:6] = [0.1, -0.2, 0.3, 1.0, 2.0, -3.0]
    plant.SetVelocities(context, v)
    V_WB = manip.base_body.EvalSpatialVelocityInWorld(context)
    np.testing.assert_allclose(V_WB.rotational(), v[:3], atol=1e-14)
    np.testing.assert_allclose(V_WB.translational(), v[3:6], atol=1e-14)
    np.testing.assert_allclose(plant.gravity_field().gravity_vector(), [0, 0, -9.81])


def test_rigid_state_indices_map_rotors_state_to_rigid_state():
    rigid, rotors = dut.make_plant("rigid"), dut.make_plant("rotors")
    contexts = [m.plant.CreateDefaultContext() for m in (rigid, rotors)]
    rng = np.random.default_rng(3)
    q_arm, v_arm, v_base = rng.normal(size=7), rng.normal(size=7), rng.normal(size=6)
    for manip, context in zip((rigid, rotors), contexts):
        dut.set_nominal_posture(manip, context, p_WB=(0.5, 0.1, 2.0), yaw=-0.4)
        q = manip.plant.GetPositions(context)
        q[manip.arm_position_indices] = q_arm
        q[manip.rotor_position_indices] = [0.3, -1.2][: len(manip.rotor_joints)]
        v = rng.normal(size=manip.plant.num_velocities())
        v[manip.base_velocity_indices] = v_base
        v[manip.arm_velocity_indices] = v_arm
        manip.plant.SetPositionsAndVelocities(context, np.concatenate([q, v]))
    x_rigid = rigid.plant.GetPositionsAndVelocities(contexts[0])
    x_rotors = rotors.plant.GetPositionsAndVelocities(contexts[1])
    np.testing.assert_array_equal(rigid.rigid_state_indices, np.arange(27))
    np.testing.assert_allclose(x_rotors[rotors.rigid_state_indices], x_rigid, atol=1e-15)


def test_model_files_need_no_network():
    folder = model_directory()
    files = [p for p in folder.iterdir() if p.is_file()]
    assert {p.name for p in files} >= {
        "package.xml", "helicopter.sdf", "helicopter_rotors.sdf", "lwr.sdf", "arm_mount.dmd.yaml"
    }
    for path in files:
        text = path.read_text()
        assert "drake_models" not in text, path
        # XML namespace names are identifiers, not downloads.
        names = (text.replace("http://www.ros.org", "")
                 .replace('xmlns:drake="http://drake.mit.edu"', ""))
        assert "http" not in names, path
        for url in text.split("package://")[1:]:
            assert url.startswith("aerial_drake/"), path
    plant = MultibodyPlant(0.0)
    parser = dut.make_parser(plant)
    assert parser.package_map().GetPackageNames() == ["aerial_drake"]
    for variant in PLANT_VARIANTS:
        assert dut.make_plant(variant).plant.is_finalized()


def test_model_directory_in_checkout():
    if Path(aerial_drake.__file__).resolve().parents[1] != CHECKOUT:
        pytest.skip("aerial_drake is not imported from this checkout")
    assert model_directory() == CHECKOUT / "models" / "sdf"


def _can_build_without_network():
    """pip can build our wheel offline: setuptools >= 70.1, or >= 64 with the wheel package."""
    try:
        from importlib.metadata import version

        major, minor = (int(part) for part in version("setuptools").split(".")[:2])
    except Exception:
        return False
    return (major, minor) >= (70, 1) or (
        major >= 64 and importlib.util.find_spec("wheel") is not None
    )


def _check_models_load_from(site, tmp_path):
    """A fresh interpreter that sees only ``site`` finds the models there and builds both
    variants from them."""
    installed = site / "aerial_drake" / "sdf"
    source = CHECKOUT / "models" / "sdf"
    for path in source.rglob("*"):  # the environment models in their subfolder too
        if path.is_file() and "__pycache__" not in path.parts:
            name = path.relative_to(source)
            assert (installed / name).read_bytes() == path.read_bytes(), name
    script = (
        "from aerial_drake.robots.resources import model_directory\n"
        "from aerial_drake.robots.models import make_plant\n"
        "from aerial_drake.simulation.scenarios import shipped_scenarios\n"
        "print(model_directory())\n"
        "print(make_plant('rigid').total_mass(), make_plant('rotors').total_mass())\n"
        "print(','.join(shipped_scenarios()))\n"
        "from aerial_drake.robots.description import shipped_robots\n"
        "print(','.join(shipped_robots()))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", script], check=True, capture_output=True, text=True,
        cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(site)},
    ).stdout.split()
    assert Path(out[0]).resolve() == installed.resolve()
    assert [float(m) for m in out[1:3]] == pytest.approx([54.8, 54.8])
    # The scenario YAML files ship beside their module (package-data).
    assert out[3].split(",") == ["disturbed", "disturbed_within_limits", "nominal", "orbit",
                                 "pick_and_place", "quadrotor_ur3e",
                                 "quadrotor_ur3e_surface_slide", "quadrotor_ur3e_wall_press",
                                 "surface_slide", "wall_press"]
    # The robot descriptions ship with the model files.
    assert out[4].split(",") == ["helicopter_lwr", "quadrotor_ur3e"]


def test_model_directory_in_installed_layout(tmp_path):
    # The layout pyproject.toml installs: models/sdf/ becomes the package aerial_drake.sdf.
    site = tmp_path / "site"
    ignore = shutil.ignore_patterns("__pycache__")
    shutil.copytree(CHECKOUT / "aerial_drake", site / "aerial_drake", ignore=ignore)
    shutil.copytree(CHECKOUT / "models" / "sdf", site / "aerial_drake" / "sdf", ignore=ignore)
    _check_models_load_from(site, tmp_path)


@pytest.mark.skipif(not _can_build_without_network(), reason="no offline build backend")
def test_model_directory_in_pip_installed_package(tmp_path):
    # Build from a copy so the shared checkout gets no build/ or *.egg-info.
    source = tmp_path / "src"
    ignore = shutil.ignore_patterns("__pycache__", "*.egg-info", "build", "dist")
    for name in ("aerial_drake", "models"):
        shutil.copytree(CHECKOUT / name, source / name, ignore=ignore)
    shutil.copy(CHECKOUT / "pyproject.toml", source)
    site = tmp_path / "site"
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check", "--no-input"]
    subprocess.run(
        pip + ["install", "--quiet", "--no-deps", "--no-build-isolation", "--no-index",
               "--target", str(site), str(source)],
        check=True, capture_output=True, cwd=tmp_path,
    )
    _check_models_load_from(site, tmp_path)


@pytest.mark.parametrize("seed", range(3))
def test_arm_kinematics_is_standard_dh(seed):
    manip = dut.make_plant("rigid")
    plant = manip.plant
    context = plant.CreateDefaultContext()
    q = np.random.default_rng(seed).uniform(-ARM_LIMITS, ARM_LIMITS)
    for joint, angle in zip(manip.arm_joints, q):
        joint.set_angle(context, angle)
    base = plant.GetFrameByName("lwr_link_0")
    X_07 = plant.CalcRelativeTransform(context, base, manip.end_effector_body.body_frame())
    X_dh = dh_transform(q)
    np.testing.assert_allclose(X_07.translation(), X_dh.translation(), atol=1e-12)
    np.testing.assert_allclose(X_07.rotation().matrix(), X_dh.rotation().matrix(), atol=1e-12)
    p_0E = plant.CalcRelativeTransform(context, base, manip.end_effector_frame).translation()
    np.testing.assert_allclose(p_0E, X_dh.translation(), atol=1e-12)


@pytest.mark.parametrize("variant", PLANT_VARIANTS)
def test_nominal_posture(variant, record_property):
    manip = dut.make_plant(variant)
    plant = manip.plant
    context = plant.CreateDefaultContext()
    # The description gives no posture, so q_nominal is arm_mount.dmd.yaml's.
    assert manip.description.nominal_posture == []
    np.testing.assert_array_equal(manip.q_nominal_arm(), dmd_nominal_arm_posture())
    # Any base pose: the offset is expressed in the helicopter frame.
    dut.set_nominal_posture(manip, context, p_WB=(0.4, -1.0, 2.5), yaw=0.7)
    q = plant.GetPositions(context)[manip.arm_position_indices]
    np.testing.assert_array_equal(q, manip.q_nominal_arm())
    assert q[2] == 0.0
    # Inside the limits with margin; the elbow is folded to 83 % of its range on purpose, to
    # leave room for stretching under disturbances (docs/models.md, "How it was chosen").
    assert np.all(np.abs(q) <= 0.85 * ARM_LIMITS)

    B = manip.base_body.body_frame()
    X_WB = B.CalcPoseInWorld(context)
    p_WScm = plant.CalcCenterOfMassPositionInWorld(context)
    X_BE = plant.CalcRelativeTransform(context, B, manip.end_effector_frame)
    p_ScmE_B = X_BE.translation() - X_WB.inverse().multiply(p_WScm)
    np.testing.assert_allclose(p_ScmE_B, EE_OFFSET_NOMINAL, atol=1e-6)
    angle = X_BE.rotation().ToAngleAxis().angle()
    assert angle < np.deg2rad(1e-4)
    # The joint-7 axis is vertical (pointing down) with the end effector on it, so the
    # heading's relative yaw is joint 7 alone (docs/models.md, "Why the flange points down").
    X_B7 = plant.CalcRelativeTransform(context, B, manip.end_effector_body.body_frame())
    np.testing.assert_allclose(X_B7.rotation().matrix()[:, 2], [0, 0, -1], atol=1e-8)
    np.testing.assert_allclose(X_B7.translation(), X_BE.translation(), atol=1e-12)

    J_BE_B = plant.CalcJacobianSpatialVelocity(
        context, JacobianWrtVariable.kV, manip.end_effector_frame, np.zeros(3), B, B
    )[:, manip.arm_velocity_indices]
    sigma_6 = np.linalg.svd(J_BE_B, compute_uv=False)
    sigma_7 = np.linalg.svd(np.vstack([J_BE_B, np.eye(7)[2]]), compute_uv=False)
    record_property("sigma_min_6x7", float(sigma_6[-1]))
    record_property("sigma_min_7x7", float(sigma_7[-1]))
    record_property("cond_7x7", float(sigma_7[0] / sigma_7[-1]))
    assert sigma_6[-1] > 0.2 and sigma_7[-1] > 0.2
    assert sigma_7[0] / sigma_7[-1] < 10


def test_builder_has_geometry_and_names():
    builder = DiagramBuilder()
    manip = dut.add_to_builder(builder, "rotors", time_step=1e-3)
    diagram = builder.Build()
    assert manip.scene_graph is not None and manip.plant.is_finalized()
    assert manip.plant.time_step() == 1e-3
    inspector = manip.scene_graph.model_inspector()
    assert inspector.num_geometries() > 20
    context = diagram.CreateDefaultContext()
    dut.set_nominal_posture(manip, context, yaw=0.2)
    q = manip.plant.GetPositions(manip.plant.GetMyContextFromRoot(context))
    np.testing.assert_array_equal(q[manip.arm_position_indices], manip.q_nominal_arm())


def test_add_without_finalize_then_rpy_base():
    plant = MultibodyPlant(0.0)
    manip = dut.add_aerial_manipulator(plant, "rigid", floating_base="rpy", finalize=False)
    assert not plant.is_finalized()
    plant.Finalize()
    assert manip.base_joint.name() == "base"
    assert manip.base_joint.type_name() == "rpy_floating"


@pytest.mark.parametrize(
    "call",
    [
        lambda: dut.make_plant("quadrotor"),
        lambda: dut.add_to_builder(DiagramBuilder(), "quadrotor"),
        lambda: dut.add_aerial_manipulator(MultibodyPlant(0.0), "quadrotor"),
    ],
)
def test_bad_variant_names_the_options(call):
    with pytest.raises(ValueError, match="quadrotor.*rigid, rotors"):
        call()


def test_bad_floating_base_names_the_options():
    with pytest.raises(ValueError, match="euler.*quaternion, rpy"):
        dut.make_plant("rigid", floating_base="euler")
