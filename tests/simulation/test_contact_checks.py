"""The checks of a force task before the run (aerial_drake.simulation.contact_checks,
contact_geometry, contact_loads): each refusal comes from a concrete bad scenario, names its
field and the numbers, and the numbers are those of an independent computation; the good
scenario (a wall press) passes on the continuous and on the discrete plant."""

import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from pydrake.multibody.tree import JacobianWrtVariable

import aerial_drake.simulation.contact_checks as dut
from aerial_drake.cli import main as cli_main
from aerial_drake.control.reference_pose import mass_and_gravity
from aerial_drake.simulation.contact_geometry import Surfaces
from aerial_drake.simulation.contact_loads import check_force, largest_thrust_force
from aerial_drake.simulation.diagram import build_simulation
from aerial_drake.simulation.scenarios import ScenarioError, load_scenario

MODELS = Path(__file__).resolve().parents[2] / "models" / "sdf"

#: A wall press (the contact prototype): the helicopter + LWR brings the tool to 5 cm before
#: a wall's face at x = 1.0 m (the tool sphere's radius is 4 cm) and presses 10 N along +x.
WALL_PRESS = """\
name: wall_press_check
robot: helicopter_lwr
duration: 6.0
controller_period: 0.001
log_period: 0.001
simulator: {integration_scheme: runge_kutta3, max_step_size: 0.001, accuracy: 1.0e-6,
            use_error_control: false, target_realtime_rate: 0.0}
gains:
  K_x: [800.0, 800.0, 800.0]
  D_x: [420.0, 420.0, 420.0]
  k_R: 250.0
  k_w: 200.0
  Lambda2_bar: [1.46, 0.36, 1.46]
  K_y: [30.0, 30.0, 30.0, 10.0, 10.0, 10.0, 7.0]
  K_z: [300.0, 300.0, 300.0, 30.0, 30.0, 30.0, 30.0]
trajectory:
  kind: waypoints
  com_offset: [-0.3, 0.0, 0.6]
  joint_targets: [0.0]
  waypoints:
    com: offset
    heading: given
    points:
      - {time: 0.0, ee_position: [0.6, 0.0, 1.3], ee_rpy: [0.0, 0.0, 0.0], heading: 0.0}
      - {time: 2.5, ee_position: [EE_X, 0.0, 1.3], ee_rpy: [0.0, 0.0, 0.0], heading: 0.0}
plant: {time_step: 0.0, stiction_tolerance: 0.01}
environment:
  directives:
  - add_model: {name: wall, file: WALL_FILE}
  - add_weld:
      parent: world
      child: wall::wall
      X_PC: {translation: [1.05, 0.0, 1.5]}
actuation: {lag_rise_time: 0.0, saturate: true}
controller:
  type: paper_force
  force: {direction: [1.0, 0.0, 0.0], force: 10.0, start: 2.5, stop: 5.5, ramp: 0.5}
"""


def write_scenario(folder: Path, *, ee_x: float = 0.95,
                   wall: str = "package://aerial_drake/environments/wall.sdf",
                   robot: str = "helicopter_lwr") -> Path:
    path = folder / "wall_press.yaml"
    text = WALL_PRESS.replace("EE_X", repr(ee_x)).replace("WALL_FILE", wall)
    path.write_text(text.replace("robot: helicopter_lwr", f"robot: {robot}"))
    return path


@pytest.fixture(scope="module")
def good(tmp_path_factory):
    """The good scenario and its closed loop."""
    scenario = load_scenario(write_scenario(tmp_path_factory.mktemp("good")))
    _, loop, _ = build_simulation(scenario)
    return scenario, loop


def refusal(scenario, loop=None) -> ScenarioError:
    if loop is None:
        _, loop, _ = build_simulation(scenario)
    with pytest.raises(ScenarioError) as err:
        dut.check_contact(scenario, loop)
    return err.value


def test_the_wall_press_passes_on_the_continuous_and_the_discrete_plant(good, tmp_path):
    scenario, loop = good
    dut.check_contact(scenario, loop)
    sap = load_scenario(write_scenario(tmp_path), overrides={
        "plant.time_step": 0.001, "plant.discrete_contact_approximation": "sap"})
    _, sap_loop, _ = build_simulation(sap)
    dut.check_contact(sap, sap_loop)


