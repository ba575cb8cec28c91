"""Study files: a base scenario, its settings, the parameters to vary, the draws, the metrics
to keep; typed (Drake's ``yaml_load_typed``) and validated before any run, then expanded into
the runs (:func:`plan_runs`), each a resolved scenario whose hash is its identity.

A study file::

    name: robustness
    base: disturbed           # a shipped scenario's name, or a path relative to this file
    duration: 15.0            # optional: overrides the base's
    settings:                 # optional: scenario fields set on the base (any section)
      model_mismatch: {mass_error: 0.1}
    draws: 200                # random draws per grid point
    seed: 2026                # the draws' seed
    parameters:
      - {field: gains.k_R, values: [125, 250, 500]}              # grid (every combination)
      - {field: gains.K_y, values: [0.5, 1, 2], mode: scale}      # a list field scaled
      - {field: payload.mass, kind: uniform, low: 0.0, high: 1.0} # one draw per run
      - {field: model_mismatch.seed, kind: seed}                  # an integer per draw
    metrics: ["phase*.ee_position_error_m.max", "min_sigma_min_J3"]   # fnmatch patterns

Runs: every combination of the grids (first parameter outermost), times ``draws``. Draw ``j``
takes its random values from ``default_rng([seed, j])``, the same at every grid point (common
random numbers: a grid's points differ by the grid alone).
"""

# No "from __future__ import annotations": pydrake's yaml_load_typed needs real type objects.
import dataclasses
import fnmatch
import hashlib
import itertools
import math
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from pydrake.common.yaml import yaml_dump, yaml_dump_typed, yaml_load_typed

from aerial_drake.simulation.scenarios import (
    Scenario,
    ScenarioError,
    load_scenario,
    shipped_scenarios,
)
from aerial_drake.simulation.scenarios.reading import read_scenario_file
from aerial_drake.studies.metrics_table import DEFAULT_METRICS, metric_names
from aerial_drake.studies.relative import absolute_paths

KINDS = ("grid", "uniform", "normal", "seed")
MODES = ("set", "scale")
#: More runs than this in one study is a mistake more often than a plan.
MAX_RUNS = 100_000


@dataclass
class Parameter:
    """One varied scenario field (module docstring)."""

    # Dotted scenario field, e.g. gains.k_R or model_mismatch.seed.
    field: str = ""
    # "grid" (values), "uniform" (low, high), "normal" (mean, std), "seed" (an integer).
    kind: str = "grid"
    values: list[float] = dataclasses.field(default_factory=list)
    low: float = math.nan
    high: float = math.nan
    mean: float = math.nan
    std: float = math.nan
    # "set" the value, or "scale" the base's value (every entry of a list field).
    mode: str = "set"

    @property
    def column(self) -> str:
        return f"param.{self.field}"


@dataclass
class Study:
    name: str = "study"
    description: str = ""
    base: str = "nominal"
    # Overrides the base's duration (s); NaN keeps it.
    duration: float = math.nan
    draws: int = 1
    seed: int = 0
    parameters: list[Parameter] = field(default_factory=list)
    metrics: list[str] = field(default_factory=lambda: list(DEFAULT_METRICS))


@dataclass
class PlannedRun:
    """One run of a study: its number, draw, varied values, scenario text and identity."""

    index: int
    draw: int
    values: dict[str, float]
    scenario_text: str
    run_id: str


@dataclass
class LoadedStudy:
    """A validated study: its file, the spec, the base scenario with the settings applied,
    and the settings as given (for the provenance)."""

    path: Path
    study: Study
    base: Scenario
    settings: dict = field(default_factory=dict)


def study_directory() -> Path:
    """The shipped study files' folder."""
    return Path(__file__).resolve().parent / "files"


def shipped_studies() -> dict[str, Path]:
    return {p.stem: p for p in sorted(study_directory().glob("*.yaml"))}


def _study_path(name_or_path: str | Path) -> Path:
    path = Path(name_or_path)
    if not path.suffix and str(name_or_path) in shipped_studies():
        return shipped_studies()[str(name_or_path)]
    if not path.is_file():
        raise ScenarioError(f"no study file {str(name_or_path)!r}; shipped studies: "
                            f"{', '.join(shipped_studies())}, or give a path to a .yaml file")
    return path


def _deep_merge(base: dict, extra: dict) -> dict:
    out = dict(base)
    for key, value in extra.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = _deep_merge(out[key], value)
        else:
            out[key] = value
    return out


