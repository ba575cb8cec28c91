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
controller registered in this process (:func:`aerial_drake.simulation.controllers.
register_controller`) is unknown to spawned workers: compare it with ``jobs=1``.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import dataclasses
import json
import multiprocessing
import os
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import TextIO

import numpy as np

from aerial_drake.dynamics.equilibrium import UnreachablePose
from aerial_drake.simulation.runner import SimulationFailed, run_scenario
from aerial_drake.simulation.scenarios import ScenarioError, load_scenario
from aerial_drake.studies.paper import format_table
from aerial_drake.viz.compare import write_compare_figures
from aerial_drake.viz.plots import Run, load_run

DEFAULT_CONTROLLERS = ("paper", "uncoupled", "static_compensation")


@dataclass
class CompareResult:
    out_dir: Path
    runs: dict[str, Run] = field(default_factory=dict)  # by controller
    failures: dict[str, str] = field(default_factory=dict)
    figures: list[Path] = field(default_factory=list)
    table: str = ""

    @property
    def completed(self) -> bool:
        return not self.failures


def _scenario_for(scenario: str, controller: str, duration: float | None,
                  undisturbed: bool = False):
    overrides: dict = {"duration": duration} if duration is not None else {}
    base = load_scenario(scenario, overrides=overrides or None)
    if undisturbed:  # the same run without its disturbance windows, under its own name
        base = dataclasses.replace(base, name=f"{base.name}_undisturbed", disturbances=[])
    config = dataclasses.replace(base.controller, type=controller)
    return dataclasses.replace(base, controller=config).validate()


def _run_one(scenario: str, controller: str, duration: float | None, out: str,
             progress: bool = False, stream: TextIO | None = None,
             undisturbed: bool = False) -> str | None:
    """Run ``scenario`` with ``controller`` into ``out``; the failure message or None."""
    try:
        run_scenario(_scenario_for(scenario, controller, duration, undisturbed), out_dir=out,
                     progress=progress, stream=stream)
    except SimulationFailed as err:
        return str(err)
    return None


def run_compare(scenario: str, controllers: tuple[str, ...] = DEFAULT_CONTROLLERS,
                out_dir: str | Path = "out/compare", duration: float | None = None, *,
                jobs: int = 1, progress: bool = True, stream: TextIO | None = None,
                undisturbed: bool = False) -> CompareResult:
    """Run ``scenario`` (a shipped name or a YAML path) once per controller into
    ``out_dir/<scenario name>/<controller>/`` and write the overlays and the table there.
    ``undisturbed``: the scenario without its disturbance windows (named
    ``<name>_undisturbed``), the reference of :func:`disturbance_displacement`."""
    if not controllers:
        raise ScenarioError("--controllers: name at least one controller")
    if len(set(controllers)) != len(controllers):
        raise ScenarioError(f"--controllers: a controller is named twice: {list(controllers)}")
    first = _scenario_for(scenario, controllers[0], duration, undisturbed)
    for name in controllers[1:]:  # every name checked before anything runs
        _scenario_for(scenario, name, duration, undisturbed)
    out = Path(out_dir) / first.name
    out.mkdir(parents=True, exist_ok=True)
    result = CompareResult(out_dir=out)
    folders = {name: out / name for name in controllers}
    if jobs > 1 and len(controllers) > 1:
        context = multiprocessing.get_context("spawn")
        with concurrent.futures.ProcessPoolExecutor(min(jobs, len(controllers)),
                                                    mp_context=context) as pool:
            futures = {name: pool.submit(_run_one, scenario, name, duration, str(folder),
                                         undisturbed=undisturbed)
                       for name, folder in folders.items()}
            if progress and stream is not None:
                stream.write(f"running {list(controllers)} on '{first.name}' in "
                             f"{min(jobs, len(controllers))} processes\n")
            for name, future in futures.items():
                failure = future.result()
                if failure:
                    result.failures[name] = failure
                if progress and stream is not None:
                    stream.write(f"  {name}: {'done' if not failure else failure}\n")
    else:
        for name, folder in folders.items():
            if progress and stream is not None:
                stream.write(f"running '{first.name}' with controller '{name}' -> {folder}\n")
            failure = _run_one(scenario, name, duration, str(folder), progress, stream,
                               undisturbed)
            if failure:
                result.failures[name] = failure
    for name, folder in folders.items():
        if (folder / "log.npz").is_file():
            result.runs[name] = load_run(folder)
    if result.runs:
        result.figures = write_compare_figures(out, result.runs, first.name)
    metrics = {n: r.metrics for n, r in result.runs.items()}
    result.table = format_table(metrics)
    (out / "summary.txt").write_text(result.table + "\n")
    (out / "comparison.json").write_text(json.dumps(comparison_summary(metrics), indent=2))
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


def disturbance_displacement(disturbed: Run, undisturbed: Run,
                             windows: tuple[tuple[float, float], ...] = ((4.0, 5.0), (5.0, 6.0),
                                                                         (9.0, 10.0),
                                                                         (10.0, 11.0),
                                                                         (14.0, 15.0)),
                             ) -> list[dict]:
    """How far a disturbance moved the end effector and the CoM: per window ``[a, b]`` (s),
    the largest ``|y~[:3]_dist - y~[:3]_undist|`` and ``|x~_dist - x~_undist|`` (m) between a
    run and the same run without its disturbances, sample by sample (docs/baselines.md)."""
    n = min(len(disturbed.t), len(undisturbed.t))
    t = disturbed.t[:n]
    if not np.array_equal(t, undisturbed.t[:n]):
        raise ValueError("the two runs are not sampled at the same times")
    ee = np.linalg.norm(disturbed.diagnostic("y_tilde")[:n, :3]
                        - undisturbed.diagnostic("y_tilde")[:n, :3], axis=1)
    com = np.linalg.norm(disturbed.diagnostic("x_tilde")[:n]
                         - undisturbed.diagnostic("x_tilde")[:n], axis=1)
    out = []
    for a, b in windows:
        mask = (t >= a) & (t <= b)
        out.append({"window_s": [a, b],
                    "ee_moved_max_m": float(ee[mask].max()) if mask.any() else None,
                    "com_moved_max_m": float(com[mask].max()) if mask.any() else None})
    return out


def cli_compare(args: argparse.Namespace) -> int:
    """``aerial-drake compare SCENARIO [--controllers A,B] [--jobs N] [--duration S]
    [--out DIR] [--quiet] [--json]``."""
    controllers = tuple(c.strip() for c in args.controllers.split(",") if c.strip())
    jobs = args.jobs if args.jobs is not None else min(len(controllers), os.cpu_count() or 1)
    try:
        result = run_compare(args.scenario, controllers, Path(args.out) / "compare",
                             args.duration, jobs=jobs, progress=not args.quiet,
                             stream=sys.stderr, undisturbed=args.undisturbed)
    except (ScenarioError, UnreachablePose) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    print(result.table)
    for path in result.figures:
        if path.suffix == ".png":
            print(f"wrote {path} (and .pdf)")
    print(f"wrote {result.out_dir / 'summary.txt'} and {result.out_dir / 'comparison.json'}")
    if args.json:
        print(json.dumps(comparison_summary({n: r.metrics for n, r in result.runs.items()}),
                         indent=2))
    for name, reason in result.failures.items():
        print(f"error: {name}: {reason}", file=sys.stderr)
    return 0 if result.completed else 1
