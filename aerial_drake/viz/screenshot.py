"""Screenshots of a Meshcat page (live or ``replay.html``) in headless Chromium.

For the tests and ``tools/meshcat_screenshots.py``; the package itself never needs a browser.
Chromium is not a Python dependency: on Debian, ``apt-get install -y chromium``.

Chromium is driven over its DevTools protocol on a pipe (``--remote-debugging-pipe``: no port
is opened): open the page, let it render for ``wait`` seconds of real time, capture. The
simpler ``--screenshot --virtual-time-budget=...`` hung in 3 of 4 loads of a ``replay.html``
on this machine (Meshcat's render loop never lets virtual time run out), so it is not used.
"""

from __future__ import annotations

import base64
import contextlib
import fcntl
import json
import os
import select
import shutil
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Iterator

import numpy as np

#: Executables tried, in order, by :func:`find_chromium`.
CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")

#: Chromium's flags: headless, software WebGL, nothing fetched but the page, a fresh profile.
CHROMIUM_FLAGS = (
    "--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
    "--disable-quic", "--no-first-run", "--disable-background-networking",
    "--disable-component-update", "--disable-sync", "--hide-scrollbars",
    "--remote-debugging-pipe",
)


def find_chromium() -> str | None:
    """The path of a Chromium (or Chrome) executable on PATH, else None."""
    for name in CHROMIUM_NAMES:
        path = shutil.which(name)
        if path:
            return path
    return None


class _DevTools:
    """The DevTools protocol over Chromium's pipe (fd 3 in, fd 4 out, NUL-separated JSON)."""

    def __init__(self, write_fd: int, read_fd: int, deadline: float):
        self._write, self._read, self._deadline = write_fd, read_fd, deadline
        self._buffer, self._id = b"", 0

    def call(self, method: str, params: dict | None = None, session: str | None = None) -> dict:
        self._id += 1
        message = {"id": self._id, "method": method, "params": params or {}}
        if session is not None:
            message["sessionId"] = session
        os.write(self._write, json.dumps(message).encode() + b"\0")
        while True:
            while b"\0" in self._buffer:
                raw, self._buffer = self._buffer.split(b"\0", 1)
                reply = json.loads(raw)
                if reply.get("id") == self._id:
                    if "error" in reply:
                        raise RuntimeError(f"Chromium: {method} failed: {reply['error']}")
                    return reply["result"]
            left = self._deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"Chromium did not answer {method} in time")
            if select.select([self._read], [], [], left)[0]:
                chunk = os.read(self._read, 1 << 20)
                if not chunk:
                    raise RuntimeError(f"Chromium exited during {method}")
                self._buffer += chunk


class Page:
    """One page open in headless Chromium (see :func:`open_page`)."""

    def __init__(self, tools: _DevTools, session: str, url: str):
        self._tools, self._session, self.url = tools, session, url

    def evaluate(self, expression: str):
        """The value of the JavaScript ``expression`` in the page (JSON-able values)."""
        result = self._tools.call("Runtime.evaluate",
                                  {"expression": expression, "returnByValue": True},
                                  self._session)
        if "exceptionDetails" in result:
            details = result["exceptionDetails"]
            text = details.get("exception", {}).get("description") or details.get("text")
            raise RuntimeError(f"JavaScript failed in {self.url}: {text}")
        return result["result"].get("value")

    def capture(self, png: str | Path) -> Path:
        """Save what the page shows now as a PNG."""
        png = Path(png).resolve()
        png.parent.mkdir(parents=True, exist_ok=True)
        data = self._tools.call("Page.captureScreenshot", {"format": "png"},
                                self._session)["data"]
        png.write_bytes(base64.b64decode(data))
        return png


