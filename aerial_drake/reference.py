"""The paper's reference trajectory (Section IV-A, eqs (27)-(33)): pure math and a Drake system.

The end-effector task (27) is y_d = [x_ed; R_ed; q3d], with

    x_ed(t) = center + A_b basic(t) + A_a agile(t)                                   (28)
        basic(t) = [-sin(w_b t), -cos(w_b t), sin(w_b t) + c t]
        agile(t) = [ sin(w_a t),  cos(w_a t), cos(w_a t)]
    R_ed(t)  = R1(phi1) R2(phi2) R3(phi3)   (R1 = RotX, R2 = RotY, R3 = RotZ)        (29)
    q3d(t)   = q3_desired                                                           (30)
        phi1 = a1 sin(w_o t),  phi2 = a2 cos(w_o t),  phi3 = a3 cos(w_o t)          (31)
    b1d(t)   = [cos phi4, sin phi4, 0],  phi4 = phi4_0 + w_h t                      (32)
    x_d(t)   = x_c(t) + R3(phi4) r_o,  x_c(t) = center + A_b basic(t)               (33)

x_c is the "basic" motion realised by the whole system, A_a agile(t) the part left to the arm.
Every constant is a field of :class:`TrajectoryParams` (defaults: the paper's values). All
derivatives are analytic (closed form); the tests hold each one against a central difference.

Frames and units: every vector is expressed in World (m, m/s, rad, rad/s, ...). The angular
velocity of the desired end-effector frame satisfies d/dt R_ed = hat(w_ed) R_ed, and
dw_ed = d/dt w_ed (both in World).

Packed vectors (the three output ports of :class:`ReferenceGenerator`; use the ``pack_*`` /
``unpack_*`` helpers or :meth:`ReferenceSample.to_vectors` / :meth:`ReferenceSample.from_vectors`
rather than offsets):

- com reference, ``COM_REFERENCE_SIZE`` = 15: [x_d, x_d', x_d'', x_d''', x_d''''] (3 each).
- task reference, ``TASK_REFERENCE_SIZE`` = 27:
  [p_ed (3), R_ed row-major (9), q3d (1), v_ed (3), w_ed (3), q3d_dot (1),
  a_ed (3), dw_ed (3), q3d_ddot (1)].
  Its three blocks of 13 / 7 / 7 are y_d, y_d_dot and y_d_ddot of (27) (the SO(3) part at
  velocity level given as w_ed, dw_ed).
- heading reference, ``HEADING_REFERENCE_SIZE`` = 9: [b1d, b1d', b1d''] (3 each).

Do not add ``from __future__ import annotations`` here: Drake's ``yaml_load_typed`` needs the
real (non-string) field types of :class:`TrajectoryParams`.
"""

import copy
import dataclasses
import math
import typing

import numba
import numpy as np
from pydrake.systems.framework import BasicVector, Context, Diagram, DiagramBuilder, LeafSystem
from pydrake.systems.primitives import Demultiplexer

__all__ = [
    "COM_REFERENCE_SIZE",
    "TASK_REFERENCE_SIZE",
    "HEADING_REFERENCE_SIZE",
    "TrajectoryParams",
    "ReferenceSample",
    "TaskReference",
    "evaluate_reference",
    "sample_reference",
    "pack_com_reference",
    "pack_task_reference",
    "pack_heading_reference",
    "unpack_com_reference",
    "unpack_task_reference",
    "unpack_heading_reference",
    "ReferenceGenerator",
]

COM_REFERENCE_SIZE = 15
TASK_REFERENCE_SIZE = 27
HEADING_REFERENCE_SIZE = 9
_TOTAL_SIZE = COM_REFERENCE_SIZE + TASK_REFERENCE_SIZE + HEADING_REFERENCE_SIZE

# Offsets inside the task reference vector (use unpack_task_reference instead of these).
_TASK_P = slice(0, 3)
_TASK_R = slice(3, 12)
_TASK_Q3 = 12
_TASK_V = slice(13, 16)
_TASK_W = slice(16, 19)
_TASK_Q3_DOT = 19
_TASK_A = slice(20, 23)
_TASK_DW = slice(23, 26)
_TASK_Q3_DDOT = 26

