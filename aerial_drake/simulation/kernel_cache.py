"""numba's cache of the kernels a run calls: whether it is warm, compiling it one process of
the machine at a time (here, in a child process, or in the background), and the reference
implementations for a run that must not wait for it.

The first use after installing compiles the control law, its tracking errors and the paper
reference (about 35 s of one core on this project's 2-core machine, up to a minute loaded;
docs/performance.md, "Cold start"). numba writes each kernel's cache as a data file and an
index, each to a temporary name then renamed (``numba.core.caching``), so a compile stopped
at any point (Ctrl-C, a kill) leaves a cache numba can use: complete entries load, a missing
one compiles again; :func:`kernels_cache_is_cold` reads it the same way.

Who waits for the compile:

- ``aerial-drake run SCENARIO`` does not (unless ``--wait-compile``): it starts
  :func:`start_background_compile`, which compiles once the run has ended, and runs at once
  on the reference implementations (:func:`reference_implementations`: the law and
  the tracking errors in numpy and Drake, the paper reference interpreted), which agree with
  the compiled law to round-off, not to the bit; its output and ``metrics.json``
  (``control_law``) say so. Later runs load the compiled kernels.
- ``aerial-drake run paper``, ``compare`` and the study workers do: their results must be
  those of every later run, to the bit. They wait for a compile under way (a line every few
  seconds), else compile themselves.

One compile at a time per cache and user: :func:`compile_lock` (an ``flock`` on a file in the
temporary directory, released by the system when its holder exits however it exits).
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Callable, Iterator, TextIO

from aerial_drake.control.compiled.law import (
    LAW_KERNELS,
    compile_law,
    is_cached,
    law_cache_is_cold,
    use_reference_law,
)
from aerial_drake.trajectories.paper import (
    REFERENCE_KERNELS,
    compile_reference,
    use_interpreted_reference,
)

#: Why a run on a cold cache runs the reference implementations (metrics.json's
#: ``control_law`` says "reference" and this).
COLD_REASON = ("numba's cache is cold (first run after installing); the compiled law is built "
               "in the background after this run")


def compile_kernels(law_kernels: tuple[str, ...] = ()) -> None:
    """Compile, or load from numba's cache, every numba kernel a run calls from Python: the
    control law and the reference's, and the law kernels named in ``law_kernels`` (a
    scenario's ``controller.kernel``, e.g. ``("fast",)``: compiled only for a run that chooses
    it). From their argument types alone, so before any model is built; the command line
    calls this on the first run after installing and then restarts itself
    (``aerial_drake.cli.restart``)."""
    compile_law(law_kernels)
    compile_reference()


def kernels_cache_is_cold(law_kernels: tuple[str, ...] = ()) -> bool:
    """Whether any kernel :func:`compile_kernels` compiles (with ``law_kernels``) would compile
    rather than load (:func:`aerial_drake.control.compiled.is_cached`)."""
    return law_cache_is_cold(law_kernels) or not all(
        is_cached(kernel, signature) for kernel, signature in REFERENCE_KERNELS)


def _cache_tag() -> str:
    """A short name of where numba caches the law (next to the installed package, or under
    ``NUMBA_CACHE_DIR``): one lock per cache, so that compiles of different installs or
    cache folders never wait for each other."""
    try:
        # numba's internals (untyped): guarded by the except below.
        where = str(LAW_KERNELS[0][0]._cache._cache_path)  # type: ignore[attr-defined]
    except AttributeError:
        where = str(Path(__file__).resolve().parents[1])
    return hashlib.sha1(where.encode()).hexdigest()[:10]


def lock_path() -> Path:
    """The lock file for compiling the kernels into this process's cache (one per user and
    cache, in the temporary directory)."""
    return Path(tempfile.gettempdir()) / f"aerial_drake_kernels_{os.getuid()}_{_cache_tag()}.lock"


def log_path() -> Path:
    """Where the background compile writes what it did (one per user and cache, appended)."""
    return Path(tempfile.gettempdir()) / f"aerial_drake_compile_{os.getuid()}_{_cache_tag()}.log"


def _holder(lock) -> str:
    """The process id the lock's holder wrote into the lock file ("" if none)."""
    lock.seek(0)
    return lock.read().strip()


