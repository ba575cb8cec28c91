"""A study's runs serially in one process against local Dask clusters of every worker count
the machine has, in one sitting; and one worker's memory over many runs.

The same ``--runs`` runs (the first of the shipped ``robustness`` study, ``--duration`` s each)
go through :func:`aerial_drake.studies.worker.run_planned`, one after the other in a process
of their own, then on ``LocalCluster(n_workers=N, threads_per_worker=1, processes=True)``
(aerial_drake.studies.executor) for each N of ``--workers`` (default: 1 up to the machine's
cores), alternately ``--repeats`` times so all see the same drift of the machine. The numba
kernels are compiled (or loaded) before any timing. Printed per worker count: the wall times
(median, and the range over repeats), runs per minute per worker, the speed-up and the
parallel efficiency (serial time / (N x cluster time)) with and without the cluster's
start-up, the per-run overhead of the cluster, the peak resident memory per worker; then the
cost of a 10,000-run study on N workers from those figures.

``--memory-runs K`` (default 0: skipped) runs K runs of ``--memory-duration`` s one after the
other in one process, as one worker does, and prints its resident memory after the first
ten, at the middle and at the end, and the growth per 100 runs after the first ten (a leak
shows as a steady growth; the first runs load and compile).

    python benchmarks/bench_study.py [--runs 20] [--duration 15] [--repeats 2] [--workers 1 2]
                                     [--memory-runs 200 --memory-duration 2]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time


def _runs(count: int, duration: float):
    from aerial_drake.studies.spec import load_study, plan_runs
    return plan_runs(load_study("robustness", duration=duration), limit=count)


def serial(count: int, duration: float) -> dict:
    """In this process: the runs one after the other (after warming the kernels)."""
    from aerial_drake.studies.worker import ensure_warm, peak_memory_mb, run_planned
    runs = _runs(count, duration)
    ensure_warm()
    start = time.perf_counter()
    rows = [run_planned(r.scenario_text) for r in runs]
    return {"wall_s": time.perf_counter() - start, "peak_rss_mb": peak_memory_mb(),
            "completed": sum(bool(r["completed"]) for r in rows)}


def cluster(count: int, duration: float, workers: int) -> dict:
    """On a new local cluster of ``workers`` processes: from its start to the last result,
    and from the first submission to the last result."""
    from aerial_drake.studies.executor import execute, study_client
    from aerial_drake.studies.worker import peak_memory_mb
    runs = _runs(count, duration)
    rows = []
    start = time.perf_counter()
    with study_client(workers) as (client, _):
        submitted = time.perf_counter()
        execute(client, runs, lambda run, row: rows.append(row))
        done = time.perf_counter()
        memory = list(client.run(peak_memory_mb).values())
    return {"wall_s": done - start, "steady_wall_s": done - submitted,
            "worker_peak_rss_mb": memory, "completed": sum(bool(r["completed"]) for r in rows)}


def resident_mb() -> float:
    """This process's resident memory now (MB), from /proc (Linux)."""
    with open("/proc/self/statm") as f:
        pages = int(f.read().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 2**20


def memory_growth(count: int, duration: float) -> dict:
    """``count`` runs one after the other in this process (as one worker runs them): the
    resident memory after each."""
    from aerial_drake.studies.spec import load_study, plan_runs
    from aerial_drake.studies.worker import ensure_warm, run_planned
    ensure_warm()
    study = load_study("robustness", duration=duration)
    runs = plan_runs(study, limit=count)  # the study has 200 draws; more repeat them
    resident = []
    for k in range(count):
        run_planned(runs[k % len(runs)].scenario_text)
        resident.append(resident_mb())
    return {"resident_mb": resident}


def _hours(seconds: float) -> str:
    return f"{seconds / 3600:.1f} h" if seconds >= 3600 else f"{seconds / 60:.0f} min"


def _spread(values: list[float]) -> str:
    return f"{min(values):.1f}-{max(values):.1f}" if len(values) > 1 else f"{values[0]:.1f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--duration", type=float, default=15.0)
    parser.add_argument("--repeats", type=int, default=2)
    cores = len(os.sched_getaffinity(0))
    parser.add_argument("--workers", type=int, nargs="+", default=list(range(1, cores + 1)))
    parser.add_argument("--memory-runs", type=int, default=0)
    parser.add_argument("--memory-duration", type=float, default=2.0)
    parser.add_argument("--serial", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--memory", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.serial:
        print(json.dumps(serial(args.runs, args.duration)))
        return
    if args.memory:
        print(json.dumps(memory_growth(args.memory_runs, args.memory_duration)))
        return
    print(f"machine: {platform.machine()}, {platform.platform()}, python "
          f"{platform.python_version()}, {cores} cores, load average "
          f"{', '.join(f'{x:.2f}' for x in os.getloadavg())}; {args.runs} runs of "
          f"{args.duration:g} s (robustness study), worker counts {args.workers}", flush=True)
    compile_first = "from aerial_drake.simulation.runner import compile_kernels; compile_kernels()"
    subprocess.run([sys.executable, "-c", compile_first], check=True)
    serial_runs: list[dict] = []
    cluster_runs: dict[int, list[dict]] = {n: [] for n in args.workers}
    for k in range(args.repeats):
        done = subprocess.run([sys.executable, __file__, "--serial", "--runs", str(args.runs),
                               "--duration", str(args.duration)],
                              check=True, capture_output=True, text=True)
        serial_runs.append(json.loads(done.stdout.strip().splitlines()[-1]))
        print(f"  repeat {k}: serial {serial_runs[-1]['wall_s']:.1f} s", flush=True)
        for n in args.workers:
            cluster_runs[n].append(cluster(args.runs, args.duration, n))
            print(f"  repeat {k}: {n} worker(s) {cluster_runs[n][-1]['wall_s']:.1f} s (from "
                  f"start-up), {cluster_runs[n][-1]['steady_wall_s']:.1f} s (from submission)",
                  flush=True)
    walls = [r["wall_s"] for r in serial_runs]
    t_serial = statistics.median(walls)
    print(f"serial wall (median, range)     {t_serial:8.1f} s ({_spread(walls)}; "
          f"{t_serial / args.runs:.2f} s per run, {60 * args.runs / t_serial:.1f} runs per "
          "minute)")
    rates = {}
    for n in args.workers:
        rows = cluster_runs[n]
        t_cluster = statistics.median(r["wall_s"] for r in rows)
        t_steady = statistics.median(r["steady_wall_s"] for r in rows)
        rates[n] = 60 * args.runs / t_steady / n
        print(f"{n} worker(s): cluster wall {t_cluster:.1f} s from start-up "
              f"({_spread([r['wall_s'] for r in rows])}), {t_steady:.1f} s from submission "
              f"({_spread([r['steady_wall_s'] for r in rows])})")
        print(f"  runs per minute per worker      {rates[n]:8.2f} (from submission)")
        print(f"  speed-up with start-up          {t_serial / t_cluster:8.2f} "
              f"(parallel efficiency {t_serial / t_cluster / n:.2f})")
        print(f"  speed-up from submission        {t_serial / t_steady:8.2f} "
              f"(parallel efficiency {t_serial / t_steady / n:.2f})")
        print(f"  per-run overhead of the cluster {(n * t_steady - t_serial) / args.runs:8.3f} s "
              f"from submission, {(n * t_cluster - t_serial) / args.runs:.3f} s with start-up")
        memory = [m for r in rows for m in r["worker_peak_rss_mb"]]
        print(f"  peak RSS per worker             {max(memory):8.0f} MB (max over workers and "
              "repeats)")
        print(f"  completed runs: {rows[-1]['completed']} of {args.runs}")
    print(f"serial process peak RSS {max(r['peak_rss_mb'] for r in serial_runs):.0f} MB; "
          f"completed runs: serial {serial_runs[-1]['completed']} of {args.runs}")
    n_max = max(args.workers)
    per_run_s = 60.0 / rates[n_max]
    print(f"a 10,000-run study of {args.duration:g} s runs at {rates[n_max]:.2f} runs per minute"
          f" per worker ({n_max} worker(s) here): "
          + ", ".join(f"{w} workers {_hours(10000 * per_run_s / w)}" for w in
                      (2, 8, 32, 128)) + " (the same rate per worker; start-up not counted)")
    if args.memory_runs:
        done = subprocess.run([sys.executable, __file__, "--memory", "--memory-runs",
                               str(args.memory_runs), "--memory-duration",
                               str(args.memory_duration)],
                              check=True, capture_output=True, text=True)
        resident = json.loads(done.stdout.strip().splitlines()[-1])["resident_mb"]
        first = resident[min(9, len(resident) - 1)]
        growth = (resident[-1] - first) / max(1, len(resident) - 10) * 100
        print(f"one worker, {len(resident)} runs of {args.memory_duration:g} s: resident "
              f"{first:.0f} MB after 10, {resident[len(resident) // 2]:.0f} MB at the middle, "
              f"{resident[-1]:.0f} MB at the end; growth {growth:+.2f} MB per 100 runs after "
              "the first ten")


if __name__ == "__main__":
    main()
