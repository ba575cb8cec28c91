"""The paper's reference trajectory (Section IV-A, eqs (27)-(33)): pure math and a Drake system.

The end-effector task (27) is y_d = [x_ed; R_ed; q_jd], with::

    x_ed(t) = center + A_b basic(t) + A_a agile(t)                                   (28)
        basic(t) = [-sin(w_b t), -cos(w_b t), sin(w_b t) + c t]
        agile(t) = [ sin(w_a t),  cos(w_a t), cos(w_a t)]
    R_ed(t)  = R1(phi1) R2(phi2) R3(phi3)   (R1 = RotX, R2 = RotY, R3 = RotZ)        (29)
    q_jd(t)  = joint_targets  (the task's joint components; the paper's q3d)        (30)
        phi1 = a1 sin(w_o t),  phi2 = a2 cos(w_o t),  phi3 = a3 cos(w_o t)          (31)
    b1d(t)   = [cos phi4, sin phi4, 0],  phi4 = phi4_0 + w_h t                      (32)
    x_d(t)   = x_c(t) + R3(phi4) r_o,  x_c(t) = center + A_b basic(t)               (33)

x_c is the "basic" motion realised by the whole system, A_a agile(t) the part left to the arm.
Every constant is a field of :class:`TrajectoryParams` (defaults: the paper's values). All
derivatives are analytic (closed form); the tests hold each one against a central difference.

Frames and units: every vector is expressed in World (m, m/s, rad, rad/s, ...). The angular
velocity of the desired end-effector frame satisfies d/dt R_ed = hat(w_ed) R_ed, and
dw_ed = d/dt w_ed (both in World).

The reference at a time (:func:`evaluate_reference`) or over times (:func:`sample_reference`)
comes as a :class:`~aerial_drake.trajectories.reference.ReferenceSample` (its packed layout is
in :mod:`aerial_drake.trajectories.reference`);
:class:`~aerial_drake.trajectories.generator.ReferenceGenerator` is the Drake source of it.

Do not add ``from __future__ import annotations`` here: Drake's ``yaml_load_typed`` needs the
real (non-string) field types of :class:`TrajectoryParams`.
"""

import math
import types
import typing

import numba
import numpy as np

from aerial_drake.trajectories.base import ReferenceSource
from aerial_drake.trajectories.params import TrajectoryParams
from aerial_drake.trajectories.reference import (
    ReferenceSample,
    packed_reference_size,
    packed_slices,
)

__all__ = ["TrajectoryParams", "PaperReference", "constants", "joint_targets",
           "evaluate_reference", "sample_reference", "compile_reference",
           "use_interpreted_reference"]


def joint_targets(params: TrajectoryParams, defaults=None) -> np.ndarray:
    """The desired joint angles: the scenario's, else ``defaults`` (the robot's nominal
    posture at the task's joints), else the paper's one q3d = 0."""
    if params.joint_targets:
        return np.asarray(params.joint_targets, dtype=float)
    return np.zeros(1) if defaults is None else np.asarray(defaults, dtype=float)


def constants(params: TrajectoryParams, joint_defaults=None) -> np.ndarray:
    """The constants array the compiled formulas read: :class:`_Constants` then the joint
    targets (see :func:`joint_targets` for ``joint_defaults``). ValueError naming the field
    if ``params`` is not a valid paper kind."""
    if params.kind != "paper":
        raise ValueError(f"trajectory kind '{params.kind}' is not the paper's (28)-(33): use "
                         "aerial_drake.trajectories.kinds.reference_of for any kind")
    errors = params.errors()
    if errors:
        raise ValueError("Invalid TrajectoryParams: " + "; ".join(errors) + ".")
    return _constants(params, joint_defaults)


def _constants(params: TrajectoryParams, joint_defaults=None) -> np.ndarray:
    return np.concatenate([_Constants.from_params(params).as_array(),
                           joint_targets(params, joint_defaults)])


def evaluate_reference(params: TrajectoryParams, t: float, joint_defaults=None
                       ) -> ReferenceSample:
    """The paper kind's reference and its analytic derivatives at time t (s) (any kind:
    :func:`aerial_drake.trajectories.kinds.evaluate_reference`)."""
    k = constants(params, joint_defaults)
    n_joints = k.size - _N_CONSTANTS
    packed = np.empty(packed_reference_size(n_joints))
    _kernels()[0](k, float(t), packed)
    com, task, heading = packed_slices(n_joints)
    return ReferenceSample.from_vectors(packed[com], packed[task], packed[heading])


