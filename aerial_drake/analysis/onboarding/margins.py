"""The largest constant load along a direction that the closed loop holds at rest within its
limits (:mod:`.loaded_rest`): a push on the vehicle (``robot check``'s push margins) or a
force or torque at the end effector (the wrench the arm can hold).

The search follows the equilibrium as the load grows from 0 (continuation, each step from
the last equilibrium, its size halved while an arm joint moves more than
:data:`MAX_JOINT_STEP` in it, doubled while it moves far less), checking the limits at every
step and the sign of ``det J_3`` between steps (a singularity passed between two steps), up
to the first load that breaks a limit or finds no equilibrium, then bisects between the
largest load held and that one to :data:`RELATIVE_TOLERANCE` of it. The largest load is the
first limit met along the path, as a push that grows slowly meets it. The binding limit is
what the smallest breaking load violates."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TextIO

import numpy as np

from aerial_drake.analysis.onboarding.loaded_rest import RestLoop, RestState
from aerial_drake.analysis.wrench_deflection import ExternalForce
from aerial_drake.dynamics.equilibrium import kinematic_J3

#: The bisection stops when the bracket is this fraction of its upper end.
RELATIVE_TOLERANCE = 0.01
#: The bisection stops below this fraction of the cap (a margin of about 0).
FLOOR = 1e-4
#: The searches' caps, in units of the robot's weight m g: a vehicle push (N) and an
#: end-effector force (N); an end-effector torque's cap is the weight times the nominal
#: distance from the CoM to the end effector (N m).
PUSH_CAP_WEIGHTS = 3.0
EE_FORCE_CAP_WEIGHTS = 2.0
#: The continuation's step is halved while an arm joint moves more than this (rad) in one
#: step (and doubled below a quarter of it): the limits are checked at every step, so none
#: is passed between two of them unseen.
MAX_JOINT_STEP = 0.1
#: The six directions, in the heading frame [b1d, e3 x b1d, e3].
DIRECTIONS = (("+x", 0, 1.0), ("-x", 0, -1.0), ("+y", 1, 1.0), ("-y", 1, -1.0),
              ("+z", 2, 1.0), ("-z", 2, -1.0))


@dataclass(frozen=True)
class Margin:
    """The largest load along one direction held within the limits."""

    kind: str  # "vehicle push", "end-effector force", "end-effector torque"
    direction: str  # "+x", ... (heading frame)
    unit: str  # "N" or "N m"
    largest: float  # magnitude held (to RELATIVE_TOLERANCE), 0 if even the first fails
    capped: bool  # every limit kept up to the cap: ``largest`` is the cap
    binding: str  # what the smallest breaking load violates ("" when capped)
    com_deflection: np.ndarray  # (3) World, m: the CoM's move at ``largest``
    ee_displacement: np.ndarray  # (3) World, m: the end effector's move at ``largest``
    state: RestState | None  # the loop at rest at ``largest`` (None when 0)

    def to_json(self) -> dict:
        return {"kind": self.kind, "direction": self.direction, "unit": self.unit,
                "largest": self.largest, "capped": self.capped, "binding": self.binding,
                "com_deflection_m": self.com_deflection.tolist(),
                "ee_displacement_m": self.ee_displacement.tolist(),
                "nearest_limit": None if self.state is None else self.state.nearest[0],
                "nearest_limit_usage": None if self.state is None else self.state.nearest[1],
                "sigma_min_J3": None if self.state is None else self.state.sigma_min,
                "command": None if self.state is None else self.state.command.tolist()}


def largest_load(loop: RestLoop, load: Callable[[np.ndarray, np.ndarray], ExternalForce],
                 unit_vector: np.ndarray, cap: float, q0: np.ndarray,
                 ) -> tuple[float, bool, str, RestState | None]:
    """``(largest, capped, binding, state)`` of the module docstring for ``load(start,
    end)`` (a :class:`RestLoop` load between two vectors) along ``unit_vector``, from the
    unloaded equilibrium ``q0``."""
    model = loop.subject.model
    arm = model.arm_position_indices
    at_rest = loop.limits_at(q0)
    if not at_rest.ok:  # nothing to push from
        return 0.0, False, "at the nominal posture already: " + at_rest.violated[0], None
    lo, state_lo, q_lo = 0.0, None, q0
    sign_lo = _j3_sign(loop, q0)
    step = cap / 32.0

    def attempt(size: float) -> tuple[RestState | None, str, float]:
        """The loop at rest under ``size`` from the last held equilibrium: its state (None
        past a limit) and the arm's largest joint move."""
        external = load(lo * unit_vector, size * unit_vector)
        q, why = loop.equilibrium(external, q_lo)
        if q is None:
            return None, why, np.inf
        state = loop.limits_at(q, external)
        moved = float(np.abs(q[arm] - q_lo[arm]).max())
        if not state.ok:
            return None, state.violated[0], moved
        if _j3_sign(loop, q) != sign_lo:  # J_3 went singular between the two loads
            return None, ("Assumption 1: J_3 singular between "
                          f"{lo:.4g} and {size:.4g} (its determinant changed sign)"), moved
        return state, "", moved

    hi, why_hi = None, ""
    while hi is None:
        size = min(lo + step, cap)
        state, why, moved = attempt(size)
        if moved > MAX_JOINT_STEP and step > cap / 1024.0:  # too far in one step: halve
            step *= 0.5
            continue
        if state is None:
            hi, why_hi = size, why
            break
        lo, state_lo, q_lo = size, state, state.q
        if lo >= cap:
            return cap, True, "", state_lo
        if moved < 0.25 * MAX_JOINT_STEP:
            step *= 2.0
    while hi - lo > RELATIVE_TOLERANCE * hi and hi > FLOOR * cap:
        mid = 0.5 * (lo + hi)
        state, why, _ = attempt(mid)
        if state is None:
            hi, why_hi = mid, why
        else:
            lo, state_lo, q_lo = mid, state, state.q
    return lo, False, why_hi, state_lo


