"""Median time of one full decomposition (Section II: M, C, g, J_b, Q, J_g, J_bw, Z, N, T,
T^-1, T_dot, Lambda, Gamma, and the input map) at one state of our model, in microseconds:
the numpy reference path on Drake's kinematics, and the compiled one (aerial_drake.control.compiled)
that the simulation's controller uses, with their ratio.

    python benchmarks/bench_decomposition.py [--repeats N]
"""

from __future__ import annotations

import argparse
import platform
import statistics
import time

import numpy as np

from aerial_drake.control import compiled
from aerial_drake.dynamics.decoupling import DecoupledDynamics
from aerial_drake.dynamics.kinematic_tree import KinematicTree
from aerial_drake.robots.models import make_plant


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=2000)
    args = parser.parse_args()
    plant = make_plant("rigid").plant
    ctx = plant.CreateDefaultContext()
    dd = DecoupledDynamics(plant)
    rng = np.random.default_rng(0)
    states = []
    for _ in range(16):
        q = plant.GetPositions(ctx) + np.concatenate([[0, 0, 0, 0], rng.normal(size=3),
                                                      rng.uniform(-0.5, 0.5, 7)])
        states.append((q, rng.normal(size=plant.num_velocities())))
    tree = KinematicTree.from_plant(plant, dd.base_body)
    compiled.decompose(tree, *states[0])  # compile or load from numba's cache
    reference, fast = [], []
    for k in range(args.repeats):
        q, v = states[k % len(states)]
        plant.SetPositions(ctx, q)
        plant.SetVelocities(ctx, v)
        start = time.perf_counter()
        d = dd.compute(ctx)
        _ = d.input_map
        reference.append(time.perf_counter() - start)
        start = time.perf_counter()
        compiled.decompose(tree, q, v)
        fast.append(time.perf_counter() - start)
    print(f"machine: {platform.machine()}, {platform.processor() or platform.platform()}, "
          f"python {platform.python_version()}")
    for name, times in (("numpy + Drake", reference), ("compiled", fast)):
        print(f"full decomposition, {name}: median {1e6 * statistics.median(times):.1f} us, "
              f"10th percentile {1e6 * np.percentile(times, 10):.1f} us "
              f"({args.repeats} evaluations)")
    print(f"ratio: {statistics.median(reference) / statistics.median(fast):.1f}x")


if __name__ == "__main__":
    main()
