"""Section IV in one call: the nominal and disturbed runs, their metrics, and Figs. 3-6.

``aerial-drake run paper`` (or :func:`run_paper`) simulates the shipped scenarios ``nominal``
and ``disturbed`` and writes::

    OUT/paper/nominal/    log.npz, metrics.json, scenario.yaml
    OUT/paper/disturbed/  log.npz, metrics.json, scenario.yaml
    OUT/paper/fig3_end_effector.{png,pdf}  fig4_com.*  fig5_orientation_errors.*  fig6_inputs.*
    OUT/paper/summary.txt  (the table printed in the terminal)

``--seed N`` (:func:`perturb_initial`): without it every run is deterministic, from the
scenario files' documented initial offsets. With it, each run's initial offsets get a
reproducible random perturbation drawn from ``numpy.random.default_rng(N)``, uniform within
:data:`SEED_BOUNDS`; the paper run draws the nominal's perturbation first, then the
disturbed's, from the one generator (so ``run nominal --seed N`` starts where ``run paper
--seed N``'s nominal run does). The perturbed offsets are in each run's ``scenario.yaml``.

:func:`run_paper` is three library steps, each callable alone: the batch
(:func:`load_paper_scenarios`, :func:`run_paper_cases`), the figures
(:func:`write_paper_figures`, the only one that imports matplotlib) and the report
(:func:`write_paper_report`). The command line (:mod:`aerial_drake.cli.paper`) prints.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import TextIO

import numpy as np

from aerial_drake.simulation.outputs import write_text_atomically
from aerial_drake.simulation.run_folder import Run
from aerial_drake.simulation.scenarios import Scenario, load_scenario
from aerial_drake.studies.batch import run_batch
from aerial_drake.studies.summary import format_table

PAPER_SCENARIOS = ("nominal", "disturbed")

#: Half-widths of the uniform ``--seed`` perturbation, per component: base position (m),
#: base roll/pitch/yaw (rad), arm joints (rad). Smaller than the scenarios' own offsets
#: (0.05 m, 0.05 rad), so a perturbed start stays in the regime the tests cover (the nominal
#: start saturates some inputs for a few milliseconds; much larger offsets saturate longer).
SEED_BOUNDS = {"base_position_offset": 0.02, "base_rpy_offset": 0.02, "arm_offset": 0.02}


def perturb_initial(scenario: Scenario, seed: int,
                    rng: np.random.Generator | None = None) -> Scenario:
    """A copy of ``scenario`` whose initial offsets are moved by a uniform random draw within
    :data:`SEED_BOUNDS`, from ``rng`` if given, else from ``default_rng(seed)``; the seed is
    noted in the description. The input is not modified."""
    rng = rng if rng is not None else np.random.default_rng(seed)
    init = scenario.initial
    changes = {}
    for name, bound in SEED_BOUNDS.items():
        value = np.asarray(getattr(init, name), dtype=float)
        changes[name] = (value + rng.uniform(-bound, bound, size=value.shape)).tolist()
    return dataclasses.replace(
        scenario, initial=dataclasses.replace(init, **changes),
        description=f"{scenario.description} Initial offsets perturbed with seed {seed}.",
    ).validate()


@dataclass
class PaperResult:
    """What :func:`run_paper` produced."""

    out_dir: Path
    runs: dict[str, Run] = field(default_factory=dict)  # loaded from the run folders
    failures: dict[str, str] = field(default_factory=dict)  # scenario name -> reason
    figures: list[Path] = field(default_factory=list)
    table: str = ""
    # The signal that stopped the study (its remaining runs were not started), if one did.
    interrupted: int | None = None

    @property
    def completed(self) -> bool:
        return not self.failures and all(n in self.runs for n in PAPER_SCENARIOS)


def load_paper_scenarios(duration: float | None = None, *, seed: int | None = None,
                         overrides: dict | None = None) -> dict[str, Scenario]:
    """The paper's scenarios (:data:`PAPER_SCENARIOS`), loaded and checked: ``duration``
    overrides their duration (s), ``overrides`` more top-level fields, ``seed`` perturbs their
    initial offsets from one generator, the nominal's first (module docstring)."""
    rng = np.random.default_rng(seed) if seed is not None else None
    overrides = dict(overrides or {})
    if duration is not None:
        overrides["duration"] = duration
    scenarios = {}
    for name in PAPER_SCENARIOS:
        scenarios[name] = load_scenario(name, overrides=overrides or None)
        if seed is not None:  # (and so rng)
            scenarios[name] = perturb_initial(scenarios[name], seed, rng)
    return scenarios


def run_paper_cases(scenarios: dict[str, Scenario], out_dir: str | Path, *,
                    progress: bool = True, stream: TextIO | None = None) -> PaperResult:
    """The batch: run each of ``scenarios`` into ``out_dir/<name>/`` and load the complete
    runs (:func:`aerial_drake.studies.batch.run_batch`); no figure, no table."""
    out = Path(out_dir)
    batch = run_batch(scenarios, {name: out / name for name in scenarios},
                      progress=progress, stream=stream)
    return PaperResult(out_dir=out, runs=batch.runs, failures=batch.failures,
                       interrupted=batch.interrupted)


def write_paper_report(result: PaperResult) -> str:
    """The report: the runs' metrics side by side (:func:`aerial_drake.studies.summary.
    format_table`), set as ``result.table`` and written to ``out_dir/summary.txt``."""
    result.table = format_table({n: r.metrics for n, r in result.runs.items()})
    write_text_atomically(result.out_dir / "summary.txt", result.table + "\n")
    return result.table


def write_paper_figures(result: PaperResult) -> list[Path]:
    """The figures: Figs. 3-6 of the nominal run (and the disturbed one, if complete) into
    ``out_dir`` (:func:`aerial_drake.viz.plots.write_figures`; matplotlib is imported here),
    set as ``result.figures``; none without a complete nominal run."""
    if "nominal" in result.runs:
        from aerial_drake.viz.plots import write_figures
        result.figures = write_figures(result.out_dir, result.runs["nominal"],
                                       result.runs.get("disturbed"))
    return result.figures


def run_paper(out_dir: str | Path = "out/paper", duration: float | None = None, *,
              seed: int | None = None, progress: bool = True,
              stream: TextIO | None = None, overrides: dict | None = None) -> PaperResult:
    """Run the nominal and disturbed scenarios into ``out_dir/<name>/``, write Figs. 3-6 and
    ``summary.txt`` into ``out_dir``, and return the result (the table is printed by the
    command line, not here).

    ``duration`` overrides both scenarios' duration (s); ``seed`` perturbs their initial
    offsets (module docstring); ``overrides`` replaces more top-level fields of both. Both
    scenarios are loaded and checked before either runs. A run that fails (an assumption
    violated, divergence) still leaves its logs up to the failure; the figures are drawn from
    whatever was logged. A signal (SIGINT, SIGTERM, SIGHUP) stops the study: the run it
    stopped writes its logs, the remaining run is not started, no figure is drawn, and
    :attr:`PaperResult.interrupted` holds the signal's number.
    """
    scenarios = load_paper_scenarios(duration, seed=seed, overrides=overrides)
    result = run_paper_cases(scenarios, out_dir, progress=progress, stream=stream)
    if result.interrupted is not None:
        result.table = format_table({n: r.metrics for n, r in result.runs.items()})
        return result
    write_paper_figures(result)
    write_paper_report(result)
    return result