# Where each packed vector sits in the concatenation [com, task, heading].
_COM = slice(0, COM_REFERENCE_SIZE)
_TASK = slice(COM_REFERENCE_SIZE, COM_REFERENCE_SIZE + TASK_REFERENCE_SIZE)
_HEADING = slice(COM_REFERENCE_SIZE + TASK_REFERENCE_SIZE, _TOTAL_SIZE)


@dataclasses.dataclass
class TrajectoryParams:
    """Constants of the reference trajectory (28)-(33); defaults are the paper's values.

    Loadable by ``pydrake.common.yaml.yaml_load_typed`` (a misspelt key is an error).
    Call :meth:`validate` before use (:class:`ReferenceGenerator` and the pure functions do).
    """

    # Centre of the basic motion, World [x, y, z] (m).
    center: typing.List[float] = dataclasses.field(default_factory=lambda: [0.6, 0.0, 1.3])
    # Amplitude A_b of the basic motion (m).
    basic_amplitude: float = 0.5
    # Angular frequency w_b of the basic motion (rad/s).
    basic_frequency: float = 0.5
    # Climb rate c of the basic motion's z term, scaled by A_b (1/s): z gains A_b c t.
    basic_climb_rate: float = 0.045
    # Amplitude A_a of the agile motion (m).
    agile_amplitude: float = 0.1
    # Angular frequency w_a of the agile motion (rad/s).
    agile_frequency: float = 3.0
    # Amplitudes [a1, a2, a3] of the orientation angles phi1, phi2, phi3 of (31) (rad).
    orientation_amplitudes: typing.List[float] = dataclasses.field(
        default_factory=lambda: [0.5, 0.5, 0.5]
    )
    # Angular frequency w_o of the orientation angles (rad/s).
    orientation_frequency: float = 3.0
    # Desired angle of the arm's third joint, q3d (rad).
    q3_desired: float = 0.0
    # Initial helicopter heading phi4_0 (rad).
    heading_initial: float = 0.0
    # Heading rate w_h, phi4 = phi4_0 + w_h t (rad/s); either sign.
    heading_rate: float = 0.5
    # Offset r_o from x_c to the desired CoM, rotated by R3(phi4), [x, y, z] (m).
    com_offset: typing.List[float] = dataclasses.field(default_factory=lambda: [-0.3, 0.0, 0.6])

    def validate(self) -> None:
        """Raises ValueError naming every bad field and how to fix it."""
        errors = []
        for name, meaning in (
            ("center", "[x, y, z] in m"),
            ("orientation_amplitudes", "[a1, a2, a3] in rad"),
            ("com_offset", "[x, y, z] in m"),
        ):
            value = getattr(self, name)
            try:
                length = len(value)
            except TypeError:
                length = None
            if length != 3:
                errors.append(
                    f"'{name}' must be a list of 3 floats {meaning}, got {value!r}: "
                    "give exactly three entries"
                )
                continue
            if not all(_is_finite_number(x) for x in value):
                errors.append(f"'{name}' must hold finite numbers, got {value!r}")
            elif name == "orientation_amplitudes" and any(x < 0 for x in value):
                errors.append(
                    f"'{name}' must be >= 0, got {value!r}: flip the sign through the "
                    "angle's phase instead (an amplitude is a magnitude)"
                )
        for name in (
            "basic_amplitude",
            "basic_frequency",
            "basic_climb_rate",
            "agile_amplitude",
            "agile_frequency",
            "orientation_frequency",
            "q3_desired",
            "heading_initial",
            "heading_rate",
        ):
            value = getattr(self, name)
            if not _is_finite_number(value):
                errors.append(f"'{name}' must be a finite float, got {value!r}")
            elif name.endswith(("_amplitude", "_frequency")) and value < 0:
                errors.append(f"'{name}' must be >= 0, got {value!r}: use its magnitude")
        if errors:
            raise ValueError("Invalid TrajectoryParams: " + "; ".join(errors) + ".")


def _is_finite_number(x) -> bool:
    return isinstance(x, (int, float, np.floating, np.integer)) and math.isfinite(x)


