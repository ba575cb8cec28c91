"""Raw YAML data held against the schema's types, to name the field that does not fit
(Drake's loader says what failed to convert, not where): used on a scenario file's data
(:mod:`.loading`) and on overrides (:mod:`aerial_drake.simulation.scenarios.overrides`)."""

# No "from __future__ import annotations": the schema's field types are compared as objects.
import dataclasses
from typing import Any

import numpy as np
from pydrake.systems.analysis import SimulatorConfig

from aerial_drake.simulation.scenarios.checks import show


def find_bad_field(data: Any, schema: Any, prefix: str = "") -> str | None:
    """The dotted name of the first value in ``data`` that does not fit ``schema``'s type
    (Drake's loader says what failed to convert, not where), with what was expected."""
    if not isinstance(data, dict) or not dataclasses.is_dataclass(schema):
        return None
    types = {f.name: f.type for f in dataclasses.fields(schema)}
    for key, value in data.items():
        name = f"{prefix}{key}"
        kind = types.get(key)
        if kind is None:
            return f"{name} (not a field of {prefix.rstrip('.') or 'the scenario'}; fields: " \
                   f"{', '.join(types)})"
        if dataclasses.is_dataclass(kind) or kind is SimulatorConfig:
            if not isinstance(value, dict):
                what = "an empty section" if value is None else f"got {show(value)}"
                return f"{name} (expected a section of fields, {what}: give its fields, " \
                       "or remove the line to keep the defaults)"
            if dataclasses.is_dataclass(kind):
                found = find_bad_field(value, kind, name + ".")
                if found:
                    return found
            continue
        args = getattr(kind, "__args__", None)
        if args:  # a list
            if not isinstance(value, list):
                return f"{name} (expected a list, got {show(value)})"
            item = args[0]
            for i, v in enumerate(value):
                if dataclasses.is_dataclass(item):
                    if not isinstance(v, dict):
                        return f"{name}[{i}] (expected a section of fields, got {show(v)})"
                    found = find_bad_field(v, item, f"{name}[{i}].")
                    if found:
                        return found
                elif mismatch(item, v):
                    return f"{name}[{i}] ({mismatch(item, v)})"
            continue
        if mismatch(kind, value):
            return f"{name} ({mismatch(kind, value)})"
    return None


def mismatch(kind: Any, v: Any) -> str | None:
    """What is wrong with ``v`` as a value of type ``kind`` (float, str, bool), or None."""
    if kind is float and (isinstance(v, bool) or not isinstance(v, (int, float))):
        if isinstance(v, str):  # YAML 1.1 reads 1e3 as text; Drake converts it
            try:
                float(v)
                return None
            except ValueError:
                pass
        return f"expected a number, got {show(v)}"
    if kind is str and not isinstance(v, str):
        return f"expected text, got {show(v)}"
    if kind is bool and not isinstance(v, bool):
        return f"expected true or false, got {show(v)}"
    return None


def plain_values(value: Any) -> Any:
    """``value`` (a scenario, a section, a list) with every numpy array as a list and every
    numpy scalar as a Python number, recursively through dataclasses and lists: what the
    Python API accepts in a vector field (``force=np.array(...)``), read as the YAML's list
    would be. A copy where anything changed (the caller's objects are left alone), else the
    same object."""
    if isinstance(value, np.ndarray):
        return plain_values(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (list, tuple)):
        items = [plain_values(v) for v in value]
        changed = any(a is not b for a, b in zip(items, value))
        return (list(items) if isinstance(value, list) else tuple(items)) if changed else value
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        changes = {}
        for f in dataclasses.fields(value):
            old = getattr(value, f.name)
            new = plain_values(old)
            if new is not old:
                changes[f.name] = new
        return dataclasses.replace(value, **changes) if changes else value
    return value


def find_array(value: Any, prefix: str = "") -> str | None:
    """The dotted name (``disturbances[0].force``) of the first numpy array in ``value`` (a
    scenario or a section), or None. (A numpy scalar passes: it compares as a number.)"""
    if isinstance(value, np.ndarray):
        return prefix or "scenario"
    if isinstance(value, (list, tuple)):
        return next((found for i, v in enumerate(value)
                     if (found := find_array(v, f"{prefix}[{i}]"))), None)
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return next((found for f in dataclasses.fields(value)
                     if (found := find_array(getattr(value, f.name),
                                             f"{prefix}.{f.name}" if prefix else f.name))),
                    None)
    return None
