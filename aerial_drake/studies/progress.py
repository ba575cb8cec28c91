"""A study's progress bar on stderr: runs done of the total, how many failed, the rate and
the estimated time left (from this session's runs alone: a resumed study's earlier rows say
nothing of this cluster's speed)."""

from __future__ import annotations

import time
from typing import TextIO


def _duration(seconds: float) -> str:
    seconds = max(0, int(round(seconds)))
    hours, rest = divmod(seconds, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}h{minutes:02d}m" if hours else f"{minutes}m{secs:02d}s"


class StudyProgress:
    """``[#####-----] 45/200 runs, 2 failed, 12.0 runs/min, 13m00s left``: rewritten in place
    on a terminal, one line per run in a log file."""

    WIDTH = 30

    def __init__(self, total: int, done: int, failed: int, stream: TextIO | None) -> None:
        self.total, self.done, self.failed = total, done, failed
        self._first_done = done
        self.stream = stream
        isatty = getattr(stream, "isatty", None)
        self._terminal = bool(isatty and isatty())
        self._start = time.perf_counter()

    def line(self) -> str:
        filled = self.WIDTH * self.done // max(1, self.total)
        bar = "#" * filled + "-" * (self.WIDTH - filled)
        ran = self.done - self._first_done
        elapsed = time.perf_counter() - self._start
        if ran > 0 and elapsed > 0:
            rate = ran / elapsed
            pace = f", {60 * rate:.1f} runs/min, {_duration((self.total - self.done) / rate)} left"
        else:
            pace = ", estimating time left"
        return f"[{bar}] {self.done}/{self.total} runs, {self.failed} failed{pace}"

    def update(self, completed: bool | None = None) -> None:
        """Count one more run (``completed`` False: a failed one), then show the bar; with
        None, only show it."""
        if completed is not None:
            self.done += 1
            self.failed += 0 if completed else 1
        if self.stream is None:
            return
        if self._terminal:
            self.stream.write(f"\r{self.line()}")
        else:
            self.stream.write(f"{self.line()}\n")
        self.stream.flush()

    def close(self) -> None:
        if self.stream is not None and self._terminal:
            self.stream.write("\n")
            self.stream.flush()