def test_the_trace_finds_the_wall_face_where_it_is(good):
    """The tool (r = 0.04 m) at x = 0.95 m touches the face at x = 1.0 m after 0.01 m; the
    point contact stiffnesses are the model files' (3e4 and 1e8 N/m)."""
    scenario, loop = good
    surfaces = Surfaces(loop.simulated_plant)
    (tool,) = surfaces.tools
    assert tool.radius == pytest.approx(0.04) and tool.stiffness == 3.0e4
    hit = surfaces.trace(np.array([0.95, 0.0, 1.3]), np.array([1.0, 0.0, 0.0]), tool.radius,
                         5.0)
    assert hit.distance == pytest.approx(0.01, abs=1e-6)
    assert hit.name.startswith("wall") and hit.stiffness == 1.0e8
    # Slanted toward the wall: the face is 0.01 / cos(angle) ahead.
    slant = np.array([math.cos(0.5), math.sin(0.5), 0.0])
    assert surfaces.trace(np.array([0.95, 0.0, 1.3]), slant, 0.04, 5.0).distance == \
        pytest.approx(0.01 / math.cos(0.5), abs=1e-5)
    # Away from it: nothing.
    assert not surfaces.trace(np.array([0.95, 0.0, 1.3]), -slant, 0.04, 5.0).found
    # The wall-tool pair is point contact under the default hydroelastic_with_fallback.
    sample = next(s for s in dut.window_samples(scenario, loop.controller_model,
                                                loop.controller.force_task,
                                                loop.reference.source) if s.share > 0)
    assert surfaces.point_contact(tool, sample.X_WB, np.array([1.0, 0.0, 0.0]), hit)


def test_no_environment_is_refused_at_load(tmp_path):
    path = write_scenario(tmp_path)
    text = path.read_text()
    path.write_text(text[:text.index("environment:")] + text[text.index("actuation:"):])
    with pytest.raises(ScenarioError) as err:
        load_scenario(path)
    assert err.value.field == "environment"
    assert "no environment" in str(err.value) and "environment.directives" in str(err.value)


def test_an_environment_without_collision_geometry_is_refused(tmp_path):
    wall = (MODELS / "environments" / "wall.sdf").read_text()
    start, stop = wall.index("<collision"), wall.index("</collision>") + len("</collision>")
    (tmp_path / "ghost.sdf").write_text(wall[:start] + wall[stop:])
    scenario = load_scenario(write_scenario(tmp_path, wall="ghost.sdf"))
    err = refusal(scenario)
    assert err.field == "environment" and "no collision geometry" in str(err)


def test_a_surface_out_of_reach_is_refused_with_its_distance(tmp_path):
    """The reference stops 0.15 m before the face: the tool's sphere is 0.11 m from it,
    0.06 m more than max_shift (0.05 m)."""
    scenario = load_scenario(write_scenario(tmp_path, ee_x=0.85))
    err = refusal(scenario)
    assert err.field == "controller.force.direction"
    text = str(err)
    assert "0.110 m ahead" in text and "0.060 m more than controller.force.max_shift" in text
    assert "waypoints" in text
    # With a larger max_shift it passes.
    wide = load_scenario(write_scenario(tmp_path, ee_x=0.85),
                         overrides={"controller.force.max_shift": 0.12})
    _, loop, _ = build_simulation(wide)
    dut.check_contact(wide, loop)


def test_a_direction_away_from_any_surface_is_refused(tmp_path):
    scenario = load_scenario(write_scenario(tmp_path),
                             overrides={"controller.force.direction": [0.0, 1.0, 0.0]})
    err = refusal(scenario)
    assert err.field == "controller.force.direction"
    assert f"no surface of the environment lies within {dut.SEARCH_DISTANCE:g} m" in str(err)


def test_the_cli_exits_2_before_simulating(tmp_path, capsys):
    path = write_scenario(tmp_path, ee_x=0.85)
    status = cli_main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet",
                       "--no-plots"])
    assert status == 2
    assert "controller.force.direction" in capsys.readouterr().err
    assert not (tmp_path / "out" / "wall_press_check" / "log.npz").exists()


def stiff_tool_robot(folder: Path, stiffness: float) -> Path:
    """The paper's robot with a stiffer tool pad (its lwr.sdf's point contact stiffness)."""
    for name in ("helicopter.sdf", "helicopter_rotors.sdf", "helicopter_lwr.robot.yaml"):
        shutil.copy(MODELS / name, folder / name)
    lwr = (MODELS / "lwr.sdf").read_text()
    old = "<drake:point_contact_stiffness>3.0e4</drake:point_contact_stiffness>"
    assert lwr.count(old) == 1
    (folder / "lwr.sdf").write_text(lwr.replace(
        old, f"<drake:point_contact_stiffness>{stiffness:g}</drake:point_contact_stiffness>"))
    mount = (MODELS / "arm_mount.dmd.yaml").read_text()
    (folder / "arm_mount.dmd.yaml").write_text(
        mount.replace("package://aerial_drake/lwr.sdf", "package://stiff_tool/lwr.sdf"))
    robot = folder / "helicopter_lwr.robot.yaml"
    robot.write_text(robot.read_text().replace(
        "models:\n", "package_map: {stiff_tool: .}\nmodels:\n", 1))
    return robot


