"""Section IV in one call: the nominal and disturbed runs, their metrics, and Figs. 3-6.

``aerial-drake run paper`` (or :func:`run_paper`) simulates the shipped scenarios ``nominal``
and ``disturbed`` and writes::

    OUT/paper/nominal/    log.npz, metrics.json, scenario.yaml
    OUT/paper/disturbed/  log.npz, metrics.json, scenario.yaml
    OUT/paper/fig3_end_effector.{png,pdf}  fig4_com.*  fig5_orientation_errors.*  fig6_inputs.*
    OUT/paper/summary.txt  (the table printed in the terminal)

``--seed N`` (:func:`perturb_initial`): without it every run is deterministic, from the
scenario files' documented initial offsets. With it, each run's initial offsets get a
reproducible random perturbation drawn from ``numpy.random.default_rng(N)``, uniform within
:data:`SEED_BOUNDS`; the paper run draws the nominal's perturbation first, then the
disturbed's, from the one generator (so ``run nominal --seed N`` starts where ``run paper
--seed N``'s nominal run does). The perturbed offsets are in each run's ``scenario.yaml``.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import dataclasses
import multiprocessing
import signal
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, TextIO

import numpy as np

from aerial_drake.dynamics.equilibrium import UnreachablePose
from aerial_drake.simulation.interrupts import Interrupted, handling, signal_name
from aerial_drake.simulation.metrics import saturated_after_key
from aerial_drake.simulation.outputs import OutputError, strict_json, write_text_atomically
from aerial_drake.simulation.runner import SimulationFailed, SimulationInterrupted, run_scenario
from aerial_drake.simulation.scenarios import Scenario, ScenarioError, load_scenario
from aerial_drake.studies.reporting import report_error, report_exception
from aerial_drake.viz.plots import Run, load_run, write_figures

PAPER_SCENARIOS = ("nominal", "disturbed")

#: Half-widths of the uniform ``--seed`` perturbation, per component: base position (m),
#: base roll/pitch/yaw (rad), arm joints (rad). Smaller than the scenarios' own offsets
#: (0.05 m, 0.05 rad), so a perturbed start stays in the regime the tests cover (the nominal
#: start saturates some inputs for a few milliseconds; much larger offsets saturate longer).
SEED_BOUNDS = {"base_position_offset": 0.02, "base_rpy_offset": 0.02, "arm_offset": 0.02}


def perturb_initial(scenario: Scenario, seed: int,
                    rng: np.random.Generator | None = None) -> Scenario:
    """A copy of ``scenario`` whose initial offsets are moved by a uniform random draw within
    :data:`SEED_BOUNDS`, from ``rng`` if given, else from ``default_rng(seed)``; the seed is
    noted in the description. The input is not modified."""
    rng = rng if rng is not None else np.random.default_rng(seed)
    init = scenario.initial
    changes = {}
    for name, bound in SEED_BOUNDS.items():
        value = np.asarray(getattr(init, name), dtype=float)
        changes[name] = (value + rng.uniform(-bound, bound, size=value.shape)).tolist()
    return dataclasses.replace(
        scenario, initial=dataclasses.replace(init, **changes),
        description=f"{scenario.description} Initial offsets perturbed with seed {seed}.",
    ).validate()


@dataclass
class PaperResult:
    """What :func:`run_paper` produced."""

    out_dir: Path
    runs: dict[str, Run] = field(default_factory=dict)  # loaded from the run folders
    failures: dict[str, str] = field(default_factory=dict)  # scenario name -> reason
    figures: list[Path] = field(default_factory=list)
    table: str = ""
    # The signal that stopped the study (its remaining runs were not started), if one did.
    interrupted: int | None = None

    @property
    def completed(self) -> bool:
        return not self.failures and all(n in self.runs for n in PAPER_SCENARIOS)


def run_paper(out_dir: str | Path = "out/paper", duration: float | None = None, *,
              seed: int | None = None, progress: bool = True,
              stream: TextIO | None = None, overrides: dict | None = None) -> PaperResult:
    """Run the nominal and disturbed scenarios into ``out_dir/<name>/``, write Figs. 3-6 and
    ``summary.txt`` into ``out_dir``, and return the result (the table is printed by the
    command line, not here).

    ``duration`` overrides both scenarios' duration (s); ``seed`` perturbs their initial
    offsets (module docstring); ``overrides`` replaces more top-level fields of both. Both
    scenarios are loaded and checked before either runs. A run that fails (an assumption
    violated, divergence) still leaves its logs up to the failure; the figures are drawn from
    whatever was logged. A signal (SIGINT, SIGTERM, SIGHUP) stops the study: the run it
    stopped writes its logs, the remaining run is not started, no figure is drawn, and
    :attr:`PaperResult.interrupted` holds the signal's number.
    """
    out = Path(out_dir)
    result = PaperResult(out_dir=out)
    rng = np.random.default_rng(seed) if seed is not None else None
    overrides = dict(overrides or {})
    if duration is not None:
        overrides["duration"] = duration
    scenarios = {}
    for name in PAPER_SCENARIOS:  # every check before the first run
        scenarios[name] = load_scenario(name, overrides=overrides or None)
        if seed is not None:  # (and so rng)
            scenarios[name] = perturb_initial(scenarios[name], seed, rng)
    batch = run_batch(scenarios, {name: out / name for name in scenarios},
                      progress=progress, stream=stream)
    result.runs, result.failures, result.interrupted = (batch.runs, batch.failures,
                                                        batch.interrupted)
    if result.interrupted is not None:
        result.table = format_table({n: r.metrics for n, r in result.runs.items()})
        return result
    if "nominal" in result.runs:
        result.figures = write_figures(out, result.runs["nominal"], result.runs.get("disturbed"))
    result.table = format_table({n: r.metrics for n, r in result.runs.items()})
    write_text_atomically(out / "summary.txt", result.table + "\n")
    return result


# --- Running several scenarios into their folders (run paper, compare) -----------------------
#: Seconds a terminated worker gets to write the logs of its interrupted run before it is killed.
WORKER_STOP_TIMEOUT_S = 60.0


@dataclass
class Batch:
    """What :func:`run_batch` produced: the complete runs, loaded; the reason for each run
    that failed or was not started; the signal that stopped the batch, if one did."""

    runs: dict[str, Run] = field(default_factory=dict)
    failures: dict[str, str] = field(default_factory=dict)
    interrupted: int | None = None


#: In a worker process: the signal that stopped one of its runs (then it starts no other: a
#: terminated worker finishes writing its logs, and must not take the next queued run).
_worker_stopped: list[int] = []
#: In a worker process: set by the parent when the batch stops, so that a worker that takes a
#: queued run from the pool's queue afterwards does not start it (pool initializer).
_worker_stop_event: Any = None


def _init_worker(stop_event: Any) -> None:
    global _worker_stop_event
    _worker_stop_event = stop_event


def _run_in_worker(rebuild: Callable[[str], Scenario], key: str,
                   folder: str) -> tuple[str | None, int | None]:
    """In a worker process: run ``rebuild(key)`` into ``folder``; (failure, signal) or
    (None, None). (A Scenario does not pickle, so the worker builds its own.)"""
    if _worker_stopped:
        return f"'{key}' not started: interrupted", _worker_stopped[0]
    if _worker_stop_event is not None and _worker_stop_event.is_set():
        return f"'{key}' not started: interrupted", signal.SIGTERM
    try:
        with handling():  # a signal before the simulation, too, stops the run cleanly
            run_scenario(rebuild(key), out_dir=folder, progress=False)
    except SimulationInterrupted as err:
        _worker_stopped.append(err.signum)
        return str(err), err.signum
    except Interrupted as err:  # before its simulation started: nothing written
        _worker_stopped.append(err.signum)
        return f"'{key}' not started: interrupted", err.signum
    except SimulationFailed as err:
        return str(err), None
    return None, None


def run_batch(scenarios: dict[str, Scenario], folders: dict[str, Path], *, jobs: int = 1,
              rebuild: Callable[[str], Scenario] | None = None, progress: bool = True,
              stream: TextIO | None = None, labels: dict[str, str] | None = None) -> Batch:
    """Run each of ``scenarios`` (by key) into ``folders[key]``; load the complete runs (those
    whose folder holds ``metrics.json``, written last) and collect the failures.

    A run that fails (SimulationFailed) is recorded and the next one runs. A signal (SIGINT,
    SIGTERM, SIGHUP) stops the batch: the run it stopped writes its logs, the remaining runs
    are not started (each recorded as "not started: interrupted"), and
    :attr:`Batch.interrupted` holds the signal's number. Other errors (an output folder that
    cannot be used, results not written) stop the batch and are raised.

    With ``jobs`` > 1 the runs go to a pool of that many "spawn" worker processes, each
    building its scenario with ``rebuild(key)`` (picklable: a module-level function or a
    ``functools.partial`` of one). On a signal in this process the pending runs are
    cancelled and the workers terminated (SIGTERM: a running simulation writes its logs up to
    there, as in one process), then waited for. ``labels[key]``: the progress line's name.
    """
    batch = Batch()
    labels = labels or {}
    say = stream.write if progress and stream is not None else None
    with handling():  # the signals stop the batch between runs too
        if jobs > 1 and len(scenarios) > 1:
            if rebuild is None:
                raise ValueError("run_batch: jobs > 1 needs rebuild (workers build their "
                                 "own scenarios)")
            _run_pooled(batch, scenarios, folders, jobs, rebuild, say, labels)
        else:
            _run_serial(batch, scenarios, folders, progress, stream, say, labels)
    return batch


def _load_complete(batch: Batch, key: str, folder: Path) -> None:
    if (folder / "metrics.json").is_file():  # the completeness marker (simulation.outputs)
        batch.runs[key] = load_run(folder)


def _not_started(batch: Batch, keys) -> None:
    for key in keys:
        if key not in batch.failures and key not in batch.runs:
            batch.failures[key] = f"'{key}' not started: interrupted"


def _run_serial(batch: Batch, scenarios: dict[str, Scenario], folders: dict[str, Path],
                progress: bool, stream: TextIO | None, say, labels: dict[str, str]) -> None:
    for key, scenario in scenarios.items():
        folder = folders[key]
        if say:
            say(f"running {labels.get(key, repr(key))} ({scenario.duration:g} s) -> "
                f"{folder}\n")
        try:
            try:
                run_scenario(scenario, out_dir=folder, progress=progress, stream=stream)
            except SimulationInterrupted as err:
                batch.failures[key] = str(err)
                batch.interrupted = err.signum
            except SimulationFailed as err:
                batch.failures[key] = str(err)
            _load_complete(batch, key, folder)
        except KeyboardInterrupt as err:  # before the simulation, or while loading its logs
            signum = getattr(err, "signum", signal.SIGINT)
            batch.failures.setdefault(key, f"interrupted ({signal_name(signum)}) outside "
                                           "the simulation")
            batch.interrupted = signum
        if batch.interrupted is not None:
            _not_started(batch, scenarios)
            return


def _run_pooled(batch: Batch, scenarios: dict[str, Scenario], folders: dict[str, Path],
                jobs: int, rebuild: Callable[[str], Scenario], say,
                labels: dict[str, str]) -> None:
    workers = min(jobs, len(scenarios))
    context = multiprocessing.get_context("spawn")
    stop_event = context.Event()
    pool = concurrent.futures.ProcessPoolExecutor(
        workers, mp_context=context, initializer=_init_worker, initargs=(stop_event,))
    futures: dict[str, concurrent.futures.Future] = {}
    try:
        futures = {key: pool.submit(_run_in_worker, rebuild, key, str(folders[key]))
                   for key in scenarios}
        if say:
            say(f"running {', '.join(labels.get(k, repr(k)) for k in scenarios)} in "
                f"{workers} processes\n")
        for key, future in futures.items():
            failure, signum = future.result()
            if failure:
                batch.failures[key] = failure
            if say:
                say(f"  {labels.get(key, repr(key))}: {failure or 'done'}\n")
            if signum is not None:  # the worker itself was signalled (e.g. Ctrl-C's group)
                batch.interrupted = signum
                break
    except KeyboardInterrupt as err:
        batch.interrupted = getattr(err, "signum", signal.SIGINT)
    except BaseException:
        stop_event.set()
        _stop_pool(pool, futures)
        raise
    if batch.interrupted is None:
        pool.shutdown(wait=True)
    else:
        stop_event.set()  # before the workers are stopped: none starts a queued run
        _stop_pool(pool, futures)
        for key, future in futures.items():
            if key in batch.failures:
                continue
            if future.cancelled() or not folders[key].exists():  # (queued in a worker)
                batch.failures[key] = f"'{key}' not started: interrupted"
            elif future.done() and future.exception() is None:
                failure, _ = future.result()
                if failure:
                    batch.failures[key] = failure
            else:
                batch.failures[key] = (f"'{key}' interrupted ({signal_name(batch.interrupted)})"
                                       f" in its worker process; logs up to there are in "
                                       f"{folders[key]}")
    for key in scenarios:
        _load_complete(batch, key, folders[key])


def _stop_pool(pool: concurrent.futures.ProcessPoolExecutor,
               futures: dict[str, concurrent.futures.Future]) -> None:
    """Cancel the runs not started, terminate the workers (SIGTERM, so a running simulation
    writes its logs) and wait for them (killed after :data:`WORKER_STOP_TIMEOUT_S`)."""
    for future in futures.values():
        future.cancel()
    # The executor has no public way to stop its workers before Python 3.14.
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        if process.is_alive():
            process.terminate()
    for process in processes:
        process.join(WORKER_STOP_TIMEOUT_S)
        if process.is_alive():
            process.kill()
            process.join()


# --- The terminal table ---------------------------------------------------------------------
def _phase_rows(metrics: dict[str, dict]) -> list[tuple[str, list[str]]]:
    names = list(metrics)
    rows = []
    quantities = (("EE position", "ee_position_error_m", 1e3, "mm"),
                  ("CoM position", "com_position_error_m", 1e3, "mm"),
                  ("base attitude", "base_attitude_error_rad", 1e3, "mrad"),
                  ("EE orientation", "ee_orientation_error_rad", 1e3, "mrad"))
    phases = metrics[names[0]]["phases"]
    for label, key, scale, unit in quantities:
        rows.append((f"max {label} error ({unit})", [""] * len(names)))
        for k, phase in enumerate(phases):
            cells = []
            for n in names:
                ph = metrics[n]["phases"][k] if k < len(metrics[n]["phases"]) else {}
                cells.append(f"{scale * ph[key]['max']:.2f}" if key in ph else "-")
            rows.append((f"  {phase['start_s']:g}-{phase['end_s']:g} s", cells))
    return rows


def format_table(metrics: dict[str, dict]) -> str:
    """The runs' main metrics side by side (columns: runs), as plain text."""
    if not metrics:
        return "no run produced a log"
    names = list(metrics)
    rows: list[tuple[str, list[str]]] = []

    def row(label, fn):
        cells = []
        for n in names:
            try:
                cells.append(fn(metrics[n]))
            except (KeyError, IndexError, TypeError):
                cells.append("-")
        rows.append((label, cells))

    row("completed", lambda m: "yes" if m.get("completed") else f"NO: {m.get('failure')}")
    row("simulated time (s)", lambda m: f"{m['simulated_time_s']:.2f}")
    row("wall time (s)", lambda m: f"{m['wall_time_s']:.1f}")
    rows += _phase_rows(metrics)
    n_windows = max(len(m.get("disturbance_response", [])) for m in metrics.values())
    for w in range(n_windows):
        first = next(m["disturbance_response"][w] for m in metrics.values()
                     if len(m.get("disturbance_response", [])) > w)
        a, b = first["evaluated_s"]
        start, stop = first["window_s"]
        rows.append((f"disturbance on {first['target']} {start:g}-{stop:g} s, peaks over "
                     f"{a:g}-{b:g} s", [""] * len(names)))
        row("  EE position error peak (mm)",
            lambda m: f"{1e3 * m['disturbance_response'][w]['ee_position_error_peak_m']:.2f}")
        row("  CoM error peak (mm)",
            lambda m: f"{1e3 * m['disturbance_response'][w]['com_error_peak_m']:.2f}")
        row("  ratio EE / CoM",
            lambda m: f"{m['disturbance_response'][w]['ee_to_com_peak_ratio']:.4f}")
    # Saturated time: one row per input that sat at a limit in any run.
    late = saturated_after_key()
    saturated = [k for k in dict.fromkeys(k for m in metrics.values()
                                          for k in m.get("saturated_s_total", {}))
                 if any(m.get("saturated_s_total", {}).get(k, 0) > 0 for m in metrics.values())]
    rows.append(("saturated time (s): whole run / after 0.5 s",
                 [""] * len(names) if saturated else ["none"] * len(names)))
    for key in saturated:
        row(f"  {key}", lambda m, k=key: f"{m['saturated_s_total'][k]:.3f} / "
                                         f"{m[late][k]:.3f}")
    row("min sigma_min(J_3)", lambda m: f"{m['min_sigma_min_J3']:.4f}")
    row("min |f_d| (N)", lambda m: f"{m['min_f_d_norm_N']:.1f}")
    for side in ("left", "right"):
        row(f"rotor {side} speed min..max (rad/s)",
            lambda m, s=side: f"{m['rotors'][s]['speed_min_rad_s']:.3f}.."
                              f"{m['rotors'][s]['speed_max_rad_s']:.3f}")
        row(f"rotor {side} drive torque RMS / max (N m)",
            lambda m, s=side: f"{m['rotors'][s]['drive_torque_rms_N_m']:.2f} / "
                              f"{m['rotors'][s]['drive_torque_max_abs_N_m']:.2f}")
    width = max(len(label) for label, _ in rows) + 2
    col = max([12] + [len(c) + 2 for _, cells in rows for c in cells]
              + [len(n) + 2 for n in names])
    lines = [" " * width + "".join(f"{n:>{col}}" for n in names)]
    lines += [f"{label:<{width}}" + "".join(f"{c:>{col}}" for c in cells)
              for label, cells in rows]
    return "\n".join(lines)