@dataclasses.dataclass(frozen=True)
class ReferenceSample:
    """The reference at one time t (all in World).

    From :func:`sample_reference` every field gets an extra leading axis over time (the
    scalar fields become arrays of shape (N,)).
    """

    # x_d and its 1st..4th time derivatives, row k = k-th derivative (5, 3) (m, m/s, ...).
    com: np.ndarray
    # End-effector position, velocity, acceleration x_ed, x_ed', x_ed'' (3) (m, m/s, m/s^2).
    p_ed: np.ndarray
    v_ed: np.ndarray
    a_ed: np.ndarray
    # Desired end-effector orientation (3, 3); d/dt R_ed = hat(w_ed) R_ed.
    R_ed: np.ndarray
    # Angular velocity and acceleration of R_ed (3) (rad/s, rad/s^2).
    w_ed: np.ndarray
    dw_ed: np.ndarray
    # Desired third joint angle and its derivatives (rad, rad/s, rad/s^2).
    q3d: float
    q3d_dot: float
    q3d_ddot: float
    # Heading direction b1d and its 1st and 2nd derivatives, rows (3, 3).
    b1d: np.ndarray

    def to_vectors(self) -> typing.Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The packed (com, task, heading) reference vectors (see the module docstring)."""
        return pack_com_reference(self), pack_task_reference(self), pack_heading_reference(self)

    @classmethod
    def from_vectors(
        cls, com: np.ndarray, task: np.ndarray, heading: np.ndarray
    ) -> "ReferenceSample":
        """Inverse of :meth:`to_vectors` (also for arrays with a leading time axis)."""
        t = unpack_task_reference(task)
        return cls(
            com=unpack_com_reference(com),
            p_ed=t.p_ed,
            v_ed=t.v_ed,
            a_ed=t.a_ed,
            R_ed=t.R_ed,
            w_ed=t.w_ed,
            dw_ed=t.dw_ed,
            q3d=t.q3d,
            q3d_dot=t.q3d_dot,
            q3d_ddot=t.q3d_ddot,
            b1d=unpack_heading_reference(heading),
        )


class TaskReference(typing.NamedTuple):
    """The task reference vector's pieces (views into it): y_d, y_d_dot, y_d_ddot of (27)."""

    p_ed: np.ndarray
    R_ed: np.ndarray
    q3d: typing.Union[float, np.ndarray]
    v_ed: np.ndarray
    w_ed: np.ndarray
    q3d_dot: typing.Union[float, np.ndarray]
    a_ed: np.ndarray
    dw_ed: np.ndarray
    q3d_ddot: typing.Union[float, np.ndarray]


def pack_com_reference(sample: ReferenceSample) -> np.ndarray:
    """[x_d, x_d', x_d'', x_d''', x_d''''] (15,), or (N, 15) for a time-sampled sample."""
    com = np.asarray(sample.com)
    return com.reshape(com.shape[:-2] + (COM_REFERENCE_SIZE,)).copy()


def pack_task_reference(sample: ReferenceSample) -> np.ndarray:
    """[p_ed, R_ed (row-major), q3d, v_ed, w_ed, q3d_dot, a_ed, dw_ed, q3d_ddot] (27,)."""
    p_ed = np.asarray(sample.p_ed)
    lead = p_ed.shape[:-1]
    out = np.empty(lead + (TASK_REFERENCE_SIZE,))
    out[..., _TASK_P] = p_ed
    out[..., _TASK_R] = np.asarray(sample.R_ed).reshape(lead + (9,))
    out[..., _TASK_Q3] = sample.q3d
    out[..., _TASK_V] = sample.v_ed
    out[..., _TASK_W] = sample.w_ed
    out[..., _TASK_Q3_DOT] = sample.q3d_dot
    out[..., _TASK_A] = sample.a_ed
    out[..., _TASK_DW] = sample.dw_ed
    out[..., _TASK_Q3_DDOT] = sample.q3d_ddot
    return out


def pack_heading_reference(sample: ReferenceSample) -> np.ndarray:
    """[b1d, b1d', b1d''] (9,), or (N, 9) for a time-sampled sample."""
    b1d = np.asarray(sample.b1d)
    return b1d.reshape(b1d.shape[:-2] + (HEADING_REFERENCE_SIZE,)).copy()