def apparent_mass_by_forward_dynamics(model, q, p_WC, d) -> float:
    """1 / (the acceleration of the point along d per newton pushed along d), from Drake's
    forward dynamics (articulated bodies, not the mass matrix), at rest."""
    from pydrake.multibody.math import SpatialForce
    from pydrake.multibody.plant import ExternallyAppliedSpatialForce
    plant = model.plant
    context = plant.CreateDefaultContext()
    plant.SetPositions(context, q)
    body = model.end_effector_body
    p_BC = plant.EvalBodyPoseInWorld(context, body).inverse().multiply(p_WC)

    def point_acceleration(force: float) -> np.ndarray:
        push = ExternallyAppliedSpatialForce()
        push.body_index, push.p_BoBq_B = body.index(), p_BC
        push.F_Bq_W = SpatialForce(np.zeros(3), force * d)
        plant.get_applied_spatial_force_input_port().FixValue(context, [push])
        vdot = plant.EvalTimeDerivatives(context).get_vector().CopyToVector()[
            plant.num_positions():]
        J = plant.CalcJacobianTranslationalVelocity(
            context, JacobianWrtVariable.kV, body.body_frame(), p_BC, plant.world_frame(),
            plant.world_frame())
        return J @ vdot

    return 1.0 / float(d @ (point_acceleration(1.0) - point_acceleration(0.0)))


def test_the_apparent_mass_is_the_forward_dynamics_one(good):
    scenario, loop = good
    model, d = loop.controller_model, np.array([1.0, 0.0, 0.0])
    sample = dut.window_samples(scenario, model, loop.controller.force_task,
                                loop.reference.source)[20]
    p_WC = sample.X_WB.translation() + 0.04 * d
    m_eff = dut.apparent_mass(model, sample.q, p_WC, d)
    assert 0.5 < m_eff < mass_and_gravity(model)[0]
    assert m_eff == pytest.approx(apparent_mass_by_forward_dynamics(model, sample.q, p_WC, d),
                                  rel=1e-6)


def test_a_contact_too_stiff_for_the_fixed_step_is_refused(tmp_path):
    """A 3e7 N/m tool against the 1e8 N/m wall: k = 2.3e7 N/m in series; omega h > 1 at
    h = 1 ms. The message's numbers are those of the series stiffness and the apparent
    mass; a step short enough, error control or the discrete plant pass."""
    robot = stiff_tool_robot(tmp_path, 3.0e7)
    scenario = load_scenario(write_scenario(tmp_path, robot=str(robot)))
    _, loop, _ = build_simulation(scenario)
    err = refusal(scenario, loop)
    assert err.field == "simulator.max_step_size"
    k = 3.0e7 * 1.0e8 / (3.0e7 + 1.0e8)
    d = np.array([1.0, 0.0, 0.0])
    sample = next(s for s in dut.window_samples(scenario, loop.controller_model,
                                                loop.controller.force_task,
                                                loop.reference.source) if s.share > 0)
    m_eff = apparent_mass_by_forward_dynamics(loop.controller_model, sample.q,
                                              sample.X_WB.translation() + 0.04 * d, d)
    omega_h = math.sqrt(k / m_eff) * 1e-3
    assert omega_h > dut.MAX_OMEGA_STEP
    assert f"in series k = {k:.3g} N/m" in str(err)
    assert f"omega h = {omega_h:.3g}" in str(err)
    # Each fix passes, with the force loop's damping raised to the stiff contact (its own
    # check: k T / D <= 1, aerial_drake.simulation.contact_rates).
    for overrides in ({"simulator.max_step_size": 0.9e-3 / omega_h},
                      {"simulator.use_error_control": True},
                      {"plant.time_step": 0.001, "plant.discrete_contact_approximation": "sap"}):
        overrides["controller.force.admittance_damping"] = k * 1e-3
        fixed = load_scenario(write_scenario(tmp_path, robot=str(robot)), overrides=overrides)
        _, fixed_loop, _ = build_simulation(fixed)
        dut.check_contact(fixed, fixed_loop)


def largest_in_message(text: str) -> float:
    return float(text.split("the largest force it holds is ")[1].split(" N")[0])


