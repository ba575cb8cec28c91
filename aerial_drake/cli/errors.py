"""How the command line reports an error: one line on stderr (no traceback), and with
``--json`` a JSON error object on stdout, and which exit status each error gets
(:func:`exit_status_for`): 2 bad input (the message names the file, field or option, the
value and the fix), 1 a run that failed, 3 results not written, 128 + n stopped by signal n
(docs/reliability.md, "Exit statuses"). Every command reports through here. The standard
library only: the command line imports this before anything else."""

from __future__ import annotations

import argparse
import json
import signal
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


#: The exit status of each error the command line expects, by the exception's class
#: (``module.QualifiedName``; docs/reliability.md, "Exit statuses"). The classes are named, not
#: imported, so that this module stays light; :func:`exit_status_for` walks the exception's
#: classes from the most derived, so ResultsNotWritten (an OutputError) gets 3.
EXIT_STATUSES = {
    "aerial_drake.simulation.scenarios.checks.ScenarioError": 2,  # bad input
    "aerial_drake.dynamics.equilibrium.UnreachablePose": 2,       # bad input (the start pose)
    "aerial_drake.robots.description.RobotDescriptionError": 2,   # bad input (a description)
    "aerial_drake.analysis.onboarding.errors.OnboardingError": 2,  # robot init/check input
    "aerial_drake.simulation.outputs.ResultsNotWritten": 3,       # results lost (a full disk)
    "aerial_drake.simulation.outputs.OutputError": 2,             # the output folder
    "aerial_drake.simulation.runner.SimulationFailed": 1,         # the run failed
}
#: Interruptions: 128 + the signal's number (``signum``; 130 for a bare KeyboardInterrupt).
_INTERRUPTED = "aerial_drake.simulation.runner.SimulationInterrupted"


def interruption_in(err: BaseException) -> KeyboardInterrupt | None:
    """The KeyboardInterrupt (Ctrl-C, or a stop signal: simulation.interrupts) behind ``err``
    in its chain of causes, if any: a signal during an import of a compiled module (pydrake's,
    while loading) comes back as ``ImportError: initialization failed`` raised from it."""
    seen: set[int] = set()
    while err is not None and id(err) not in seen:
        if isinstance(err, KeyboardInterrupt):
            return err
        seen.add(id(err))
        err = err.__cause__ or (None if err.__suppress_context__  # type: ignore[assignment]
                                else err.__context__)
    return None


def exit_status_for(err: BaseException) -> int | None:
    """The command line's exit status for ``err``: 128 + n for an interruption by signal n
    (SimulationInterrupted, a KeyboardInterrupt), else :data:`EXIT_STATUSES`' entry for its
    class; None for an error not foreseen (a bug: the command line's catch-all). An error
    raised from an interruption (:func:`interruption_in`) is that interruption."""
    interrupt = interruption_in(err)
    if interrupt is not None:
        return 128 + getattr(interrupt, "signum", signal.SIGINT)
    for cls in type(err).__mro__:
        name = f"{cls.__module__}.{cls.__qualname__}"
        if name == _INTERRUPTED:
            return 128 + getattr(err, "signum", signal.SIGINT)
        if name in EXIT_STATUSES:
            return EXIT_STATUSES[name]
    return None


def report_exception(args: argparse.Namespace, err: BaseException,
                     note: str | None = None) -> int:
    """:func:`report_error` with :func:`exit_status_for`'s status; an error it does not know
    is raised again (for the command line's catch-all)."""
    status = exit_status_for(err)
    if status is None:
        raise err
    return report_error(args, status, err, note)
