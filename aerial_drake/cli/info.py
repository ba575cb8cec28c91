"""``aerial-drake info`` (the models and scenarios) and ``aerial-drake scenarios [show NAME]``."""

from __future__ import annotations

import argparse
import sys

import numpy as np

from aerial_drake.cli.errors import report_error


def cmd_info(args: argparse.Namespace) -> int:
    """``aerial-drake info``: the shipped robots' plant variants and the shipped scenarios."""
    from aerial_drake.robots.description import load_robot_description, shipped_robots
    from aerial_drake.robots.models import make_plant
    from aerial_drake.simulation.scenarios import shipped_scenarios

    for name in shipped_robots():
        robot = load_robot_description(name)
        print(f"robot '{name}': task {list(robot.task)}")
        for variant in robot.variant_names():
            _print_variant(make_plant(variant, robot=robot), variant)
    print(f"shipped scenarios: {sorted(shipped_scenarios())}")
    return 0


def _print_variant(manip, variant: str) -> None:
    """One plant variant's sizes, mass and joints (``aerial-drake info``)."""
    plant = manip.plant
    ctx = plant.CreateDefaultContext()
    print(f"  plant variant '{variant}': {plant.num_bodies() - 1} bodies, "
          f"{plant.num_positions()} positions, {plant.num_velocities()} velocities, "
          f"{plant.num_actuators()} actuators, total mass "
          f"{plant.CalcTotalMass(ctx):.3f} kg")
    I = manip.base_body.CalcSpatialInertiaInBodyFrame(ctx).CalcRotationalInertia()
    print(f"    vehicle body '{manip.base_body.name()}': mass "
          f"{manip.base_body.get_mass(ctx):.3f} kg, inertia diag "
          f"{np.round(np.diag(I.CopyToFullMatrix3()), 4).tolist()} kg m^2")
    print(f"    arm joints: {[j.name() for j in manip.arm_joints]}")
    print(f"    arm effort limits (N m): {manip.arm_effort_limits().tolist()}")
    if manip.rotor_joints:
        print(f"    rotor joints: {[j.name() for j in manip.rotor_joints]}")


def _first_line(text: str) -> str:
    """The first sentence of a description, on one line."""
    flat = " ".join(text.split())
    end = flat.find(": ")
    return flat if end < 0 else flat[:end]


def cmd_scenarios(args: argparse.Namespace) -> int:
    """``aerial-drake scenarios [show NAME]``: list the shipped scenarios, or print one's file."""
    from aerial_drake.simulation.scenarios import ScenarioError, load_scenario, shipped_scenarios
    shipped = shipped_scenarios()
    if args.action is None:
        width = max(len(n) for n in shipped)
        for name in shipped:
            sc = load_scenario(name)
            print(f"{name:<{width}}  {_first_line(sc.description)} ({sc.plant_variant} plant, "
                  f"{sc.duration:g} s, {len(sc.disturbances)} disturbance windows)")
        print("\n'aerial-drake scenarios show NAME > my.yaml' prints one to edit; "
              "'aerial-drake run my.yaml' runs it.")
        return 0
    if args.name is None:
        return report_error(args, 2, "'scenarios show' needs a NAME; shipped scenarios: "
                            f"{sorted(shipped)}")
    if args.name not in shipped:
        return report_error(args, 2, f"no shipped scenario '{args.name}'. Valid names are: "
                            f"{sorted(shipped)}")
    try:
        load_scenario(args.name)  # the shipped file as shipped: it loads
    except ScenarioError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    # The file itself, comments (units, sources) included: ready to save and edit.
    sys.stdout.write(shipped[args.name].read_text())
    return 0
