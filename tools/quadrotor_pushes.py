"""quadrotor_ur3e under 50 N pushes on the vehicle along +-x and +-y (4-5 s, its shipped
trajectory, no other window): the paper's law against paper_plus with the observer's force
fed forward and its wrench compensated (docs/control.md, "Wrench compensation"), with the
scenario's gains and with the gain check's attitude gains (k_R 382, k_w 52.6).

    python tools/quadrotor_pushes.py [DURATION (s), default 8] [VARIANTS, default
                                      paper,plus,plus_fast]

Prints, per push and variant: completed or the failure, the end-effector error's peak over
4-6 s and after 6 s, and the CoM error's peak from 4 s.
"""

from __future__ import annotations

import dataclasses
import sys

from aerial_drake.control.plus import PlusParams
from aerial_drake.simulation.runner import RunResult, SimulationFailed, run_scenario
from aerial_drake.simulation.scenarios import Scenario, load_scenario
from aerial_drake.simulation.scenarios.schema import Disturbance, Observer
from aerial_drake.simulation.tracking import entries

R = dataclasses.replace


def variant(scenario: Scenario, name: str) -> Scenario:
    if name.startswith("plus"):
        scenario = R(scenario, observer=Observer(enabled=True, bandwidth=20.0),
                     controller=R(scenario.controller, type="paper_plus", plus=PlusParams(
                         vehicle_force_feedforward=True, wrench_compensation=True)))
    if name.endswith("fast"):
        scenario = R(scenario, gains=R(scenario.gains, k_R=382.0, k_w=52.6))
    return scenario


def main() -> None:
    duration = float(sys.argv[1]) if len(sys.argv) > 1 else 8.0
    names = sys.argv[2].split(",") if len(sys.argv) > 2 else ["paper", "plus", "plus_fast"]
    base = load_scenario("quadrotor_ur3e")
    for axis, sign in ((0, 1), (0, -1), (1, 1), (1, -1)):
        force = [0.0, 0.0, 0.0]
        force[axis] = 50.0 * sign
        push = Disturbance(target="vehicle", start=4.0, stop=5.0, force=force,
                           torque=[0.0] * 3)
        scenario = R(base, duration=duration, disturbances=[push])
        for name in names:
            try:
                result: RunResult | None = run_scenario(variant(scenario, name),
                                                        progress=False)
            except SimulationFailed as failed:
                result = failed.result
            if result is None:
                print(f"F = {force} {name}: could not run")
                continue
            tracking = entries(result.log["tracking"], result.layouts["tracking"])
            t = result.log["t"]
            ee, com = tracking["ee_position_error"][:, 0], tracking["com_error"][:, 0]
            after = ee[t >= 6.0]
            late = f"{1e3 * after.max():.2f} mm" if after.size else "-"
            print(f"F = {force} {name:9s} "
                  f"{'completed' if result.completed else (result.failure or '')[:100]}; "
                  f"EE peak 4-6 s {1e3 * ee[(t >= 4) & (t < 6)].max():.2f} mm, after 6 s "
                  f"{late}; CoM peak {1e3 * com[t >= 4].max():.1f} mm", flush=True)


if __name__ == "__main__":
    main()
