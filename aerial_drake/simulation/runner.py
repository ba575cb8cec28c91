"""Simulate a scenario: initial state, progress, failure messages, logs and metrics."""

from __future__ import annotations

import signal
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, TextIO

import numpy as np
from pydrake.common.yaml import yaml_dump_typed
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.analysis import ApplySimulatorConfig, Simulator
from pydrake.systems.framework import Context

from aerial_drake.control.compiled import reference_law_reason
from aerial_drake.control.law import AssumptionViolation
from aerial_drake.control.reference_pose import reference_configuration
from aerial_drake.control.registry import ControllerFactory
from aerial_drake.simulation.contact_checks import check_contact
from aerial_drake.simulation.diagram import ClosedLoop, build_simulation
from aerial_drake.simulation.disturbances import resolve_random_disturbances
from aerial_drake.simulation.feasibility import check_reference, check_start_posture
from aerial_drake.simulation.interrupts import deferred, handling, signal_name
from aerial_drake.simulation.joint_limits import LimitMonitor
from aerial_drake.simulation.kernel_cache import compile_kernels  # noqa: F401 (callers' name)
from aerial_drake.simulation.nonfinite import (
    SIGNAL_MEANING,
    cut_at_divergence,
    first_non_finite_output,
    first_non_finite_sample,
    likely_cause,
)
from aerial_drake.simulation.outputs import (
    FolderLock,
    check_extra_names,
    prepare_folder,
    strict_json,
    write_result_set,
)
from aerial_drake.simulation.perturbations import start_perturbations
from aerial_drake.simulation.run_log import (
    collect_log,
    controller_period,
    layout_json,
    run_metrics,
)
from aerial_drake.simulation.scenarios import Scenario, ScenarioError
from aerial_drake.simulation.scenarios.checks import REALTIME, estimated_log_mb, number
from aerial_drake.simulation.scenarios.fields import plain_values
from aerial_drake.simulation.tracking import Layout


class SimulationFailed(RuntimeError):
    """The closed loop could not be simulated to the end; the message says when and why.
    ``result``: the run up to the failure (its log and metrics), where the runner got that
    far (studies record its metrics in the failed run's row)."""

    result: RunResult | None = None


class SimulationInterrupted(SimulationFailed):
    """A signal stopped the run (SIGINT/Ctrl-C, SIGTERM, SIGHUP); what was logged is written
    all the same. ``signum`` is the signal's number (the command line exits 128 + it)."""

    def __init__(self, message: str, signum: int = signal.SIGINT) -> None:
        super().__init__(message)
        self.signum = signum

    @property
    def exit_status(self) -> int:
        return 128 + self.signum


@dataclass
class RunResult:
    scenario: Scenario
    log: dict[str, np.ndarray]
    metrics: dict
    wall_time_s: float
    completed: bool = True
    failure: str | None = None
    out_dir: Path | None = None
    #: One name per task row (robots.task.TaskLayout.labels), stored with the log's layout.
    task_labels: tuple[str, ...] = ()
    #: The (name, size) pairs of the logged vectors ``diagnostics`` (the controller's) and
    #: ``tracking`` (simulation.tracking), by array name; stored in log.npz's ``layout``.
    layouts: dict[str, Layout] = field(default_factory=dict)


def set_initial_state(scenario: Scenario, loop: ClosedLoop, plant_context: Context) -> None:
    """The reference configuration at t = 0 with the scenario's documented offsets, at rest
    (rotors, if any, already at speed)."""
    model, sim = loop.controller_model, loop.simulated_plant
    q_model = reference_configuration(scenario, model, reference=loop.reference.source)
    ctx = model.plant.CreateDefaultContext()
    model.plant.SetPositions(ctx, q_model)
    X_WB = model.plant.EvalBodyPoseInWorld(ctx, model.base_body)
    init = scenario.initial
    R0 = RollPitchYaw(init.base_rpy_offset).ToRotationMatrix() @ X_WB.rotation()
    p0 = X_WB.translation() + np.asarray(init.base_position_offset)
    sim.plant.SetFreeBodyPose(plant_context, sim.base_body, RigidTransform(R0, p0))
    offsets = init.arm_offset or [0.0] * model.n
    for joint, mj, offset in zip(sim.arm_joints, model.arm_joints, offsets):
        joint.set_angle(plant_context, q_model[mj.position_start()] + offset)
    for joint, sign in zip(sim.rotor_joints, sim.rotor_directions):
        joint.set_angular_rate(plant_context, sign * scenario.rotors.speed)