@contextlib.contextmanager
def open_page(url: str, *, size: tuple[int, int] = (1024, 768), wait: float = 4.0,
              chromium: str | None = None, timeout: float = 90.0) -> Iterator[Page]:
    """Open ``url`` in headless Chromium at ``size`` (width, height) pixels and wait ``wait``
    s for it to load and render. Raises RuntimeError (or TimeoutError) naming the cause;
    Chromium is stopped on leaving the block."""
    chromium = chromium or find_chromium()
    if chromium is None:
        raise RuntimeError(f"no Chromium found (tried {', '.join(CHROMIUM_NAMES)}); on Debian: "
                           "apt-get install -y chromium")
    to_chromium, from_us = os.pipe()
    to_us, from_chromium = os.pipe()
    # Above 10 so the child's dup2 onto 3 and 4 cannot clobber them.
    child_in = fcntl.fcntl(to_chromium, fcntl.F_DUPFD, 10)
    child_out = fcntl.fcntl(from_chromium, fcntl.F_DUPFD, 10)

    def _pipe_fds() -> None:  # in the child, before exec
        os.dup2(child_in, 3)
        os.dup2(child_out, 4)

    with tempfile.TemporaryDirectory(prefix="aerial_drake_chromium_") as profile:
        process = subprocess.Popen(
            [chromium, *CHROMIUM_FLAGS, f"--user-data-dir={profile}",
             f"--window-size={size[0]},{size[1]}", "about:blank"],
            preexec_fn=_pipe_fds, close_fds=False, stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        for fd in (to_chromium, from_chromium, child_in, child_out):
            os.close(fd)
        try:
            tools = _DevTools(from_us, to_us, time.monotonic() + timeout)
            targets = tools.call("Target.getTargets")["targetInfos"]
            target = next(t["targetId"] for t in targets if t["type"] == "page")
            session = tools.call("Target.attachToTarget",
                                 {"targetId": target, "flatten": True})["sessionId"]
            tools.call("Emulation.setDeviceMetricsOverride",
                       {"width": size[0], "height": size[1], "deviceScaleFactor": 1,
                        "mobile": False}, session)
            navigation = tools.call("Page.navigate", {"url": url}, session)
            if navigation.get("errorText"):
                raise RuntimeError(f"Chromium could not open {url}: {navigation['errorText']}")
            time.sleep(wait)
            yield Page(tools, session, url)
            try:
                tools.call("Browser.close")
            except (OSError, RuntimeError, TimeoutError):
                pass
        finally:
            try:
                process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
            os.close(from_us)
            os.close(to_us)


def screenshot(url: str, png: str | Path, *, size: tuple[int, int] = (1024, 768),
               wait: float = 4.0, script: str | None = None, chromium: str | None = None,
               timeout: float = 90.0) -> Path:
    """A PNG of ``url`` as headless Chromium shows it ``wait`` s after opening it.

    ``script``: JavaScript run then, one second before the capture; e.g.
    :func:`replay_time_script` shows a replay at a chosen time.
    """
    with open_page(url, size=size, wait=wait, chromium=chromium, timeout=timeout) as page:
        if script is not None:
            page.evaluate(script)
            time.sleep(1.0)
        return page.capture(png)


def replay_time_script(t: float) -> str:
    """JavaScript that stops a Meshcat replay's animation at ``t`` s (Meshcat's Animator)."""
    return f"viewer.animator.pause(); viewer.animator.seek({float(t)!r}); true"


def colourful_fraction(png: str | Path, box: tuple[float, float, float, float] = (0, 0, 1, 1),
                       *, saturation: float = 0.25) -> float:
    """Fraction of the pixels in ``box`` (left, top, right, bottom as fractions of the image)
    whose colour channels spread by more than ``saturation``. Meshcat's background and grid
    are grey; the robot (blue fuselage, orange links) and the overlays are coloured."""
    import matplotlib.image

    image = matplotlib.image.imread(str(png))[..., :3].astype(float)
    if image.max() > 1.0:  # 8-bit integers
        image /= 255.0
    h, w = image.shape[:2]
    left, top, right, bottom = box
    region = image[int(top * h):int(bottom * h), int(left * w):int(right * w)]
    spread = region.max(axis=-1) - region.min(axis=-1)
    return float(np.mean(spread > saturation))
