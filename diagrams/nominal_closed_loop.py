"""The nominal closed loop (Fig. 2 of the paper): build it from a scenario, write its block
diagram, and run it.

    python diagrams/nominal_closed_loop.py [SCENARIO] [--duration S] [--out DIR]
"""

from __future__ import annotations

import argparse
from pathlib import Path

from _common import write_graphviz

from aerial_drake.simulation.diagram import build_closed_loop
from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import load_scenario


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario", nargs="?", default="nominal")
    parser.add_argument("--duration", type=float, default=2.0)
    parser.add_argument("--out", default="out/diagrams")
    args = parser.parse_args()
    scenario = load_scenario(args.scenario, overrides={"duration": args.duration})
    out = Path(args.out)

    # Depth 1: the closed loop's blocks (plant, reference, controller, lag, saturation,
    # actuators) as a Diagram of their own; the run below adds the same systems straight into
    # the simulation's diagram (aerial_drake.simulation.diagram.build_simulation).
    for path in write_graphviz(build_closed_loop(scenario).diagram,
                               out / f"{scenario.name}_closed_loop"):
        print(f"wrote {path}")

    result = run_scenario(scenario, out_dir=out / scenario.name)
    print(f"ran {result.metrics['simulated_time_s']:.2f} s; logs in {result.out_dir}")


if __name__ == "__main__":
    main()