@contextlib.contextmanager
def compile_lock(wait: bool = True, stream: TextIO | None = None) -> Iterator[bool]:
    """Hold the machine's compile lock; yields whether it is held (False only with ``wait``
    false and another process holding it). While waiting, a line on ``stream`` every few
    seconds (:class:`Ticker`) names the holder."""
    with open(lock_path(), "a+") as lock:
        try:
            fcntl.flock(lock.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            if not wait:
                yield False
                return
            pid = _holder(lock)
            with Ticker(stream, f"aerial_drake: waiting for the numba compile under way "
                                f"(process {pid or '?'}; log {log_path()})"):
                fcntl.flock(lock.fileno(), fcntl.LOCK_EX)
        try:
            lock.seek(0)
            lock.truncate()
            lock.write(str(os.getpid()))
            lock.flush()
            yield True
        finally:
            fcntl.flock(lock.fileno(), fcntl.LOCK_UN)


def compile_is_under_way() -> bool:
    """Whether another process holds the compile lock now (a probe: takes and drops it)."""
    with open(lock_path(), "a+") as lock:
        try:
            fcntl.flock(lock.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return True
        fcntl.flock(lock.fileno(), fcntl.LOCK_UN)
        return False


class Ticker:
    """A context manager that says ``label`` with the seconds elapsed on ``stream`` (None:
    nothing) every ``every`` s from a thread while the block runs (numba's compile and a
    lock's wait leave the thread its turns): on a terminal one line rewritten, else one line
    per report. Says how long it took at the end."""

    def __init__(self, stream: TextIO | None, label: str, every: float = 5.0) -> None:
        self.stream, self.label = stream, label
        tty = stream is not None and getattr(stream, "isatty", lambda: False)()
        self.every = 1.0 if tty else every
        self._start_of_line = "\r" if tty else ""
        self._end_of_line = "" if tty else "\n"
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self.start = 0.0

    def _say(self, text: str) -> None:
        if self.stream is not None:
            self.stream.write(f"{self._start_of_line}{self.label} ... {text}"
                              f"{self._end_of_line}")
            self.stream.flush()

    def _run(self) -> None:
        while not self._stop.wait(self.every):
            self._say(f"{time.perf_counter() - self.start:.0f} s")

    def __enter__(self) -> Ticker:
        self.start = time.perf_counter()
        self._say("")
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join()
        took = time.perf_counter() - self.start
        self._say(f"{'done' if exc[0] is None else 'stopped'} ({took:.0f} s)")
        if self._end_of_line == "" and self.stream is not None:
            self.stream.write("\n")


def _python_for_this_package(statement: str) -> list[str]:
    """A command running ``statement`` with this very package first on the path (not one a
    working directory's source tree would shadow: the same installed files, so the same
    cache)."""
    root = str(Path(__file__).resolve().parents[2])
    return [sys.executable, "-c", f"import sys; sys.path.insert(0, {root!r}); {statement}"]


#: The background compile's program (:func:`start_background_compile`), standard library
#: only until it compiles: it takes the cache's lock at once (so that a second cold run
#: starts none), drops to the lowest priority, waits for the end of its standard input,
#: which comes when the run that started it ends (:func:`release_background_compile`) or
#: its process exits however it exits (so that the two never compete for the CPU), then
#: imports this package and compiles.
_BACKGROUND = """
import fcntl, os, signal, sys, time
signal.signal(signal.SIGHUP, signal.SIG_IGN)
os.nice(19)
lock = open({lock!r}, "a+")
fcntl.flock(lock.fileno(), fcntl.LOCK_EX)
lock.seek(0); lock.truncate(); lock.write(str(os.getpid())); lock.flush()
print(time.strftime("%Y-%m-%d %H:%M:%S"), "process", os.getpid(), "waits for the run of",
      {parent}, "to end", flush=True)
sys.stdin.read()
sys.path.insert(0, {root!r})
from aerial_drake.simulation.kernel_cache import background_compile
background_compile({law_kernels!r})
"""

#: The background compiles this process started (kept so that Python does not warn about a
#: child still running when the object is collected; nobody waits for them).
_STARTED: list[subprocess.Popen] = []


def start_background_compile(law_kernels: tuple[str, ...] = ()) -> int | None:
    """Start the compile in a process of its own (:data:`_BACKGROUND`), detached from the
    terminal's signals (its own process group: a Ctrl-C in the terminal does not stop it;
    it ignores SIGHUP): it compiles once this process calls
    :func:`release_background_compile` or ends, at the lowest priority, and then exits (30 s
    to a minute); its output is appended to :func:`log_path`. Returns its
    process id, or None where a compile is already under way. ``law_kernels``: as
    :func:`compile_kernels`'s.

    Not a session of its own: Linux's scheduler gives each session (autogroup) an equal
    share of the CPU whatever its processes' nice values, so a compile in a session of its
    own would take as much of a busy machine as the runs after it; in the run's session its
    nice value holds (docs/performance.md, "Cold start")."""
    if compile_is_under_way():
        return None
    program = _BACKGROUND.format(lock=str(lock_path()), parent=os.getpid(),
                                 root=str(Path(__file__).resolve().parents[2]),
                                 law_kernels=tuple(law_kernels))
    group = ({"process_group": 0} if sys.version_info >= (3, 11)
             else {"preexec_fn": os.setpgrp})
    with open(log_path(), "ab") as log:
        child = subprocess.Popen(
            [sys.executable, "-c", program], stdin=subprocess.PIPE, stdout=log,
            stderr=subprocess.STDOUT, close_fds=True, **group)  # type: ignore[call-overload]
    _STARTED.append(child)
    return child.pid


def release_background_compile() -> None:
    """Let the background compiles this process started begin (the run is over): close
    their standard input. (The system closes it too when this process exits.)"""
    for child in _STARTED:
        if child.stdin is not None and not child.stdin.closed:
            child.stdin.close()


def background_compile(law_kernels: tuple[str, ...] = ()) -> None:
    """The background compile's work, its lock held (:data:`_BACKGROUND`): compile if the
    cache is still cold (another process may have compiled it meanwhile)."""
    if not kernels_cache_is_cold(law_kernels):
        print(f"process {os.getpid()}: the cache is warm already", flush=True)
        return
    print(f"{time.strftime('%Y-%m-%d %H:%M:%S')} process {os.getpid()}: compiling the "
          "kernels", flush=True)
    start = time.perf_counter()
    compile_kernels(law_kernels)
    print(f"process {os.getpid()}: done in {time.perf_counter() - start:.1f} s; cache "
          f"{'still cold' if kernels_cache_is_cold(law_kernels) else 'warm'}", flush=True)


def compile_in_child(stream: TextIO | None = None) -> None:
    """Compile the kernels in a child process and wait for it (a line every few seconds on
    ``stream``), so that this process, which then loads them, does not keep the compile's
    memory (about 200 MB, docs/performance.md, "Memory"): for long-lived processes (study
    workers). Falls back to compiling here if the child fails."""
    with Ticker(stream, "aerial_drake: compiling the numba kernels (first use on this "
                        "machine; cached afterwards)"):
        done = subprocess.run(_python_for_this_package(
            "from aerial_drake.simulation.kernel_cache import compile_kernels; "
            "compile_kernels()"), stdin=subprocess.DEVNULL, capture_output=True)
    if done.returncode != 0 or kernels_cache_is_cold():
        compile_kernels()


@contextlib.contextmanager
def reference_implementations(reason: str) -> Iterator[None]:
    """In the block, this process builds runs on the reference implementations: controllers
    and tracking errors (:func:`aerial_drake.control.compiled.use_reference_law`) and the
    paper reference (interpreted, :func:`aerial_drake.trajectories.paper.
    use_interpreted_reference`); nothing compiles. Restored after it."""
    use_reference_law(reason)
    use_interpreted_reference(True)
    try:
        yield
    finally:
        use_reference_law(None)
        use_interpreted_reference(False)


def warm_or_started(stream: TextIO | None, law_kernels: tuple[str, ...] = ()
                    ) -> tuple[bool, Callable[[], None]]:
    """For a run that need not wait (module docstring): ``(True, nothing)`` when the cache is
    warm; else start the background compile (or find one under way), say so on ``stream``,
    and return ``(False, note)``, ``note()`` saying at the end of the run whether the compile
    has finished. ``law_kernels``: the run's law kernels beyond the default
    (:func:`compile_kernels`)."""
    if not kernels_cache_is_cold(law_kernels):
        return True, lambda: None
    pid = start_background_compile(law_kernels)
    if stream is not None:
        when = (f"when this run ends (process {pid})" if pid is not None
                else "by a compile already under way")
        stream.write("aerial_drake: numba's cache is cold (first run after installing): this "
                     "run uses the reference implementation of the law (numpy; the compiled "
                     "law's results to round-off, not to the bit); the compiled law is built "
                     f"in the background {when}; log {log_path()}\n")
        stream.flush()

    def note() -> None:
        if stream is None:
            return
        if pid is not None:
            state = ("starts now (30 s to a minute, at the lowest priority); runs started "
                     "before it has finished use the reference implementation too")
        elif kernels_cache_is_cold(law_kernels) or compile_is_under_way():
            state = "still under way"
        else:
            state = "done: later runs use the compiled law"
        stream.write(f"aerial_drake: the background compile {state}\n")
        stream.flush()

    return False, note