def test_a_force_beyond_the_thrust_is_refused_at_the_thrusts_bound(tmp_path):
    """With the thrust maximum lowered to 560 N, holding still while pressing F along +x
    needs |m g e3 + F x| <= 560 N: F <= sqrt(560^2 - (m g)^2)."""
    scenario = load_scenario(write_scenario(tmp_path), overrides={
        "actuation.thrust_max": 560.0, "controller.force.force": 200.0})
    err = refusal(scenario)
    assert err.field == "controller.force.force" and "the thrust maximum binds" in str(err)
    m, g = mass_and_gravity(scenario.controller_model())
    assert largest_in_message(str(err)) == pytest.approx(math.sqrt(560.0 ** 2 - (m * g) ** 2),
                                                         abs=0.06)


def test_a_force_beyond_the_body_torques_is_refused_where_drake_statics_bind(good):
    """The largest force the body torques hold: at it, the moment about the vehicle frame's
    origin from Drake's own statics (the base rows of -tau_g + F J^T d, the quaternion
    joint's [w; v] World rows) reaches the body torque bound."""
    scenario, loop = good
    model, force = loop.controller_model, loop.controller.force_task
    d = np.array([1.0, 0.0, 0.0])
    samples = dut.window_samples(scenario, model, force, loop.reference.source)
    surfaces = Surfaces(loop.simulated_plant)
    dut.check_reach(scenario, surfaces, samples, force, d)
    largest = check_force(scenario, model, samples, force, d)
    assert math.isfinite(largest) and largest > force.force
    plant = model.plant
    context = plant.CreateDefaultContext()
    moments = []
    for sample in samples:
        if sample.share < 1:
            continue
        plant.SetPositions(context, sample.q)
        p_BC = sample.X_WB.inverse().multiply(sample.contact_point(d))
        J = plant.CalcJacobianTranslationalVelocity(
            context, JacobianWrtVariable.kV, model.end_effector_body.body_frame(), p_BC,
            plant.world_frame(), plant.world_frame())
        u = -plant.CalcGravityGeneralizedForces(context) + largest * (J.T @ d)
        R_WB = plant.EvalBodyPoseInWorld(context, model.base_body).rotation()
        moments.append(R_WB.inverse().multiply(u[model.base_velocity_indices[:3]]))
    assert np.max(np.abs(moments)) == pytest.approx(model.body_torque_limits().max(),
                                                    rel=1e-9)
    force.force, old = largest * 1.01, force.force
    try:
        err = refusal(scenario, loop)
    finally:
        force.force = old
    assert err.field == "controller.force.force" and "body torque" in str(err)
    assert largest_in_message(str(err)) == pytest.approx(largest, rel=1e-3)


def test_largest_thrust_force_pressing_down_meets_the_thrust_minimum():
    """Pressing down (d = -e3) unloads the thrust: |m g - F| >= low until F = m g - low."""
    a = np.array([0.0, 0.0, 500.0])
    bound, binds = largest_thrust_force(a, np.array([0.0, 0.0, -1.0]), 100.0, 900.0)
    assert (bound, binds) == (pytest.approx(400.0), "minimum")
    bound, binds = largest_thrust_force(a, np.array([0.0, 0.0, 1.0]), 100.0, 900.0)
    assert (bound, binds) == (pytest.approx(400.0), "maximum")
    assert largest_thrust_force(a, np.array([1.0, 0.0, 0.0]), 0.0, math.inf) == \
        (math.inf, "")


def test_a_reference_deep_in_the_surface_is_refused(tmp_path):
    """The reference puts the tool's sphere 0.09 m into the wall (centre at x = 1.05 m,
    radius 0.04 m, face at 1.0 m), more than max_shift backs out."""
    scenario = load_scenario(write_scenario(tmp_path, ee_x=1.05))
    err = refusal(scenario)
    assert err.field == "controller.force.max_shift"
    assert "0.090 m deep into 'wall" in str(err)


def test_largest_in_box_stops_at_the_first_bound_either_side():
    from aerial_drake.simulation.contact_loads import largest_in_box
    v0, a = np.array([1.0, -2.0, 0.0]), np.array([1.0, -0.5, 0.0])
    lower, upper = np.array([-5.0, -4.0, -1.0]), np.array([4.0, 3.0, 1.0])
    assert largest_in_box(v0, a, lower, upper) == (pytest.approx(3.0), 0)  # 1 + 3 = 4
    assert largest_in_box(v0, np.array([0.1, -0.5, 0.0]), lower, upper) == \
        (pytest.approx(4.0), 1)  # -2 - 4 (0.5) = -4
    assert largest_in_box(np.array([5.0, 0.0, 0.0]), a, lower, upper) == (0.0, 0)
    assert largest_in_box(v0, np.zeros(3), lower, upper) == (math.inf, -1)
