"""Median time of one evaluation of the compiled control law (aerial_drake.control.compiled), on the
states and references a short run of a paper scenario visited, in microseconds: the kernel
alone (``CompiledLaw.__call__``, what the simulation's controller calls at each sample) and
through ``DecoupledController.evaluate`` (which adds the output arrays and the status checks).

    python benchmarks/bench_law.py [--scenario nominal] [--duration 2] [--calls 20000]

The machine's speed drifts: compare two versions of the law in one process, alternating
(e.g. with this script's ``time_calls`` on both), not across runs.
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np


def logged_inputs(scenario_name: str, duration: float, rows: int = 300):
    """The controller and ``rows`` (state, com, task, heading) inputs of a run's log."""
    from aerial_drake.simulation.diagram import build_closed_loop
    from aerial_drake.simulation.runner import run_scenario
    from aerial_drake.simulation.scenarios import load_scenario

    scenario = load_scenario(scenario_name, overrides={"duration": duration})
    log = run_scenario(scenario, progress=False).log
    loop = build_closed_loop(scenario)
    idx = loop.simulated_plant.rigid_state_indices
    picks = np.linspace(0, len(log["t"]) - 1, rows).astype(int)
    inputs = [(np.ascontiguousarray(log["plant_state"][k][idx]), log["com_reference"][k],
               log["task_reference"][k], log["heading_reference"][k]) for k in picks]
    return loop.controller, inputs


def time_calls(evaluate, inputs, calls: int, block: int = 20) -> np.ndarray:
    """Per-call times (s) of ``evaluate(*inputs[k])``, measured over blocks of ``block``
    consecutive calls (short blocks: a slow moment of the machine spoils few of them)."""
    times = []
    for start in range(0, calls, block):
        t0 = time.perf_counter()
        for k in range(start, start + block):
            evaluate(*inputs[k % len(inputs)])
        times.append((time.perf_counter() - t0) / block)
    return np.array(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="nominal")
    parser.add_argument("--duration", type=float, default=2.0)
    parser.add_argument("--calls", type=int, default=20000)
    args = parser.parse_args()
    controller, inputs = logged_inputs(args.scenario, args.duration)
    law = controller._compiled
    command, diagnostics = (np.empty_like(a) for a in controller.evaluate(*inputs[0]))

    def kernel(x, com, task, heading):
        law(x, com, task, heading, command, diagnostics)

    print(f"machine: {platform.machine()}, {platform.processor() or platform.platform()}, "
          f"python {platform.python_version()}")
    for name, evaluate in (("CompiledLaw.__call__", kernel),
                           ("DecoupledController.evaluate", controller.evaluate)):
        times = 1e6 * time_calls(evaluate, inputs, args.calls)
        print(f"{name}: median {np.median(times):.1f} us, 10th percentile "
              f"{np.percentile(times, 10):.1f} us ({args.calls} calls, {args.scenario} states)")


if __name__ == "__main__":
    main()
