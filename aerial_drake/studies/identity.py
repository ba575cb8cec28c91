"""A study's identity, kept with its table: what its rows were run from.

The identity is every field that decides which runs a study plans and what each simulates:
the study's name (every run carries it), the duration, the draws' seed, the varied parameters
(fields, kinds, values, ranges, modes), the settings as given, and the base scenario's
resolved text (its file, the settings and the duration applied). ``provenance.json`` holds
them (``study.spec``, ``study.settings``, ``study.base_scenario``), so a table written
before this check is checked too. Not in it: the description, the metrics kept (a change of
columns is refused by the table itself) and the number of draws (draw ``j`` takes the same
values whatever their number, so more draws extend a study and its rows stay right).

A study resumed into a folder whose table was run from another identity is refused
(:class:`StudyChanged`) before any run, naming what changed: rows of two specs are never
mixed in one table.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from aerial_drake.simulation.outputs import OutputError, finite_or_none
from aerial_drake.studies.table import read_table_text

#: The study file's fields that are part of its identity (module docstring).
SPEC_FIELDS = ("name", "duration", "seed", "parameters")


class StudyChanged(OutputError):
    """The folder's table was run from another study spec (module docstring)."""


def identity(provenance_study: dict[str, Any]) -> dict[str, Any]:
    """The identity (module docstring) in a provenance's ``study`` section, as JSON values."""
    spec = provenance_study.get("spec") or {}
    found = {name: spec.get(name) for name in SPEC_FIELDS}
    found["settings"] = provenance_study.get("settings")
    found["base_scenario"] = provenance_study.get("base_scenario")
    return json.loads(json.dumps(finite_or_none(found)))


def _shown(value: Any) -> str:
    text = json.dumps(value)
    return text if len(text) <= 80 else text[:77] + "..."


def changes(before: dict[str, Any], now: dict[str, Any]) -> list[str]:
    """What differs between two identities, one phrase per field."""
    said = []
    for key in (*SPEC_FIELDS, "settings", "base_scenario"):
        if before.get(key) == now.get(key):
            continue
        if key == "base_scenario":
            said.append("the base scenario (its file, or the settings or duration applied "
                        "to it)")
        elif key == "duration" and None in (before.get(key), now.get(key)):
            base = "the base scenario's"
            said.append(f"duration: {before.get(key) or base} before, "
                        f"{now.get(key) or base} now")
        else:
            said.append(f"{key}: {_shown(before.get(key))} before, {_shown(now.get(key))} now")
    return said


def check_same_study(table: Path, provenance: Path, now: dict[str, Any]) -> None:
    """Refuse (StudyChanged, naming the folder, what changed and the fix) to add rows to
    ``table`` if its rows were run from another identity than ``now`` (a provenance
    ``study`` section), or if it has rows but no readable ``provenance``."""
    fix = ("give another --out for the new spec, or --restart to discard the folder's "
           "results and run the study from the start")
    if not table.is_file() or len(read_table_text(table, fix).splitlines()) < 2:
        return  # no rows: nothing to mix with
    try:
        stored = json.loads(provenance.read_text(encoding="utf-8"))["study"]
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise StudyChanged(f"{table.parent}: its results.csv has rows but its "
                           f"{provenance.name} cannot be read ({type(err).__name__}: {err}), "
                           f"so the spec they were run from is unknown: {fix}") from None
    said = changes(identity(stored), identity(now))
    if said:
        raise StudyChanged(f"{table.parent} holds rows run from another study spec; "
                           f"changed: {'; '.join(said)}. Nothing was run: {fix}")
