"""``aerial-drake robot init MODEL`` (a robot description and a hover scenario from a URDF or
SDF: :func:`aerial_drake.analysis.onboarding.init_robot`) and ``aerial-drake robot check FILE``
(the margins at the nominal posture: :func:`aerial_drake.analysis.onboarding.check_robot`)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from aerial_drake.cli.errors import report_exception


def cmd_robot_init(args: argparse.Namespace) -> int:
    """``aerial-drake robot init MODEL [--vehicle BODY] [--end-effector FRAME] ...``."""
    from aerial_drake.analysis.onboarding import InitOptions, format_init, init_robot

    options = InitOptions(
        model=Path(args.model), vehicle=args.vehicle, end_effector=args.end_effector,
        name=args.name, out=None if args.out is None else Path(args.out),
        thrust_to_weight=args.thrust_to_weight,
        body_torque=None if args.body_torque is None else [float(x) for x in args.body_torque],
        tool_axis=args.tool_axis, tool_direction=args.tool_direction,
        task=None if args.task is None else [t.strip() for t in args.task.split(",")],
        force=args.force)
    try:
        result = init_robot(options, stream=None if args.quiet else sys.stdout)
    except Exception as err:  # bad input: exit 2 (errors.EXIT_STATUSES); else a bug
        return report_exception(args, err)
    print(format_init(result))
    if args.json:
        print(json.dumps(result.to_json(), indent=2, allow_nan=False))
    return 0


def cmd_robot_check(args: argparse.Namespace) -> int:
    """``aerial-drake robot check FILE [--scenario S] [--json]``."""
    from aerial_drake.analysis.onboarding import check_robot, format_check

    try:
        report = check_robot(Path(args.file), scenario=args.scenario,
                             stream=None if args.quiet else sys.stdout)
    except Exception as err:
        return report_exception(args, err)
    print(format_check(report))
    if args.json:
        print(json.dumps(report.to_json(), indent=2, allow_nan=False))
    return 0
