"""The registry of reference kinds (:data:`REFERENCE_KINDS`: each kind's name, its section of
:class:`~aerial_drake.trajectories.params.TrajectoryParams` and how its
:class:`~aerial_drake.trajectories.base.ReferenceSource` is built), the one validation of a
``trajectory:`` section (:func:`validate_trajectory`), and the one entry point
:func:`reference_of`.

A run builds its reference once (:func:`reference_of`, in
:func:`aerial_drake.simulation.diagram.add_closed_loop`) and hands that object to everything
that reads it: the :class:`~aerial_drake.trajectories.generator.ReferenceGenerator`, the
checks, the start posture, the logs and Meshcat, so each shows the reference the run flew.
:func:`evaluate_reference` and :func:`sample_reference` build one for a single use.

Adding a kind: its section's dataclass (with ``errors(n_joints)``) as a field of
TrajectoryParams, its module with a ReferenceSource, and one entry here.
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import numpy as np

from aerial_drake.trajectories.base import ReferenceSource
from aerial_drake.trajectories.hover import HoverReference
from aerial_drake.trajectories.paper import PaperReference, joint_targets
from aerial_drake.trajectories.params import TrajectoryParams
from aerial_drake.trajectories.python_kind import python_reference
from aerial_drake.trajectories.reference import ReferenceSample
from aerial_drake.trajectories.waypoints import WaypointsReference

__all__ = ["ReferenceKind", "REFERENCE_KINDS", "KINDS", "validate_trajectory", "reference_of",
           "evaluate_reference", "sample_reference"]


@dataclasses.dataclass(frozen=True)
class ReferenceKind:
    """One reference kind: ``section``, the TrajectoryParams field holding its own numbers
    (None: the top-level fields, the paper kind's); ``build(params, joint_targets)``, its
    reference from valid params and the task's joint angles (:func:`joint_targets`);
    ``user_derivatives``: its derivatives are the user's, not constructed here, so the
    scenario's load-time check tests them against finite differences over the run."""

    section: str | None
    build: Callable[[TrajectoryParams, np.ndarray], ReferenceSource]
    user_derivatives: bool = False


#: The kinds ``trajectory.kind`` may name (docs/trajectories.md lists each).
REFERENCE_KINDS: dict[str, ReferenceKind] = {
    "paper": ReferenceKind(None, PaperReference),
    "hover": ReferenceKind("hover", lambda params, targets: HoverReference(
        params.hover, targets, np.asarray(params.com_offset, dtype=float))),
    "waypoints": ReferenceKind("waypoints", lambda params, targets: WaypointsReference(
        params.waypoints, targets, np.asarray(params.com_offset, dtype=float))),
    "python": ReferenceKind("python", lambda params, targets: python_reference(
        params.python, targets), user_derivatives=True),
}
#: Their names, in the registry's order.
KINDS = tuple(REFERENCE_KINDS)


def validate_trajectory(params: TrajectoryParams, n_joints: int | None = None) -> None:
    """ValueError naming every bad field of the ``trajectory:`` section and how to fix it:
    the kind (one of the registry's), its own section, the shared fields. ``n_joints``: the
    task's joint components, where a kind's section gives joint angles (None: not checked)."""
    if not isinstance(params.kind, str) or params.kind not in REFERENCE_KINDS:
        raise ValueError(f"Invalid TrajectoryParams: 'kind' must be one of {KINDS}, got "
                         f"{params.kind!r}.")
    section = REFERENCE_KINDS[params.kind].section
    errors = [] if section is None else getattr(params, section).errors(n_joints)
    errors += params.errors()
    if errors:
        raise ValueError("Invalid TrajectoryParams: " + "; ".join(errors) + ".")


def reference_of(params: TrajectoryParams, joint_defaults=None) -> ReferenceSource:
    """The reference ``params`` describes, validated once (:func:`validate_trajectory`).
    ``joint_defaults``: the task's joint angles where ``joint_targets`` is empty (the robot's
    nominal posture at the task's joints). ValueError naming the field if the section is
    invalid."""
    # As many as joint_targets() gives: the section's, else the defaults, else the paper's q3d.
    if params.joint_targets:
        n_joints = len(params.joint_targets)
    else:
        n_joints = 1 if joint_defaults is None else len(joint_defaults)
    validate_trajectory(params, n_joints)
    targets = joint_targets(params, joint_defaults)
    return REFERENCE_KINDS[params.kind].build(params, targets)


def evaluate_reference(params: TrajectoryParams, t: float, joint_defaults=None
                       ) -> ReferenceSample:
    """The reference of any kind and its derivatives at time t (s); builds it for this call
    (a run's own: ``loop.reference.source.evaluate(t)``)."""
    return reference_of(params, joint_defaults).evaluate(t)


def sample_reference(params: TrajectoryParams, times: np.ndarray, joint_defaults=None
                     ) -> ReferenceSample:
    """:func:`evaluate_reference` over a 1-D array of N times: every field of the result has a
    leading time axis of length N (e.g. com is (N, 5, 3), R_ed is (N, 3, 3))."""
    return reference_of(params, joint_defaults).sample(np.asarray(times, dtype=float))
