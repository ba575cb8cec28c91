"""Reading a scenario file's text: every way a file can be unreadable gives a ScenarioError
that says where and how to fix it (a folder, binary or non-UTF-8 bytes, a YAML syntax error, a
tab, an unknown tag, an empty file, a top level that is not a mapping)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pydrake.common.yaml import yaml_load_data

from aerial_drake.simulation.scenarios.checks import ScenarioError

#: Larger files are not scenarios (the shipped ones are about 4 kB).
MAX_FILE_BYTES = 1_000_000


def read_scenario_file(path: Path) -> tuple[str, dict[str, Any]]:
    """The text of the scenario file at ``path`` and its YAML data (a mapping)."""
    if path.is_dir():
        raise ScenarioError(f"{path} is a folder, not a scenario file: give the path of a "
                            ".yaml file (e.g. aerial_drake/simulation/scenarios/nominal.yaml)")
    if not path.exists():
        raise ScenarioError(f"scenario file not found: {path}")
    try:
        size = path.stat().st_size
        if size > MAX_FILE_BYTES:
            raise ScenarioError(f"{path}: {size} bytes is too large for a scenario file "
                                f"(limit {MAX_FILE_BYTES}); is it the right file?")
        raw = path.read_bytes()
    except OSError as err:
        raise ScenarioError(f"{path}: cannot be read ({err.strerror or err})") from None
    if b"\0" in raw:
        raise ScenarioError(f"{path}: a binary file (it holds NUL bytes), not a YAML scenario")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as err:
        line = raw[:err.start].count(b"\n") + 1
        raise ScenarioError(f"{path}: line {line}: byte 0x{raw[err.start]:02x} is not UTF-8 "
                            "text; save the file as UTF-8") from None
    try:
        data = yaml_load_data(text)
    except Exception as err:  # PyYAML's errors, or Drake's
        raise ScenarioError(f"{path}: {_yaml_problem(err, text)}") from None
    if data is None:
        raise ScenarioError(f"{path}: the file is empty (no fields): a scenario is a mapping "
                            "of fields, e.g. a copy of aerial_drake/simulation/scenarios/"
                            "nominal.yaml")
    if not isinstance(data, dict):
        raise ScenarioError(f"{path}: the top level must be a mapping of scenario fields "
                            f"(name: ..., duration: ...), not a {type(data).__name__}")
    return text, data


def _yaml_problem(err: Exception, text: str) -> str:
    """A YAML error in one line: where, what, and the fix for the common cases."""
    mark = getattr(err, "problem_mark", None) or getattr(err, "context_mark", None)
    problem = getattr(err, "problem", None) or str(err).splitlines()[0]
    where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark is not None else ""
    hint = ""
    if "'\\t'" in problem or "\t" in problem:
        hint = "; YAML indents with spaces, never tabs: replace the tab with spaces"
    elif "!" in str(err) and ("tag" in str(err) or "ConstructorError" in type(err).__name__):
        hint = "; YAML tags (!name) are not used in scenario files: remove it"
    elif type(err).__name__ == "ConstructorError":
        hint = "; remove the YAML tag (!name) or anchor there"
    return f"YAML syntax error at {where}{problem}{hint}"
