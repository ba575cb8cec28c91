"""One entry point for every reference kind: :func:`reference_of` (the
:class:`~aerial_drake.trajectories.base.ReferenceSource` a ``trajectory:`` section names),
and :func:`evaluate_reference` / :func:`sample_reference` on it. Everything that reads a
run's reference (the generator, the logs, the checks, Meshcat) goes through here, so each
shows the reference the run used."""

from __future__ import annotations

import numpy as np

from aerial_drake.trajectories.base import ReferenceSource
from aerial_drake.trajectories.hover import HoverReference
from aerial_drake.trajectories.paper import PaperReference, joint_targets
from aerial_drake.trajectories.params import TrajectoryParams
from aerial_drake.trajectories.python_kind import python_reference
from aerial_drake.trajectories.reference import ReferenceSample
from aerial_drake.trajectories.waypoints import WaypointsReference

__all__ = ["reference_of", "evaluate_reference", "sample_reference"]


def reference_of(params: TrajectoryParams, joint_defaults=None) -> ReferenceSource:
    """The reference ``params`` describes. ``joint_defaults``: the task's joint angles where
    ``joint_targets`` is empty (the robot's nominal posture at the task's joints). ValueError
    naming the field if the section is invalid."""
    params.validate()
    targets = joint_targets(params, joint_defaults)
    offset = np.asarray(params.com_offset, dtype=float)
    if params.kind == "paper":
        return PaperReference(params, joint_defaults)
    if params.kind == "hover":
        return HoverReference(params.hover, targets, offset)
    if params.kind == "waypoints":
        return WaypointsReference(params.waypoints, targets, offset)
    return python_reference(params.python, targets)


def evaluate_reference(params: TrajectoryParams, t: float, joint_defaults=None
                       ) -> ReferenceSample:
    """The reference of any kind and its derivatives at time t (s)."""
    return reference_of(params, joint_defaults).evaluate(t)


def sample_reference(params: TrajectoryParams, times: np.ndarray, joint_defaults=None
                     ) -> ReferenceSample:
    """:func:`evaluate_reference` over a 1-D array of N times: every field of the result has a
    leading time axis of length N (e.g. com is (N, 5, 3), R_ed is (N, 3, 3))."""
    return reference_of(params, joint_defaults).sample(np.asarray(times, dtype=float))
