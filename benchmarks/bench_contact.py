"""What contact costs: a contact scenario against the same run in free flight, and the
continuous plant against a discrete SAP plant on the same task (docs/contact.md).

For each scenario, alternating in rounds (each run its own process, numba's cache filled
first):

- ``contact``: the scenario as shipped (paper_force pressing on the environment);
- ``free``: the same run in free flight: no environment (so no contact geometry to query, no
  contact wrench, no force sensor) and the paper's controller on the same motion reference;
- ``sap`` (``--plants``): the scenario on a discrete plant, ``time_step`` 1 ms and
  ``discrete_contact_approximation: sap``, with its force metrics.

Printed: the median wall time of each, and the ratios contact / free and sap / contact (the
median and 10th-90th percentile of each round's ratio), with the machine's load.

    python benchmarks/bench_contact.py [--rounds 5] [--scenarios wall_press ...] [--plants]
                                       [--duration S]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

import numpy as np

SUBJECTS = {
    "contact": {},
    "free": {"environment.directives": [], "controller.type": "paper"},
    "sap": {"plant.time_step": 0.001, "plant.discrete_contact_approximation": "sap"},
}


def worker(scenario_name: str, subject: str, duration: str) -> dict:
    import warnings

    from aerial_drake.simulation.runner import run_scenario
    from aerial_drake.simulation.scenarios import load_scenario

    warnings.simplefilter("ignore")
    overrides = dict(SUBJECTS[subject])
    if float(duration) > 0:
        overrides["duration"] = float(duration)
    scenario = load_scenario(scenario_name, overrides=overrides or None, validate=False)
    if subject == "free":  # the paper's controller has no force task
        from dataclasses import replace

        from aerial_drake.control.force.params import ForceTaskParams
        scenario = replace(scenario, controller=replace(scenario.controller,
                                                        force=ForceTaskParams()))
    scenario.validate()
    start = time.perf_counter()
    result = run_scenario(scenario, progress=False)
    wall = time.perf_counter() - start
    contact = result.metrics.get("contact") or {}
    return {"wall_s": wall, "completed": result.completed,
            "force_error_max_rel": contact.get("force_error_max_rel"),
            "peak_pressing_force_N": contact.get("peak_pressing_force_N"),
            "contact_transitions_run": contact.get("contact_transitions_run")}


def _run(scenario: str, subject: str, duration: float) -> dict:
    out = subprocess.run([sys.executable, __file__, "--worker", scenario, subject, str(duration)],
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def _spread(values: list[float]) -> str:
    a = np.asarray(values)
    return (f"{np.median(a):.3f} (10th-90th {np.percentile(a, 10):.3f}-"
            f"{np.percentile(a, 90):.3f}, n = {len(a)})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--scenarios", nargs="+",
                        default=["wall_press", "quadrotor_ur3e_wall_press"])
    parser.add_argument("--plants", action="store_true",
                        help="also the discrete SAP plant on each scenario")
    parser.add_argument("--duration", type=float, default=0.0,
                        help="simulated seconds (default: the scenario's own)")
    parser.add_argument("--worker", nargs=3, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        print(json.dumps(worker(*args.worker)))
        return
    subjects = ["contact", "free"] + (["sap"] if args.plants else [])
    print(f"bench_contact: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, "
          f"load {os.getloadavg()[0]:.1f}, {args.rounds} rounds, subjects {subjects}")
    _run(args.scenarios[0], "free", args.duration)  # numba's cache filled before anything is timed
    walls: dict[tuple[str, str], list[float]] = {}
    extra: dict[tuple[str, str], dict] = {}
    for _ in range(args.rounds):
        for scenario in args.scenarios:
            for subject in subjects:
                row = _run(scenario, subject, args.duration)
                walls.setdefault((scenario, subject), []).append(row["wall_s"])
                extra[(scenario, subject)] = row
    for scenario in args.scenarios:
        print(f"\n{scenario}")
        for subject in subjects:
            w = walls[(scenario, subject)]
            row = extra[(scenario, subject)]
            print(f"  {subject:8s} wall {statistics.median(w):.2f} s (min {min(w):.2f}); "
                  f"completed {row['completed']}; force error max "
                  f"{row['force_error_max_rel']}, peak {row['peak_pressing_force_N']} N, "
                  f"contact made/lost {row['contact_transitions_run']}")
        ratio = [c / f for c, f in zip(walls[(scenario, "contact")], walls[(scenario, "free")])]
        print(f"  contact / free flight: {_spread(ratio)}  (goal <= 3)")
        if args.plants:
            ratio = [s / c for s, c in zip(walls[(scenario, "sap")],
                                           walls[(scenario, "contact")])]
            print(f"  discrete SAP / continuous: {_spread(ratio)}")
    print(f"\nload at the end {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
