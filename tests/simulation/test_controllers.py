"""The controller interface and registry (aerial_drake.control.registry): choosing a controller
by the scenario's ``controller`` section, validating it, and a user-defined controller (a plain
LeafSystem defined here, not on the base) through the same scenario machinery and metrics."""

import dataclasses
import json

import numpy as np
import pytest
from pydrake.systems.framework import LeafSystem

from aerial_drake.control import registry as dut
from aerial_drake.control.baselines import BaselineController
from aerial_drake.control.controller import DecoupledController
from aerial_drake.control.interface import check_controller_ports
from aerial_drake.robots.models import make_plant
from aerial_drake.simulation import controllers as back_compat
from aerial_drake.simulation.diagram import build_closed_loop
from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import ScenarioError, load_scenario
from aerial_drake.simulation.tracking import entries
from aerial_drake.trajectories.reference import unpack_task_reference


class HoldController(LeafSystem):
    """A user's controller: hover thrust, no body torque, the arm's gravity compensated;
    continuous (no ``period``), one diagnostics entry (its thrust) and no
    ``diagnostics_layout``."""

    def __init__(self, model):
        super().__init__()
        self._model, self._plant = model, model.plant
        self._ctx = model.plant.CreateDefaultContext()
        nx = model.plant.num_multibody_states()
        self._n = len(model.arm_joints)
        self.DeclareVectorInputPort("state", nx)
        self.DeclareVectorInputPort("com_reference", 15)
        self.DeclareVectorInputPort("task_reference", 27)
        self.DeclareVectorInputPort("heading_reference", 9)
        self.DeclareVectorOutputPort("command", 4 + self._n, self._command)
        self.DeclareVectorOutputPort("diagnostics", 1, lambda c, o: o.SetFromVector(
            self.GetOutputPort("command").Eval(c)[:1]))

    def _command(self, context, output):
        self._plant.SetPositionsAndVelocities(self._ctx, self.get_input_port(0).Eval(context))
        m = self._plant.CalcTotalMass(self._ctx)
        tau_g = self._plant.CalcGravityGeneralizedForces(self._ctx)[6:]
        output.SetFromVector(np.concatenate([[m * 9.81], np.zeros(3), -tau_g]))


def hold_factory(scenario, model):
    return HoldController(model)


def test_default_is_the_papers_controller_and_the_shipped_files_say_nothing():
    for name in ("nominal", "disturbed", "orbit"):
        assert load_scenario(name).controller.type == "paper"
    loop = build_closed_loop(load_scenario("nominal"))
    assert isinstance(loop.controller, DecoupledController)


@pytest.mark.parametrize("kind", ("uncoupled", "static_compensation"))
def test_a_scenario_chooses_a_baseline(tmp_path, kind):
    path = tmp_path / "s.yaml"
    base = load_scenario("nominal")
    path.write_text(f"name: b\ncontroller:\n  type: {kind}\n  baseline:\n"
                    "    vehicle_inertia: [1.5, 0.4, 1.5]\n" + _required(base))
    scenario = load_scenario(path)
    loop = build_closed_loop(scenario)
    assert isinstance(loop.controller, BaselineController) and loop.controller.kind == kind


def _required(base):
    """The YAML of the fields a scenario must set (the gains), from ``base``; the input
    limits are the robot description's."""
    g = base.gains
    return (f"gains:\n  K_x: {g.K_x}\n  D_x: {g.D_x}\n  k_R: {g.k_R}\n  k_w: {g.k_w}\n"
            f"  Lambda2_bar: {g.Lambda2_bar}\n  K_y: {g.K_y}\n  K_z: {g.K_z}\n")


@pytest.mark.parametrize("section, match", [
    ("controller:\n  typ: uncoupled\n", "typ"),
    ("controller:\n  type: lqr\n", "controller.type: 'lqr' is not one of.*uncoupled"),
    ("controller:\n  type: uncoupled\n  baseline:\n    vehicle_inertia: [1.0]\n",
     "vehicle_inertia"),
    ("controller:\n  baseline:\n    sigma_min_limt: 0.1\n", "sigma_min_limt"),
])
def test_a_bad_controller_section_names_the_field(tmp_path, section, match):
    path = tmp_path / "s.yaml"
    path.write_text("name: b\n" + section + _required(load_scenario("nominal")))
    with pytest.raises(ScenarioError, match=match):
        load_scenario(path)