def unpack_com_reference(vector: np.ndarray) -> np.ndarray:
    """The com reference vector as rows [x_d, x_d', ..., x_d''''] (5, 3) (a view)."""
    vector = np.asarray(vector)
    _check_size(vector, COM_REFERENCE_SIZE, "com reference")
    return vector.reshape(vector.shape[:-1] + (5, 3))


def unpack_task_reference(vector: np.ndarray) -> TaskReference:
    """The task reference vector's pieces (views into it; scalars as floats for a 1-D vector)."""
    vector = np.asarray(vector)
    _check_size(vector, TASK_REFERENCE_SIZE, "task reference")
    scalar = float if vector.ndim == 1 else (lambda x: x)
    return TaskReference(
        p_ed=vector[..., _TASK_P],
        R_ed=vector[..., _TASK_R].reshape(vector.shape[:-1] + (3, 3)),
        q3d=scalar(vector[..., _TASK_Q3]),
        v_ed=vector[..., _TASK_V],
        w_ed=vector[..., _TASK_W],
        q3d_dot=scalar(vector[..., _TASK_Q3_DOT]),
        a_ed=vector[..., _TASK_A],
        dw_ed=vector[..., _TASK_DW],
        q3d_ddot=scalar(vector[..., _TASK_Q3_DDOT]),
    )


def unpack_heading_reference(vector: np.ndarray) -> np.ndarray:
    """The heading reference vector as rows [b1d, b1d', b1d''] (3, 3) (a view)."""
    vector = np.asarray(vector)
    _check_size(vector, HEADING_REFERENCE_SIZE, "heading reference")
    return vector.reshape(vector.shape[:-1] + (3, 3))


def _check_size(vector: np.ndarray, size: int, what: str) -> None:
    if vector.ndim == 0 or vector.shape[-1] != size:
        raise ValueError(
            f"A {what} vector has {size} entries (last axis), got shape {vector.shape}"
        )


def evaluate_reference(params: TrajectoryParams, t: float) -> ReferenceSample:
    """The reference and its analytic derivatives at time t (s)."""
    params.validate()
    packed = np.empty(_TOTAL_SIZE)
    _fill_reference(_Constants.from_params(params).as_array(), float(t), packed)
    return ReferenceSample.from_vectors(packed[_COM], packed[_TASK], packed[_HEADING])


def sample_reference(params: TrajectoryParams, times: np.ndarray) -> ReferenceSample:
    """:func:`evaluate_reference` over a 1-D array of N times, vectorised.

    Every field of the result has a leading time axis of length N (e.g. com is (N, 5, 3),
    R_ed is (N, 3, 3), q3d is (N,)).
    """
    params.validate()
    times = np.asarray(times, dtype=float)
    if times.ndim != 1:
        raise ValueError(f"times must be a 1-D array, got shape {times.shape}")
    packed = np.empty((times.size, _TOTAL_SIZE))
    _fill_reference_over_time(_Constants.from_params(params).as_array(), times, packed)
    return ReferenceSample.from_vectors(packed[:, _COM], packed[:, _TASK], packed[:, _HEADING])


class _Constants(typing.NamedTuple):
    """The parameters as plain floats, in the order the formulas use them."""

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
    q3: float
    phi4_0: float
    w_h: float
    rx: float
    ry: float
    rz: float

    @classmethod
    def from_params(cls, p: TrajectoryParams) -> "_Constants":
        return cls(
            *map(float, p.center),
            float(p.basic_amplitude),
            float(p.basic_frequency),
            float(p.basic_climb_rate),
            float(p.agile_amplitude),
            float(p.agile_frequency),
            *map(float, p.orientation_amplitudes),
            float(p.orientation_frequency),
            float(p.q3_desired),
            float(p.heading_initial),
            float(p.heading_rate),
            *map(float, p.com_offset),
        )

    def as_array(self) -> np.ndarray:
        """The constants as a float array, in field order (what the compiled code reads)."""
        return np.array(self, dtype=float)


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
    """The concatenation [com (15), task (27), heading (9)] at time t, written into ``out``.

    ``k`` holds the :class:`_Constants` in their order (a float array).
    """
    cx, cy, cz, A_b, w_b, climb_rate = k[0], k[1], k[2], k[3], k[4], k[5]
    A_a, w_a, a1, a2, a3, w_o = k[6], k[7], k[8], k[9], k[10], k[11]
    q3, phi4_0, w_h, rx, ry, rz = k[12], k[13], k[14], k[15], k[16], k[17]
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
    com, task, heading = out[_COM], out[_TASK], out[_HEADING]
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
    for n, start in enumerate((_TASK_P.start, _TASK_V.start, _TASK_A.start)):
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
        task[_TASK_R.start + i] = R_ed[i]

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
        task[_TASK_W.start + i] = w_ed[i]
        task[_TASK_DW.start + i] = dw_ed[i]

    # (30) q3d constant.
    task[_TASK_Q3] = q3
    task[_TASK_Q3_DOT] = 0.0
    task[_TASK_Q3_DDOT] = 0.0

    # (32) [b1d, b1d', b1d''].
    for n in range(3):
        heading[3 * n] = ch[n]
        heading[3 * n + 1] = sh[n]
        heading[3 * n + 2] = 0.0