def cli_run(args: argparse.Namespace, overrides: dict | None = None) -> int:
    """``aerial-drake run paper [--duration S] [--out DIR] [--seed N] [--quiet] [--json]``;
    ``overrides``: the options already turned into scenario fields (aerial_drake.cli)."""
    out = Path(args.out) / "paper"
    say = sys.stderr if args.json else sys.stdout  # with --json, stdout holds the JSON alone
    print(f"running the paper's scenarios {PAPER_SCENARIOS} -> {out}", file=say, flush=True)
    try:
        result = run_paper(out, seed=getattr(args, "seed", None), progress=not args.quiet,
                           stream=sys.stderr, overrides=overrides)
    except (ScenarioError, UnreachablePose, OutputError) as err:  # ResultsNotWritten: 3
        return report_exception(args, err)
    if result.interrupted is not None:
        reasons = "; ".join(result.failures.values())
        return report_error(args, 128 + result.interrupted, reasons,
                            f"logs up to the interruption are in {out}")
    print(result.table, file=say)
    for path in result.figures:
        if path.suffix == ".png":
            print(f"wrote {path} (and .pdf)", file=say)
    folders = ", ".join(str(out / n) for n in result.runs)
    print(f"wrote {out / 'summary.txt'}; run folders {folders}", file=say)
    if args.json:
        print(strict_json({n: r.metrics for n, r in result.runs.items()}))
    for name, reason in result.failures.items():
        print(f"error: {reason}", file=sys.stderr)
    return 0 if result.completed else 1