def test_a_controller_without_the_interfaces_ports_is_refused():
    model = make_plant("rigid")

    class NoDiagnostics(LeafSystem):
        def __init__(self):
            super().__init__()
            self.DeclareVectorInputPort("state", model.plant.num_multibody_states())
            for name, size in (("com_reference", 15), ("task_reference", 27),
                               ("heading_reference", 9)):
                self.DeclareVectorInputPort(name, size)
            self.DeclareVectorOutputPort("command", 11, lambda c, o: o.SetZero())

    with pytest.raises(ValueError, match="no output port 'diagnostics'"):
        check_controller_ports(NoDiagnostics(), model.plant.num_multibody_states(), 7, 1)
    with pytest.raises(ValueError, match="no output port 'diagnostics'"):
        build_closed_loop(load_scenario("nominal"),
                          controller_factory=lambda s, m: NoDiagnostics())
    with pytest.raises(ValueError, match="built-in"):
        dut.register_controller("paper", hold_factory)

    class WrongLayout(HoldController):
        diagnostics_layout = (("thrust", 1), ("extra", 2))

    with pytest.raises(ValueError, match="'diagnostics' has size 1 but its diagnostics_layout "
                                         "sums to 3"):
        check_controller_ports(WrongLayout(model), model.plant.num_multibody_states(), 7, 1)


def test_the_simulation_layers_names_are_the_registrys():
    """aerial_drake.simulation.controllers only re-exports (back-compatibility)."""
    from aerial_drake.control import reference_pose

    for name in back_compat.__all__:
        home = reference_pose if name == "body_offset_in_heading_frame" else dut
        assert getattr(back_compat, name) is getattr(home, name), name
    dut.register_controller("test_back_compat", hold_factory)
    assert "test_back_compat" in back_compat.controller_types()


def test_a_user_defined_controller_runs_through_the_scenario_machinery(tmp_path):
    """Registered by name, chosen by a scenario file, run by run_scenario: its logs and
    metrics are the same machinery's, its errors measured from the log and its own
    diagnostics logged apart."""
    dut.register_controller("test_hold", hold_factory)
    path = tmp_path / "hold.yaml"
    # The default reference (the paper's) starts with joint 6 past its limit (docs/paper.md,
    # "Joint limits"); this test is about the controller, so the limits are only reported.
    path.write_text("name: hold\nduration: 0.3\ncontroller:\n  type: test_hold\n"
                    "joint_limits:\n  positions: report\n"
                    + _required(load_scenario("nominal")))
    scenario = load_scenario(path)
    result = run_scenario(scenario, out_dir=tmp_path / "out", progress=False)
    assert result.completed
    assert (tmp_path / "out" / "metrics.json").is_file()
    m = result.metrics
    assert m["controller_evaluations"] is None  # the user's system does not count
    phase = m["phases"][0]
    assert phase["samples"] == len(result.log["t"]) == 301
    # The metrics' EE error is the distance of the logged end effector from the reference,
    # recomputed here from the logged plant state.
    model = make_plant("rigid")
    ctx = model.plant.CreateDefaultContext()
    errors = []
    for x, task in zip(result.log["plant_state"][::50], result.log["task_reference"][::50]):
        model.plant.SetPositionsAndVelocities(ctx, x)
        p = model.end_effector_frame.CalcPoseInWorld(ctx).translation()
        errors.append(np.linalg.norm(p - unpack_task_reference(task).p_ed))
    layout = json.loads(str(np.load(tmp_path / "out" / "log.npz")["layout"]))
    tracked = entries(result.log["tracking"], layout["tracking"])
    logged = tracked["ee_position_error"][::50, 0]
    np.testing.assert_allclose(logged, errors, rtol=1e-9, atol=1e-12)
    # Its own diagnostics (the thrust), one entry with no layout of its own: named generically;
    # the paper law's entries it does not define are not faked (no sigma_min_J3 of its own,
    # the margin comes from the tracking errors).
    np.testing.assert_array_equal(result.log["diagnostics"][:, 0], result.log["command"][0, 0])
    assert layout["diagnostics"] == [["d0", 1]]
    assert m["min_f_d_norm_N"] is None
    assert phase["ee_position_error_m"]["max"] == pytest.approx(
        tracked["ee_position_error"].max())
    # The same system handed straight to the runner, without registering: the same run.
    again = run_scenario(dataclasses.replace(scenario, controller=dataclasses.replace(
        scenario.controller, type="paper")), controller_factory=hold_factory, progress=False)
    np.testing.assert_array_equal(again.log["plant_state"], result.log["plant_state"])


def test_analyze_refuses_another_controllers_scenario(tmp_path):
    from aerial_drake.analysis.report import analyze

    path = tmp_path / "s.yaml"
    path.write_text("name: b\ncontroller:\n  type: uncoupled\n" + _required(load_scenario(
        "nominal")))
    with pytest.raises(ScenarioError, match="analyze studies the paper's controller"):
        analyze(tmp_path / "out", scenario=str(path))
