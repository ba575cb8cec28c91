"""The tracking errors (aerial_drake.simulation.tracking): their definitions against Drake's
own CoM and end-effector poses and control.law.task_error on random states, the compiled
kernel against the reference implementation, the paper law's diagnostics of the same names
to the bit in a run, metrics for a controller with other or no diagnostics entries, and the
plots of a run folder written before the tracking errors existed."""

import dataclasses
import json
import math

import numpy as np
import pytest
from pydrake.math import RollPitchYaw
from pydrake.systems.framework import BasicVector, LeafSystem

from aerial_drake.control.law import diagnostics_layout, rotation_angle, task_error
from aerial_drake.robots.models import make_plant
from aerial_drake.simulation import diagram as diagram_module
from aerial_drake.simulation.run_folder import load_run
from aerial_drake.simulation.run_log import controller_diagnostics_layout
from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import load_scenario
from aerial_drake.simulation.tracking import (
    Tracking,
    TrackingErrors,
    entries,
    heading_and_tilt,
    tracking_layout,
)
from aerial_drake.trajectories.reference import (
    COM_REFERENCE_SIZE,
    HEADING_REFERENCE_SIZE,
    task_reference_size,
    unpack_heading_reference,
    unpack_task_reference,
)
from aerial_drake.viz.run_plots import write_overlay
from tests.states import random_states


@pytest.fixture(scope="module")
def model():
    return make_plant("rigid")


def _samples(model, seed=1):
    """Random states (tests.states) and random references, one row each per sample."""
    rng = np.random.default_rng(seed)
    X = np.array([np.concatenate([q, v]) for q, v in random_states(model.plant, seed)])
    count = len(X)
    com = rng.normal(size=(count, COM_REFERENCE_SIZE))
    task = np.zeros((count, task_reference_size(model.task.n_joints)))
    heading = np.zeros((count, HEADING_REFERENCE_SIZE))
    for k in range(count):
        t = unpack_task_reference(task[k])  # views into the row
        t.p_ed[:] = rng.normal(size=3)
        t.R_ed[:] = RollPitchYaw(rng.uniform(-3.0, 3.0, 3)).ToRotationMatrix().matrix()
        t.q_jd[:] = rng.uniform(-2.0, 2.0, model.task.n_joints)
        yaw = rng.uniform(-3.0, 3.0)
        unpack_heading_reference(heading[k])[0] = [math.cos(yaw), math.sin(yaw), 0.0]
    return X, com, task, heading


def test_tracking_errors_are_their_definitions(model):
    X, com, task, heading = _samples(model)
    out = entries(Tracking(model)(X, com, task, heading), tracking_layout(model.n))
    plant, ctx = model.plant, model.plant.CreateDefaultContext()
    for k, x in enumerate(X):
        plant.SetPositionsAndVelocities(ctx, x)
        x_t = plant.CalcCenterOfMassPositionInWorld(ctx) - com[k, 0:3]
        x_t_dot = plant.CalcCenterOfMassTranslationalVelocityInWorld(ctx) - com[k, 3:6]
        X_WE = model.end_effector_frame.CalcPoseInWorld(ctx)
        ref = unpack_task_reference(task[k])
        y_t, R_err = task_error(X_WE.translation(), X_WE.rotation().matrix(),
                                x[list(model.task.joint_positions)], ref.p_ed, ref.R_ed,
                                ref.q_jd, model.task.rows)
        R = plant.EvalBodyPoseInWorld(ctx, model.base_body).rotation().matrix()
        np.testing.assert_allclose(out["x_tilde"][k], x_t, atol=1e-10)
        np.testing.assert_allclose(out["x_tilde_dot"][k], x_t_dot, atol=1e-9)
        np.testing.assert_allclose(out["y_tilde"][k], y_t, atol=1e-10)
        np.testing.assert_allclose(out["com_error"][k], np.linalg.norm(x_t), atol=1e-10)
        np.testing.assert_allclose(out["ee_position_error"][k],
                                   np.linalg.norm(X_WE.translation() - ref.p_ed), atol=1e-10)
        np.testing.assert_allclose(out["ee_orientation_error"][k], rotation_angle(R_err),
                                   atol=1e-7)  # (an arccos: steep near 0 and pi)
        np.testing.assert_allclose([out["heading_error"][k, 0], out["base_tilt"][k, 0]],
                                   heading_and_tilt(R, heading[k, 0:3]), atol=1e-7)


