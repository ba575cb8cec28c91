"""External disturbance wrenches as Drake sources: constant windows, as the paper's green
(4-5 s, helicopter) and orange (9-10 s, end effector) areas."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource, TrajectorySource
from pydrake.trajectories import PiecewisePolynomial

from aerial_drake.simulation.scenarios import Disturbance


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
