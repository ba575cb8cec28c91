"""The scenario fields set from the command line, collected in one place
(:func:`scenario_overrides`), and which option set a field an error names
(:func:`option_note`).

The options ``--duration`` (``run``, ``compare``) and ``--max-log-mb`` (``run``) set
top-level fields (:data:`FIELD_OPTIONS`), and ``--set KEY=VALUE`` (``run``, ``compare``;
repeatable) any field by its dotted name, VALUE read as YAML
(:func:`aerial_drake.simulation.scenarios.parse_assignments`); the dictionary goes as
``overrides`` to
:func:`aerial_drake.simulation.scenarios.load_scenario` (``run SCENARIO``),
:func:`aerial_drake.studies.paper.run_paper` (``run paper``) and
:func:`aerial_drake.studies.compare.run_compare` (``compare``). A field set twice
(``--duration 2 --set duration=3``) is refused. (``--seed`` perturbs the initial offsets
after loading:
:func:`aerial_drake.studies.paper.perturb_initial`; ``study`` passes its ``--duration`` to
:func:`aerial_drake.studies.spec.load_study`, which applies it to every run.)
"""

from __future__ import annotations

import argparse

#: Scenario field -> the option (argparse ``dest``) that sets it, on the commands that have it.
FIELD_OPTIONS = {"duration": "duration", "max_log_mb": "max_log_mb"}


def scenario_overrides(args: argparse.Namespace) -> dict:
    """The scenario fields the command line sets, ``{field: value}`` (empty: none); an option
    the command does not have, or left unset, sets nothing. A bad ``--set`` text, or a field
    set by two options, is a ScenarioError naming them."""
    from aerial_drake.simulation.scenarios import ScenarioError, parse_assignments

    overrides = parse_assignments(getattr(args, "assignments", None) or [])
    for field, dest in FIELD_OPTIONS.items():
        value = getattr(args, dest, None)
        if value is None:
            continue
        if field in overrides:
            raise ScenarioError(f"--{dest.replace('_', '-')} and --set {field}=... both set "
                                f"{field}; keep one", field)
        overrides[field] = value
    return overrides


def option_note(err: BaseException, overrides: dict,
                args: argparse.Namespace | None = None) -> str:
    """Which command-line option set the field an error names, if one did: its own option
    (``--duration``) or ``--set``."""
    field = getattr(err, "field", None)
    if not (isinstance(field, str) and field in overrides):
        return ""
    dest = FIELD_OPTIONS.get(field)
    if dest is not None and (args is None or getattr(args, dest, None) is not None):
        return f" (set by --{dest.replace('_', '-')})"
    return " (set by --set)"
