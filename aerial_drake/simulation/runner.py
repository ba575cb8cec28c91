"""Simulate a scenario: initial state, progress, failure messages, logs and metrics."""

from __future__ import annotations

import json
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, TextIO, cast

import numpy as np
from pydrake.common.yaml import yaml_dump_typed
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.analysis import ApplySimulatorConfig, Simulator
from pydrake.systems.framework import Context
from pydrake.systems.primitives import VectorLogSink

from aerial_drake.control.compiled import compile_law
from aerial_drake.control.law import (
    DIAGNOSTICS_LAYOUT,
    AssumptionViolation,
    desired_attitude,
    desired_force,
)
from aerial_drake.dynamics.equilibrium import solve_configuration
from aerial_drake.robots.models import (
    ROTOR_DIRECTIONS,
    AerialManipulator,
    nominal_end_effector_offset,
)
from aerial_drake.simulation.diagram import ClosedLoop, build_simulation, input_limits
from aerial_drake.simulation.metrics import (
    compute_metrics,
    disturbance_response,
    limits_by_input,
    phase_edges,
    rotor_metrics,
)
from aerial_drake.simulation.scenarios import Scenario, ScenarioError
from aerial_drake.trajectories.paper import compile_reference, evaluate_reference, sample_reference


class SimulationFailed(RuntimeError):
    """The closed loop could not be simulated to the end; the message says when and why."""


class SimulationInterrupted(SimulationFailed):
    """The user stopped the run (Ctrl-C); what was logged is written all the same."""


@dataclass
class RunResult:
    scenario: Scenario
    log: dict[str, np.ndarray]
    metrics: dict
    wall_time_s: float
    completed: bool = True
    failure: str | None = None
    out_dir: Path | None = None


def reference_configuration(scenario: Scenario, model: AerialManipulator,
                            t: float = 0.0) -> np.ndarray:
    """Positions of ``model`` that realise the reference at time ``t`` exactly: CoM on x_d,
    base attitude R_d of (13) for zero CoM error, end effector on (p_ed, R_ed), q3 = q3d."""
    ref = evaluate_reference(scenario.trajectory, t)
    m = model.plant.CalcTotalMass(model.plant.CreateDefaultContext())
    g = -model.plant.gravity_field().gravity_vector()[2]
    x = ref.com
    zero = np.zeros(3)
    # (10) with zero CoM error; its derivatives are then m times x_d's 3rd and 4th.
    f_d = desired_force(m, g, x, zero, zero, zero, zero)
    R_d = desired_attitude(f_d, m * x[3], m * x[4], ref.b1d)[0]
    # Joint limits are not imposed: the simulated plant does not enforce them, and at t = 0 the
    # paper's reference needs joint 6 about 0.19 rad past its 120 deg (docs/control.md).
    return solve_configuration(model, p_WG=x[0], R_WB=R_d, p_WE=ref.p_ed, R_WE=ref.R_ed,
                               q3=cast(float, ref.q3d),  # one instant: a scalar
                               respect_joint_limits=False)


#: How far (m) the desired end effector may stray from its nominal offset to the desired CoM,
#: in the heading frame: the mount was chosen to keep J_3 conditioned 0.1 m and 0.5 rad away
#: from nominal (docs/models.md); beyond 0.2 m the arm nears its reach or a singularity.
WORKSPACE_RADIUS = 0.2


def check_workspace(scenario: Scenario, model: AerialManipulator, *,
                    radius: float = WORKSPACE_RADIUS, rate: float = 50.0) -> None:
    """Raise ScenarioError if the reference leaves the arm's workspace at any sampled time.

    The arm holds the end effector at a fixed offset from the system CoM in the heading frame
    (x_d = x_c + R3(phi4) r_o, (33)); the task is feasible while the desired offset
    R3(phi4)^T (p_ed - x_d) stays within ``radius`` of the model's nominal one.
    """
    nominal = nominal_end_effector_offset(model)
    times = np.linspace(0.0, scenario.duration, int(scenario.duration * rate) + 1)
    ref = sample_reference(scenario.trajectory, times)
    offset = ref.p_ed - ref.com[:, 0]
    b1 = ref.b1d[:, 0]  # heading direction (unit, horizontal)
    x_h = np.einsum("ti,ti->t", offset, b1)
    y_h = -offset[:, 0] * b1[:, 1] + offset[:, 1] * b1[:, 0]
    dev = np.linalg.norm(np.column_stack([x_h, y_h, offset[:, 2]]) - nominal, axis=1)
    worst = int(np.argmax(dev))
    if dev[worst] > radius:
        raise ScenarioError(
            f"trajectory: the desired end effector leaves the arm's workspace at t = "
            f"{times[worst]:.2f} s: it is {dev[worst]:.3f} m from its nominal offset "
            f"{np.round(nominal, 3).tolist()} m to the desired CoM (heading frame; limit "
            f"{radius} m). Reduce trajectory.agile_amplitude or keep trajectory.com_offset "
            "near the model's nominal offset.")