def sample_reference(params: TrajectoryParams, times: np.ndarray, joint_defaults=None
                     ) -> ReferenceSample:
    """:func:`evaluate_reference` over a 1-D array of N times, vectorised.

    Every field of the result has a leading time axis of length N (e.g. com is (N, 5, 3),
    R_ed is (N, 3, 3), q_jd is (N, n_j)).
    """
    k = constants(params, joint_defaults)
    times = np.asarray(times, dtype=float)
    if times.ndim != 1:
        raise ValueError(f"times must be a 1-D array, got shape {times.shape}")
    n_joints = k.size - _N_CONSTANTS
    packed = np.empty((times.size, packed_reference_size(n_joints)))
    _kernels()[1](k, times, packed)
    com, task, heading = packed_slices(n_joints)
    return ReferenceSample.from_vectors(packed[:, com], packed[:, task], packed[:, heading])


class PaperReference(ReferenceSource):
    """``kind: paper``: (28)-(33) by the compiled formulas, from ``params`` already checked
    (:func:`aerial_drake.trajectories.kinds.reference_of` does; :func:`constants` checks)."""

    kind = "paper"

    def __init__(self, params: TrajectoryParams, joint_defaults=None) -> None:
        self.constants = _constants(params, joint_defaults)
        super().__init__(self.constants.size - _N_CONSTANTS)
        # Chosen once: compiled, or interpreted where this process must not compile.
        self._fill, self._fill_over_time = _kernels()

    def fill(self, t: float, out: np.ndarray) -> None:
        self._fill(self.constants, float(t), out)

    def packed(self, times: np.ndarray) -> np.ndarray:
        times = np.asarray(times, dtype=float)
        if times.ndim != 1:
            raise ValueError(f"times must be a 1-D array, got shape {times.shape}")
        out = np.empty((times.size, self.size))
        self._fill_over_time(self.constants, times, out)
        return out


class _Constants(typing.NamedTuple):
    """The parameters as plain floats, in the order the formulas use them (the joint
    targets follow them in the compiled code's array)."""

    cx: float
    cy: float
    cz: float
    A_b: float
    w_b: float
    c: float
    A_a: float
    w_a: float
    a1: float
    a2: float
    a3: float
    w_o: float
    phi4_0: float
    w_h: float
    rx: float
    ry: float
    rz: float

    @classmethod
    def from_params(cls, p: TrajectoryParams) -> "_Constants":
        return cls._make([
            *map(float, p.center),
            float(p.basic_amplitude),
            float(p.basic_frequency),
            float(p.basic_climb_rate),
            float(p.agile_amplitude),
            float(p.agile_frequency),
            *map(float, p.orientation_amplitudes),
            float(p.orientation_frequency),
            float(p.heading_initial),
            float(p.heading_rate),
            *map(float, p.com_offset),
        ])

    def as_array(self) -> np.ndarray:
        """The constants as a float array, in field order (what the compiled code reads)."""
        return np.array(self, dtype=float)


_N_CONSTANTS = len(_Constants._fields)


@numba.njit(cache=True)
def _sin_derivatives(s, c, w: float, amplitude: float = 1.0) -> tuple:
    """d^k/dt^k of amplitude * sin(w t + phase), k = 0..4, given s, c = sin, cos of the angle."""
    w2 = w * w
    return (
        amplitude * s,
        amplitude * w * c,
        -amplitude * w2 * s,
        -amplitude * w2 * w * c,
        amplitude * w2 * w2 * s,
    )


@numba.njit(cache=True)
def _cos_derivatives(s, c, w: float, amplitude: float = 1.0) -> tuple:
    """d^k/dt^k of amplitude * cos(w t + phase), k = 0..4, given s, c = sin, cos of the angle."""
    w2 = w * w
    return (
        amplitude * c,
        -amplitude * w * s,
        -amplitude * w2 * c,
        amplitude * w2 * w * s,
        amplitude * w2 * w2 * c,
    )


