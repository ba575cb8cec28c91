"""The benchmark scripts run and print their figures (smoke tests with tiny sizes; the
figures themselves belong in docs/performance.md, not in timed tests)."""

import subprocess
import sys
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parent.parent / "benchmarks"


@pytest.mark.parametrize("script, args, expected", [
    ("bench_plant.py", ["--repeats", "1", "--duration", "0.05"], ["rigid", "rotors"]),
    ("bench_decomposition.py", ["--repeats", "20"], ["compiled", "ratio"]),
    ("bench_sim.py", ["--repeats", "1", "--duration", "0.05", "--scenarios", "nominal",
                      "--kernels", "exact", "fast"],
     ["nominal/exact", "nominal/fast", "peak RSS", "loop/plant", "load average"]),
    ("bench_law.py", ["--calls", "40", "--rounds", "2", "--duration", "0.05"],
     ["nominal (n = 7)", "quadrotor_ur3e (n = 6)", "kernel time quadrotor_ur3e / nominal",
      "the law's rigid-body part", "the law's Section II", "nominal: law / Pinocchio",
      "the fast kernel's Section II", "nominal: fast kernel / exact kernel",
      "nominal: fast law / Pinocchio"]),
    ("bench_contact.py", ["--rounds", "1", "--duration", "0.05", "--plants", "--scenarios",
                          "wall_press"],
     ["contact / free flight", "discrete SAP / continuous", "load"]),
    ("bench_references.py", ["--repeats", "1", "--duration", "0.05", "--calls", "50"],
     ["us per evaluation", "ratio to paper", "waypoints", "python"]),
    ("bench_study.py", ["--runs", "2", "--duration", "0.05", "--repeats", "1", "--workers",
                        "1", "2", "--memory-runs", "12", "--memory-duration", "0.05"],
     ["speed-up", "parallel efficiency", "per-run overhead", "peak RSS per worker",
      "runs per minute per worker", "10,000-run study", "growth"]),
])
def test_benchmark_runs(script, args, expected):
    done = subprocess.run([sys.executable, str(BENCHMARKS / script), *args],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    for word in expected:
        assert word in done.stdout
