"""A time limit on the user's code run at load (``kind: python``): a function that never
returns would otherwise hang the load with no output.

:func:`time_limit` arms the process's real-time interval timer (``SIGALRM``) in the main
thread, so no thread is started and none is left behind; elsewhere (a worker thread, a
platform without ``setitimer``) it imposes no limit. The timer interrupts Python code only: a
call blocked inside C code is interrupted when it returns to Python.
"""

from __future__ import annotations

import contextlib
import signal
import threading
import time
from collections.abc import Iterator

__all__ = ["TimeLimitExceeded", "time_limit"]


class TimeLimitExceeded(BaseException):
    """The code under :func:`time_limit` ran past its limit. A BaseException (as
    KeyboardInterrupt is), so the user's own ``except Exception`` cannot swallow it."""


@contextlib.contextmanager
def time_limit(seconds: float, what: str) -> Iterator[None]:
    """Raise :class:`TimeLimitExceeded` ("``what`` did not return within ``seconds`` s") in
    the code of the ``with`` block once it has run ``seconds``; the previous SIGALRM handler
    and any timer already armed (less the time spent here) are restored on the way out."""
    if (threading.current_thread() is not threading.main_thread()
            or not hasattr(signal, "setitimer")):
        yield
        return

    def expired(signum, frame):
        raise TimeLimitExceeded(f"{what} did not return within {seconds:g} s")

    previous = signal.signal(signal.SIGALRM, expired)
    outer_delay, outer_interval = signal.setitimer(signal.ITIMER_REAL, seconds)
    start = time.monotonic()
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)
        if outer_delay > 0.0:
            left = outer_delay - (time.monotonic() - start)
            signal.setitimer(signal.ITIMER_REAL, max(left, 1e-6), outer_interval)