def set_initial_state(scenario: Scenario, loop: ClosedLoop, plant_context: Context) -> None:
    """The reference configuration at t = 0 with the scenario's documented offsets, at rest
    (rotors, if any, already at speed)."""
    model, sim = loop.controller_model, loop.simulated_plant
    q_model = reference_configuration(scenario, model)
    ctx = model.plant.CreateDefaultContext()
    model.plant.SetPositions(ctx, q_model)
    X_WB = model.plant.EvalBodyPoseInWorld(ctx, model.base_body)
    init = scenario.initial
    R0 = RollPitchYaw(init.base_rpy_offset).ToRotationMatrix() @ X_WB.rotation()
    p0 = X_WB.translation() + np.asarray(init.base_position_offset)
    sim.plant.SetFreeBodyPose(plant_context, sim.base_body, RigidTransform(R0, p0))
    for joint, mj, offset in zip(sim.arm_joints, model.arm_joints, init.arm_offset):
        joint.set_angle(plant_context, q_model[mj.position_start()] + offset)
    for joint, sign in zip(sim.rotor_joints, ROTOR_DIRECTIONS):
        joint.set_angular_rate(plant_context, sign * scenario.rotors.speed)


def _prime_held_inputs(loop: ClosedLoop, context: Context) -> None:
    """Start the controller's hold and the lag at the controller's first command, so t = 0 has
    no step."""
    controller = loop.controller
    controller_context = controller.GetMyMutableContextFromRoot(context)
    if controller.period > 0:
        controller.hold_sample(controller_context)
    if loop.lag is not None:
        cmd = controller.get_command_output_port().Eval(controller_context)
        loop.lag.set_initial_output_value(loop.lag.GetMyMutableContextFromRoot(context),
                                          cmd[:4])


def _is_terminal(stream) -> bool:
    isatty = getattr(stream, "isatty", None)
    return bool(isatty and isatty())


class _Progress:
    """Prints simulated time, wall time and real-time factor, one report per call."""

    def __init__(self, duration: float, stream) -> None:
        self.duration, self.stream = duration, stream
        # On a terminal the line rewrites itself; in a log file each report is its own line.
        self._end = "" if stream is not None and _is_terminal(stream) else "\n"
        self._start = "\r" if not self._end else ""
        self.start = time.perf_counter()

    def report(self, t: float) -> None:
        """One progress report at simulated time ``t`` (s); nothing without a stream."""
        if self.stream is None:
            return
        wall = time.perf_counter() - self.start
        self.stream.write(f"{self._start}  t = {t:6.2f} / {self.duration:g} s   wall "
                          f"{wall:6.1f} s   real-time factor {t / max(wall, 1e-9):5.1f}x"
                          f"{self._end}")
        self.stream.flush()


def pause_times(duration: float, period: float, every: float = 1.0) -> list[float]:
    """Where :func:`_advance` pauses the simulation: multiples of ``period`` (the loggers'
    period) about ``every`` seconds apart, then ``duration``.

    Drake times the loggers' samples at ``k * period`` (k an integer), so the simulator ends a
    step there anyway: stopping AdvanceTo at the same doubles adds no step and leaves every
    number of the run unchanged.
    """
    stride = max(1, round(every / period))
    times = []
    k = stride
    while k * period < duration:
        times.append(k * period)
        k += stride
    return times + [duration]


def _advance(simulator: Simulator, plant: MultibodyPlant, pauses: list[float],
             progress: _Progress) -> None:
    """Advance to each of ``pauses`` in turn, reporting progress; stop early at a pause where
    the plant's state is not finite (:func:`run_scenario` then finds when from the log).

    Checking between AdvanceTo calls replaces a per-step Simulator monitor, which cost a Python
    call at every 1 ms step. The controller checks the state at each of its evaluations, so a
    closed loop stops at the first non-finite sample anyway.
    """
    context = simulator.get_context()
    plant_context = plant.GetMyContextFromRoot(context)
    for t in pauses:
        simulator.AdvanceTo(t)
        progress.report(context.get_time())
        if not np.all(np.isfinite(plant.GetPositionsAndVelocities(plant_context))):
            return


