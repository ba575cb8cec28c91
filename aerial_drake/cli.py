"""Command line: ``aerial-drake run SCENARIO``, ``aerial-drake info``.

``SCENARIO`` is a shipped scenario name (``nominal``) or a path to a YAML file.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np


def _cmd_info(args: argparse.Namespace) -> int:
    from aerial_drake.models import PLANT_VARIANTS, make_plant
    from aerial_drake.scenarios import shipped_scenarios

    for variant in PLANT_VARIANTS:
        manip = make_plant(variant)
        plant = manip.plant
        ctx = plant.CreateDefaultContext()
        print(f"plant variant '{variant}': {plant.num_bodies() - 1} bodies, "
              f"{plant.num_positions()} positions, {plant.num_velocities()} velocities, "
              f"{plant.num_actuators()} actuators, total mass "
              f"{plant.CalcTotalMass(ctx):.3f} kg")
        I = manip.base_body.CalcSpatialInertiaInBodyFrame(ctx).CalcRotationalInertia()
        print(f"  base body '{manip.base_body.name()}': mass "
              f"{manip.base_body.get_mass(ctx):.3f} kg, inertia diag "
              f"{np.round(np.diag(I.CopyToFullMatrix3()), 4).tolist()} kg m^2")
        print(f"  arm joints: {[j.name() for j in manip.arm_joints]}")
        print(f"  arm effort limits (N m): {manip.arm_effort_limits().tolist()}")
        if manip.rotor_joints:
            print(f"  rotor joints: {[j.name() for j in manip.rotor_joints]}")
    print(f"shipped scenarios: {sorted(shipped_scenarios())}")
    return 0


def _print_summary(result) -> None:
    m = result.metrics
    print(f"scenario '{m['scenario']}': simulated {m['simulated_time_s']:.2f} s in "
          f"{m['wall_time_s']:.2f} s wall (real-time factor {m['real_time_factor']:.1f}x)")
    header = f"{'phase (s)':>14} {'EE pos max (mm)':>16} {'EE rot max (mrad)':>18} " \
             f"{'CoM max (mm)':>13} {'base att max (mrad)':>20}"
    print(header)
    for p in m["phases"]:
        if p["samples"] == 0:
            continue
        print(f"{p['start_s']:6.1f}-{p['end_s']:<6.1f} "
              f"{1e3 * p['ee_position_error_m']['max']:16.3f} "
              f"{1e3 * p['ee_orientation_error_rad']['max']:18.3f} "
              f"{1e3 * p['com_position_error_m']['max']:13.3f} "
              f"{1e3 * p['base_attitude_error_rad']['max']:20.3f}")
    print(f"min sigma_min(J3) = {m['min_sigma_min_J3']:.4f}, min |f_d| = "
          f"{m['min_f_d_norm_N']:.1f} N")
    sat = {k: v for k, v in m["saturated_s_total"].items() if v > 0}
    print(f"saturated time (s): {sat if sat else 'none'}")
    if result.out_dir is not None:
        print(f"wrote {result.out_dir / 'log.npz'} and {result.out_dir / 'metrics.json'}")


def _cmd_run(args: argparse.Namespace) -> int:
    from aerial_drake.runner import SimulationFailed, run_scenario
    from aerial_drake.scenarios import ScenarioError, load_scenario

    overrides = {}
    if args.duration is not None:
        overrides["duration"] = args.duration
    try:
        scenario = load_scenario(args.scenario, overrides=overrides)
    except ScenarioError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    out = Path(args.out) / scenario.name
    print(f"running scenario '{scenario.name}' ({scenario.duration:g} s) -> {out}")
    try:
        result = run_scenario(scenario, out_dir=out, progress=not args.quiet)
    except SimulationFailed as err:
        print(f"error: {err}", file=sys.stderr)
        print(f"logs up to the failure are in {out}", file=sys.stderr)
        return 1
    _print_summary(result)
    if args.json:
        print(json.dumps(result.metrics, indent=2))
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="aerial-drake",
        description="Task-space tracking control for underactuated aerial manipulators, on Drake.")
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="simulate a scenario and write log.npz and metrics.json")
    run.add_argument("scenario", help="shipped scenario name (e.g. nominal) or a YAML file")
    run.add_argument("--duration", type=float, default=None, help="override the duration (s)")
    run.add_argument("--out", default="out", help="output folder (default: ./out)")
    run.add_argument("--quiet", action="store_true", help="no progress line")
    run.add_argument("--json", action="store_true", help="also print metrics.json")
    run.set_defaults(func=_cmd_run)
    info = sub.add_parser("info", help="print a summary of the models and scenarios")
    info.set_defaults(func=_cmd_info)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
