"""The first run after installing against a later one: the cold/warm ratio of
``aerial-drake run SCENARIO --duration D --no-plots`` (issue 29, item 1: goal <= 3).

Each round, in one sitting, a pair of commands seconds apart (the same phase of a shared
machine's load): ``warm``, the command on the cache the previous round's background compile
wrote, then ``cold``, the same command on a fresh, empty numba cache (``NUMBA_CACHE_DIR`` a new
folder: what a fresh install has; it runs on the reference law while the cache compiles in
the background, docs/performance.md "Cold start"); then that background compile is waited
for (not timed: it would slow the next pair down). One cold command before the rounds makes
the first round's warm cache. With ``--wait-compile`` a third
command per round, on another fresh cache: ``aerial-drake run --wait-compile``, which
compiles first and restarts (the behaviour before the cold start; ``run paper``'s, and a
study worker's, today). Every command is its own process, started as a user starts it;
its wall time is the process's, imports included. Printed: each round's figures, then the
medians and the spread (min-max: a few rounds) of each and of the ratios, the peak resident
memory of each command (its own process; the background compile's not included), the
background compile's time, and the machine's load.

    python benchmarks/bench_cold_start.py [--rounds 3] [--duration 2] [--scenario nominal]
        [--wait-compile]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: Waits, in a process on the given cache, for the compile under way (its lock), and prints
#: whether the cache is still cold after it.
_WAIT = ("from aerial_drake.simulation.kernel_cache import compile_lock, kernels_cache_is_cold\n"
         "with compile_lock():\n    print(kernels_cache_is_cold())")


def _env(cache: Path) -> dict[str, str]:
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH")) if p)
    env.pop("AERIAL_DRAKE_RESTARTED_AFTER_COMPILE", None)
    return env


def command(args: argparse.Namespace, cache: Path, out: Path, *extra: str) -> dict:
    """One ``aerial-drake run`` as a user starts it (its own process, in an empty working
    folder): wall time (s), peak RSS (MB), and whether it ran the reference law."""
    argv = [sys.executable, "-m", "aerial_drake", "run", args.scenario, "--duration",
            str(args.duration), "--no-plots", "--quiet", "--out", str(out), *extra]
    start = time.perf_counter()
    with tempfile.TemporaryFile() as log:
        child = subprocess.Popen(argv, cwd=out, env=_env(cache), stdout=log, stderr=log)
        _, status, usage = os.wait4(child.pid, 0)
        wall = time.perf_counter() - start
        child.returncode = os.waitstatus_to_exitcode(status)
        log.seek(0)
        text = log.read().decode(errors="replace")
    if child.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} failed ({child.returncode}):\n{text[-2000:]}")
    return {"wall_s": wall, "rss_mb": usage.ru_maxrss / 1024.0,
            "reference_law": "reference implementation" in text}


def wait_for_background(cache: Path) -> float:
    """Wait for the background compile on ``cache``; its remaining time (s)."""
    start = time.perf_counter()
    for _ in range(10):  # (it takes the lock within moments of starting: retry a little)
        done = subprocess.run([sys.executable, "-c", _WAIT], env=_env(cache),
                              capture_output=True, text=True, check=True,
                              cwd=tempfile.gettempdir())
        if done.stdout.strip().splitlines()[-1] == "False":
            return time.perf_counter() - start
        time.sleep(1.0)
    raise SystemExit("the background compile left the cache cold:\n" + done.stderr)


def spread(values: list[float]) -> str:
    return (f"median {statistics.median(values):7.2f}  (min {min(values):.2f}, max "
            f"{max(values):.2f}, n {len(values)})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--duration", type=float, default=2.0)
    parser.add_argument("--scenario", default="nominal")
    parser.add_argument("--wait-compile", action="store_true",
                        help="also time 'run --wait-compile' on a fresh cache each round")
    args = parser.parse_args()
    print(f"aerial-drake run {args.scenario} --duration {args.duration:g} --no-plots; "
          f"{args.rounds} rounds; load average at start {os.getloadavg()}; "
          f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}", flush=True)
    rows: dict[str, list[float]] = {"cold": [], "warm": [], "cold/warm": [],
                                    "background compile after the cold run": []}
    if args.wait_compile:
        rows["cold --wait-compile"] = []
        rows["cold --wait-compile/warm"] = []
    rss: dict[str, list[float]] = {"cold": [], "warm": [], "cold --wait-compile": []}
    with tempfile.TemporaryDirectory(prefix="bench_cold_") as tmp:
        out = Path(tmp, "out")
        out.mkdir()
        # A warm cache for the first pair: the cold command of a round before the first.
        previous = Path(tmp, "cache_start")
        first = command(args, previous, out)
        print(f"before the rounds: cold {first['wall_s']:.2f} s (not counted: no warm run "
              "next to it)", flush=True)
        wait_for_background(previous)
        for r in range(args.rounds):
            # A pair of adjacent commands (seconds apart: the same phase of a shared machine's
            # load): warm on the previous round's cache, then cold on a new one.
            cache = Path(tmp, f"cache{r}")
            warm = command(args, previous, out)
            cold = command(args, cache, out)
            left = wait_for_background(cache)  # not timed: the next pair starts after it
            if not cold["reference_law"] or warm["reference_law"]:
                raise SystemExit(f"round {r}: expected the reference law cold and the compiled "
                                 f"law warm; got {cold}, {warm}")
            rows["cold"].append(cold["wall_s"])
            rows["warm"].append(warm["wall_s"])
            rows["cold/warm"].append(cold["wall_s"] / warm["wall_s"])
            rows["background compile after the cold run"].append(left)
            rss["cold"].append(cold["rss_mb"])
            rss["warm"].append(warm["rss_mb"])
            line = (f"round {r}: warm {warm['wall_s']:.2f} s, cold {cold['wall_s']:.2f} s, "
                    f"ratio {cold['wall_s'] / warm['wall_s']:.2f} (background compile "
                    f"finished {left:.1f} s after the cold run)")
            if args.wait_compile:
                old = command(args, Path(tmp, f"cache_wait{r}"), out, "--wait-compile")
                rows["cold --wait-compile"].append(old["wall_s"])
                rows["cold --wait-compile/warm"].append(old["wall_s"] / warm["wall_s"])
                rss["cold --wait-compile"].append(old["rss_mb"])
                line += f"; cold --wait-compile {old['wall_s']:.2f} s"
            print(line, f"load {os.getloadavg()[0]:.2f}", flush=True)
            previous = cache
    print()
    for name, values in rows.items():
        print(f"{name:40s} {spread(values)}")
    for name, values in rss.items():
        if values:
            print(f"peak RSS (MB), {name:26s} {spread(values)}")
    print(f"load average at end {os.getloadavg()}")


if __name__ == "__main__":
    main()