def _simulate(simulator: Simulator, loop: ClosedLoop, pauses: list[float],
              progress: _Progress) -> tuple[str | None, bool, float]:
    """Run the simulation; returns the failure message (None if it reached the end), whether
    Ctrl-C stopped it, and the wall time (s)."""
    failure, interrupted = None, False
    start = time.perf_counter()
    try:
        _prime_held_inputs(loop, simulator.get_mutable_context())
        simulator.Initialize()
        _advance(simulator, loop.simulated_plant.plant, pauses, progress)
    except (AssumptionViolation, FloatingPointError, RuntimeError) as err:
        failure = str(err)
    except KeyboardInterrupt:
        time_now = simulator.get_context().get_time()
        failure, interrupted = f"interrupted (Ctrl-C) at t = {time_now:.3f} s", True
    return failure, interrupted, time.perf_counter() - start


def _collect_log(scenario: Scenario, loop: ClosedLoop, loggers: dict[str, VectorLogSink],
                 context: Context) -> dict[str, np.ndarray]:
    """The loggers' samples as ``{"t": times, port: (samples, size)}``, cut to a common
    length, with the references at the sample times (what the reference ports gave there)
    and, for a sampled controller, the diagnostics re-aligned to their sample times."""
    log = {port: logger.FindLog(context) for port, logger in loggers.items()}
    arrays = {"t": log["plant_state"].sample_times()}
    for port, entry in log.items():
        arrays[port] = entry.data().T
    n = min(len(v) for v in arrays.values())
    arrays = {k: v[:n] for k, v in arrays.items()}
    references = sample_reference(scenario.trajectory, arrays["t"]).to_vectors()
    arrays.update(zip(("com_reference", "task_reference", "heading_reference"), references))
    if loop.controller.period > 0 and n > 0:
        arrays = _align_held_diagnostics(arrays, loop)
    return arrays


def _align_held_diagnostics(arrays: dict[str, np.ndarray], loop: ClosedLoop,
                            ) -> dict[str, np.ndarray]:
    """Each sample's diagnostics at its own time.

    A sampled controller holds the diagnostics of its sample at t_k with the command, and the
    loggers publish at t_k before the update at t_k: the logged row k holds the diagnostics of
    t_k-1 (row 0, the primed hold, those of t_0). So row k is taken from logged row k+1, and
    the last row's from the law at the last logged state and references (what the update at
    that time computes, to the last bit). Where the law refuses that state: an assumption
    violated, the run stopped there, so the row goes (as a failed sample logs nothing); a
    non-finite state, the row stays with NaN diagnostics (the run is cut at that sample).
    """
    held = arrays["diagnostics"]
    x = arrays["plant_state"][-1][loop.simulated_plant.rigid_state_indices]
    try:
        last = loop.controller.evaluate(x, *(arrays[k][-1] for k in (
            "com_reference", "task_reference", "heading_reference")))[1]
    except FloatingPointError:
        last = np.full(held.shape[1], np.nan)
    except AssumptionViolation:
        arrays = {k: v[:-1] for k, v in arrays.items()}
        arrays["diagnostics"] = held[1:]
        return arrays
    arrays["diagnostics"] = np.vstack([held[1:], last])
    return arrays


def _first_non_finite_sample(arrays: dict[str, np.ndarray]) -> int | None:
    """Index of the first logged plant state that is not finite, if any."""
    bad = ~np.all(np.isfinite(arrays["plant_state"]), axis=1)
    return int(np.argmax(bad)) if bad.any() else None


def _cut_at_divergence(arrays: dict[str, np.ndarray], index: int,
                       ) -> tuple[dict[str, np.ndarray], float, str]:
    """The log up to its first non-finite plant state (at ``index``), that sample's time and
    the failure message. The first non-finite sample is where the run went wrong, whatever
    stopped it later, so the log ends there, as the message says."""
    arrays = {k: v[:index + 1] for k, v in arrays.items()}
    t = float(arrays["t"][index])
    return arrays, t, f"t = {t:.4f} s: the plant state became non-finite (diverged)"


def compile_kernels() -> None:
    """Compile, or load from numba's cache, every numba kernel a run calls from Python: the
    control law and the reference's. From their argument types alone, so before any model
    is built; the command line calls this on the first run after installing and then
    restarts itself (``aerial_drake.cli``)."""
    compile_law()
    compile_reference()


