"""``aerial-drake analyze``: the stability analysis (:func:`aerial_drake.analysis.analyze`) and
its report (:func:`aerial_drake.analysis.format_report`)."""

from __future__ import annotations

import argparse
import sys


def cmd_analyze(args: argparse.Namespace) -> int:
    """``aerial-drake analyze [--out DIR] [--scenario NAME] [--fast] [--seed N] [--quiet]``."""
    from aerial_drake.analysis import (
        FAST_SETTINGS,
        FULL_SETTINGS,
        UnreachablePose,
        analyze,
        format_report,
    )
    from aerial_drake.simulation.scenarios import ScenarioError

    settings = FAST_SETTINGS if args.fast else FULL_SETTINGS
    try:
        report = analyze(args.out, scenario=args.scenario, settings=settings, seed=args.seed,
                         stream=None if args.quiet else sys.stdout)
    except (ScenarioError, UnreachablePose) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    print(format_report(report))
    return 0
