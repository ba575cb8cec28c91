"""Overrides of a loaded scenario's fields, by dotted name into the nested sections
(``{"gains.k_R": 300, "trajectory.hover.ee_position": [0.6, 0, 1.3]}``), and the command
line's ``KEY=VALUE`` assignments that give them (:func:`parse_assignments`).

Each override is checked for its name and its type here (a ScenarioError naming
``overrides['gains.k_R']`` and the fix); its value is checked by the validation pass after.
A list replaces the list it names whole; a section (a dataclass) is given as an instance of
its class, or field by field with dotted names.
"""


# No "from __future__ import annotations": the schema's field types are compared as objects.
import copy
import dataclasses
import re
import typing
from collections.abc import Iterable
from typing import Any

from pydrake.common.yaml import yaml_dump, yaml_load_data, yaml_load_typed

from aerial_drake.simulation.scenarios.checks import ScenarioError, show
from aerial_drake.simulation.scenarios.fields import find_bad_field, mismatch

__all__ = ["apply_overrides", "parse_assignments"]

_DOTTED = re.compile(r"[A-Za-z_]\w*(\.[A-Za-z_]\w*)*")
_EXAMPLE = "e.g. gains.k_R=300 or initial.base_position_offset=[0.1, 0, 0]"


def parse_assignments(texts: Iterable[str]) -> dict[str, Any]:
    """``KEY=VALUE`` texts (the command line's ``--set``) as overrides: ``{KEY: VALUE}`` with
    VALUE read as YAML (``300``, ``[0.1, 0, 0]``, ``true``, ``rk3``). A text that is not an
    assignment, a KEY that is not a dotted name, an empty or unreadable VALUE, or a KEY given
    twice is a ScenarioError naming the text. Names and types are checked when the overrides
    are applied (:func:`apply_overrides`)."""
    out: dict[str, Any] = {}
    for text in texts:
        if not isinstance(text, str) or "=" not in text:
            raise ScenarioError(f"--set {text!r}: expected KEY=VALUE ({_EXAMPLE})")
        key, raw = (part.strip() for part in text.split("=", 1))
        if not _DOTTED.fullmatch(key):
            raise ScenarioError(f"--set {text!r}: {key!r} is not a field's dotted name "
                                f"({_EXAMPLE})")
        if not raw:
            raise ScenarioError(f"--set {text!r}: no value after '=' ({_EXAMPLE})", key)
        try:
            value = yaml_load_data(raw)
        except Exception as err:  # PyYAML's errors
            problem = getattr(err, "problem", None) or str(err).splitlines()[0]
            raise ScenarioError(f"--set {text!r}: the value {raw!r} is not YAML ({problem}); "
                                "quote text, bracket lists: [0.1, 0, 0]", key) from None
        if key in out:
            raise ScenarioError(f"--set {text!r}: {key} is set twice; keep one", key)
        out[key] = value
    return out


def apply_overrides(scenario: Any, overrides: dict) -> Any:
    """A copy of ``scenario`` (a :class:`.schema.Scenario`, not modified) with the fields
    named by ``overrides``' dotted keys replaced, each checked for its name and type
    (ScenarioError naming ``overrides['key']`` and the fix); values are checked by
    validate()."""
    if not isinstance(overrides, dict):
        raise ScenarioError(f"overrides: expected a dict of field -> value, got "
                            f"{type(overrides).__name__}")
    for key, value in overrides.items():
        where = f"overrides[{key!r}]"
        if not isinstance(key, str) or not _DOTTED.fullmatch(key):
            raise ScenarioError(f"{where}: not a field's dotted name ({_EXAMPLE})")
        scenario = _replaced(scenario, key.split("."), value, where, "")
    return scenario


def _replaced(section: Any, parts: list[str], value: Any, where: str, prefix: str) -> Any:
    """A copy of ``section`` with the field at ``parts`` (below ``prefix``) set to ``value``."""
    head, name = parts[0], prefix + parts[0]
    kinds = _field_types(section)
    if head not in kinds:
        owner = f"section {prefix.rstrip('.')}" if prefix else "the scenario"
        raise ScenarioError(f"{where}: {name} is not a field of {owner}; its fields: "
                            f"{', '.join(kinds)}", name)
    kind = kinds[head]
    if len(parts) > 1:
        inner = getattr(section, head)
        if not _field_types(inner):
            raise ScenarioError(f"{where}: {name} is a value, not a section: set {name} "
                                "itself", name)
        new = _replaced(inner, parts[1:], value, where, name + ".")
    else:
        new = _converted(kind, value, where, name, getattr(section, head))
    if dataclasses.is_dataclass(section) and not isinstance(section, type):
        return dataclasses.replace(section, **{head: new})
    section = copy.copy(section)  # a pydrake struct (SimulatorConfig)
    setattr(section, head, new)
    return section


def _field_types(section: Any) -> dict[str, Any]:
    """Field name -> type of a dataclass, or of a pydrake struct (its ``__fields__``, the
    type read from the current value); empty for a value."""
    if dataclasses.is_dataclass(section):
        return {f.name: f.type for f in dataclasses.fields(section)}
    fields = getattr(type(section), "__fields__", None)
    if fields is not None:
        return {f.name: type(getattr(section, f.name)) for f in fields}
    return {}


def _converted(kind: Any, value: Any, where: str, name: str, current: Any) -> Any:
    """``value`` as a value of field ``name`` (type ``kind``), or a ScenarioError."""
    def refuse(expected: str) -> typing.NoReturn:
        raise ScenarioError(f"{where}: expected {expected}, got {show(value)} ({_EXAMPLE})",
                            name)

    if dataclasses.is_dataclass(kind) or _field_types(current):
        if isinstance(value, type(current)):
            return value
        label = kind.__name__ if isinstance(kind, type) else type(current).__name__
        refuse(f"a {label} (or set its fields one by one: '{name}.<field>')")
    if typing.get_origin(kind) is list:
        if not isinstance(value, (list, tuple)):
            refuse("a list (it replaces the whole list)")
        (item,) = typing.get_args(kind)
        return [_item(item, v, where, f"{name}[{i}]") for i, v in enumerate(value)]
    return _scalar(kind, value, where, name, refuse)


def _item(kind: Any, value: Any, where: str, name: str) -> Any:
    """One item of a list field: a number, or a section (an instance, or its fields)."""
    if isinstance(kind, type) and dataclasses.is_dataclass(kind):
        if isinstance(value, kind):
            return value
        bad = (find_bad_field(value, kind, name + ".") if isinstance(value, dict) else
               f"{name} (expected a {kind.__name__} or a mapping of its fields, got "
               f"{show(value)})")
        if bad:
            raise ScenarioError(f"{where}: {bad}", bad.split(" ")[0])
        return yaml_load_typed(schema=kind, data=yaml_dump(value))
    bad = mismatch(kind, value)
    if bad:
        raise ScenarioError(f"{where}: {name}: {bad}", name)
    return float(value) if kind is float else value


def _scalar(kind: Any, value: Any, where: str, name: str, refuse: Any) -> Any:
    if kind is float:
        if mismatch(float, value):
            refuse("a number")
        return float(value)
    if kind is int:
        if isinstance(value, bool) or not isinstance(value, int):
            refuse("an integer")
        return value
    if kind is str and not isinstance(value, str):
        refuse("text")
    if kind is bool and not isinstance(value, bool):
        refuse("true or false")
    return value
