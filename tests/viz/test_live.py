"""Catching the live view: ``run --meshcat`` waits for a browser before the simulation starts,
``--no-wait`` does not, ``--hold`` keeps the page after the run, the URL is printed once.

The command runs in a subprocess, as a user starts it; every step waits for the line that
says it happened (never a fixed sleep). The deadlines only stop a hung test.
"""

import os
import queue
import re
import signal
import subprocess
import sys
import threading
import time
import urllib.request

import pytest

from aerial_drake.viz import live as dut
from aerial_drake.viz.screenshot import find_chromium, open_page

DEADLINE = 300.0  # s: only for a hung command, never a timing assumption
PROGRESS = re.compile(r"t = +[0-9.]+ / [0-9.]+ s")


class Command:
    """``python -m aerial_drake ARGS`` with its merged stdout and stderr read line by line."""

    def __init__(self, *args: str):
        env = dict(os.environ, PYTHONUNBUFFERED="1")
        self.process = subprocess.Popen(
            [sys.executable, "-m", "aerial_drake", *args], stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT, text=True, env=env)
        self.lines: list[str] = []
        self._queue: queue.Queue = queue.Queue()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        for line in self.process.stdout:
            self._queue.put(line.rstrip("\n"))
        self._queue.put(None)

    def expect(self, pattern: str | re.Pattern) -> re.Match:
        """Read lines until one matches ``pattern``; fail if the command ends first."""
        deadline = time.monotonic() + DEADLINE
        while True:
            try:
                line = self._queue.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                pytest.fail(f"no line matching {pattern!r} in {DEADLINE} s:\n" +
                            "\n".join(self.lines))
            if line is None:
                pytest.fail(f"the command ended before {pattern!r}:\n" + "\n".join(self.lines))
            self.lines.append(line)
            match = re.search(pattern, line)
            if match:
                return match

    def finish(self) -> int:
        status = self.process.wait(timeout=DEADLINE)
        while (line := self._queue.get(timeout=DEADLINE)) is not None:
            self.lines.append(line)
        return status

    def kill(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait()


@pytest.fixture
def command():
    started: list[Command] = []

    def start(*args: str) -> Command:
        started.append(Command(*args))
        return started[-1]

    yield start
    for c in started:
        c.kill()


def _answers(url: str) -> bool:
    with urllib.request.urlopen(url, timeout=30) as response:
        return response.status == 200 and "meshcat" in response.read().decode().lower()


def test_the_run_waits_for_a_browser_then_starts(command, tmp_path):
    if find_chromium() is None:
        pytest.skip("no Chromium (Debian: apt-get install -y chromium)")
    run = command("run", "nominal", "--meshcat", "--meshcat-port", "0", "--duration", "0.3",
                  "--out", str(tmp_path), "--no-plots")
    url = run.expect(r"Meshcat: open (http://\S+) in a browser").group(1)
    run.expect("waiting up to .* for a browser")
    # The page is there before the simulation starts, and a plain fetch does not start it.
    assert _answers(url)
    assert run.process.poll() is None
    assert not any(PROGRESS.search(line) for line in run.lines)
    with open_page(url, wait=0.0):
        run.expect("a browser connected; starting the simulation")
        connected = len(run.lines) - 1
        run.expect(PROGRESS)  # the simulation has started, and reports its progress
        assert run.finish() == 0
    assert all(not PROGRESS.search(line) for line in run.lines[:connected])
    assert sum("http://" in line for line in run.lines) == 1  # the URL once
    assert (tmp_path / "nominal" / "log.npz").is_file()
    assert (tmp_path / "nominal" / "replay.html").is_file()


def test_no_wait_starts_at_once_and_hold_serves_until_ctrl_c(command, tmp_path):
    run = command("run", "nominal", "--meshcat", "--meshcat-port", "0", "--duration", "0.3",
                  "--out", str(tmp_path), "--no-plots", "--no-wait", "--hold")
    url = run.expect(r"Meshcat: open (http://\S+) in a browser").group(1)
    run.expect(PROGRESS)  # no browser, no wait
    run.expect("the finished run stays on the page")
    assert (tmp_path / "nominal" / "metrics.json").is_file()
    assert _answers(url)  # still served after the run
    assert run.process.poll() is None
    run.process.send_signal(signal.SIGINT)
    assert run.finish() == 0
    assert not any("waiting up to" in line for line in run.lines)


class _FakeMeshcat:
    """Reports a browser from the ``connect_at``-th look on (never if None)."""

    def __init__(self, connect_at: int | None):
        self.looks, self.connect_at = 0, connect_at

    def GetNumActiveConnections(self) -> int:
        self.looks += 1
        return int(self.connect_at is not None and self.looks >= self.connect_at)


class _Clock:
    """Advances one second per reading."""

    def __init__(self):
        self.now = 0.0

    def __call__(self) -> float:
        self.now += 1.0
        return self.now


def test_wait_returns_when_a_browser_connects(capsys):
    meshcat = _FakeMeshcat(connect_at=3)
    assert dut.wait_for_browser(meshcat, timeout=100.0, stream=sys.stdout, clock=_Clock(),
                                poll=0.0)
    assert meshcat.looks == 3
    assert "a browser connected" in capsys.readouterr().out


def test_wait_times_out_with_a_message_and_the_run_goes_on(capsys):
    meshcat = _FakeMeshcat(connect_at=None)
    assert not dut.wait_for_browser(meshcat, timeout=5.0, stream=sys.stdout, clock=_Clock(),
                                    poll=0.0)
    out = capsys.readouterr().out
    assert "waiting up to 5 s" in out and "no browser connected within 5 s" in out
    assert "starting the simulation anyway" in out
