"""Re-measure the wall times the documentation quotes, and print them dated.

    python tools/docs_timings.py [--suite] [--out DIR]

Measures, one after the other on this machine, in a warm numba cache:

- ``aerial-drake run paper``: each run's simulation wall time (``metrics.json``'s
  ``wall_time_s``) and the whole command's (both runs, figures, summary);
- ``aerial-drake analyze``, the full analysis, and ``analyze --fast``;
- with ``--suite``: ``python -m pytest -q -n auto --dist loadgroup``, the whole test suite
  (the README's test command).

Prints one Markdown table with the date (UTC), the interpreter, drake and the machine's core
count. README.md, docs/paper.md and docs/analysis.md quote these numbers with that date;
run this again to refresh them rather than editing the numbers by hand.
"""

from __future__ import annotations

import argparse
import datetime
import importlib.metadata
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def timed(*command: str) -> float:
    """Wall time (s) of ``command``, which must succeed."""
    start = time.perf_counter()
    subprocess.run(command, check=True, cwd=ROOT, stdout=subprocess.DEVNULL)
    return time.perf_counter() - start


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--suite", action="store_true", help="also time the whole test suite")
    parser.add_argument("--out", default=None, help="where the runs write (default: a "
                        "temporary folder)")
    args = parser.parse_args(argv)
    cli = [sys.executable, "-m", "aerial_drake"]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(args.out or tmp)
        paper = timed(*cli, "run", "paper", "--quiet", "--out", str(out))
        walls = [json.loads((out / "paper" / n / "metrics.json").read_text())["wall_time_s"]
                 for n in ("nominal", "disturbed")]
        rows.append(("`aerial-drake run paper`: simulation of nominal / disturbed (15 s each)",
                     f"{walls[0]:.1f} s / {walls[1]:.1f} s"))
        rows.append(("`aerial-drake run paper`: the whole command", f"{paper:.0f} s"))
        analyze = timed(*cli, "analyze", "--quiet", "--out", str(out / "analysis"))
        rows.append(("`aerial-drake analyze` (full)", f"{analyze:.0f} s"))
        fast = timed(*cli, "analyze", "--fast", "--quiet", "--out", str(out / "fast"))
        rows.append(("`aerial-drake analyze --fast`", f"{fast:.0f} s"))
    if args.suite:
        suite = timed(sys.executable, "-m", "pytest", "-q", "-n", "auto", "--dist", "loadgroup",
                      "-p", "no:cacheprovider")
        rows.append(("`python -m pytest -q -n auto --dist loadgroup` (whole suite)",
                     f"{int(suite // 60)} min {suite % 60:02.0f} s"))
    when = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    print(f"Measured {when} by `python tools/docs_timings.py{' --suite' if args.suite else ''}`"
          f" (Python {platform.python_version()}, drake {importlib.metadata.version('drake')}, "
          f"{os.cpu_count()} cores, shared):\n")
    print("| what | wall time |\n|---|---|")
    for what, value in rows:
        print(f"| {what} | {value} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
