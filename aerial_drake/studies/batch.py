"""Several scenarios run into their own folders, one after the other or in a process pool
(:func:`run_batch`): the batch under ``aerial-drake run paper``
(:mod:`aerial_drake.studies.paper`) and ``aerial-drake compare``
(:mod:`aerial_drake.studies.compare`). The complete runs are loaded with
:func:`aerial_drake.simulation.run_folder.load_run` (no matplotlib)."""

from __future__ import annotations

import concurrent.futures
import multiprocessing
import multiprocessing.connection
import signal
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, TextIO

from aerial_drake.simulation.interrupts import Interrupted, handling, signal_name
from aerial_drake.simulation.run_folder import Run, load_run
from aerial_drake.simulation.runner import SimulationFailed, SimulationInterrupted, run_scenario
from aerial_drake.simulation.scenarios import Scenario

#: Seconds a terminated worker gets to write the logs of its interrupted run before it is killed.
WORKER_STOP_TIMEOUT_S = 60.0
#: Seconds the pool's own thread gets to finish once its workers have exited (it joins them).
POOL_THREAD_STOP_TIMEOUT_S = 10.0


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
    there, as in one process), then waited for and joined: none is left when this returns.
    ``labels[key]``: the progress line's name.
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
    for index, (key, scenario) in enumerate(scenarios.items(), 1):
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
            if say:
                say(f"  [{index}/{len(scenarios)}] "
                    f"{labels.get(key, repr(key))}: {batch.failures.get(key, 'done')}\n")
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
        keys = {future: key for key, future in futures.items()}
        # A line per run as it finishes (in the order they finish), with the count.
        for count, future in enumerate(concurrent.futures.as_completed(keys), 1):
            key = keys[future]
            failure, signum = future.result()
            if failure:
                batch.failures[key] = failure
            if say:
                say(f"  [{count}/{len(keys)}] {labels.get(key, repr(key))}: "
                    f"{failure or 'done'}\n")
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
    writes its logs), wait for them to exit (killed after :data:`WORKER_STOP_TIMEOUT_S`) and
    join them: on return no worker is running and every worker's exit is recorded (none is
    left in ``multiprocessing.active_children()``)."""
    for future in futures.values():
        future.cancel()
    # The executor has no public way to stop its workers before Python 3.14.
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool_thread = getattr(pool, "_executor_manager_thread", None)
    pool.shutdown(wait=False, cancel_futures=True)
    for process in _running(processes, 0.0):  # (by its sentinel: a pid already reaped is
        process.terminate()                   # never signalled, it may be another's now)
    running = _running(processes, WORKER_STOP_TIMEOUT_S)
    for process in running:
        process.kill()
    _running(running, WORKER_STOP_TIMEOUT_S)
    # The pool's own thread joins the workers too. Of two threads waiting for one child, one
    # gets its exit status and the other an error (ECHILD) that leaves the child "alive" to
    # multiprocessing until the first thread records the status, which a loaded machine can
    # delay past our return. So the pool's thread finishes first, then each worker is joined.
    if pool_thread is not None:
        pool_thread.join(POOL_THREAD_STOP_TIMEOUT_S)
    for process in processes:
        process.join(POOL_THREAD_STOP_TIMEOUT_S)


def _running(processes: list[Any], timeout: float) -> list[Any]:
    """Those of ``processes`` that have not exited after waiting up to ``timeout`` seconds for
    all of them (a process's sentinel is ready once it has exited; no status is reaped)."""
    deadline = time.monotonic() + timeout
    pending = {process.sentinel: process for process in processes}
    while pending:
        for sentinel in multiprocessing.connection.wait(
                list(pending), max(0.0, deadline - time.monotonic())):
            del pending[sentinel]
        if time.monotonic() >= deadline:
            break
    return list(pending.values())
