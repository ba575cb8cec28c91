"""The reference at one time (:class:`ReferenceSample`) and its packed vectors: the layout
that the generator's output ports, the controller's input ports and the logs share.

Frames and units: every vector is expressed in World (m, m/s, rad, rad/s, ...). The angular
velocity of the desired end-effector frame satisfies d/dt R_ed = hat(w_ed) R_ed, and
dw_ed = d/dt w_ed (both in World).

Packed vectors (the three output ports of
:class:`~aerial_drake.trajectories.generator.ReferenceGenerator`; use the ``pack_*`` /
``unpack_*`` helpers or :meth:`ReferenceSample.to_vectors` / :meth:`ReferenceSample.from_vectors`
rather than offsets):

- com reference, ``COM_REFERENCE_SIZE`` = 15: [x_d, x_d', x_d'', x_d''', x_d''''] (3 each).
- task reference, ``TASK_REFERENCE_SIZE`` = 27:
  [p_ed (3), R_ed row-major (9), q3d (1), v_ed (3), w_ed (3), q3d_dot (1),
  a_ed (3), dw_ed (3), q3d_ddot (1)].
  Its three blocks of 13 / 7 / 7 are y_d, y_d_dot and y_d_ddot of (27) (the SO(3) part at
  velocity level given as w_ed, dw_ed).
- heading reference, ``HEADING_REFERENCE_SIZE`` = 9: [b1d, b1d', b1d''] (3 each).
"""

import dataclasses
import typing

import numpy as np

__all__ = [
    "COM_REFERENCE_SIZE",
    "TASK_REFERENCE_SIZE",
    "HEADING_REFERENCE_SIZE",
    "ReferenceSample",
    "TaskReference",
    "pack_com_reference",
    "pack_task_reference",
    "pack_heading_reference",
    "unpack_com_reference",
    "unpack_task_reference",
    "unpack_heading_reference",
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
    q3d: typing.Union[float, np.ndarray]
    q3d_dot: typing.Union[float, np.ndarray]
    q3d_ddot: typing.Union[float, np.ndarray]
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

