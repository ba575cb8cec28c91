"""One scenario, several controllers: ``aerial-drake compare SCENARIO --controllers
paper,uncoupled,static_compensation`` (or :func:`run_compare`) writes::

    OUT/compare/<scenario>/<controller>/   log.npz, metrics.json, scenario.yaml (as ``run``)
    OUT/compare/<scenario>/compare_fig3_end_effector.{png,pdf}  compare_fig4_com.*
        compare_fig5_orientation_errors.*  compare_fig6_inputs.*   (one line per controller)
    OUT/compare/<scenario>/summary.txt   the metrics per phase side by side (also printed)
    OUT/compare/<scenario>/comparison.json   the disturbance responses and per-phase errors

The runs are independent simulations: with ``jobs`` > 1 they run in a process pool of that
many workers ("spawn" processes, each loading the scenario and the numba cache afresh, about
5 s of start-up each), else one after the other in this process with progress lines. A
controller registered in this process (:func:`aerial_drake.control.registry.
register_controller`) is unknown to spawned workers: compare it with ``jobs=1``.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass, field
from pathlib import Path
from typing import TextIO

import numpy as np

from aerial_drake.simulation.metrics import RESPONSE_TAIL_S
from aerial_drake.simulation.outputs import OutputError, strict_json, write_text_atomically
from aerial_drake.simulation.run_folder import Run
from aerial_drake.simulation.scenarios import ScenarioError, folder_name, load_scenario
from aerial_drake.studies.batch import run_batch
from aerial_drake.studies.summary import format_table

DEFAULT_CONTROLLERS = ("paper", "uncoupled", "static_compensation")
#: The most worker processes ``jobs`` may ask for (as the command line's ``--jobs``).
MAX_JOBS = 256


@dataclass
class CompareResult:
    out_dir: Path
    runs: dict[str, Run] = field(default_factory=dict)  # by controller
    failures: dict[str, str] = field(default_factory=dict)
    figures: list[Path] = field(default_factory=list)
    table: str = ""
    # The signal that stopped the comparison (its remaining runs were not started), if one did.
    interrupted: int | None = None

    @property
    def completed(self) -> bool:
        return not self.failures and self.interrupted is None


def _scenario_for(scenario: str, controller: str, duration: float | None,
                  undisturbed: bool = False, overrides: dict | None = None):
    overrides = dict(overrides or {})
    if duration is not None:
        overrides["duration"] = duration
    base = load_scenario(scenario, overrides=overrides or None)
    if undisturbed:  # the same run without its disturbance windows, under its own name
        base = dataclasses.replace(base, name=f"{base.name}_undisturbed", disturbances=[])
    config = dataclasses.replace(base.controller, type=controller)
    return dataclasses.replace(base, controller=config).validate()


def _rebuild(scenario: str, duration: float | None, undisturbed: bool,
             overrides: dict | None, controller: str):
    """:func:`_scenario_for` with the controller last, for a worker process (picklable with
    functools.partial; a Scenario itself does not pickle)."""
    return _scenario_for(scenario, controller, duration, undisturbed, overrides)


def _controller_folders(out: Path, controllers: tuple[str, ...]) -> dict[str, Path]:
    """Each controller's run folder, from its sanitised name (never outside ``out``)."""
    folders: dict[str, Path] = {}
    for name in controllers:
        safe = folder_name(name)
        if not safe:
            raise ScenarioError(f"--controllers: {name!r} cannot name a run folder")
        if any(f.name == safe for f in folders.values()):
            raise ScenarioError(f"--controllers: two controllers share the run folder "
                                f"'{safe}': {list(controllers)}")
        folders[name] = out / safe
    return folders