def test_compiled_kernel_matches_the_reference_implementation(model):
    X, com, task, heading = _samples(model, seed=2)
    X[3, 9] = np.nan  # a non-finite state: a NaN row in both
    compiled = Tracking(model)(X, com, task, heading)
    reference = Tracking(model, compiled=False)(X, com, task, heading)
    assert np.all(np.isnan(compiled[3])) and np.all(np.isnan(reference[3]))
    np.testing.assert_allclose(compiled, reference, rtol=1e-8, atol=1e-9)
    sigma_min = entries(compiled, tracking_layout(model.n))["sigma_min_J3"]
    assert np.all(np.delete(sigma_min, 3) > 0)


def test_heading_and_tilt_of_known_attitudes():
    yaw, roll = 0.3, 0.2
    R = RollPitchYaw(0.0, 0.0, yaw).ToRotationMatrix().matrix()
    heading, tilt = heading_and_tilt(R, np.array([1.0, 0.0, 0.0]))
    assert heading == pytest.approx(yaw) and tilt == pytest.approx(0.0, abs=1e-12)
    R = RollPitchYaw(roll, 0.0, 0.0).ToRotationMatrix().matrix()
    heading, tilt = heading_and_tilt(R, np.array([1.0, 0.0, 0.0]))
    assert heading == pytest.approx(0.0, abs=1e-12) and tilt == pytest.approx(roll)
    # b1d along the body's -x: half a turn.
    assert heading_and_tilt(np.eye(3), np.array([-1.0, 0.0, 0.0]))[0] == pytest.approx(math.pi)


def test_tracking_errors_system(model):
    X, com, task, heading = _samples(model, seed=3)
    system = TrackingErrors(model)
    context = system.CreateDefaultContext()
    for name, value in zip(("state", "com_reference", "task_reference", "heading_reference"),
                           (X[0], com[0], task[0], heading[0])):
        system.GetInputPort(name).FixValue(context, value)
    np.testing.assert_array_equal(
        system.GetOutputPort("tracking_errors").Eval(context),
        Tracking(model)(X[0], com[0], task[0], heading[0]))


@pytest.fixture(scope="module")
def short_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("tracking") / "nominal"
    scenario = dataclasses.replace(load_scenario("nominal"), duration=0.2)
    return run_scenario(scenario, out_dir=folder, progress=False), folder


def test_tracking_equals_the_paper_laws_diagnostics_to_the_bit(short_run):
    result, folder = short_run
    with np.load(folder / "log.npz") as log:
        layout = json.loads(str(log["layout"]))
        tracking = entries(log["tracking"], layout["tracking"])
        diagnostics = entries(log["diagnostics"], layout["diagnostics"])
        assert len(log["tracking"]) == len(log["t"]) == len(log["diagnostics"])
    assert [tuple(p) for p in layout["diagnostics"]] == list(diagnostics_layout(7))
    shared = set(tracking) & set(diagnostics)
    assert shared == {"x_tilde", "x_tilde_dot", "y_tilde", "sigma_min_J3", "com_error",
                      "ee_position_error", "ee_orientation_error"}
    for name in shared:
        assert np.array_equal(tracking[name], diagnostics[name]), name
    phase = result.metrics["phases"][0]
    assert phase["min_f_d_norm_N"] > 0 and phase["base_attitude_error_rad"]["max"] > 0


class _OwnController(LeafSystem):
    """A controller of the interface's ports with diagnostics of its own (zero command)."""

    def __init__(self, model, width, layout=None):
        super().__init__()
        nx = model.plant.num_positions() + model.plant.num_velocities()
        self.DeclareVectorInputPort("state", nx)
        self.DeclareVectorInputPort("com_reference", COM_REFERENCE_SIZE)
        self.DeclareVectorInputPort("task_reference", task_reference_size(model.task.n_joints))
        self.DeclareVectorInputPort("heading_reference", HEADING_REFERENCE_SIZE)
        self.DeclareVectorOutputPort("command", 4 + model.n, self._zero)
        self.DeclareVectorOutputPort("diagnostics", width, self._zero)
        if layout is not None:
            self.diagnostics_layout = layout

    def _zero(self, context, output: BasicVector) -> None:
        output.SetZero()


