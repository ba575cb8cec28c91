"""External disturbance wrenches as Drake sources: constant windows, as the paper's green
(4-5 s, helicopter) and orange (9-10 s, end effector) areas, and the random windows of a
scenario's ``random_disturbances`` section drawn into such windows."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource, TrajectorySource
from pydrake.trajectories import PiecewisePolynomial

from aerial_drake.simulation.scenarios import Disturbance, Scenario


def wrench_schedule(disturbances: Sequence[Disturbance], target: str,
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Breaks and 6-vector wrenches ``[torque; force]`` (World), piecewise constant, of the
    windows acting on ``target``; overlapping windows add."""
    windows = [d for d in disturbances if d.target == target]
    times = sorted({0.0} | {d.start for d in windows} | {d.stop for d in windows})
    values = []
    for t in times:
        w = np.zeros(6)
        for d in windows:
            if d.start <= t < d.stop:
                w += np.concatenate([d.torque, d.force])
        values.append(w)
    return np.array(times), np.array(values)


def add_wrench_source(builder: DiagramBuilder, disturbances: Sequence[Disturbance],
                      target: str) -> ConstantVectorSource | TrajectorySource:
    """A source system whose output is the disturbance wrench on ``target`` over time."""
    times, values = wrench_schedule(disturbances, target)
    if len(times) == 1:
        source = ConstantVectorSource(np.zeros(6))
    else:
        # Zero-order-hold pieces: value k holds on [times[k], times[k+1]); hold the last.
        breaks = np.append(times, times[-1] + 1.0)
        samples = np.vstack([values, values[-1]]).T
        source = TrajectorySource(PiecewisePolynomial.ZeroOrderHold(breaks, samples))
    source.set_name(f"{target}_disturbance")
    return builder.AddSystem(source)


def _draw(rng: np.random.Generator, interval: list[float]) -> float:
    return float(rng.uniform(interval[0], interval[1]))


def _unit_vector(rng: np.random.Generator) -> np.ndarray:
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def random_windows(scenario: Scenario) -> list[Disturbance]:
    """The scenario's windows after its ``random_disturbances`` section's draws (the
    section's docstring): its own windows, redirected if it asks, then the new ones."""
    r = scenario.random_disturbances
    rng = np.random.default_rng(r.seed)
    windows = list(scenario.disturbances)
    if r.redirect:
        windows = [dataclasses.replace(
            d, force=(np.linalg.norm(d.force) * _unit_vector(rng)).tolist(),
            torque=(np.linalg.norm(d.torque) * _unit_vector(rng)).tolist()) for d in windows]
    for _ in range(int(r.count)):
        start = _draw(rng, r.start)
        length = _draw(rng, r.length)
        force = _draw(rng, r.force) * _unit_vector(rng)
        torque = _draw(rng, r.torque) * _unit_vector(rng)
        windows.append(Disturbance(target=r.target, start=start, stop=start + length,
                                   force=force.tolist(), torque=torque.tolist()))
    return windows


def resolve_random_disturbances(scenario: Scenario) -> Scenario:
    """``scenario`` with its random windows drawn into ``disturbances`` and the random
    section reset (so resolving twice draws nothing more); the same object when it asks for
    none. The input is not modified."""
    r = scenario.random_disturbances
    if not (r.count or r.redirect):
        return scenario
    return dataclasses.replace(
        scenario, disturbances=random_windows(scenario),
        random_disturbances=dataclasses.replace(r, count=0, redirect=False))
