"""Catching the live view: wait for a browser before the simulation starts, hold the page after.

``aerial-drake run SCENARIO --meshcat`` prints the URL once, then :func:`wait_for_browser`
holds the start of the simulation until a browser has the page open (Drake's
``Meshcat.GetNumActiveConnections()``: open websockets, so a plain HTTP fetch does not count),
or until a timeout, after which the run starts anyway (the replay is written either way).
``--no-wait`` skips the wait. With ``--hold``, :func:`hold` keeps the server up after the run,
so the page (now with the recording under Open Controls > Animations) stays reachable until
Ctrl-C.

Drake itself logs "Meshcat listening for connections at URL" when a server starts;
:func:`quiet_drake_info` mutes that one line, so the command line prints the URL once.
"""

from __future__ import annotations

import contextlib
import logging
import time
from typing import Callable, Iterator, TextIO

#: Default seconds to wait for a browser (``--wait-timeout``).
WAIT_TIMEOUT_S = 120.0
#: Seconds between two looks at the number of connections.
POLL_S = 0.05


@contextlib.contextmanager
def quiet_drake_info() -> Iterator[None]:
    """Drake's Python log (``logging.getLogger("drake")``) at WARNING inside the block."""
    logger = logging.getLogger("drake")
    level = logger.level
    logger.setLevel(logging.WARNING)
    try:
        yield
    finally:
        logger.setLevel(level)


def wait_for_browser(meshcat, *, timeout: float = WAIT_TIMEOUT_S, stream: TextIO | None = None,
                     clock: Callable[[], float] = time.monotonic, poll: float = POLL_S) -> bool:
    """Block until ``meshcat`` has a browser connected, or ``timeout`` seconds passed; True if
    one connected. Says what it waits for, and what happened, on ``stream``."""

    def say(message: str) -> None:
        if stream is not None:
            stream.write(message + "\n")
            stream.flush()

    if meshcat.GetNumActiveConnections() > 0:
        say("Meshcat: a browser is connected; starting the simulation")
        return True
    say(f"Meshcat: waiting up to {timeout:g} s for a browser to open the page before the "
        "simulation starts (--no-wait starts at once; Ctrl-C stops)")
    deadline = clock() + timeout
    while clock() < deadline:
        if meshcat.GetNumActiveConnections() > 0:
            say("Meshcat: a browser connected; starting the simulation")
            return True
        time.sleep(poll)
    say(f"Meshcat: no browser connected within {timeout:g} s; starting the simulation anyway "
        "(the replay is written at the end)")
    return False


def hold(meshcat, *, stream: TextIO | None = None, poll: float = 0.5) -> None:
    """Keep serving ``meshcat`` until Ctrl-C (KeyboardInterrupt, caught here)."""
    try:  # the message inside: a Ctrl-C right after it is caught too
        if stream is not None:
            stream.write("Meshcat: the finished run stays on the page (Open Controls > "
                         "Animations replays it); Ctrl-C to stop\n")
            stream.flush()
        while True:
            time.sleep(poll)
    except KeyboardInterrupt:
        if stream is not None:
            stream.write("Meshcat: stopped\n")
