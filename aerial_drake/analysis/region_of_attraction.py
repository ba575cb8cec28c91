"""A sampled region of attraction: the fraction of runs that converge from sampled initial
offsets of growing size (:func:`region_of_attraction`)."""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass

import numpy as np

from aerial_drake.analysis.settings import FULL_SETTINGS
from aerial_drake.control.law import diagnostics_slices
from aerial_drake.simulation.scenarios import Scenario, load_scenario

# --- Region of attraction -------------------------------------------------------------------
#: Offsets of size 1: base position (m), base roll-pitch-yaw (rad), arm joints (rad), as
#: vector norms; a run of size s draws each from the sphere of radius s times these.
ROA_UNIT = {"base_position_offset": 0.1, "base_rpy_offset": 0.1, "arm_offset": 0.1}


@dataclass
class RegionOfAttraction:
    scales: list[float]
    runs: list[dict]  # scale, offsets, completed, failure, V0, VT, converged
    duration: float
    min_decay_rate: float
    wall_time_s: float

    @property
    def fractions(self) -> list[float]:
        out = []
        for s in self.scales:
            runs = [r for r in self.runs if r["scale"] == s]
            out.append(sum(r["converged"] for r in runs) / len(runs) if runs else math.nan)
        return out

    def summary(self) -> dict:
        return {"scales": self.scales, "unit": ROA_UNIT, "duration_s": self.duration,
                "criterion": f"run completes and V(T) <= exp(-{self.min_decay_rate:g} T) V(0)",
                "converged_fraction": self.fractions,
                "runs_per_scale": [sum(r["scale"] == s for r in self.runs)
                                   for s in self.scales],
                "wall_time_s": self.wall_time_s, "runs": self.runs}


def _unit_vector(rng: np.random.Generator, n: int) -> np.ndarray:
    u = rng.normal(size=n)
    return u / np.linalg.norm(u)


def region_of_attraction(base: Scenario | str = "nominal", *,
                         scales: tuple[float, ...] = FULL_SETTINGS.roa_scales,
                         samples: int = FULL_SETTINGS.roa_samples,
                         duration: float = FULL_SETTINGS.roa_duration,
                         min_decay_rate: float = 1.0, seed: int = 0,
                         ) -> RegionOfAttraction:
    """Run ``base`` (its sampling, saturation and integrator; disturbances removed) from
    ``samples`` random initial offsets at each scale s: base position, base roll-pitch-yaw
    and arm joint offsets, each a random direction times ``s * ROA_UNIT``. A run converges
    if it completes (no assumption violated, no divergence) and V decays on average at least
    at ``min_decay_rate`` (1/s): ``V(T) <= exp(-min_decay_rate T) V(0)`` (at hover the
    slowest closed-loop pole, about -1.2/s, makes V decay at about 2.4/s). Draws come from
    ``numpy.random.default_rng(seed)``."""
    from aerial_drake.simulation.runner import SimulationFailed, run_scenario

    scenario = load_scenario(base) if isinstance(base, str) else base
    scenario = dataclasses.replace(scenario, duration=duration, disturbances=[])
    rng = np.random.default_rng(seed)
    n = scenario.controller_model().n
    V = diagnostics_slices(n)["V"]
    runs, start = [], time.perf_counter()
    for s in scales:
        for _ in range(samples):
            offsets = {
                "base_position_offset": s * ROA_UNIT["base_position_offset"] * _unit_vector(rng, 3),
                "base_rpy_offset": s * ROA_UNIT["base_rpy_offset"] * _unit_vector(rng, 3),
                "arm_offset": s * ROA_UNIT["arm_offset"] * _unit_vector(rng, n),
            }
            initial = dataclasses.replace(scenario.initial,
                                          **{k: v.tolist() for k, v in offsets.items()})
            run = dataclasses.replace(scenario, initial=initial).validate()
            row = {"scale": s, **{k: v.tolist() for k, v in offsets.items()},
                   "completed": True, "failure": None, "V0": math.nan, "VT": math.nan}
            try:
                log = run_scenario(run, progress=False).log["diagnostics"][:, V].ravel()
                row["V0"], row["VT"] = float(log[0]), float(log[-1])
            except SimulationFailed as err:
                row["completed"], row["failure"] = False, str(err)
            row["converged"] = bool(row["completed"] and
                                    row["VT"] <= math.exp(-min_decay_rate * duration) * row["V0"])
            runs.append(row)
    return RegionOfAttraction(scales=list(scales), runs=runs, duration=duration,
                              min_decay_rate=min_decay_rate,
                              wall_time_s=time.perf_counter() - start)


