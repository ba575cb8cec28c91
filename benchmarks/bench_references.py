"""Each reference kind against the paper kind: per-evaluation cost and whole-run time.

Scenarios (15 s, helicopter and LWR, 1 kHz controller): ``paper`` is the shipped nominal
(the paper kind), ``waypoints`` the shipped pick_and_place, ``hover`` the nominal with a hover
section at the paper reference's pose at t = 0, and ``python`` the nominal with a python kind
whose function returns the paper's reference (so the same motion, given by a user's code).

- per evaluation: the median time of one ``fill`` of the source a run evaluates, over times
  spread across the run (in one process, kinds alternated);
- whole run: loading the scenario (with its checks) and running it, each run its own process
  (numba's cache filled first), the kinds alternated round by round (paper, waypoints, hover,
  python, paper, ...), so all see the same drift of a shared machine's speed. Printed: the
  median, the 10th-90th percentile, and each kind's ratio to the paper kind (median of the
  per-round ratios; goal <= 1.15).

    python benchmarks/bench_references.py [--repeats 5] [--duration 15] [--kinds ...]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

KINDS = ("paper", "waypoints", "hover", "python")

_PYTHON_MODULE = '''\
"""A user's reference: the paper's (28)-(33) with the nominal scenario's constants."""
from aerial_drake.trajectories.paper import evaluate_reference
from aerial_drake.trajectories.params import TrajectoryParams

_PARAMS = TrajectoryParams(**{params!r})


def reference(t):
    return evaluate_reference(_PARAMS, t, [0.0])
