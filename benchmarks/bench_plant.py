"""The floor under the real-time factor: the simulated plant alone, integrated as the paper's
runs integrate it (continuous MultibodyPlant, runge_kutta3 at a fixed 1 ms step, the
scenario's simulator settings), with constant zero inputs and no other system.

Prints, per plant variant, the median wall time per step in microseconds and the real-time
factor that this alone allows; the closed loop cannot be faster (docs/performance.md).

    python benchmarks/bench_plant.py [--repeats 3] [--duration 5]
"""

from __future__ import annotations

import argparse
import platform
import statistics
import time

import numpy as np
from pydrake.systems.analysis import ApplySimulatorConfig, Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource

from aerial_drake.robots.models import add_to_builder
from aerial_drake.simulation.scenarios import load_scenario

#: The scenario whose simulator settings (integrator, step) are used for each plant variant.
SCENARIOS = {"rigid": "nominal", "rotors": "disturbed"}


def step_time(variant: str, duration: float) -> float:
    """Wall time per 1 ms step (s) of the plant alone over ``duration`` simulated seconds."""
    return plant_alone(load_scenario(SCENARIOS[variant]), duration, variant)[0]


def plant_alone(scenario, duration: float, variant: str | None = None) -> tuple[float, float]:
    """Wall time per step (s) and in all (s) of ``scenario``'s simulated plant alone (its
    plant variant unless ``variant`` is given, its robot, plant config and environment, and its
    simulator settings) over ``duration`` simulated seconds, zero inputs, nothing else but
    the SceneGraph it is registered with: the floor under the closed loop of that scenario."""
    builder = DiagramBuilder()
    sim = add_to_builder(builder, variant or scenario.plant_variant,
                         robot=scenario.robot_description(), plant_config=scenario.plant,
                         environment=scenario.environment.model_directives(),
                         environment_packages=scenario.environment.packages)
    plant = sim.plant
    zero = builder.AddSystem(ConstantVectorSource(np.zeros(plant.num_actuated_dofs())))
    builder.Connect(zero.get_output_port(), plant.get_actuation_input_port())
    simulator = Simulator(builder.Build())
    ApplySimulatorConfig(scenario.simulator, simulator)
    start = time.perf_counter()
    simulator.Initialize()
    simulator.AdvanceTo(duration)
    wall = time.perf_counter() - start
    return wall / simulator.get_num_steps_taken(), wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--duration", type=float, default=5.0)
    args = parser.parse_args()
    print(f"machine: {platform.machine()}, {platform.platform()}, python "
          f"{platform.python_version()}")
    print(f"{'plant':>8} {'us/step':>9} {'RT factor (plant alone)':>24}")
    for variant in SCENARIOS:
        median = statistics.median(step_time(variant, args.duration)
                                   for _ in range(args.repeats))
        print(f"{variant:>8} {1e6 * median:9.1f} {1e-3 / median:24.1f}")


if __name__ == "__main__":
    main()
