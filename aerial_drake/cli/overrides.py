"""The scenario fields set from the command line, collected in one place
(:func:`scenario_overrides`), and which option set a field an error names
(:func:`option_note`).

Today the options ``--duration`` and ``--max-log-mb`` of ``run`` set top-level fields; the
dictionary goes to :func:`aerial_drake.simulation.scenarios.load_scenario` (``run SCENARIO``)
and :func:`aerial_drake.studies.paper.run_paper` (``run paper``) as ``overrides``. A new
option that sets scenario fields (e.g. ``--set KEY=VALUE``) adds its pairs here, and both
commands take them. (``--seed`` perturbs the initial offsets after loading:
:func:`aerial_drake.studies.paper.perturb_initial`; ``compare`` and ``study`` pass their
``--duration`` to :func:`aerial_drake.studies.compare.run_compare` and
:func:`aerial_drake.studies.spec.load_study`.)
"""

from __future__ import annotations

import argparse


def scenario_overrides(args: argparse.Namespace) -> dict:
    """The scenario fields the command line sets, ``{field: value}`` (empty: none)."""
    overrides: dict = {}
    if args.duration is not None:
        overrides["duration"] = args.duration
    if args.max_log_mb is not None:
        overrides["max_log_mb"] = args.max_log_mb
    return overrides


def option_note(err: BaseException, overrides: dict) -> str:
    """Which command-line option set the field an error names, if one did."""
    field = getattr(err, "field", None)
    if isinstance(field, str) and field in overrides:
        return f" (set by --{field.replace('_', '-')})"
    return ""
