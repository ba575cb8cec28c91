"""Median time of one evaluation of the compiled control law (aerial_drake.control.compiled), on the
states and references a short run of a paper scenario visited, in microseconds: the kernel
alone (``CompiledLaw.__call__``, what the simulation's controller calls at each sample) and
through ``DecoupledController.evaluate`` (which adds the output arrays and the status checks).

    python benchmarks/bench_law.py [--scenarios nominal quadrotor_ur3e] [--calls 20000]

One scenario per shipped robot by default, the robots alternating in rounds so their ratio
holds while the machine's speed drifts.

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
    parser.add_argument("--scenarios", nargs="+", default=["nominal", "quadrotor_ur3e"],
                        help="one scenario per shipped robot by default")
    parser.add_argument("--duration", type=float, default=2.0)
    parser.add_argument("--calls", type=int, default=20000)
    parser.add_argument("--rounds", type=int, default=10,
                        help="the robots alternate in this many rounds (one sitting)")
    args = parser.parse_args()
    subjects = {}
    for name in args.scenarios:
        controller, inputs = logged_inputs(name, args.duration)
        law = controller._compiled
        command, diagnostics = (np.empty_like(a) for a in controller.evaluate(*inputs[0]))

        def kernel(x, com, task, heading, law=law, command=command, diagnostics=diagnostics):
            law(x, com, task, heading, command, diagnostics)

        subjects[name] = (controller, inputs, kernel)

    print(f"machine: {platform.machine()}, {platform.processor() or platform.platform()}, "
          f"python {platform.python_version()}")
    per_round = max(args.calls // args.rounds, 20)
    times: dict = {(name, kind): [] for name in subjects
                   for kind in ("CompiledLaw.__call__", "DecoupledController.evaluate")}
    for _ in range(args.rounds):  # interleaved: each robot in every round
        for name, (controller, inputs, kernel) in subjects.items():
            for kind, evaluate in (("CompiledLaw.__call__", kernel),
                                   ("DecoupledController.evaluate", controller.evaluate)):
                times[name, kind].append(1e6 * time_calls(evaluate, inputs, per_round))
    for (name, kind), chunks in times.items():
        t = np.concatenate(chunks)
        controller = subjects[name][0]
        print(f"{name} (n = {controller._n}): {kind}: median {np.median(t):.1f} us, "
              f"10th-90th percentile {np.percentile(t, 10):.1f}-{np.percentile(t, 90):.1f} us "
              f"({per_round * args.rounds} calls in {args.rounds} interleaved rounds)")
    if len(subjects) > 1:
        first = next(iter(subjects))
        base = np.median(np.concatenate(times[first, "CompiledLaw.__call__"]))
        for name in list(subjects)[1:]:
            other = np.median(np.concatenate(times[name, "CompiledLaw.__call__"]))
            print(f"kernel time {name} / {first}: {other / base:.3f}")


if __name__ == "__main__":
    main()
