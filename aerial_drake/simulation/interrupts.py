"""SIGINT, SIGTERM and SIGHUP stop a run the same way: as :class:`Interrupted` (a
``KeyboardInterrupt``) raised where the run is, so the runner writes what was logged and the
command line exits 128 + the signal's number.

While the results are being written (:func:`deferred`) a signal is held, not raised: the
files are finished first, then the run stops (a Ctrl-C after the simulation never loses
``metrics.json``). Handlers are installed only in the main thread and restored afterwards
(:func:`handling`), so a caller's own handlers come back when a run returns.
"""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager
from typing import Any, Iterator

#: The signals that stop a run (SIGHUP: the terminal closed).
STOP_SIGNALS = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP")
                     if hasattr(signal, name))


class Interrupted(KeyboardInterrupt):
    """A run stopped by a signal; ``signum`` is its number (SIGINT for a plain Ctrl-C)."""

    def __init__(self, signum: int = signal.SIGINT) -> None:
        super().__init__(signal_name(signum))
        self.signum = signum

    @property
    def exit_status(self) -> int:
        return 128 + self.signum


def signal_name(signum: int) -> str:
    try:
        name = signal.Signals(signum).name
    except ValueError:
        name = f"signal {signum}"
    return "Ctrl-C" if name == "SIGINT" else name


def exit_status_of(err: BaseException) -> int:
    """128 + the signal's number for an interruption (130 for a bare KeyboardInterrupt)."""
    return getattr(err, "exit_status", 128 + signal.SIGINT)


_state: dict[str, Any] = {"depth": 0, "defer": 0, "pending": None, "saved": {}}


def _handler(signum: int, frame: Any) -> None:
    if _state["defer"]:
        if _state["pending"] is None:
            _state["pending"] = signum
        return
    raise Interrupted(signum)


@contextmanager
def handling() -> Iterator[None]:
    """Stop on SIGINT, SIGTERM and SIGHUP by raising :class:`Interrupted` (nestable; only in
    the main thread, elsewhere a no-op)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    if _state["depth"] == 0:
        _state["saved"] = {s: signal.signal(s, _handler) for s in STOP_SIGNALS}
    _state["depth"] += 1
    try:
        yield
    finally:
        _state["depth"] -= 1
        if _state["depth"] == 0:
            for s, previous in _state["saved"].items():
                signal.signal(s, previous)
            _state["saved"] = {}


@contextmanager
def deferred() -> Iterator[list[int]]:
    """Hold stop signals inside the block; yields a list that holds the held signal's number
    afterwards (empty if none came). The caller decides what to do with it."""
    held: list[int] = []
    _state["defer"] += 1
    try:
        yield held
    finally:
        _state["defer"] -= 1
        if _state["pending"] is not None:
            held.append(_state["pending"])
            if _state["defer"] == 0:
                _state["pending"] = None