# Compiled (numba; IEEE arithmetic, no fastmath, so the same doubles as interpreted Python):
# the generator evaluates it at every controller sample, where interpreted it cost about 30 us.
@numba.njit(cache=True)
def _fill_reference(k: np.ndarray, t: float, out: np.ndarray) -> None:
    """The concatenation [com (15), task (24 + 3 n_j), heading (9)] at time t, written
    into ``out``.

    ``k`` holds the :class:`_Constants` in their order, then the n_j joint targets.
    """
    cx, cy, cz, A_b, w_b, climb_rate = k[0], k[1], k[2], k[3], k[4], k[5]
    A_a, w_a, a1, a2, a3, w_o = k[6], k[7], k[8], k[9], k[10], k[11]
    phi4_0, w_h, rx, ry, rz = k[12], k[13], k[14], k[15], k[16]
    nj = k.shape[0] - 17
    # Offsets of the task reference (reference.TaskReferenceLayout.of(nj)).
    P, R, Q, V = 0, 3, 12, 12 + nj
    W, QD, A, DW, QDD = 15 + nj, 18 + nj, 18 + 2 * nj, 21 + 2 * nj, 24 + 2 * nj
    sin, cos = math.sin, math.cos

    # (28) basic motion x_c = center + A_b [-sin(w_b t), -cos(w_b t), sin(w_b t) + c t].
    angle = w_b * t
    s_b, c_b = sin(angle), cos(angle)
    sb = _sin_derivatives(s_b, c_b, w_b, A_b)
    cb = _cos_derivatives(s_b, c_b, w_b, A_b)
    climb = (A_b * climb_rate * t, A_b * climb_rate, 0.0, 0.0, 0.0)
    x_c = np.empty((5, 3))
    for n in range(5):
        x_c[n, 0] = -sb[n] + (cx if n == 0 else 0.0)
        x_c[n, 1] = -cb[n] + (cy if n == 0 else 0.0)
        x_c[n, 2] = sb[n] + climb[n] + (cz if n == 0 else 0.0)

    # (32) heading phi4 = phi4_0 + w_h t; b1d = [cos phi4, sin phi4, 0].
    phi4 = phi4_0 + w_h * t
    s4, c4 = sin(phi4), cos(phi4)
    sh = _sin_derivatives(s4, c4, w_h)
    ch = _cos_derivatives(s4, c4, w_h)

    # (33) x_d = x_c + R3(phi4) r_o; the k-th derivative of R3(phi4) r_o rotates only its xy part.
    task_end = 15 + 24 + 3 * nj
    com, task, heading = out[:15], out[15:task_end], out[task_end:task_end + 9]
    for n in range(5):
        com[3 * n] = x_c[n, 0] + ch[n] * rx - sh[n] * ry
        com[3 * n + 1] = x_c[n, 1] + sh[n] * rx + ch[n] * ry
        com[3 * n + 2] = x_c[n, 2] + (rz if n == 0 else 0.0)

    # (28) agile motion A_a [sin(w_a t), cos(w_a t), cos(w_a t)], added to x_c for x_ed; its
    # value, velocity and acceleration are the task's p_ed, v_ed, a_ed.
    angle = w_a * t
    s_a, c_a = sin(angle), cos(angle)
    sa = _sin_derivatives(s_a, c_a, w_a, A_a)
    ca = _cos_derivatives(s_a, c_a, w_a, A_a)
    for n, start in enumerate((P, V, A)):
        task[start] = x_c[n, 0] + sa[n]
        task[start + 1] = x_c[n, 1] + ca[n]
        task[start + 2] = x_c[n, 2] + ca[n]

    # (31) phi1 = a1 sin(w_o t), phi2 = a2 cos(w_o t), phi3 = a3 cos(w_o t), up to 2nd derivative.
    angle = w_o * t
    so, co = sin(angle), cos(angle)
    phi1 = _sin_derivatives(so, co, w_o, a1)
    phi2 = _cos_derivatives(so, co, w_o, a2)
    phi3 = _cos_derivatives(so, co, w_o, a3)
    s1, c1 = sin(phi1[0]), cos(phi1[0])
    s2, c2 = sin(phi2[0]), cos(phi2[0])
    s3, c3 = sin(phi3[0]), cos(phi3[0])

    # (29) R_ed = R1(phi1) R2(phi2) R3(phi3), row-major.
    R_ed = (
        c2 * c3, -c2 * s3, s2,
        s1 * s2 * c3 + c1 * s3, -s1 * s2 * s3 + c1 * c3, -s1 * c2,
        -c1 * s2 * c3 + s1 * s3, c1 * s2 * s3 + s1 * c3, c1 * c2,
    )  # fmt: skip
    for i in range(9):
        task[R + i] = R_ed[i]

    # w_ed = phi1' e1 + phi2' b + phi3' c with the World axes e1, b = R1 e2, c = R1 R2 e3.
    # Differentiating, e1' = 0, b' = (phi1' e1) x b, c' = (phi1' e1 + phi2' b) x c, so
    # dw_ed = phi1'' e1 + phi2'' b + phi3'' c + phi1' phi2' (e1 x b) + phi3' (w_12 x c).
    d1, d2, d3 = phi1[1], phi2[1], phi3[1]
    dd1, dd2, dd3 = phi1[2], phi2[2], phi3[2]
    b = (0.0, c1, s1)
    c = (s2, -s1 * c2, c1 * c2)
    e1_x_b = (0.0, -s1, c1)
    w_12 = (d1, d2 * c1, d2 * s1)
    w_12_x_c = (
        w_12[1] * c[2] - w_12[2] * c[1],
        w_12[2] * c[0] - w_12[0] * c[2],
        w_12[0] * c[1] - w_12[1] * c[0],
    )
    w_ed = (d1 + d2 * b[0] + d3 * c[0], d2 * b[1] + d3 * c[1], d2 * b[2] + d3 * c[2])
    dw_ed = (
        dd1 + dd2 * b[0] + dd3 * c[0] + d1 * d2 * e1_x_b[0] + d3 * w_12_x_c[0],
        dd2 * b[1] + dd3 * c[1] + d1 * d2 * e1_x_b[1] + d3 * w_12_x_c[1],
        dd2 * b[2] + dd3 * c[2] + d1 * d2 * e1_x_b[2] + d3 * w_12_x_c[2],
    )
    for i in range(3):
        task[W + i] = w_ed[i]
        task[DW + i] = dw_ed[i]

    # (30) the joint targets constant.
    for i in range(nj):
        task[Q + i] = k[17 + i]
        task[QD + i] = 0.0
        task[QDD + i] = 0.0

    # (32) [b1d, b1d', b1d''].
    for n in range(3):
        heading[3 * n] = ch[n]
        heading[3 * n + 1] = sh[n]
        heading[3 * n + 2] = 0.0