@pytest.mark.parametrize("width, layout, names", [
    (2, (("my_margin", 2),), ["my_margin"]),
    (3, None, ["d0", "d1", "d2"]),
])
def test_metrics_of_a_controller_with_its_own_diagnostics(monkeypatch, tmp_path, width,
                                                          layout, names):
    # (The port check wants the paper law's diagnostics size today; the run does not.)
    monkeypatch.setattr(diagram_module, "check_controller_ports", lambda *args: None)
    scenario = dataclasses.replace(load_scenario("nominal"), duration=0.05)
    result = run_scenario(scenario, out_dir=tmp_path, progress=False,
                          controller_factory=lambda s, m: _OwnController(m, width, layout))
    assert [name for name, _ in result.layouts["diagnostics"]] == names
    phase = result.metrics["phases"][0]
    assert phase["base_attitude_error_rad"] is None and phase["min_f_d_norm_N"] is None
    assert result.metrics["min_f_d_norm_N"] is None and result.metrics["min_sigma_min_J3"] > 0
    assert phase["ee_position_error_m"]["max"] > 0
    assert result.metrics["heading_error_rad"]["max"] >= 0
    run = load_run(tmp_path)
    assert run.diagnostic("base_attitude_error") is None
    assert run.tracking("x_tilde").shape == (len(run.t), 3)


def test_controller_diagnostics_layout_fallbacks():
    class Method:
        def diagnostics_layout(self):
            return (("a", 1), ("b", 2))

    assert controller_diagnostics_layout(Method(), 3, 7) == (("a", 1), ("b", 2))
    paper = diagnostics_layout(7)
    width = sum(size for _, size in paper)
    assert controller_diagnostics_layout(object(), width, 7) == paper
    # A layout of another width than the port's is not believed.
    assert controller_diagnostics_layout(Method(), 2, 7) == (("d0", 1), ("d1", 1))


def test_a_run_folder_without_tracking_errors_still_plots(short_run, tmp_path):
    """A folder written before the tracking errors: no ``tracking`` array, the layout with
    the diagnostics only; its errors come from the diagnostics and `plot` draws it."""
    _, folder = short_run
    old = tmp_path / "old"
    old.mkdir()
    with np.load(folder / "log.npz") as log:
        arrays = {k: log[k] for k in log.files if k not in ("tracking", "layout")}
        layout = json.loads(str(log["layout"]))
    np.savez_compressed(old / "log.npz", layout=np.array(json.dumps(
        {"diagnostics": layout["diagnostics"], "task": []})), **arrays)
    for name in ("metrics.json", "scenario.yaml"):
        (old / name).write_bytes((folder / name).read_bytes())
    new_run, old_run = load_run(folder), load_run(old)
    for name in ("x_tilde", "y_tilde", "ee_orientation_error"):
        np.testing.assert_array_equal(old_run.tracking(name), new_run.tracking(name))
    with pytest.raises(KeyError, match="heading_error"):
        old_run.tracking("heading_error")
    written = write_overlay([old], tmp_path / "figures")
    assert {p.name for p in written} >= {"fig3_end_effector.png", "fig5_orientation_errors.png"}


def test_with_sensing_noise_the_tracking_errors_are_the_true_ones(model):
    """The controller's diagnostics are of what it measured; the tracking errors of the
    plant's true state (docs: intended, the metrics are the true errors)."""
    scenario = load_scenario("nominal")
    noisy = dataclasses.replace(scenario.sensing, base_position_std=0.01, seed=3)
    result = run_scenario(dataclasses.replace(scenario, duration=0.05, sensing=noisy),
                          progress=False)
    log, layouts = result.log, result.layouts
    tracking = entries(log["tracking"], layouts["tracking"])
    diagnostics = entries(log["diagnostics"], layouts["diagnostics"])
    assert not np.allclose(tracking["x_tilde"], diagnostics["x_tilde"], atol=1e-4)
    plant, ctx = model.plant, model.plant.CreateDefaultContext()
    for k in (0, len(log["t"]) // 2, len(log["t"]) - 1):
        plant.SetPositionsAndVelocities(ctx, log["plant_state"][k])  # (the rigid plant)
        np.testing.assert_allclose(
            tracking["x_tilde"][k],
            plant.CalcCenterOfMassPositionInWorld(ctx) - log["com_reference"][k, :3],
            atol=1e-10)
