"""A study's runs serially in one process against a 2-worker local Dask cluster, in one sitting.

The same ``--runs`` runs (the first of the shipped ``robustness`` study, ``--duration`` s each)
go through :func:`aerial_drake.studies.worker.run_planned`, one after the other in a process
of their own, then on ``LocalCluster(n_workers=2, threads_per_worker=1, processes=True)``
(aerial_drake.studies.executor), alternately ``--repeats`` times so both see the same drift
of the machine. The numba kernels are compiled (or loaded) before any timing. Printed: each
wall time, the speed-up and the parallel efficiency (speed-up / workers) with and without the
cluster's start-up, the per-run overhead of the cluster (worker time beyond the serial time,
per run) and the peak resident memory per worker and of the serial process.

    python benchmarks/bench_study.py [--runs 20] [--duration 15] [--repeats 2] [--workers 2]
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--duration", type=float, default=15.0)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--serial", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.serial:
        print(json.dumps(serial(args.runs, args.duration)))
        return
    print(f"machine: {platform.machine()}, {platform.platform()}, python "
          f"{platform.python_version()}, {len(os.sched_getaffinity(0))} cores; "
          f"{args.runs} runs of {args.duration:g} s (robustness study)", flush=True)
    compile_first = "from aerial_drake.simulation.runner import compile_kernels; compile_kernels()"
    subprocess.run([sys.executable, "-c", compile_first], check=True)
    serial_runs, cluster_runs = [], []
    for k in range(args.repeats):
        done = subprocess.run([sys.executable, __file__, "--serial", "--runs", str(args.runs),
                               "--duration", str(args.duration)],
                              check=True, capture_output=True, text=True)
        serial_runs.append(json.loads(done.stdout.strip().splitlines()[-1]))
        print(f"  repeat {k}: serial {serial_runs[-1]['wall_s']:.1f} s", flush=True)
        cluster_runs.append(cluster(args.runs, args.duration, args.workers))
        print(f"  repeat {k}: cluster {cluster_runs[-1]['wall_s']:.1f} s (from start-up), "
              f"{cluster_runs[-1]['steady_wall_s']:.1f} s (from submission)", flush=True)
    t_serial = statistics.median(r["wall_s"] for r in serial_runs)
    t_cluster = statistics.median(r["wall_s"] for r in cluster_runs)
    t_steady = statistics.median(r["steady_wall_s"] for r in cluster_runs)
    n = args.workers
    print(f"serial wall (median)            {t_serial:8.1f} s "
          f"({t_serial / args.runs:.2f} s per run)")
    print(f"cluster wall, from start-up     {t_cluster:8.1f} s")
    print(f"cluster wall, from submission   {t_steady:8.1f} s")
    print(f"speed-up with start-up          {t_serial / t_cluster:8.2f} "
          f"(parallel efficiency {t_serial / t_cluster / n:.2f})")
    print(f"speed-up from submission        {t_serial / t_steady:8.2f} "
          f"(parallel efficiency {t_serial / t_steady / n:.2f})")
    print(f"per-run overhead of the cluster {(n * t_steady - t_serial) / args.runs:8.3f} s "
          f"from submission, {(n * t_cluster - t_serial) / args.runs:.3f} s with start-up")
    memory = [m for r in cluster_runs for m in r["worker_peak_rss_mb"]]
    print(f"peak RSS per worker             {max(memory):8.0f} MB (max over workers and "
          f"repeats); serial process {max(r['peak_rss_mb'] for r in serial_runs):.0f} MB")
    print(f"completed runs: serial {serial_runs[-1]['completed']}, cluster "
          f"{cluster_runs[-1]['completed']} of {args.runs}")


if __name__ == "__main__":
    main()