def _prime_held_inputs(loop: ClosedLoop, context: Context) -> None:
    """Start the controller's hold and the lag at the controller's first command, so t = 0 has
    no step."""
    controller = loop.controller
    controller_context = controller.GetMyMutableContextFromRoot(context)
    if controller_period(controller) > 0:
        controller.hold_sample(controller_context)
    if loop.lag is not None:
        cmd = controller.GetOutputPort("command").Eval(controller_context)
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
             progress: _Progress, limits: LimitMonitor) -> None:
    """Advance to each of ``pauses`` in turn, reporting progress; stop early at a pause where
    the plant's state is not finite or past a stopping ``limits`` (the log then says when).

    Checking between AdvanceTo calls replaces a per-step Simulator monitor, which cost a Python
    call at every 1 ms step. The controller checks the state at each of its evaluations, so a
    closed loop stops at the first non-finite sample anyway.
    """
    context = simulator.get_context()
    plant_context = plant.GetMyContextFromRoot(context)
    for t in pauses:
        simulator.AdvanceTo(t)
        progress.report(context.get_time())
        x = plant.GetPositionsAndVelocities(plant_context)
        if not np.all(np.isfinite(x)) or limits.past(x):
            return


def _simulate(simulator: Simulator, loop: ClosedLoop, pauses: list[float], progress: _Progress,
              limits: LimitMonitor) -> tuple[str | None, int | None, float]:
    """Run the simulation; returns the failure message (None if it reached the end), the
    number of the signal that stopped it (None if none did), and the wall time (s)."""
    failure, interrupted = None, None
    start = time.perf_counter()
    try:
        _prime_held_inputs(loop, simulator.get_mutable_context())
        simulator.Initialize()
        _advance(simulator, loop.simulated_plant.plant, pauses, progress, limits)
    except (AssumptionViolation, FloatingPointError) as err:
        failure = str(err)
    except RuntimeError as err:  # Drake's own (e.g. a NaN force): add the time
        time_now = simulator.get_context().get_time()
        failure = f"t = {time_now:.4f} s: {err}"
    except KeyboardInterrupt as err:  # (Interrupted: SIGINT, SIGTERM, SIGHUP)
        time_now = simulator.get_context().get_time()
        interrupted = getattr(err, "signum", signal.SIGINT)
        failure = f"interrupted ({signal_name(interrupted)}) at t = {time_now:.3f} s"
    return failure, interrupted, time.perf_counter() - start