def run_compare(scenario: str, controllers: tuple[str, ...] = DEFAULT_CONTROLLERS,
                out_dir: str | Path = "out/compare", duration: float | None = None, *,
                jobs: int = 1, progress: bool = True, stream: TextIO | None = None,
                undisturbed: bool = False, overrides: dict | None = None) -> CompareResult:
    """Run ``scenario`` (a shipped name or a YAML path) once per controller into
    ``out_dir/<scenario folder name>/<controller>/`` and write the overlays and the table
    there (the folder names sanitised as ``run``'s: Scenario.folder_name).
    ``undisturbed``: the scenario without its disturbance windows (named
    ``<name>_undisturbed``), the reference of :func:`disturbance_displacement`.
    ``overrides`` replaces more top-level fields of the scenario (``duration`` wins over one
    there).

    Every scenario is built and checked before anything runs (ScenarioError,
    UnreachablePose); an output folder that cannot be used raises OutputError. A controller
    whose run fails is recorded in :attr:`CompareResult.failures` and the next one runs. A
    signal (SIGINT, SIGTERM, SIGHUP) stops the comparison as it stops ``run paper``: the
    running run(s) write their logs, the remaining controllers are not started, no figure,
    summary or comparison is written, and :attr:`CompareResult.interrupted` holds the
    signal's number (:func:`aerial_drake.studies.batch.run_batch`, also with ``jobs`` > 1).
    Only complete run folders (``metrics.json`` present) are loaded and drawn."""
    if isinstance(jobs, bool) or not isinstance(jobs, int) or not 1 <= jobs <= MAX_JOBS:
        raise ScenarioError(f"jobs must be an integer, 1 to {MAX_JOBS} (1 runs the "
                            f"controllers one after the other); got {jobs!r}", "jobs")
    if not controllers:
        raise ScenarioError("--controllers: name at least one controller")
    if len(set(controllers)) != len(controllers):
        raise ScenarioError(f"--controllers: a controller is named twice: {list(controllers)}")
    scenarios = {name: _scenario_for(scenario, name, duration, undisturbed, overrides)
                 for name in controllers}  # every name checked before anything runs
    first = scenarios[controllers[0]]
    out = Path(out_dir) / first.folder_name
    folders = _controller_folders(out, controllers)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise OutputError(f"output folder {out} cannot be created ({err.strerror or err}): "
                          "choose another --out") from None
    result = CompareResult(out_dir=out)
    batch = run_batch(scenarios, folders, jobs=jobs,
                      rebuild=functools.partial(_rebuild, scenario, duration, undisturbed,
                                                overrides),
                      progress=progress, stream=stream,
                      labels={n: f"'{first.name}' with controller '{n}'" for n in controllers})
    result.runs, result.failures, result.interrupted = (batch.runs, batch.failures,
                                                        batch.interrupted)
    metrics = {n: r.metrics for n, r in result.runs.items()}
    result.table = format_table(metrics)
    if result.interrupted is not None:
        return result
    if result.runs:
        from aerial_drake.viz.compare import write_compare_figures  # (matplotlib: here only)
        result.figures = write_compare_figures(out, result.runs, first.name)
    write_text_atomically(out / "summary.txt", result.table + "\n")
    write_text_atomically(out / "comparison.json", strict_json(comparison_summary(metrics)))
    return result


def comparison_summary(metrics: dict[str, dict]) -> dict:
    """Per controller: each phase's end-effector and CoM error (max, RMS, m) and the
    disturbance responses (peaks and the EE/CoM ratio)."""
    out = {}
    for name, m in metrics.items():
        phases = [{"start_s": p["start_s"], "end_s": p["end_s"],
                   **{k: p[k] for k in ("ee_position_error_m", "com_position_error_m",
                                        "base_attitude_error_rad", "ee_orientation_error_rad")
                      if k in p}} for p in m.get("phases", [])]
        out[name] = {"completed": m.get("completed"), "failure": m.get("failure"),
                     "phases": phases,
                     "disturbance_response": m.get("disturbance_response", [])}
    return out


def displacement_windows(scenario) -> list[tuple[float, float]]:
    """The windows :func:`disturbance_displacement` reports, from ``scenario``'s
    disturbances: each window ``[start, stop]`` and the second after it, ``[stop, stop +
    RESPONSE_TAIL_S]`` cut at the next window's start (the metrics' response tail)."""
    spans = sorted((float(d.start), float(d.stop)) for d in scenario.disturbances)
    starts = [a for a, _ in spans]
    out: list[tuple[float, float]] = []
    for a, b in spans:
        out.append((a, b))
        end = min([b + RESPONSE_TAIL_S] + [s for s in starts if s > a])
        if end > b:
            out.append((b, end))
    return out


def disturbance_displacement(disturbed: Run, undisturbed: Run,
                             windows: tuple[tuple[float, float], ...] | None = None,
                             ) -> list[dict]:
    """How far a disturbance moved the end effector and the CoM: per window ``[a, b]`` (s),
    the largest ``|y~[:3]_dist - y~[:3]_undist|`` and ``|x~_dist - x~_undist|`` (m) between a
    run and the same run without its disturbances, sample by sample (docs/baselines.md).
    ``windows``: by default :func:`displacement_windows` of the disturbed run's scenario."""
    if windows is None:
        windows = tuple(displacement_windows(disturbed.scenario))
    n = min(len(disturbed.t), len(undisturbed.t))
    t = disturbed.t[:n]
    if not np.array_equal(t, undisturbed.t[:n]):
        raise ValueError("the two runs are not sampled at the same times")
    ee = np.linalg.norm(disturbed.tracking("y_tilde")[:n, :3]
                        - undisturbed.tracking("y_tilde")[:n, :3], axis=1)
    com = np.linalg.norm(disturbed.tracking("x_tilde")[:n]
                         - undisturbed.tracking("x_tilde")[:n], axis=1)
    out = []
    for a, b in windows:
        mask = (t >= a) & (t <= b)
        out.append({"window_s": [float(a), float(b)],
                    "ee_moved_max_m": float(ee[mask].max()) if mask.any() else None,
                    "com_moved_max_m": float(com[mask].max()) if mask.any() else None})
    return out