def _base_scenario(path: Path, study: Study, settings: dict) -> Scenario:
    """The base scenario (shipped name, or a path relative to the study file) with the
    settings and the duration applied, validated; errors name the study file's field. A file
    the base names (a robot ...) starts at the base's folder, one the settings name at the
    study file's (:mod:`aerial_drake.studies.relative`)."""
    base = Path(study.base)
    if base.suffix:
        base = base if base.is_absolute() else path.parent / base
        base_path = base
    elif study.base in shipped_scenarios():
        base_path = shipped_scenarios()[study.base]
    else:
        raise ScenarioError(f"{path}: base: no shipped scenario {study.base!r} (shipped: "
                            f"{', '.join(shipped_scenarios())}) and not a .yaml path", "base")
    _, data = read_scenario_file(base_path)
    # Each file's relative paths start at its own folder (the merged copy is written elsewhere).
    merged = _deep_merge(absolute_paths(data, base_path.parent),
                         absolute_paths(settings, path.parent))
    overrides = {} if math.isnan(study.duration) else {"duration": study.duration}
    # load_scenario reads a file (and names it in its errors, replaced below by the study's).
    with tempfile.TemporaryDirectory() as folder:
        merged_path = Path(folder) / f"{study.name}_base.yaml"
        merged_path.write_text(yaml_dump(merged))
        try:
            return load_scenario(merged_path, overrides=overrides or None)
        except ScenarioError as err:
            message = str(err).replace(str(merged_path), f"{path}: settings (on base "
                                       f"{study.base!r})")
            raise ScenarioError(message, err.field) from None


def load_study(name_or_path: str | Path, *, duration: float | None = None,
               draws: int | None = None) -> LoadedStudy:
    """Load and validate a study file (a shipped study's name or a path), with its
    ``duration`` and ``draws`` replaced if given; raise ScenarioError naming the file, the
    field, the value and the fix."""
    path = _study_path(name_or_path)
    _, data = read_scenario_file(path)
    settings = data.pop("settings", None) or {}
    if not isinstance(settings, dict):
        raise ScenarioError(f"{path}: settings: expected a section of scenario fields, got "
                            f"{settings!r}", "settings")
    known = {f.name for f in dataclasses.fields(Study)}
    for key in data:
        if key not in known:
            raise ScenarioError(f"{path}: {key}: not a field of a study; fields: "
                                f"{', '.join(sorted(known | {'settings'}))}", key)
    try:
        study = yaml_load_typed(schema=Study, data=yaml_dump(data))
    except (RuntimeError, ValueError, TypeError, AssertionError) as err:
        raise ScenarioError(f"{path}: {err or type(err).__name__}") from None
    if duration is not None:
        study = dataclasses.replace(study, duration=float(duration))
    if draws is not None:
        study = dataclasses.replace(study, draws=draws)
    base = _base_scenario(path, study, settings)
    check_study(study, base, path)
    return LoadedStudy(path=path, study=study, base=base, settings=settings)


def _fail(path: Path, where: str, message: str) -> ScenarioError:
    return ScenarioError(f"{path}: {where}: {message}", where)


def _field_value(scenario: Scenario, dotted: str) -> Any:
    value: Any = scenario
    for part in dotted.split("."):
        if not dataclasses.is_dataclass(value) or not hasattr(value, part):
            raise KeyError(part)
        value = getattr(value, part)
    return value


def check_study(study: Study, base: Scenario, path: Path) -> None:
    """Every check of a study's values (module docstring)."""
    if not isinstance(study.draws, int) or not 1 <= study.draws <= MAX_RUNS:
        raise _fail(path, "draws", f"must be an integer from 1 to {MAX_RUNS}; got "
                    f"{study.draws!r}")
    if not isinstance(study.seed, int) or study.seed < 0:
        raise _fail(path, "seed", f"must be an integer >= 0; got {study.seed!r}")
    seen = set()
    for i, p in enumerate(study.parameters):
        where = f"parameters[{i}]"
        try:
            value = _field_value(base, p.field)
        except KeyError:
            raise _fail(path, f"{where}.field", f"{p.field!r} is not a scenario field (e.g. "
                        "gains.k_R, payload.mass, model_mismatch.seed)") from None
        if p.field in seen:
            raise _fail(path, f"{where}.field", f"{p.field!r} is varied twice")
        seen.add(p.field)
        if dataclasses.is_dataclass(value) or isinstance(value, (str, bool)):
            raise _fail(path, f"{where}.field", f"{p.field!r} is not a number or a list "
                        "of numbers")
        if p.kind not in KINDS:
            raise _fail(path, f"{where}.kind", f"{p.kind!r} is not one of {', '.join(KINDS)}")
        if p.mode not in MODES:
            raise _fail(path, f"{where}.mode", f"{p.mode!r} is not one of {', '.join(MODES)}")
        _check_kind(path, where, p, value)
    if _grid_size(study) * study.draws > MAX_RUNS:
        raise _fail(path, "parameters", f"{_grid_size(study) * study.draws} runs, more than "
                    f"{MAX_RUNS}: fewer grid values or draws")
    names = metric_names(base)
    for i, pattern in enumerate(study.metrics):
        if not fnmatch.filter(names, pattern):
            raise _fail(path, f"metrics[{i}]", f"{pattern!r} matches no metric; metrics: "
                        f"{', '.join(names)}")
    # Every run must build: each planned scenario is validated now (cheap: no model built).
    ids: dict[str, int] = {}
    for run in plan_runs(LoadedStudy(path, study, base)):
        try:
            scenario_from_text(run.scenario_text)
        except ScenarioError as err:
            raise ScenarioError(f"{path}: run {run.index} ({_values_text(run.values)}): "
                                f"{err}", err.field) from None
        if run.run_id in ids:
            raise _fail(path, "parameters", f"runs {ids[run.run_id]} and {run.index} are the "
                        "same scenario: with draws > 1 vary a random parameter (e.g. a "
                        "seed), or set draws: 1")
        ids[run.run_id] = run.index