def run_scenario(scenario: Scenario, *, out_dir: str | Path | None = None,
                 progress: bool = True, stream: TextIO | None = None,
                 configure: Callable | None = None,
                 realtime_rate: float | None = None,
                 controller_factory: ControllerFactory | None = None,
                 before_start: Callable[[], None] | None = None,
                 extra_files: Callable[[], dict[str, str]] | None = None) -> RunResult:
    """Simulate ``scenario``; write ``log.npz``, ``scenario.yaml`` and ``metrics.json`` (last)
    to the folder ``out_dir`` if given (docs/reliability.md).

    The scenario is validated and ``out_dir`` checked and locked before any model is built
    (ScenarioError, OutputError). A failure (an assumption of the paper violated, a
    non-finite value) stops the run with :class:`SimulationFailed` naming the time and the
    reason; the logs up to that instant are still written first. ``configure(builder,
    loop)`` may add systems (e.g. a visualiser) before the diagram is built.
    ``realtime_rate`` overrides the scenario's target real-time rate (e.g. 1.0 to watch it).
    SIGINT (Ctrl-C), SIGTERM and SIGHUP stop the run the same way, with
    :class:`SimulationInterrupted`; one arriving while the files are written is held until
    they are complete. ``controller_factory`` (``factory(scenario, model) -> system``,
    :mod:`aerial_drake.control.registry`) overrides the scenario's ``controller.type``.
    ``before_start()`` is called once everything is built and the initial state set, just
    before the simulation (and its wall clock) starts: e.g. to wait for a browser to open the
    live view. ``extra_files()`` gives more ``{name: text}`` files for the run's folder (e.g.
    the viewer's ``replay.html``), written with the others, inside the folder's lock and
    before ``metrics.json``; it is called once the simulation has stopped, however it stopped.
    A name that is not a plain file name in the folder (``..``, absolute, a separator) or
    names a run's own file is refused with OutputError before anything is written.
    """
    if not isinstance(scenario, Scenario):
        raise ScenarioError(f"scenario: expected a Scenario, got {type(scenario).__name__} "
                            f"{scenario!r}; load one with aerial_drake.simulation.scenarios."
                            "load_scenario(name_or_path)", "scenario")
    scenario = plain_values(scenario)  # numpy arrays in vector fields read as lists
    scenario.validate()
    # Random windows drawn into concrete ones: the metrics' phases and scenario.yaml see them.
    scenario = resolve_random_disturbances(scenario)
    if realtime_rate is not None:  # the range of simulator.target_realtime_rate
        number("realtime_rate", realtime_rate, REALTIME)
    need_mb = estimated_log_mb(scenario.duration, scenario.log_period)
    lock = prepare_folder(out_dir, need_mb) if out_dir is not None else None
    try:
        with handling():
            return _run_locked(scenario, lock, progress, stream, configure, realtime_rate,
                               controller_factory, before_start,
                               extra_files)
    finally:
        if lock is not None:
            lock.release()


def _run_locked(scenario: Scenario, lock: FolderLock | None, progress: bool,
                stream: TextIO | None, configure: Callable | None,
                realtime_rate: float | None, controller_factory: ControllerFactory | None,
                before_start: Callable[[], None] | None,
                extra_files: Callable[[], dict[str, str]] | None) -> RunResult:
    stream = stream if stream is not None else sys.stderr
    builder, loop, loggers = build_simulation(scenario, controller_factory=controller_factory)
    scenario = loop.scenario or scenario  # its end-effector windows bounded by the arm's hold
    if lock is not None:
        _note_replaced_results(scenario, lock.folder, stream)
    check_reference(scenario, loop.controller_model, loop.reference.source)
    check_contact(scenario, loop)  # a force task's surface, contact step, loads
    if getattr(loop.controller, "compiled", True) is False and reference_law_reason() is None:
        # (Where the process chose the reference law, its caller says so: kernel_cache.)
        # Said once: every valid description is compiled today (quaternion base, revolute
        # and weld joints); this is for a structure a later change admits.
        stream.write(f"note: the compiled control law cannot serve this robot "
                     f"({getattr(loop.controller, 'not_compiled_reason', '')}); the reference "
                     "implementation runs instead, about 100 times slower\n")
    if configure is not None:
        configure(builder, loop)
    diagram = builder.Build()
    diagram.set_name(f"scenario_{scenario.folder_name}")
    simulator = Simulator(diagram)
    ApplySimulatorConfig(scenario.simulator, simulator)
    if realtime_rate is not None:
        simulator.set_target_realtime_rate(realtime_rate)
    context = simulator.get_mutable_context()
    plant_context = loop.simulated_plant.plant.GetMyMutableContextFromRoot(context)
    set_initial_state(scenario, loop, plant_context)
    x0 = loop.simulated_plant.plant.GetPositionsAndVelocities(plant_context)
    check_start_posture(scenario, loop.controller_model,
                        x0[loop.simulated_plant.rigid_state_indices])
    start_perturbations(scenario, loop, context)  # model mismatch, payload, sensor's delay
    if before_start is not None:
        before_start()
    progress_lines = _Progress(scenario.duration, stream if progress else None)
    limits = LimitMonitor.of(scenario, loop.simulated_plant)  # joint_limits: stop
    failure, interrupted, wall = _simulate(simulator, loop, pause_times(
        scenario.duration, scenario.log_period), progress_lines, limits)
    # From here on a signal is held until the files are written (interrupts.deferred).
    with deferred() as held:
        if progress and _is_terminal(stream):
            stream.write("\n")  # end the self-rewriting progress line
        arrays, layouts = collect_log(scenario, loop, loggers, context)
        sim_time = float(context.get_time())
        diverged = first_non_finite_sample(arrays)
        crossed = limits.cut(arrays, diverged[0] if diverged else None)
        if crossed is not None:  # past a joint limit first: the log ends there
            (arrays, sim_time, failure), interrupted = crossed, None
        elif diverged is not None:
            arrays, sim_time, failure = cut_at_divergence(arrays, *diverged,
                                                          likely_cause(scenario))
            interrupted = None
        elif failure is not None and "NaN" in failure:  # Drake's check, between samples
            bad = first_non_finite_output(loop, context)
            what = SIGNAL_MEANING[bad] if bad else "a non-finite value"
            failure = (f"t = {sim_time:.4f} s: {what} (first non-finite signal: "
                       f"'{bad or 'unknown'}'); Drake: {failure.split(': ', 1)[-1]}; "
                       f"{likely_cause(scenario)}")
        metrics = run_metrics(scenario, loop, arrays, layouts, wall, sim_time, failure)
        result = RunResult(scenario=scenario, log=arrays, metrics=metrics, wall_time_s=wall,
                           completed=failure is None, failure=failure, layouts=layouts,
                           task_labels=_task_labels(loop))
        extra = extra_files() if extra_files is not None else {}
        check_extra_names(extra, RUN_FILES)  # before anything is written
        if lock is not None:
            result.out_dir = write_outputs(result, lock.folder, extra)
    if interrupted is None and held:  # a signal while writing: the files are complete
        interrupted = held[0]
        failure = failure or (f"interrupted ({signal_name(interrupted)}) while writing the "
                              "results; they are complete")
    if interrupted is not None:
        raise SimulationInterrupted(f"scenario '{scenario.name}' stopped: {failure}",
                                    interrupted)
    if failure is not None:
        error = SimulationFailed(f"scenario '{scenario.name}' stopped: {failure}")
        error.result = result
        raise error
    return result


