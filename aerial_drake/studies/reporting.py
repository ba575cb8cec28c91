"""How the command line reports an error: one line on stderr (no traceback), and with
``--json`` a JSON error object on stdout. Here, below the command line, so that the study
commands (aerial_drake.studies.paper.cli_run) report the same way."""

from __future__ import annotations

import argparse
import json
import sys


def report_error(args: argparse.Namespace, status: int, err: BaseException | str,
                 note: str | None = None) -> int:
    """Print ``error: ...`` (and ``note``) on stderr, and with ``--json`` a JSON error object
    on stdout; returns ``status`` (the exit statuses: docs/reliability.md)."""
    message = str(err)
    print(f"error: {message}", file=sys.stderr)
    if note:
        print(note, file=sys.stderr)
    if getattr(args, "json", False):
        kind = type(err).__name__ if isinstance(err, BaseException) else "error"
        print(json.dumps({"error": {"exit_status": status, "kind": kind,
                                    "field": getattr(err, "field", None),
                                    "message": message, "note": note}}, indent=2))
    return status
