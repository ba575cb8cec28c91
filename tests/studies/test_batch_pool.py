"""Tests of how run_batch stops its process pool on a signal (aerial_drake.studies.batch):
when the stop returns, every worker has exited and been joined, whatever the timing of the
pool's own thread, which joins the same workers."""

import concurrent.futures
import multiprocessing
import os
import threading
import time

from aerial_drake.studies import batch


def test_the_stop_returns_with_every_worker_joined_when_the_pool_reaps_late(monkeypatch):
    """The pool's thread and the stop both join the workers; of two threads waiting for one
    child, one gets its exit status and the other an error (ECHILD) that leaves the child
    "alive" until the first records it. Here the pool's thread reaps first and records late
    (as a loaded machine can delay it): the stop still returns only once each worker's exit
    is recorded, so none is left in multiprocessing.active_children()."""
    real_waitpid = os.waitpid

    def waitpid(pid, options):
        if threading.current_thread() is threading.main_thread():
            if options == 0:  # a blocking wait here: the pool's thread reaps first
                time.sleep(0.2)
            return real_waitpid(pid, options)
        reaped = real_waitpid(pid, options)
        if reaped[0] == pid:  # the pool's thread got the status: it records it late
            time.sleep(1.5)
        return reaped

    before = set(multiprocessing.active_children())
    pool = concurrent.futures.ProcessPoolExecutor(
        2, mp_context=multiprocessing.get_context("spawn"))
    futures = {str(k): pool.submit(time.sleep, 60) for k in range(3)}
    workers = set(multiprocessing.active_children()) - before
    assert len(workers) == 2
    monkeypatch.setattr(os, "waitpid", waitpid)
    batch._stop_pool(pool, futures)
    assert {w.name: w.exitcode for w in workers if w.exitcode is None} == {}
    # Terminated by a signal, not waited out (a worker that finished its 60 s runs would
    # have exited with 0): no bound on the wall time, which would depend on the machine.
    assert all(w.exitcode < 0 for w in workers), {w.name: w.exitcode for w in workers}
    assert not workers & set(multiprocessing.active_children())
    assert futures["2"].cancelled() or futures["2"].done()