'''


def _nominal_parts() -> tuple[str, str]:
    from aerial_drake.simulation.scenarios import shipped_scenarios

    base = shipped_scenarios()["nominal"].read_text()
    start, end = base.index("trajectory:"), base.index("\n# The start")
    return base[:start], base[end:]


def write_scenarios(folder: Path) -> dict[str, str]:
    """The four scenarios (names or paths) of the module docstring, written into ``folder``."""
    from aerial_drake.simulation.scenarios import load_scenario

    nominal = load_scenario("nominal", validate=False).trajectory
    head, tail = _nominal_parts()
    a2, a3 = nominal.orientation_amplitudes[1], nominal.orientation_amplitudes[2]
    from aerial_drake.trajectories.kinds import evaluate_reference

    p0 = evaluate_reference(nominal, 0.0, [0.0]).p_ed
    hover = ("trajectory:\n  kind: hover\n  joint_targets: [0.0]\n"
             f"  com_offset: {list(map(float, nominal.com_offset))}\n  hover:\n"
             f"    ee_position: {[round(float(x), 12) for x in p0]}\n"
             f"    ee_rpy: [0.0, {a2}, {a3}]\n    heading: {float(nominal.heading_initial)}\n")
    params = {name: getattr(nominal, name) for name in (
        "center", "basic_amplitude", "basic_frequency", "basic_climb_rate", "agile_amplitude",
        "agile_frequency", "orientation_amplitudes", "orientation_frequency",
        "heading_initial", "heading_rate", "com_offset", "joint_targets")}
    params = {k: (list(map(float, v)) if isinstance(v, list) else float(v))
              for k, v in params.items()}
    (folder / "bench_user_reference.py").write_text(_PYTHON_MODULE.format(params=params))
    python = ("trajectory:\n  kind: python\n  joint_targets: [0.0]\n  python:\n"
              "    function: 'bench_user_reference:reference'\n    path: .\n")
    out = {"paper": "nominal", "waypoints": "pick_and_place"}
    for kind, section in (("hover", hover), ("python", python)):
        path = folder / f"bench_{kind}.yaml"
        path.write_text(head.replace("name: nominal", f"name: bench_{kind}") + section + tail)
        out[kind] = str(path)
    return out


def _run_source(scenario):
    """The reference source a run of ``scenario`` evaluates (as the closed loop builds it)."""
    from aerial_drake.simulation.diagram import build_closed_loop

    return build_closed_loop(scenario).reference.source


def evaluation_worker(scenarios: dict[str, str], duration: float, calls: int,
                      rounds: int) -> dict:
    """Microseconds per ``fill`` of each kind's run source, per round (kinds alternated)."""
    from aerial_drake.simulation.scenarios import load_scenario

    sources = {}
    for kind, name in scenarios.items():
        scenario = load_scenario(name, overrides={"duration": duration})
        sources[kind] = _run_source(scenario)
    times = np.linspace(0.0, duration, calls)
    per_kind: dict[str, list[float]] = {kind: [] for kind in sources}
    for _ in range(rounds):
        for kind, source in sources.items():
            out = np.empty(source.size)
            fill = source.fill
            start = time.perf_counter()
            for t in times:
                fill(float(t), out)
            per_kind[kind].append(1e6 * (time.perf_counter() - start) / calls)
    return per_kind


def run_worker(name: str, duration: float) -> dict:
    """Load (with every check) and run one scenario; wall times in seconds."""
    start = time.perf_counter()
    from aerial_drake.simulation.runner import run_scenario
    from aerial_drake.simulation.scenarios import load_scenario

    imported = time.perf_counter()
    scenario = load_scenario(name, overrides={"duration": duration})
    result = run_scenario(scenario, progress=False)
    done = time.perf_counter()
    return {"whole_s": done - imported, "simulate_s": result.wall_time_s,
            "imports_s": imported - start}


def _subprocess(args: list[str], cwd: str) -> dict:
    done = subprocess.run([sys.executable, __file__, *args], check=True, capture_output=True,
                          text=True, cwd=cwd)
    return json.loads(done.stdout.strip().splitlines()[-1])


def _percentiles(values: list[float]) -> tuple[float, float]:
    return float(np.percentile(values, 10)), float(np.percentile(values, 90))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--duration", type=float, default=15.0)
    parser.add_argument("--calls", type=int, default=1000,
                        help="evaluations per kind and round (per-evaluation cost)")
    parser.add_argument("--rounds", type=int, default=21,
                        help="rounds of the per-evaluation cost, kinds alternated")
    parser.add_argument("--kinds", nargs="+", default=list(KINDS), choices=KINDS)
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    parser.add_argument("--evaluate", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        print(json.dumps(run_worker(args.worker, args.duration)))
        return
    if args.evaluate:
        print(json.dumps(evaluation_worker(json.loads(args.evaluate), args.duration,
                                           args.calls, args.rounds)))
        return

    print(f"machine: {platform.machine()}, {platform.platform()}, python "
          f"{platform.python_version()}, {len(os.sched_getaffinity(0))} cores, load "
          f"{' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    kinds = ["paper"] + [k for k in args.kinds if k != "paper"]
    with tempfile.TemporaryDirectory() as folder:
        scenarios = write_scenarios(Path(folder))
        scenarios = {k: scenarios[k] for k in kinds}
        compile_first = ("from aerial_drake.simulation.runner import compile_kernels; "
                         "compile_kernels()")
        subprocess.run([sys.executable, "-c", compile_first], check=True)
        cost = _subprocess(["--evaluate", json.dumps(scenarios), "--duration",
                            str(args.duration), "--calls", str(args.calls), "--rounds",
                            str(args.rounds)], folder)
        print(f"per evaluation ({args.rounds} rounds of {args.calls} calls, kinds alternated)")
        print(f"{'kind':>10} {'us per evaluation':>18} {'p10-p90':>12} {'/ paper':>8}")
        paper_cost = statistics.median(cost["paper"])
        for kind in kinds:
            lo, hi = _percentiles(cost[kind])
            median = statistics.median(cost[kind])
            print(f"{kind:>10} {median:18.2f} {lo:5.2f}-{hi:<6.2f} {median / paper_cost:8.2f}")
        runs: dict[str, list[dict]] = {k: [] for k in kinds}
        for _ in range(args.repeats):  # alternated: one run of each kind per round
            for kind in kinds:
                runs[kind].append(_subprocess(["--worker", scenarios[kind], "--duration",
                                               str(args.duration)], folder))
    print(f"whole run ({args.duration:g} s simulated; load with checks + run), "
          f"{args.repeats} rounds alternated")
    print(f"{'kind':>10} {'median (s)':>11} {'p10-p90 (s)':>14} {'simulate (s)':>13} "
          f"{'ratio to paper':>15} {'ratio p10-p90':>14}")
    paper = [r["whole_s"] for r in runs["paper"]]
    for kind in kinds:
        whole = [r["whole_s"] for r in runs[kind]]
        ratios = [w / p for w, p in zip(whole, paper)]
        lo, hi = _percentiles(whole)
        rlo, rhi = _percentiles(ratios)
        print(f"{kind:>10} {statistics.median(whole):11.2f} {lo:6.2f}-{hi:<7.2f} "
              f"{statistics.median(r['simulate_s'] for r in runs[kind]):13.2f} "
              f"{statistics.median(ratios):15.3f} {rlo:6.3f}-{rhi:<7.3f}", flush=True)


if __name__ == "__main__":
    main()