def _j3_sign(loop: RestLoop, q: np.ndarray) -> float:
    """The sign of det J_3 at ``q``: it flips where J_3 is singular."""
    plant = loop.subject.model.plant
    plant.SetPositions(loop.context, q)
    return float(np.sign(np.linalg.det(kinematic_J3(loop.subject.model, loop.context))))


def direction_margins(loop: RestLoop, kind: str, stream: TextIO | None = None,
                      directions: tuple[str, ...] | None = None) -> list[Margin]:
    """The :class:`Margin` of each of :data:`DIRECTIONS` (or of those named in
    ``directions``) for ``kind``: "vehicle push", "end-effector force" or "end-effector
    torque" (about the heading frame's axes)."""
    subject = loop.subject
    H = subject.heading_axes
    q0 = subject.q0
    com0, ee0 = loop.com_and_ee(q0)
    weight = subject.weight
    if kind == "vehicle push":
        unit, cap = "N", PUSH_CAP_WEIGHTS * weight

        def load(a: np.ndarray, b: np.ndarray) -> ExternalForce:
            return loop.vehicle_push(a, b)
    elif kind == "end-effector force":
        unit, cap = "N", EE_FORCE_CAP_WEIGHTS * weight

        def load(a: np.ndarray, b: np.ndarray) -> ExternalForce:
            return loop.ee_wrench(np.concatenate([a, np.zeros(3)]),
                                  np.concatenate([b, np.zeros(3)]))
    elif kind == "end-effector torque":
        unit, cap = "N m", weight * float(np.linalg.norm(ee0 - com0))

        def load(a: np.ndarray, b: np.ndarray) -> ExternalForce:
            return loop.ee_wrench(np.concatenate([np.zeros(3), a]),
                                  np.concatenate([np.zeros(3), b]))
    else:
        raise ValueError(f"kind {kind!r}: one of 'vehicle push', 'end-effector force', "
                         "'end-effector torque'")
    out = []
    for label, axis, sign in DIRECTIONS:
        if directions is not None and label not in directions:
            continue
        u = sign * H[:, axis]
        largest, capped, binding, state = largest_load(loop, load, u, cap, q0)
        if stream is not None:
            stream.write(f"  {kind} {label}: {largest:.4g} {unit}"
                         f"{' (cap)' if capped else ''}\n")
            stream.flush()
        com, ee = loop.com_and_ee(state.q) if state is not None else (com0, ee0)
        out.append(Margin(kind=kind, direction=label, unit=unit, largest=float(largest),
                          capped=capped, binding=binding, com_deflection=com - com0,
                          ee_displacement=ee - ee0, state=state))
    return out
