"""The scenario fields set from the command line, collected in one place
(:func:`scenario_overrides`), and which option set a field an error names
(:func:`option_note`).

Today the options ``--duration`` (``run``, ``compare``) and ``--max-log-mb`` (``run``) set
top-level fields (:data:`FIELD_OPTIONS`); the dictionary goes as ``overrides`` to
:func:`aerial_drake.simulation.scenarios.load_scenario` (``run SCENARIO``),
:func:`aerial_drake.studies.paper.run_paper` (``run paper``) and
:func:`aerial_drake.studies.compare.run_compare` (``compare``). A new option that sets
scenario fields (e.g. ``--set KEY=VALUE``) adds its pairs in :func:`scenario_overrides`, and
the three commands take them. (``--seed`` perturbs the initial offsets after loading:
:func:`aerial_drake.studies.paper.perturb_initial`; ``study`` passes its ``--duration`` to
:func:`aerial_drake.studies.spec.load_study`, which applies it to every run.)
"""

from __future__ import annotations

import argparse

#: Scenario field -> the option (argparse ``dest``) that sets it, on the commands that have it.
FIELD_OPTIONS = {"duration": "duration", "max_log_mb": "max_log_mb"}


def scenario_overrides(args: argparse.Namespace) -> dict:
    """The scenario fields the command line sets, ``{field: value}`` (empty: none); an option
    the command does not have, or left unset, sets nothing."""
    overrides: dict = {}
    for field, dest in FIELD_OPTIONS.items():
        value = getattr(args, dest, None)
        if value is not None:
            overrides[field] = value
    return overrides


def option_note(err: BaseException, overrides: dict) -> str:
    """Which command-line option set the field an error names, if one did."""
    field = getattr(err, "field", None)
    if isinstance(field, str) and field in overrides:
        return f" (set by --{field.replace('_', '-')})"
    return ""
