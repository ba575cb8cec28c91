"""Reading a run folder written by :mod:`aerial_drake.simulation.runner`: ``log.npz`` (the
logged ports), ``metrics.json`` and ``scenario.yaml`` (the scenario as run), as a :class:`Run`.

Reading a run draws nothing, so it imports no matplotlib (tests/simulation/test_run_folder.py):
the paper run, ``compare`` and tools load runs without paying for it; the figures
(:mod:`aerial_drake.viz.plots`) import it when they draw.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from aerial_drake.control.law import diagnostics_slices, task_size_of_diagnostics
from aerial_drake.simulation.scenarios import Scenario, load_scenario
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

    def diagnostic(self, name: str) -> np.ndarray:
        """A diagnostics entry over time, (N, size), using the layout stored in the log."""
        return self.log["diagnostics"][:, _diagnostics_slices(self.log)[name]]

    def com(self) -> tuple[np.ndarray, np.ndarray]:
        """(desired, actual) CoM positions (N, 3) in World (m): x_d and x_d + x_tilde."""
        x_d = unpack_com_reference(self.log["com_reference"])[:, 0]
        return x_d, x_d + self.diagnostic("x_tilde")

    def end_effector(self) -> tuple[np.ndarray, np.ndarray]:
        """(desired, actual) end-effector positions (N, 3) in World (m): p_ed and
        p_ed + y_tilde[:3]."""
        p_ed = unpack_task_reference(self.log["task_reference"]).p_ed
        return p_ed, p_ed + self.diagnostic("y_tilde")[:, :3]

    def input_limits(self) -> dict[str, tuple[float | None, float | None]]:
        """``{input: (lower, upper)}`` from metrics.json (None: unbounded); empty if absent."""
        return {k: tuple(v) for k, v in self.metrics.get("input_limits", {}).items()}


def _diagnostics_slices(log: dict) -> dict[str, slice]:
    """The diagnostics layout a log was written with (this version's if it has none)."""
    if "layout" not in log:
        return diagnostics_slices(task_size_of_diagnostics(log["diagnostics"].shape[1]))
    return diagnostics_slices(json.loads(str(log["layout"]))["diagnostics"])


def load_run(folder: str | Path) -> Run:
    """Load ``log.npz``, ``metrics.json`` and ``scenario.yaml`` from a run folder."""
    folder = Path(folder)
    missing = [f for f in ("log.npz", "metrics.json", "scenario.yaml")
               if not (folder / f).is_file()]
    if missing:
        raise FileNotFoundError(f"{folder} is not a complete run folder: missing {missing} "
                                "(write one with `aerial-drake run SCENARIO`)")
    with np.load(folder / "log.npz") as data:
        log = {k: data[k] for k in data.files}
    metrics = json.loads((folder / "metrics.json").read_text())
    scenario = load_scenario(folder / "scenario.yaml")
    return Run(name=scenario.name, log=log, scenario=scenario, metrics=metrics)
