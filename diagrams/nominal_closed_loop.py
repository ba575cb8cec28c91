"""The nominal closed loop (Fig. 2 of the paper): build it from a scenario, write its block
diagram, and run it.

    python diagrams/nominal_closed_loop.py [SCENARIO] [--duration S] [--out DIR]
"""

from __future__ import annotations

from pathlib import Path

from _common import draw_closed_loop, parse_command_line

from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import load_scenario


def main() -> None:
    args = parse_command_line(__doc__)
    scenario = load_scenario(args.scenario, overrides={"duration": args.duration})
    out = Path(args.out)
    # The run below adds the same systems straight into the simulation's diagram
    # (aerial_drake.simulation.diagram.build_simulation).
    draw_closed_loop(scenario, out)

    result = run_scenario(scenario, out_dir=out / scenario.name)
    print(f"ran {result.metrics['simulated_time_s']:.2f} s; logs in {result.out_dir}")


if __name__ == "__main__":
    main()
