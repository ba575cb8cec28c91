"""The scenario's ``trajectory:`` section, checked at load for every kind: its fields
(:func:`~aerial_drake.trajectories.kinds.validate_trajectory`), the reference built
from them (a waypoint list that cannot be interpolated, a user's module that does not import,
a function whose samples have the wrong shapes), and for a kind whose derivatives are the
user's (the ``python`` kind: ``user_derivatives`` in the registry of kinds) the derivatives it
gives against finite differences over the whole run, within :data:`SAMPLING_TIME_LIMIT` (a
function that never returns is stopped and named, not waited for)."""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path
from typing import Any

import numpy as np

from aerial_drake.simulation.scenarios.checks import ScenarioError
from aerial_drake.trajectories.continuity import find_discontinuity
from aerial_drake.trajectories.kinds import REFERENCE_KINDS, reference_of
from aerial_drake.trajectories.time_limit import TimeLimitExceeded, time_limit

__all__ = ["check_trajectory", "resolve_python_path", "PYTHON_CHECK_PERIOD",
           "SAMPLING_TIME_LIMIT"]

#: Sample period of the load-time derivative check of a ``python`` reference (s).
PYTHON_CHECK_PERIOD = 0.01
#: The time that check may take (s): a few thousand calls of the user's function.
SAMPLING_TIME_LIMIT = 30.0
_QUOTED = re.compile(r"'([A-Za-z_][\w.\[\]*]*)'")


def check_trajectory(scenario: Any, joint_nominal: np.ndarray) -> None:
    """ScenarioError naming ``trajectory.<field>`` if the section does not give a reference
    for ``scenario``'s robot (``joint_nominal``: its task joints' nominal angles)."""
    try:
        source = reference_of(scenario.trajectory, joint_nominal)
    except ValueError as err:
        message = str(err)
        found = _QUOTED.search(message)
        field = "trajectory" + (f".{found.group(1)}" if found else "")
        raise ScenarioError(f"trajectory: {message}", field) from None
    if not REFERENCE_KINDS[scenario.trajectory.kind].user_derivatives:
        return
    count = max(int(math.ceil(scenario.duration / PYTHON_CHECK_PERIOD)), 3)
    times = np.linspace(0.0, scenario.duration, count + 1)
    function = scenario.trajectory.python.function
    try:
        with time_limit(SAMPLING_TIME_LIMIT, f"python.function {function!r}"):
            found_jump = find_discontinuity(source.sample, times)
    except TimeLimitExceeded:
        raise ScenarioError(f"trajectory: python.function {function!r} did not finish the "
                            f"load-time check within {SAMPLING_TIME_LIMIT:g} s (about "
                            f"{times.size} samples over [0, {scenario.duration:g}] s): a loop "
                            "that never ends, or a call far slower than the law's period? "
                            "Make f(t) return promptly", "trajectory.python.function") from None
    except Exception as err:  # the user's function: whatever it raises, named, before a run
        raise ScenarioError(f"trajectory: python.function {function!r} failed while sampled "
                            f"over [0, {scenario.duration:g}] s: {type(err).__name__}: {err}",
                            "trajectory.python.function") from None
    if found_jump is not None:
        raise ScenarioError(
            f"trajectory: python.function {scenario.trajectory.python.function!r} does not "
            f"give the law a smooth, consistent reference: {found_jump.describe()}. Each "
            "derivative must be the rate of the one below it and continuous (x_d to the 4th, "
            "p_ed, R_ed via w_ed, dw_ed and q_jd to the 2nd, b1d to the 2nd)",
            "trajectory.python.function")
    try:  # what a run flies: the function sampled onto splines, their error bound checked
        with time_limit(SAMPLING_TIME_LIMIT, f"python.function {function!r}"):
            source.for_run(scenario.duration)
    except TimeLimitExceeded:
        raise ScenarioError(f"trajectory: python.function {function!r} did not finish "
                            f"sampling onto splines within {SAMPLING_TIME_LIMIT:g} s: make f(t) "
                            "return promptly", "trajectory.python.function") from None
    except ValueError as err:
        raise ScenarioError(f"trajectory: {err}", "trajectory.python.function") from None


def resolve_python_path(scenario: Any, path: Path) -> Any:
    """``trajectory.python.path`` as an absolute folder (a relative one starts at the
    scenario file's folder), so a run folder's copy and a study's workers find it again."""
    python = scenario.trajectory.python
    if scenario.trajectory.kind != "python" or not python.path or not isinstance(
            python.path, str) or Path(python.path).expanduser().is_absolute():
        return scenario
    folder = str((path.resolve().parent / Path(python.path)).resolve())
    trajectory = dataclasses.replace(
        scenario.trajectory, python=dataclasses.replace(python, path=folder))
    return dataclasses.replace(scenario, trajectory=trajectory)