#: The files every run writes into its folder (write_outputs).
RUN_FILES = ("log.npz", "scenario.yaml", "metrics.json")


def _task_labels(loop: ClosedLoop) -> tuple[str, ...]:
    """One name per task row of the run's robot (stored with the log's layout)."""
    task = loop.controller_model.task
    return task.labels if task is not None else ()


def _note_replaced_results(scenario: Scenario, folder: Path, stream: TextIO) -> None:
    """Say so when ``folder`` holds the results of a scenario with other settings (e.g. a
    copied file that kept ``name: nominal``): they are replaced, not silently."""
    previous = folder / "scenario.yaml"
    if not ((folder / "metrics.json").is_file() and previous.is_file()):
        return
    if previous.read_text(errors="replace") != yaml_dump_typed(scenario):
        stream.write(f"note: {folder} holds the results of a run with other settings (its "
                     "scenario.yaml differs); they are replaced. To keep both, give the "
                     "scenario another name: or another --out\n")


def write_outputs(result: RunResult, out_dir: str | Path,
                  extra: dict[str, str] | None = None) -> Path:
    """Write the run's files, and ``extra`` ``{name: text}`` ones, into ``out_dir``
    (aerial_drake.simulation.outputs): each to a temporary name then renamed, ``metrics.json``
    last (a folder with ``metrics.json`` holds one run's complete set); a write that fails
    leaves none of them (OutputError)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    names = layout_json(result.layouts, result.task_labels)
    arrays: dict[str, Any] = dict(result.log)  # (typed Any: numpy's stub has a bool keyword)
    metrics = dict(result.metrics)
    metrics["completed"] = result.completed
    metrics["failure"] = result.failure
    metrics_text = strict_json(metrics)
    scenario_text = yaml_dump_typed(result.scenario)
    write_result_set(out, [
        ("log.npz", lambda f: np.savez_compressed(f, layout=np.array(names), **arrays)),
        # The scenario as run (after overrides), so a run folder describes itself.
        ("scenario.yaml", lambda f: f.write(scenario_text.encode("utf-8"))),
        *((name, lambda f, text=text: f.write(text.encode("utf-8")))
          for name, text in (extra or {}).items()),
    ], ("metrics.json", lambda f: f.write(metrics_text.encode("utf-8"))))
    return out
