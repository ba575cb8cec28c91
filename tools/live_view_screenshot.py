"""A screenshot of the live Meshcat view taken mid-run, the way a user watches one.

    python tools/live_view_screenshot.py [SCENARIO] [--at 9.0] [--out docs/img]

Starts ``aerial-drake run SCENARIO --meshcat`` (default: ``disturbed``) as a user would; the
run waits for a browser. Headless Chromium (``aerial_drake.viz.screenshot``) opens the printed
URL, which starts the simulation; once the run's progress reports simulated time ``--at`` s
or later, the page is captured while the simulation goes on (nothing pauses it), and the run
is stopped with Ctrl-C. Writes ``<out>/meshcat_live_<scenario>.png``. Needs Chromium
(Debian: apt-get install chromium).

(``tools/meshcat_screenshots.py`` instead pauses the simulation at exact times.)
"""

from __future__ import annotations

import argparse
import os
import re
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

from aerial_drake.viz.screenshot import colourful_fraction, open_page

PROGRESS = re.compile(r"t = +([0-9.]+) / ")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenario", nargs="?", default="disturbed")
    parser.add_argument("--at", type=float, default=9.0,
                        help="capture once the progress reports this simulated time (s); "
                             "9.0: the end effector's disturbance window of the paper's runs")
    parser.add_argument("--out", default="docs/img")
    parser.add_argument("--size", type=int, nargs=2, default=[960, 640])
    args = parser.parse_args(argv)
    png = Path(args.out) / f"meshcat_live_{Path(args.scenario).stem}.png"
    with tempfile.TemporaryDirectory() as tmp:
        run = subprocess.Popen(
            [sys.executable, "-m", "aerial_drake", "run", args.scenario, "--meshcat",
             "--meshcat-port", "0", "--no-plots", "--out", tmp],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
            env=dict(os.environ, PYTHONUNBUFFERED="1"))
        assert run.stdout is not None
        try:
            url = None
            for line in run.stdout:
                print(line, end="", flush=True)
                match = re.search(r"Meshcat: open (http://\S+) in a browser", line)
                if match:
                    url = match.group(1)
                    break
            if url is None:
                print("error: the run printed no Meshcat URL", file=sys.stderr)
                return 1
            with open_page(url, size=tuple(args.size), wait=0.0) as page:
                for line in run.stdout:
                    print(line, end="", flush=True)
                    match = PROGRESS.search(line)
                    if match and float(match.group(1)) >= args.at:
                        page.capture(png)
                        print(f"captured {png} after the run reported t = {match.group(1)} s "
                              f"({100 * colourful_fraction(png):.1f} % coloured pixels)")
                        break
                else:
                    print(f"error: the run ended before t = {args.at:g} s", file=sys.stderr)
                    return 1
        finally:
            if run.poll() is None:
                run.send_signal(signal.SIGINT)  # the run writes its logs and exits
                for line in run.stdout:
                    pass
            run.wait()
    return 0


if __name__ == "__main__":
    sys.exit(main())