def run_scenario(scenario: Scenario, *, out_dir: str | Path | None = None,
                 progress: bool = True, stream: TextIO | None = None,
                 configure: Callable | None = None,
                 realtime_rate: float | None = None,
                 zero_controller: bool = False,
                 before_start: Callable[[], None] | None = None) -> RunResult:
    """Simulate ``scenario``; write ``log.npz`` and ``metrics.json`` to ``out_dir`` if given.

    A failure (an assumption of the paper violated, a diverging state) stops the run with
    :class:`SimulationFailed` naming the time and the reason; the logs up to that instant are
    still written to ``out_dir`` first. ``configure(builder, loop)`` may add systems (e.g. a
    visualiser) before the diagram is built. ``realtime_rate`` overrides the scenario's
    target real-time rate (e.g. 1.0 to watch it). Ctrl-C stops the run the same way, with
    :class:`SimulationInterrupted`. ``before_start()`` is called once everything is built and
    the initial state set, just before the simulation (and its wall clock) starts: e.g. to
    wait for a browser to open the live view.
    """
    scenario.validate()
    stream = stream if stream is not None else sys.stderr
    builder, loop, loggers = build_simulation(scenario, zero_controller=zero_controller)
    check_workspace(scenario, loop.controller_model)
    if configure is not None:
        configure(builder, loop)
    diagram = builder.Build()
    diagram.set_name(f"scenario_{scenario.name}")
    simulator = Simulator(diagram)
    ApplySimulatorConfig(scenario.simulator, simulator)
    if realtime_rate is not None:
        simulator.set_target_realtime_rate(realtime_rate)
    context = simulator.get_mutable_context()
    plant_context = loop.simulated_plant.plant.GetMyMutableContextFromRoot(context)
    set_initial_state(scenario, loop, plant_context)
    if before_start is not None:
        before_start()
    progress_lines = _Progress(scenario.duration, stream if progress else None)
    failure, interrupted, wall = _simulate(
        simulator, loop, pause_times(scenario.duration, scenario.log_period), progress_lines)
    if progress and _is_terminal(stream):
        stream.write("\n")  # end the self-rewriting progress line
    arrays = _collect_log(scenario, loop, loggers, context)
    sim_time = float(context.get_time())
    diverged = _first_non_finite_sample(arrays)
    if diverged is not None:
        arrays, sim_time, failure = _cut_at_divergence(arrays, diverged)
        interrupted = False
    metrics = _metrics(scenario, loop, arrays, wall, sim_time)
    result = RunResult(scenario=scenario, log=arrays, metrics=metrics, wall_time_s=wall,
                       completed=failure is None, failure=failure)
    if out_dir is not None:
        result.out_dir = write_outputs(result, out_dir)
    if failure is not None:
        error = SimulationInterrupted if interrupted else SimulationFailed
        raise error(f"scenario '{scenario.name}' stopped: {failure}")
    return result


def _metrics(scenario: Scenario, loop: ClosedLoop, log: dict, wall: float,
             sim_time: float) -> dict:
    lower, upper = input_limits(scenario, loop.controller_model)
    windows = [(d.start, d.stop) for d in scenario.disturbances]
    edges = phase_edges(windows, scenario.duration)
    metrics = compute_metrics(log["t"], log["diagnostics"], log["applied_command"], lower,
                              upper, edges, scenario.log_period)
    metrics.update({
        "scenario": scenario.name,
        "simulated_time_s": sim_time,
        "wall_time_s": wall,
        "real_time_factor": sim_time / wall if wall > 0 else None,
        "controller_evaluations": loop.controller.evaluations,
        "input_limits": limits_by_input(lower, upper),
        "disturbance_response": disturbance_response(
            log["t"], log["diagnostics"],
            [(d.target, d.start, d.stop) for d in scenario.disturbances]),
    })
    sim = loop.simulated_plant
    if sim.rotor_joints and "rotor_drive_torque" in log:
        nq = sim.plant.num_positions()
        metrics["rotors"] = rotor_metrics(
            log["plant_state"][:, nq + sim.rotor_velocity_indices], log["rotor_drive_torque"],
            scenario.rotors.speed * np.array(ROTOR_DIRECTIONS))
    return metrics


def write_outputs(result: RunResult, out_dir: str | Path) -> Path:
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    names = json.dumps({"diagnostics": [list(x) for x in DIAGNOSTICS_LAYOUT]})
    arrays: dict[str, Any] = dict(result.log)  # (typed Any: numpy's stub has a bool keyword)
    np.savez_compressed(out / "log.npz", layout=np.array(names), **arrays)
    metrics = dict(result.metrics)
    metrics["completed"] = result.completed
    metrics["failure"] = result.failure
    (out / "metrics.json").write_text(json.dumps(metrics, indent=2))
    # The scenario as run (after overrides), so a run folder describes itself (plots read it).
    (out / "scenario.yaml").write_text(yaml_dump_typed(result.scenario))
    return out