@numba.njit(cache=True)
def _fill_reference_over_time(k: np.ndarray, times: np.ndarray, out: np.ndarray) -> None:
    """:func:`_fill_reference` at each of the N ``times``, into the rows of ``out``
    (N, 48 + 3 n_j)."""
    for i in range(times.size):
        _fill_reference(k, times[i], out[i])


def _interpreted(kernel, **callees):
    """``kernel``'s Python function with its calls to the ``callees`` (name: kernel) made to
    their Python functions: nothing of it compiles."""
    f = kernel.py_func
    names = {**f.__globals__, **{name: callee for name, callee in callees.items()}}
    return types.FunctionType(f.__code__, names, f.__name__, f.__defaults__, f.__closure__)


_FILL_PY = _interpreted(_fill_reference, _sin_derivatives=_sin_derivatives.py_func,
                        _cos_derivatives=_cos_derivatives.py_func)
_FILL_OVER_TIME_PY = _interpreted(_fill_reference_over_time, _fill_reference=_FILL_PY)
#: Set by :func:`use_interpreted_reference`.
_INTERPRETED: list[bool] = []


def use_interpreted_reference(interpreted: bool) -> None:
    """From now on in this process, evaluate (28)-(33) as interpreted Python (about 30 us per
    evaluation against 0.4 us compiled; the same doubles: IEEE arithmetic both, no fastmath,
    tests/trajectories/test_paper.py) or compiled again: for a process that must not compile
    (a cold cache's first run, :mod:`aerial_drake.simulation.kernel_cache`)."""
    _INTERPRETED[:] = [True] if interpreted else []


def _kernels() -> tuple:
    """``(fill, fill_over_time)``: the compiled kernels, or their interpreted Python."""
    if _INTERPRETED:
        return _FILL_PY, _FILL_OVER_TIME_PY
    return _fill_reference, _fill_reference_over_time


#: Every ``(kernel, signature)`` a run calls from Python (compile_reference).
_VECTOR = numba.types.Array(numba.types.float64, 1, "C")
REFERENCE_KERNELS = (
    (_fill_reference, (_VECTOR, numba.types.float64, _VECTOR)),
    (_fill_reference_over_time, (_VECTOR, _VECTOR, numba.types.Array(numba.types.float64, 2, "C"))),
)


def compile_reference() -> None:
    """Compile the reference kernels into numba's cache, or load them from it, for the
    argument types a run passes (``simulation.runner.compile_kernels``)."""
    for kernel, signature in REFERENCE_KERNELS:
        kernel.compile(signature)

