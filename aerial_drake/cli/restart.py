"""On the first run after installing: compile the numba kernels, then restart the command
(:func:`compile_first`)."""

from __future__ import annotations

import os
import sys

# Set in the restarted process, so that it never restarts again.
RESTARTED = "AERIAL_DRAKE_RESTARTED_AFTER_COMPILE"


def compile_first(restartable: bool) -> None:
    """On the first run after installing, compile the numba kernels, then restart the command.

    numba keeps what compiling the control law allocated (about 200 MB) for the rest of the
    process: compiled in the middle of a run, it stays under everything the run allocates
    after it, and that first run peaked near 600 MB against 300-400 MB for every later one
    (docs/performance.md, Memory). So the command compiles first, before the run builds
    anything, and re-executes itself exactly as it was started (``sys.orig_argv``: the same
    script or ``-m``, so the same installed package and cache; same process id); the run
    proper then loads the cached machine code like any later run. Nothing to do when the
    cache is warm, when ``restartable`` is false (:func:`aerial_drake.cli.main` called from
    Python with arguments: never replace a caller's process), or off POSIX; if the cache
    could not be written, the run goes on here."""
    if not restartable or os.environ.get(RESTARTED) or os.name != "posix":
        return
    from aerial_drake.control.compiled import law_cache_is_cold
    from aerial_drake.simulation.runner import compile_kernels
    if not law_cache_is_cold():
        return
    compile_kernels()  # says on stderr that it compiles
    if law_cache_is_cold():
        return
    print("aerial_drake: compiled and cached; restarting the command to run with the cached "
          "code", file=sys.stderr, flush=True)
    sys.stdout.flush()
    os.environ[RESTARTED] = "1"
    os.execv(sys.executable, [sys.executable, *sys.orig_argv[1:]])