@numba.njit(cache=True)
def _fill_reference_over_time(k: np.ndarray, times: np.ndarray, out: np.ndarray) -> None:
    """:func:`_fill_reference` at each of the N ``times``, into the rows of ``out`` (N, 51)."""
    for i in range(times.size):
        _fill_reference(k, times[i], out[i])


def compile_reference() -> None:
    """Compile the reference kernels into numba's cache, or load them from it, for the
    argument types a run passes (``runner.compile_kernels``)."""
    vector = numba.types.Array(numba.types.float64, 1, "C")
    _fill_reference.compile((vector, numba.types.float64, vector))
    _fill_reference_over_time.compile(
        (vector, vector, numba.types.Array(numba.types.float64, 2, "C")))


class _PackedReference(LeafSystem):
    """The concatenation [com, task, heading] (51) at the context time: one output, so one
    Python call per time; :class:`ReferenceGenerator` splits it in C++."""

    def __init__(self, constants: np.ndarray):
        super().__init__()
        self._constants = constants
        self.DeclareVectorOutputPort("references", _TOTAL_SIZE, self._calc,
                                     prerequisites_of_calc={self.time_ticket()})

    def _calc(self, context: Context, output: BasicVector) -> None:
        _fill_reference(self._constants, context.get_time(), output.get_mutable_value())


class ReferenceGenerator(Diagram):
    """The reference trajectory (28)-(33) as a Drake source: no state, no inputs.

    Output ports (functions of the context's time only; layouts in the module docstring):
    ``com_reference`` (15), ``task_reference`` (27), ``heading_reference`` (9).

    A small Diagram: the three are computed together, once per time, by one compiled call in
    a LeafSystem with a single output, and Drake's Demultiplexer splits them. The controller
    reads all three at every sample: one Python call instead of one per port (and a cache
    entry) saves about three quarters of the generator's cost in the closed loop.

    Double only (no AutoDiffXd / Expression conversion): its outputs depend on time alone, so
    linearise a diagram about a hover point with a ConstantVectorSource in its place.
    """

    def __init__(self, params: TrajectoryParams):
        super().__init__()
        params.validate()
        self._params = copy.deepcopy(params)
        builder = DiagramBuilder()
        packed = builder.AddSystem(_PackedReference(_Constants.from_params(params).as_array()))
        packed.set_name("packed_reference")
        split = builder.AddSystem(
            Demultiplexer([COM_REFERENCE_SIZE, TASK_REFERENCE_SIZE, HEADING_REFERENCE_SIZE]))
        split.set_name("split_reference")
        builder.Connect(packed.get_output_port(), split.get_input_port())
        names = ("com_reference", "task_reference", "heading_reference")
        for i, name in enumerate(names):
            builder.ExportOutput(split.get_output_port(i), name)
        builder.BuildInto(self)
        self._com_port, self._task_port, self._heading_port = map(self.GetOutputPort, names)

    def params(self) -> TrajectoryParams:
        """A copy of the parameters this system was built with."""
        return copy.deepcopy(self._params)

    def get_com_reference_output_port(self):
        return self._com_port

    def get_task_reference_output_port(self):
        return self._task_port

    def get_heading_reference_output_port(self):
        return self._heading_port
