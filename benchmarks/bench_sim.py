"""Simulation speed of the paper's scenarios (15 s, no Meshcat), printed as figures and ratios.

For each scenario: median wall time over --repeats runs, real-time factor (simulated / wall),
median control-law evaluation time (the controller replayed on the run's logged states), the
same diagram with a zero controller (plant, reference and logging only) and the scenario's
simulated plant alone (``bench_plant.plant_alone``: the plant variant, robot and simulator
settings of the scenario, zero inputs, no other system) timed in the same session, the ratios
closed loop / zero controller and closed loop / plant alone (median and 10th-90th percentile
of the ratio of each run to its neighbour in the alternation), and the peak resident memory of
one run. Each run is its own process,
so the memory figure is that run's. The numba kernels are compiled (or loaded) first, in a
process of their own, so every timed run is one with numba's cache filled; the first run
after installing is measured apart (docs/performance.md, Memory).

    python benchmarks/bench_sim.py [--repeats 3] [--duration 15] [--scenarios nominal disturbed]
                                   [--kernels exact fast]

``--kernels``: the compiled law's kernels (the scenario's ``controller.kernel``) to time, one
row each (``nominal/fast``), their closed-loop runs alternating with the zero-controller and
plant-alone runs they are compared with (default: the exact kernel only).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import time

import numpy as np


def worker(scenario_name: str, duration: float, zero: bool, plant: bool = False,
           kernel: str = "exact") -> dict:
    from aerial_drake.control.registry import zero_controller
    from aerial_drake.simulation.runner import run_scenario
    from aerial_drake.simulation.scenarios import load_scenario

    scenario = load_scenario(scenario_name, overrides={"duration": duration,
                                                       "controller.kernel": kernel})
    if plant:
        from bench_plant import plant_alone

        return {"wall_s": plant_alone(scenario, duration)[1]}
    result = run_scenario(scenario, progress=False,
                          controller_factory=zero_controller if zero else None)
    out = {"wall_s": result.wall_time_s,
           "rtf": result.metrics["simulated_time_s"] / result.wall_time_s,
           "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0}
    if not zero:
        out["controller_us"] = _controller_time(scenario, result)
    return out


def _controller_time(scenario, result, samples: int = 1000) -> float:
    """Median time of one control-law evaluation (``DecoupledController.evaluate``, what the
    simulation's controller runs at each sample) on states the run visited."""
    from aerial_drake.simulation.diagram import build_closed_loop

    loop = build_closed_loop(scenario)
    ctrl, sim = loop.controller, loop.simulated_plant
    idx = sim.rigid_state_indices
    log = result.log
    rows = np.linspace(0, len(log["t"]) - 1, samples).astype(int)
    times = []
    for k in rows:
        x = log["plant_state"][k][idx]
        start = time.perf_counter()
        ctrl.evaluate(x, log["com_reference"][k], log["task_reference"][k],
                      log["heading_reference"][k])
        times.append(time.perf_counter() - start)
    return 1e6 * statistics.median(times)


def run_worker(name: str, duration: float, zero: bool, plant: bool = False,
               kernel: str = "exact") -> dict:
    cmd = [sys.executable, __file__, "--worker", name, "--duration", str(duration),
           "--kernel", kernel]
    if zero:
        cmd.append("--zero")
    if plant:
        cmd.append("--plant")
    done = subprocess.run(cmd, check=True, capture_output=True, text=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def _load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--duration", type=float, default=15.0)
    parser.add_argument("--scenarios", nargs="+", default=["nominal", "disturbed"])
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    parser.add_argument("--zero", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--plant", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--kernels", nargs="+", default=["exact"], choices=["exact", "fast"],
                        help="the compiled law's kernels to time (controller.kernel)")
    parser.add_argument("--kernel", default="exact", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        print(json.dumps(worker(args.worker, args.duration, args.zero, args.plant,
                                args.kernel)))
        return

    print(f"machine: {platform.machine()}, {platform.platform()}, python "
          f"{platform.python_version()}, {len(os.sched_getaffinity(0))} cores")
    header = (f"{'scenario':>10} {'wall (s)':>9} {'RT factor':>10} {'ctrl (us)':>10} "
              f"{'zero-ctrl wall':>15} {'ratio':>6} {'plant wall':>11} "
              f"{'loop/plant (p10-p90)':>21} {'peak RSS (MB)':>14}")
    compile_first = ("from aerial_drake.simulation.runner import compile_kernels; "
                     "compile_kernels(); from aerial_drake.control.compiled.law import "
                     f"compile_law; compile_law({tuple(args.kernels)!r})")
    subprocess.run([sys.executable, "-c", compile_first], check=True)
    print(f"load average before: {_load()}")
    print(header)
    for name in args.scenarios:
        # Alternating, so that the medians see the same drift of the machine's speed; each
        # ratio is of runs next to each other in time.
        fulls: dict = {kernel: [] for kernel in args.kernels}
        zero, plant = [], []
        for _ in range(args.repeats):
            for kernel, full in fulls.items():
                full.append(run_worker(name, args.duration, False, kernel=kernel))
            zero.append(run_worker(name, args.duration, True))
            plant.append(run_worker(name, args.duration, False, plant=True))
        zwall = statistics.median(r["wall_s"] for r in zero)
        pwall = statistics.median(r["wall_s"] for r in plant)
        for kernel, full in fulls.items():
            wall = statistics.median(r["wall_s"] for r in full)
            ratios = [f["wall_s"] / p["wall_s"] for f, p in zip(full, plant)]
            spread = f"{statistics.median(ratios):.2f} ({np.percentile(ratios, 10):.2f}-" \
                     f"{np.percentile(ratios, 90):.2f})"
            label = name if args.kernels == ["exact"] else f"{name}/{kernel}"
            print(f"{label:>10} {wall:9.2f} {args.duration / wall:10.2f} "
                  f"{statistics.median(r['controller_us'] for r in full):10.1f} "
                  f"{zwall:15.2f} {wall / zwall:6.2f} {pwall:11.2f} {spread:>21} "
                  f"{max(r['peak_rss_mb'] for r in full):14.0f}", flush=True)
    print(f"load average after: {_load()}")

if __name__ == "__main__":
    main()
