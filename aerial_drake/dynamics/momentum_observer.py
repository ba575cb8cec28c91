"""A generalized-momentum observer of the external forces on the robot (De Luca, Haddadin et
al.), discretized at a sample period, and the map from its estimate to two wrenches. Numpy
only: the Drake system around it is :mod:`aerial_drake.control.wrench_observer`.

The model (1) with an external generalized force ``tau_ext``:
``M v_dot + C v + g = tau_act + tau_ext``. With the momentum ``p = M v`` and
``M_dot = C + C^T``, ``p_dot = tau_act + C^T v - g + tau_ext``, and the observer

    r = K_O (p(t) - p(0) - int_0^t (tau_act + C^T v - g + r) ds)

has ``r_dot = K_O (tau_ext - r)``: each entry of ``r`` follows ``tau_ext`` through a
first-order filter of bandwidth ``K_O`` (1/s), with no acceleration measured.

Discretization (sample period ``h``, samples ``k``): the momentum's change over a sample not
explained by the model,

    d_k = [ (p_k - p_{k-1}) - int (tau_act + C^T v - g) ] / h,

is the mean external force over the sample; the filter is then discretized exactly for an
input constant over the sample, ``r_k = a r_{k-1} + (1 - a) d_k`` with ``a = exp(-K_O h)``
(explicit Euler would give ``1 - a = K_O h``: the same as ``h -> 0``, unstable past
``K_O h = 2``; the exact form is stable for every bandwidth and has unit gain at rest).
The integral uses no Coriolis matrix: ``C^T v = M_dot v - C v``, and ``int M_dot v`` over a
sample is ``(M_k - M_{k-1}) (v_k + v_{k-1}) / 2`` (trapezoid), so that

    p_k - p_{k-1} - int M_dot v = (M_k + M_{k-1}) / 2 (v_k - v_{k-1}),

and the rest, the bias ``C v`` (Drake's ``CalcBiasTerm``), ``g`` and the actuation's
generalized force, by the trapezoid over the sample's two ends, the actuation with the
command held over the sample (:func:`actuation_force` at both ends' attitudes). The result is
second-order accurate in ``h`` and needs only ``M``, ``C v``, ``g`` at each sample.

The two wrenches (vehicle, end effector: :func:`split_wrenches`) are each sample's ``d_k``
split at that sample's posture, then filtered by the same ``a``: a World wrench that is
constant is then estimated without the lag that ``r``, a filter of ``J^T(q(t)) w``, has
while the robot moves (:func:`step`).

Velocity coordinates are Drake's: ``v = [w_WB (World); v_WBo (World); qdot_arm]``, so a World
wrench ``[torque; force]`` at the base origin is the generalized force on the first six
entries as it is (:func:`aerial_drake.simulation.actuators.free_body_wrench_map`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: The two wrenches of :func:`split_wrenches`, in the order of their 12-vector: the vehicle's
#: (World axes, at the base frame's origin) then the end effector's (World axes, at the
#: end-effector frame's origin), each ``[torque (N m); force (N)]``.
WRENCH_ESTIMATE_LAYOUT = (("vehicle_torque", 3), ("vehicle_force", 3),
                          ("end_effector_torque", 3), ("end_effector_force", 3))
WRENCH_ESTIMATE_SIZE = sum(size for _, size in WRENCH_ESTIMATE_LAYOUT)


def filter_pole(bandwidth: float, period: float) -> float:
    """``a = exp(-bandwidth period)``: the discrete pole of the first-order filter of
    ``bandwidth`` (1/s) sampled exactly at ``period`` (s)."""
    if not (bandwidth > 0 and math.isfinite(bandwidth)):
        raise ValueError(f"observer bandwidth must be finite and > 0 (1/s); got {bandwidth!r}")
    if not (period > 0 and math.isfinite(period)):
        raise ValueError(f"observer period must be finite and > 0 (s); got {period!r}")
    return math.exp(-bandwidth * period)


def actuation_force(R_WB: np.ndarray, command: np.ndarray) -> np.ndarray:
    """The generalized force of the command ``[f, mu (3), tau (n)]`` (2): the thrust ``f``
    along the body z axis and the body torques ``mu`` at the base origin, in World
    ``[R mu; f R e3]`` on the base's six velocities, and the joint torques ``tau``."""
    command = np.asarray(command, dtype=float)
    out = np.empty(command.size + 2)
    out[:3] = R_WB @ command[1:4]
    out[3:6] = command[0] * R_WB[:, 2]
    out[6:] = command[4:]
    return out


@dataclass(frozen=True)
class ObserverSample:
    """What the observer needs of one sample: the model's terms at the measured state."""

    M: np.ndarray  # mass matrix (nv, nv)
    v: np.ndarray  # generalized velocity (nv)
    bias: np.ndarray  # C(q, v) v (nv), Drake's CalcBiasTerm
    g: np.ndarray  # gravity on the left of (1), g = -tau_g (nv)
    R_WB: np.ndarray  # base attitude (3, 3)
    J_E: np.ndarray  # (6, nv) Jacobian of the end-effector frame's [w; v] in World


