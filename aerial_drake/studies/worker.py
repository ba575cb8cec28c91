"""One study run, as a Dask task (or a plain call): build the scenario from its text, simulate
it, and return its row. Module-level functions only, so Dask pickles them by reference; a
Drake diagram does not pickle, so each worker builds its own from the text.

Workers start warm: :func:`ensure_warm` compiles the numba kernels (or loads them from numba's
on-disk cache) once per process, under a lock file shared by every worker of a machine, so
that the first compiles and writes the cache while the others wait, then load it (a cold
cache compiled by every worker at once costs that many times the memory, and the time). The
compile runs in a child process of the first worker, whose memory goes with it. A study's
results come from the compiled law always (never the reference implementation a cold
``aerial-drake run`` uses: docs/performance.md, "Cold start").

The local cluster's workers preload this module (:func:`dask_setup`): they ignore SIGINT, so
a Ctrl-C in the terminal (sent to every process of the foreground group) reaches only the
study, which cancels the runs and closes the cluster, instead of each worker dying with its
own KeyboardInterrupt traceback.
"""

from __future__ import annotations

import os
import signal
import socket
import time
from pathlib import Path
from typing import Any

from aerial_drake.dynamics.equilibrium import UnreachablePose
from aerial_drake.simulation.kernel_cache import (
    compile_in_child,
    compile_kernels,
    compile_lock,
    kernels_cache_is_cold,
    lock_path,
)
from aerial_drake.simulation.runner import SimulationFailed, SimulationInterrupted, run_scenario
from aerial_drake.simulation.scenarios import ScenarioError
from aerial_drake.studies.metrics_table import flatten_metrics
from aerial_drake.studies.spec import scenario_from_text

_warm: list[bool] = []


def warm_lock_path() -> Path:
    """The machine's lock file for compiling the kernels (one per user;
    :func:`aerial_drake.simulation.kernel_cache.lock_path`)."""
    return lock_path()


def ensure_warm() -> None:
    """Compile or load the numba kernels once in this process, one process of the machine at
    a time (module docstring). On a cold cache the compile runs in a child process
    (:func:`~aerial_drake.simulation.kernel_cache.compile_in_child`), so that the worker,
    which then loads the cache, does not keep the compile's memory (about 200 MB) for all
    its runs; a compile under way (a first ``aerial-drake run``'s in the background) is
    waited for."""
    if _warm:
        return
    with compile_lock():
        if kernels_cache_is_cold():
            compile_in_child()
        compile_kernels()  # loads them
    _warm.append(True)


def dask_setup(worker: Any) -> None:
    """Dask's preload hook, in each local worker process as it starts (module docstring):
    SIGINT is ignored there (the study stops its workers itself)."""
    import threading
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def run_planned(scenario_text: str) -> dict[str, Any]:
    """Run the scenario of ``scenario_text``; its row: ``completed``, ``failure_kind``
    ("" / "simulation": the run failed, e.g. divergence or an assumption violated / "error":
    it could not be built or raised), ``failure``, ``failure_cause`` (the class of a
    "simulation" failure, :mod:`aerial_drake.simulation.failure_cause`), ``wall_time_s``,
    ``worker`` and the flattened metrics (those of the run up to its failure, where it got
    that far)."""
    ensure_warm()
    start = time.perf_counter()
    metrics: dict = {}
    completed, kind, failure = True, "", ""
    try:
        metrics = run_scenario(scenario_from_text(scenario_text), progress=False).metrics
    except SimulationInterrupted:  # (only in a main thread: a plain call) stops the caller
        raise
    except SimulationFailed as err:
        completed, kind, failure = False, "simulation", _one_line(str(err))
        if err.result is not None:
            metrics = err.result.metrics
    except (ScenarioError, UnreachablePose) as err:
        completed, kind, failure = False, "error", _one_line(f"{type(err).__name__}: {err}")
    except Exception as err:  # noqa: BLE001 - a run's bug is its row, never the study's end
        completed, kind, failure = False, "error", _one_line(f"{type(err).__name__}: {err}")
    cause = metrics.get("failure_cause") or {}
    return {"completed": completed, "failure_kind": kind, "failure": failure,
            "failure_cause": cause.get("cause", "") if kind == "simulation" else "",
            "wall_time_s": time.perf_counter() - start,
            "worker": f"{socket.gethostname()}:{os.getpid()}", **flatten_metrics(metrics)}


def peak_memory_mb() -> float:
    """This process's peak resident memory (MB), for the benchmark."""
    import resource
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
