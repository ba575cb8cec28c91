"""Reading a run folder written by :mod:`aerial_drake.simulation.runner`: ``log.npz`` (the
logged ports), ``metrics.json`` and ``scenario.yaml`` (the scenario as run), as a :class:`Run`
with its log's entries by name.

Reading a run draws nothing, so it imports no matplotlib (tests/simulation/test_run_folder.py):
the paper run, ``compare`` and tools load runs without paying for it; the figures
(:mod:`aerial_drake.viz.plots`) import it when they draw.

The errors (CoM, end effector, heading, sigma_min(J_3)) are the log's ``tracking`` array
(:mod:`aerial_drake.simulation.tracking`), whichever controller ran; a controller's own
quantities (e.g. ``base_attitude_error``, the angle of R_d^T R_b against the attitude it
commands) are its ``diagnostics``' entries by the names stored in the log. A folder written
before the tracking errors existed has no ``tracking``: its errors are read from the
diagnostics, in the paper law's layout it was written with.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from aerial_drake.control.law import diagnostics_layout, task_size_of_diagnostics
from aerial_drake.simulation.scenarios import Scenario, load_scenario
from aerial_drake.simulation.tracking import entries
from aerial_drake.trajectories.reference import unpack_com_reference, unpack_task_reference


@dataclass(frozen=True)
class Run:
    """One run folder, loaded."""

    name: str
    log: dict[str, np.ndarray]
    scenario: Scenario
    metrics: dict

    @property
    def t(self) -> np.ndarray:
        return self.log["t"]

    def tracking(self, name: str) -> np.ndarray:
        """A tracking error over time, (N, size) (module docstring). KeyError naming the
        entries there are for a name that is not one of them."""
        named = _named(self.log, "tracking" if "tracking" in self.log else "diagnostics")
        if name not in named:
            raise KeyError(f"no tracking error '{name}' in this run's log (it has "
                           f"{sorted(named)})")
        return named[name]

    def diagnostic(self, name: str) -> np.ndarray | None:
        """The controller's diagnostics entry ``name`` over time, (N, size), by the layout
        stored in the log; None when the controller does not report it."""
        return _named(self.log, "diagnostics").get(name)

    def com(self) -> tuple[np.ndarray, np.ndarray]:
        """(desired, actual) CoM positions (N, 3) in World (m): x_d and x_d + x_tilde."""
        x_d = unpack_com_reference(self.log["com_reference"])[:, 0]
        return x_d, x_d + self.tracking("x_tilde")

    def end_effector(self) -> tuple[np.ndarray, np.ndarray]:
        """(desired, actual) end-effector positions (N, 3) in World (m): p_ed and
        p_ed + y_tilde[:3] (the task's first rows are the position's in the paper's task;
        see robots.task)."""
        p_ed = unpack_task_reference(self.log["task_reference"]).p_ed
        return p_ed, p_ed + self.tracking("y_tilde")[:, :3]

    def input_limits(self) -> dict[str, tuple[float | None, float | None]]:
        """``{input: (lower, upper)}`` from metrics.json (None: unbounded); empty if absent."""
        return {k: tuple(v) for k, v in self.metrics.get("input_limits", {}).items()}


def _named(log: dict[str, np.ndarray], array: str) -> dict[str, np.ndarray]:
    """``{name: (N, size)}`` of the logged ``array`` by the layout stored with it (a log
    without one: the paper law's diagnostics layout, as such logs were written)."""
    if array not in log:
        return {}
    stored = json.loads(str(log["layout"])) if "layout" in log else {}
    layout = stored.get(array)
    if layout is None and array == "diagnostics":
        layout = diagnostics_layout(task_size_of_diagnostics(log[array].shape[1]))
    return entries(log[array], layout) if layout is not None else {}


class RunFolderError(ValueError):
    """A run folder's file cannot be read (truncated, corrupt); the message names the file
    and the fix. The command line exits 2 (docs/reliability.md)."""


def load_run(folder: str | Path) -> Run:
    """Load ``log.npz``, ``metrics.json`` and ``scenario.yaml`` from a run folder.

    The scenario is read, not validated: drawing a run needs only what it logged (its
    references among them), so neither the robot's files nor a ``python`` trajectory's module
    are loaded, and a run whose module has moved since still plots. A file that cannot be read
    raises :class:`RunFolderError` (FileNotFoundError for a missing one)."""
    folder = Path(folder)
    missing = [f for f in ("log.npz", "metrics.json", "scenario.yaml")
               if not (folder / f).is_file()]
    if missing:
        raise FileNotFoundError(f"{folder} is not a complete run folder: missing {missing} "
                                "(write one with `aerial-drake run SCENARIO`)")
    log = _read_log(folder / "log.npz")
    try:
        metrics = json.loads((folder / "metrics.json").read_text(encoding="utf-8"))
    except (ValueError, OSError) as err:  # (JSONDecodeError and UnicodeDecodeError: ValueError)
        raise RunFolderError(f"{folder / 'metrics.json'} cannot be read ({err}): the file is "
                             "corrupt; run the scenario again to rewrite it") from None
    if not isinstance(metrics, dict):
        raise RunFolderError(f"{folder / 'metrics.json'} holds a {type(metrics).__name__}, "
                             "not a run's metrics; run the scenario again to rewrite it")
    scenario = load_scenario(folder / "scenario.yaml", validate=False)
    return Run(name=scenario.name, log=log, scenario=scenario, metrics=metrics)


def _read_log(path: Path) -> dict[str, np.ndarray]:
    """Every array of ``log.npz`` (read now, so a truncated file fails here, naming itself)."""
    try:
        with np.load(path) as data:
            log = {k: data[k] for k in data.files}
    except Exception as err:  # BadZipFile, EOFError, zlib.error, ValueError, OSError
        raise RunFolderError(f"{path} cannot be read ({type(err).__name__}: {err}): the file "
                             "is truncated or corrupt; run the scenario again to rewrite "
                             "it") from None
    if "t" not in log:
        raise RunFolderError(f"{path} has no time array 't' (it holds {sorted(log)}): not a "
                             "run's log; run the scenario again to rewrite it")
    return log
