"""Running a study's runs on Dask (``dask.distributed``): a local cluster by default, or any
cluster by its scheduler's address.

The local cluster is ``LocalCluster(n_workers=N, threads_per_worker=1, processes=True)``:
processes, one thread each, because Drake diagrams do not pickle and Python systems hold the
GIL; each task carries its scenario as text and the worker builds its own diagram
(:mod:`aerial_drake.studies.worker`). Its scheduler allows one failure per task
(``distributed.scheduler.allowed-failures: 1``): a worker that dies is replaced by its nanny
and the run it held is retried once on a live worker, then reported as ``KilledWorker`` and
recorded as failed (kind "worker"). A cluster of your own (``--scheduler``) keeps its own
setting: start its scheduler with ``DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES=1`` for the
same rule (docs/studies.md).
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable, Iterator
from concurrent.futures import CancelledError
from contextlib import contextmanager
from typing import Any

from aerial_drake.studies.spec import PlannedRun
from aerial_drake.studies.worker import ensure_warm, run_planned

#: Retries of a run whose worker died, on the local cluster (module docstring).
ALLOWED_FAILURES = 1
#: Where Drake keeps every run's diagram alive (drake 1.51.1: aerial_drake.drake_compat), the
#: local cluster's workers retire and restart after about this long (s, staggered by
#: WORKER_LIFETIME_STAGGER_S so they do not all restart at once), Dask's ``lifetime``: a
#: worker grows about 5 MB per run (some 2.5 MB per second of 15 s runs), so some 500 MB
#: before it restarts, instead of 1 GB per 200 runs; a restart costs a few seconds (the
#: numba cache loads). Dask reschedules a run a retiring worker held: it is recorded once.
WORKER_LIFETIME_S = 180.0
WORKER_LIFETIME_STAGGER_S = 30.0
#: How long a scheduler given by its address has to answer (s): a wrong address fails fast.
CONNECT_TIMEOUT_S = 10


class ClusterError(OSError):
    """The scheduler at the address given cannot be reached (found before any run)."""


def _connect(scheduler: str) -> Any:
    from distributed import Client
    try:
        return Client(scheduler, timeout=f"{CONNECT_TIMEOUT_S}s")
    except (OSError, TimeoutError, ValueError, TypeError) as err:
        reason = " ".join(str(err).split()) or type(err).__name__
        raise ClusterError(
            f"--scheduler {scheduler}: no Dask scheduler answered there within "
            f"{CONNECT_TIMEOUT_S} s ({reason[:200]}); nothing was run: check the address "
            "(e.g. tcp://HOST:8786) and that the scheduler is running ('dask scheduler'), "
            "or leave out --scheduler for a local cluster") from None


@contextmanager
def study_client(workers: int | None = None,
                 scheduler: str | None = None) -> Iterator[tuple[Any, dict[str, Any]]]:
    """A Dask client on a new local cluster of ``workers`` processes (default: one per CPU)
    or on the scheduler at ``scheduler`` (ClusterError if it does not answer within
    CONNECT_TIMEOUT_S); yields ``(client, description)``. Every worker is
    warmed (:func:`~aerial_drake.studies.worker.ensure_warm`) before it takes a run. The
    local cluster is closed on the way out, whatever happened."""
    import dask
    from distributed import Client, LocalCluster

    if scheduler is not None:
        client = _connect(scheduler)
        cluster = None
    else:
        n = workers or os.cpu_count() or 1
        with dask.config.set({"distributed.scheduler.allowed-failures": ALLOWED_FAILURES}):
            # Each worker preloads the worker module: it ignores Ctrl-C (worker.dask_setup).
            # Its logs are silenced below CRITICAL: when a signal stops the study, a worker's
            # heartbeat to the closing scheduler fails and distributed logs that as an ERROR
            # with a traceback (seen with Python 3.12 and distributed 2026); a run's own
            # errors are its row, and a dead worker is KilledWorker, so nothing is lost.
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                   dashboard_address=None, silence_logs=logging.CRITICAL,
                                   preload=["aerial_drake.studies.worker"],
                                   **worker_lifetime())
        client = Client(cluster)
    try:
        _warm_workers(client)
        info = {"scheduler": scheduler or "local",
                "workers": len(client.scheduler_info()["workers"]),
                "threads_per_worker": 1 if scheduler is None else None}
        yield client, info
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def worker_lifetime() -> dict[str, Any]:
    """The local cluster's worker ``lifetime`` options where the installed Drake keeps every
    run's diagram alive (:data:`WORKER_LIFETIME_S`), else none."""
    from aerial_drake.drake_compat import python_systems_outlive_diagrams
    if not python_systems_outlive_diagrams():
        return {}
    return {"lifetime": f"{WORKER_LIFETIME_S}s",
            "lifetime_stagger": f"{WORKER_LIFETIME_STAGGER_S}s", "lifetime_restart": True}


def _warm_workers(client: Any) -> None:
    """Every worker warm (:func:`~aerial_drake.studies.worker.ensure_warm`): one worker of a
    machine compiles, the others then load. On a cold cache here, a line every few seconds
    on stderr while it compiles (about a minute; a remote worker host pays it too, once)."""
    import sys

    from aerial_drake.simulation.kernel_cache import Ticker, kernels_cache_is_cold
    if not kernels_cache_is_cold():
        client.run(ensure_warm)
        return
    with Ticker(sys.stderr, "aerial_drake: the workers compile the numba kernels (first use "
                            "on this machine; cached afterwards)"):
        client.run(ensure_warm)


def _failed_row(kind: str, message: str) -> dict[str, Any]:
    return {"completed": False, "failure_kind": kind, "failure": " ".join(message.split())}


def execute(client: Any, runs: list[PlannedRun],
            on_row: Callable[[PlannedRun, dict[str, Any]], None]) -> None:
    """Submit ``runs`` and call ``on_row(run, row)`` as each finishes, in the order they
    finish. A signal (KeyboardInterrupt) cancels the runs not finished and is raised again;
    the rows already given are the caller's to keep."""
    from distributed import KilledWorker, as_completed

    futures = {client.submit(run_planned, run.scenario_text, pure=False): run for run in runs}
    try:
        for future in as_completed(futures):
            run = futures[future]
            try:
                row = future.result()
            except KilledWorker as err:
                row = _failed_row("worker", f"its worker died while running it, twice "
                                  f"(retried once): {err}")
            except CancelledError as err:  # (distributed's FutureCancelledError)
                row = _failed_row("worker", f"cancelled by the cluster: {err}")
            except Exception as err:  # noqa: BLE001 - the task's own error, as its row
                row = _failed_row("error", f"{type(err).__name__}: {err}")
            on_row(run, row)
    finally:
        pending = [f for f in futures if not f.done()]
        if pending:
            client.cancel(pending)