def _values_text(values: dict[str, float]) -> str:
    return ", ".join(f"{k} = {v:g}" for k, v in values.items())


def _check_kind(path: Path, where: str, p: Parameter, value: Any) -> None:
    if p.kind == "grid":
        if not p.values:
            raise _fail(path, f"{where}.values", "a grid needs a list of values")
    elif p.kind == "uniform":
        if not (math.isfinite(p.low) and math.isfinite(p.high) and p.low <= p.high):
            raise _fail(path, f"{where}.low", f"uniform needs finite low <= high; got "
                        f"low {p.low}, high {p.high}")
    elif p.kind == "normal":
        if not (math.isfinite(p.mean) and math.isfinite(p.std) and p.std > 0):
            raise _fail(path, f"{where}.std", f"normal needs a finite mean and std > 0; got "
                        f"mean {p.mean}, std {p.std}")
    elif p.kind == "seed" and not isinstance(value, int):
        raise _fail(path, f"{where}.kind", f"'seed' is for integer fields; {p.field} is not "
                    "one")
    if p.kind == "seed" and p.mode == "scale":
        raise _fail(path, f"{where}.mode", "a seed is set, not scaled")


def _grid_size(study: Study) -> int:
    return math.prod(len(p.values) for p in study.parameters if p.kind == "grid")


def _with_field(obj: Any, parts: list[str], value: Any, mode: str) -> Any:
    """A copy of ``obj`` with the dotted field set to (or scaled by) ``value``; a scalar for
    a list field applies to every entry."""
    if not parts:
        if isinstance(obj, list):
            return [x * value if mode == "scale" else value for x in obj]
        if isinstance(obj, int) and not isinstance(obj, bool):
            return int(value)
        return obj * value if mode == "scale" else float(value)
    head = parts[0]
    return dataclasses.replace(obj, **{head: _with_field(getattr(obj, head), parts[1:],
                                                          value, mode)})


def _draw(p: Parameter, rng: np.random.Generator) -> float:
    if p.kind == "uniform":
        return float(rng.uniform(p.low, p.high))
    if p.kind == "normal":
        return float(rng.normal(p.mean, p.std))
    return int(rng.integers(0, 2 ** 31 - 1))


def scenario_text(scenario: Scenario) -> str:
    """The resolved scenario as YAML: what a worker builds, and what a run's id hashes."""
    return yaml_dump_typed(scenario)


def scenario_from_text(text: str) -> Scenario:
    """The scenario of :func:`scenario_text`, validated."""
    return yaml_load_typed(schema=Scenario, data=text).validate()


def run_id(text: str) -> str:
    """A run's identity: the hash of its resolved scenario."""
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


def plan_runs(loaded: LoadedStudy, limit: int | None = None) -> list[PlannedRun]:
    """Every run of the study, in order (module docstring); the first ``limit`` if given."""
    study, base = loaded.study, loaded.base
    grids = [p for p in study.parameters if p.kind == "grid"]
    randoms = [p for p in study.parameters if p.kind != "grid"]
    runs: list[PlannedRun] = []
    for point in itertools.product(*(p.values for p in grids)):
        for draw in range(study.draws):
            rng = np.random.default_rng([study.seed, draw])
            values = dict(zip((p.field for p in grids), point))
            values.update({p.field: _draw(p, rng) for p in randoms})
            scenario = base
            for p in study.parameters:
                scenario = _with_field(scenario, p.field.split("."), values[p.field], p.mode)
            # The study's name for every run: a run's identity is its physics alone.
            scenario = dataclasses.replace(scenario, name=study.name)
            text = scenario_text(scenario)
            runs.append(PlannedRun(index=len(runs), draw=draw, values=values,
                                   scenario_text=text, run_id=run_id(text)))
            if limit is not None and len(runs) >= limit:
                return runs
    return runs
