"""Command line: ``aerial-drake run SCENARIO``, ``plot RUN_DIR ...``, ``scenarios [show NAME]``,
``compare SCENARIO``, ``info``, ``analyze``, ``study FILE`` and ``study-plot TABLE``.

``SCENARIO`` is a shipped scenario name (``nominal``) or a path to a YAML file.

This package only parses and prints: :mod:`.parser` builds the parser; one module per command
(:mod:`.run`, :mod:`.paper`, :mod:`.compare`, :mod:`.plot`, :mod:`.info`, :mod:`.analyze`,
:mod:`.study`) turns the options into typed arguments of a library function (in
:mod:`aerial_drake.studies`, :mod:`aerial_drake.analysis`, :mod:`aerial_drake.viz`,
:mod:`aerial_drake.simulation`) and prints what it returns; :mod:`.overrides` collects the
scenario fields set from the command line; :mod:`.errors` reports errors and maps them to exit
statuses; :mod:`.restart` compiles on the first run and restarts.
"""

from __future__ import annotations

import sys
import warnings
from typing import TextIO

from aerial_drake.cli.errors import report_error
from aerial_drake.cli.parser import build_parser

__all__ = ["build_parser", "main"]


def _one_line_warning(message: Warning | str, category: type[Warning], filename: str,
                      lineno: int, file: TextIO | None = None, line: str | None = None) -> None:
    """A warning as the command line prints it: ``warning (Category): message``."""
    (file if file is not None else sys.stderr).write(
        f"warning ({category.__name__}): {message}\n")


def main(argv: list[str] | None = None) -> int:
    """Run the command in ``argv`` (default: the process's arguments); returns the exit status
    (docs/reliability.md, "Exit statuses")."""
    from aerial_drake.cli.errors import interruption_in
    from aerial_drake.simulation.interrupts import exit_status_of, handling

    args = build_parser().parse_args(argv)
    # Run as a program (its arguments from the command line): compile_first may restart it.
    args.restartable = argv is None
    try:
        with handling(), warnings.catch_warnings():  # SIGINT, SIGTERM, SIGHUP: interrupts
            if not args.debug:  # a warning as one line, not the package's source line
                warnings.showwarning = _one_line_warning
            return args.func(args)
    except KeyboardInterrupt as err:
        # One in the simulation is handled by the runner (logs written, exit 128 + signal);
        # this is one before it started (loading, compiling, solving the initial pose).
        return report_error(args, exit_status_of(err), f"interrupted ({str(err) or 'Ctrl-C'}) "
                            "outside the simulation; nothing more written")
    except Exception as err:  # a bug, or a fault not foreseen: one line unless --debug
        interrupt = interruption_in(err)  # e.g. Ctrl-C while pydrake's modules load
        if interrupt is not None and not args.debug:
            return report_error(args, exit_status_of(interrupt), f"interrupted "
                                f"({str(interrupt) or 'Ctrl-C'}) outside the simulation; "
                                "nothing more written")
        if args.debug:
            raise
        return report_error(args, 1, f"unexpected {type(err).__name__}: {err} (rerun with "
                            "--debug for the traceback, and please report it)")
