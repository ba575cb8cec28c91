"""What every reference kind provides: :class:`ReferenceSource`."""

from __future__ import annotations

import numpy as np

from aerial_drake.trajectories.reference import (
    ReferenceSample,
    packed_reference_size,
    packed_slices,
)

__all__ = ["ReferenceSource"]


class ReferenceSource:
    """A reference kind's evaluation: :meth:`fill` writes the packed [com, task, heading]
    vector (layouts in :mod:`aerial_drake.trajectories.reference`) at a time; the rest is
    built on it. ``n_joints``: the task's joint components in the task reference."""

    #: The kind's name (``trajectory.kind``).
    kind = ""

    def __init__(self, n_joints: int) -> None:
        self.n_joints = int(n_joints)
        self.size = packed_reference_size(self.n_joints)

    def fill(self, t: float, out: np.ndarray) -> None:
        """The packed reference at time t (s) into ``out`` (size :attr:`size`)."""
        raise NotImplementedError

    def for_run(self, duration: float) -> "ReferenceSource":
        """The source a run over [0, ``duration``] (s) evaluates: this one, or (the python
        kind) the same reference sampled once onto compiled splines, checked against it
        (:mod:`aerial_drake.trajectories.sampled`; ValueError naming the signal if they
        differ beyond its tolerance)."""
        return self

    def packed(self, times: np.ndarray) -> np.ndarray:
        """The packed reference at each of the 1-D ``times`` (N, size)."""
        times = np.asarray(times, dtype=float)
        if times.ndim != 1:
            raise ValueError(f"times must be a 1-D array, got shape {times.shape}")
        out = np.empty((times.size, self.size))
        for i, t in enumerate(times):
            self.fill(float(t), out[i])
        return out

    def evaluate(self, t: float) -> ReferenceSample:
        """The reference and its derivatives at time t (s)."""
        packed = np.empty(self.size)
        self.fill(float(t), packed)
        com, task, heading = packed_slices(self.n_joints)
        return ReferenceSample.from_vectors(packed[com], packed[task], packed[heading])

    def sample(self, times: np.ndarray) -> ReferenceSample:
        """:meth:`evaluate` over a 1-D array of N times: every field gets a leading axis."""
        packed = self.packed(times)
        com, task, heading = packed_slices(self.n_joints)
        return ReferenceSample.from_vectors(packed[:, com], packed[:, task],
                                            packed[:, heading])