class ObserverState:
    """The observer's memory as one flat vector (a Drake discrete state): the estimate ``r``
    (nv), the wrenches of :func:`split_wrenches` (12), and the previous sample's ``M`` (nv^2),
    ``v`` (nv), ``C v + g`` (nv) and ``R_WB`` (9). Views into ``vector``: writing them
    writes it."""

    def __init__(self, vector: np.ndarray, nv: int):
        self.vector = vector
        sizes = (nv, WRENCH_ESTIMATE_SIZE, nv * nv, nv, nv, 9)
        ends = np.cumsum(sizes)
        r, w, M, v, b, R = (vector[e - s:e] for s, e in zip(sizes, ends))
        self.r, self.wrenches, self.v, self.bias_plus_g = r, w, v, b
        self.M, self.R_WB = M.reshape(nv, nv), R.reshape(3, 3)

    @staticmethod
    def parts(nv: int) -> tuple[slice, slice]:
        """Where ``r`` and the wrenches are in the vector (the vector's first entries)."""
        return slice(0, nv), slice(nv, nv + WRENCH_ESTIMATE_SIZE)

    @staticmethod
    def size(nv: int) -> int:
        return 3 * nv + WRENCH_ESTIMATE_SIZE + nv * nv + 9

    def remember(self, sample: ObserverSample) -> None:
        """Keep ``sample`` as the previous one (the observer's start: p(0))."""
        self.M[:] = sample.M
        self.v[:] = sample.v
        self.bias_plus_g[:] = sample.bias + sample.g
        self.R_WB[:] = sample.R_WB


def start(state: ObserverState, sample: ObserverSample) -> None:
    """The observer at its first sample: ``r = 0``, wrenches zero, ``sample`` remembered."""
    state.vector[:] = 0.0
    state.remember(sample)


def residual(state: ObserverState, sample: ObserverSample, command: np.ndarray,
             period: float) -> np.ndarray:
    """``d_k``: the mean generalized force over the sample since ``state``'s previous one
    that the model with ``command`` (held over the sample) does not explain (module
    docstring)."""
    momentum_change = 0.5 * (sample.M + state.M) @ (sample.v - state.v)
    known = 0.5 * (actuation_force(state.R_WB, command) + actuation_force(sample.R_WB, command)
                   - state.bias_plus_g - (sample.bias + sample.g))
    return momentum_change / period - known


def step(state: ObserverState, sample: ObserverSample, command: np.ndarray, period: float,
         pole: float) -> None:
    """One sample: ``r_k = a r_{k-1} + (1 - a) d_k`` (``pole`` = a of :func:`filter_pole`),
    the wrenches by the same filter on :func:`split_wrenches` of ``d_k`` at this sample's
    posture, then ``sample`` remembered.

    The wrenches are filtered in their own coordinates rather than split from ``r``: a
    constant World wrench is then estimated without lag even while the robot moves, whereas
    ``r`` follows ``J^T(q(t)) w`` with the filter's lag (measured: splitting ``r`` is 5 % off
    under the paper's end-effector wrench at 20 1/s, the arm turning at up to 1.2 rad/s)."""
    d = residual(state, sample, command, period)
    state.r[:] = pole * state.r + (1.0 - pole) * d
    split = split_wrenches(d, sample.J_E)
    state.wrenches[:] = pole * state.wrenches + (1.0 - pole) * split
    state.remember(sample)


def split_wrenches(tau_ext: np.ndarray, J_E: np.ndarray) -> np.ndarray:
    """The vehicle's and the end effector's World wrenches ``[torque; force]`` (12, in
    :data:`WRENCH_ESTIMATE_LAYOUT`'s order) whose generalized force is ``tau_ext``,
    assuming external forces act only at those two points: at the base frame's origin
    (generalized force: the wrench itself on the first six entries) and at the end-effector
    frame's origin E (``J_E^T w_E``, ``J_E`` the (6, nv) Jacobian of E's spatial velocity
    ``[w; v]`` in World).

    The arm's rows see only ``w_E``: ``tau_ext,arm = J_E,arm^T w_E``, solved by least squares
    (the pseudo-inverse: exact for six or more joints away from a singularity, the
    smallest-norm wrench for fewer); the vehicle's wrench is what is left on the base's rows,
    ``tau_ext[:6] - J_E,base^T w_E`` (``J_E,base^T`` moves ``w_E`` to the base origin:
    ``[torque + p_BE x force; force]``). A contact elsewhere on the arm is read as the
    end-effector wrench that best explains its joint torques."""
    tau_ext = np.asarray(tau_ext, dtype=float)
    w_E = np.linalg.lstsq(J_E[:, 6:].T, tau_ext[6:], rcond=None)[0]
    return np.concatenate([tau_ext[:6] - J_E[:, :6].T @ w_E, w_E])
