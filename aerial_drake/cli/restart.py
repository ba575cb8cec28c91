"""On the first run after installing (numba's cache cold): :func:`compile_first` for the
commands whose results must be those of every later run (``run paper``, ``compare``): wait
for the compiled kernels, then restart the command; :func:`cold_start` for ``run SCENARIO``:
go on at once on the reference implementation while the cache is built in the background
(:mod:`aerial_drake.simulation.kernel_cache`)."""

from __future__ import annotations

import contextlib
import os
import sys
from typing import Callable, Iterator

# Set in the restarted process, so that it never restarts again.
RESTARTED = "AERIAL_DRAKE_RESTARTED_AFTER_COMPILE"


def compile_first(restartable: bool, law_kernels: tuple[str, ...] = ()) -> None:
    """On the first run after installing, compile the numba kernels, then restart the command.

    numba keeps what compiling the control law allocated (about 200 MB) for the rest of the
    process: compiled in the middle of a run, it stays under everything the run allocates
    after it, and that first run peaked near 600 MB against 300-400 MB for every later one
    (docs/performance.md, Memory). So the command compiles first, before the run builds
    anything, and re-executes itself exactly as it was started (``sys.orig_argv``: the same
    script or ``-m``, so the same installed package and cache; same process id); the run
    proper then loads the cached machine code like any later run. A compile under way (a
    first ``run SCENARIO``'s in the background) is waited for instead, and then nothing is
    left to compile here: no restart. A line every few seconds while it compiles or waits.
    Nothing to do when the cache is warm, when ``restartable`` is false
    (:func:`aerial_drake.cli.main` called from Python with arguments: never replace a
    caller's process), or off POSIX; if the cache could not be written, the run goes on
    here. ``law_kernels``: the run's law kernels beyond the default (a scenario's
    ``controller.kernel``, :func:`aerial_drake.simulation.kernel_cache.compile_kernels`)."""
    if not restartable or os.environ.get(RESTARTED) or os.name != "posix":
        return
    from aerial_drake.simulation import kernel_cache
    if not kernel_cache.kernels_cache_is_cold(law_kernels):
        return
    with kernel_cache.compile_lock(stream=sys.stderr):  # waits for a compile under way
        if not kernel_cache.kernels_cache_is_cold(law_kernels):
            return
        # (compile_law's own note says what and why, once)
        with kernel_cache.Ticker(sys.stderr, "aerial_drake: compiling"):
            kernel_cache.compile_kernels(law_kernels)
    if kernel_cache.kernels_cache_is_cold(law_kernels):
        return
    print("aerial_drake: compiled and cached; restarting the command to run with the cached "
          "code", file=sys.stderr, flush=True)
    sys.stdout.flush()
    os.environ[RESTARTED] = "1"
    os.execv(sys.executable, [sys.executable, *sys.orig_argv[1:]])


@contextlib.contextmanager
def cold_start(wait: bool, stream, law_kernels: tuple[str, ...] = ()
               ) -> Iterator[Callable[[], None]]:
    """The block of a ``run SCENARIO``: on a cold cache (and not ``wait``), start the compile
    in the background, say so on ``stream``, and run the block on the reference
    implementation (:func:`aerial_drake.simulation.kernel_cache.reference_implementations`;
    ``metrics.json`` says ``control_law``); yields ``note()``, which says at the end whether
    the compile has finished. Warm, or ``wait``: nothing here (``wait``: the caller ran
    :func:`compile_first`). ``law_kernels``: as :func:`compile_first`'s."""
    from aerial_drake.simulation import kernel_cache
    if wait:
        yield lambda: None
        return
    warm, note = kernel_cache.warm_or_started(stream, law_kernels)
    if warm:
        yield note
        return
    try:
        with kernel_cache.reference_implementations(kernel_cache.COLD_REASON):
            yield note
    finally:  # the run is over (however it ended): the compile may use the CPU now
        kernel_cache.release_background_compile()
