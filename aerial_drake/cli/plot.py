"""``aerial-drake plot RUN_DIR ...``: runs overlaid (:func:`aerial_drake.viz.run_plots.
write_overlay`)."""

from __future__ import annotations

import argparse
import sys


def cmd_plot(args: argparse.Namespace) -> int:
    """``aerial-drake plot RUN_DIR [RUN_DIR ...] [--out DIR] [--formats ...]``."""
    from aerial_drake.viz.run_plots import write_overlay
    try:
        written = write_overlay(args.run_dirs, args.out, formats=tuple(args.formats))
    except (FileNotFoundError, ValueError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    for path in written:
        print(f"wrote {path}")
    return 0
