"""A study's scenario fields that name files, made absolute before the base and the settings
are merged: a path in the base scenario file starts at that file's folder, a path in the study
file's ``settings`` at the study file's folder (as ``run``, ``compare`` and ``analyze`` read a
scenario's paths from its own file)."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

from aerial_drake.robots.description import shipped_robots


def _absolute(entry: Any, folder: Path) -> Any:
    if not isinstance(entry, str) or not entry or "://" in entry:
        return entry
    path = Path(entry).expanduser()
    return entry if path.is_absolute() else str((folder / path).resolve())


def absolute_paths(data: dict, folder: Path) -> dict:
    """A copy of the scenario fields ``data`` whose relative file paths (``robot`` unless a
    shipped robot's name, ``trajectory.python.path``, ``environment.packages`` and its
    directives' files) start at ``folder``."""
    data = copy.deepcopy(data)
    folder = folder.resolve()
    robot = data.get("robot")
    if isinstance(robot, str) and robot not in shipped_robots():
        data["robot"] = _absolute(robot, folder)
    python = (data.get("trajectory") or {}).get("python") if isinstance(
        data.get("trajectory"), dict) else None
    if isinstance(python, dict) and python.get("path"):
        python["path"] = _absolute(python["path"], folder)
    environment = data.get("environment")
    if isinstance(environment, dict):
        if isinstance(environment.get("packages"), list):
            environment["packages"] = [_absolute(p, folder) for p in environment["packages"]]
        for directive in environment.get("directives") or []:
            for key in ("add_model", "add_directives"):
                item = directive.get(key) if isinstance(directive, dict) else None
                if isinstance(item, dict) and "file" in item:
                    item["file"] = _absolute(item["file"], folder)
    return data
