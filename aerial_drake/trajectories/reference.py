"""The reference at one time (:class:`ReferenceSample`) and its packed vectors: the layout
that the generator's output ports, the controller's input ports and the logs share.

Frames and units: every vector is expressed in World (m, m/s, rad, rad/s, ...). The angular
velocity of the desired end-effector frame satisfies d/dt R_ed = hat(w_ed) R_ed, and
dw_ed = d/dt w_ed (both in World).

The task reference always holds the whole desired end-effector pose and the desired angles of
the task's joint components (``n_j`` of them: 1 for the paper's q3, 0 for a pose-only task);
the controller picks the rows its task uses (:mod:`aerial_drake.robots.task`).

Packed vectors (the three output ports of
:class:`~aerial_drake.trajectories.generator.ReferenceGenerator`; use the ``pack_*`` /
``unpack_*`` helpers or :meth:`ReferenceSample.to_vectors` / :meth:`ReferenceSample.from_vectors`
rather than offsets):

- com reference, ``COM_REFERENCE_SIZE`` = 15: [x_d and its 1st..4th derivatives] (3 each).
- task reference, :func:`task_reference_size` ``(n_j)`` = 24 + 3 n_j (27 for the paper):
  [p_ed (3), R_ed row-major (9), q_jd (n_j), v_ed (3), w_ed (3), q_jd_dot (n_j),
  a_ed (3), dw_ed (3), q_jd_ddot (n_j)]. Its three blocks are y_d, y_d_dot and y_d_ddot of
  (27) for the full task [p_E; orientation; q_j] (the SO(3) part at velocity level given as
  w_ed, dw_ed).
- heading reference, ``HEADING_REFERENCE_SIZE`` = 9: [b1d, b1d', b1d''] (3 each).
"""

import dataclasses
import typing

import numpy as np

__all__ = [
    "COM_REFERENCE_SIZE",
    "HEADING_REFERENCE_SIZE",
    "ReferenceSample",
    "TaskReference",
    "TaskReferenceLayout",
    "task_reference_size",
    "task_joint_count",
    "packed_reference_size",
    "pack_com_reference",
    "pack_task_reference",
    "pack_heading_reference",
    "unpack_com_reference",
    "unpack_task_reference",
    "unpack_heading_reference",
]

COM_REFERENCE_SIZE = 15
HEADING_REFERENCE_SIZE = 9
#: Task reference entries that do not depend on the joint components (pose and its rates).
_POSE_ENTRIES = 24


def task_reference_size(n_joints: int) -> int:
    """Size of the task reference vector for a task with ``n_joints`` joint components."""
    return _POSE_ENTRIES + 3 * int(n_joints)


def task_joint_count(size: int) -> int:
    """The number of joint components of a task reference vector of ``size`` entries."""
    n_joints, rest = divmod(int(size) - _POSE_ENTRIES, 3)
    if n_joints < 0 or rest:
        raise ValueError(f"A task reference vector has 24 + 3 n_j entries (n_j the task's "
                         f"joint components), got {size}")
    return n_joints


def packed_reference_size(n_joints: int) -> int:
    """Size of the concatenation [com, task, heading] (the generator's packed vector)."""
    return COM_REFERENCE_SIZE + task_reference_size(n_joints) + HEADING_REFERENCE_SIZE


def packed_slices(n_joints: int) -> tuple[slice, slice, slice]:
    """Where com, task and heading sit in the packed concatenation [com, task, heading]."""
    task_end = COM_REFERENCE_SIZE + task_reference_size(n_joints)
    return (slice(0, COM_REFERENCE_SIZE), slice(COM_REFERENCE_SIZE, task_end),
            slice(task_end, task_end + HEADING_REFERENCE_SIZE))


class TaskReferenceLayout(typing.NamedTuple):
    """Offsets inside a task reference vector with ``n_joints`` joint components (use
    :func:`unpack_task_reference` rather than these where you can)."""

    p: slice
    R: slice
    q: slice
    v: slice
    w: slice
    q_dot: slice
    a: slice
    dw: slice
    q_ddot: slice
    #: y_d_dot and y_d_ddot of the full task, [v_ed; w_ed; q_jd_dot] and [a_ed; dw_ed; ...].
    full_dot: slice
    full_ddot: slice

    @classmethod
    def of(cls, n_joints: int) -> "TaskReferenceLayout":
        j = int(n_joints)
        return cls(p=slice(0, 3), R=slice(3, 12), q=slice(12, 12 + j),
                   v=slice(12 + j, 15 + j), w=slice(15 + j, 18 + j),
                   q_dot=slice(18 + j, 18 + 2 * j), a=slice(18 + 2 * j, 21 + 2 * j),
                   dw=slice(21 + 2 * j, 24 + 2 * j), q_ddot=slice(24 + 2 * j, 24 + 3 * j),
                   full_dot=slice(12 + j, 18 + 2 * j), full_ddot=slice(18 + 2 * j, 24 + 3 * j))


@dataclasses.dataclass(frozen=True)
class ReferenceSample:
    """The reference at one time t (all in World).

    From :func:`sample_reference` every field gets an extra leading axis over time.
    """

    # x_d and its 1st..4th time derivatives, row k = k-th derivative (5, 3) (m, m/s, ...).
    com: np.ndarray
    # End-effector position, velocity, acceleration (3) (m, m/s, m/s^2).
    p_ed: np.ndarray
    v_ed: np.ndarray
    a_ed: np.ndarray
    # Desired end-effector orientation (3, 3); d/dt R_ed = hat(w_ed) R_ed.
    R_ed: np.ndarray
    # Angular velocity and acceleration of R_ed (3) (rad/s, rad/s^2).
    w_ed: np.ndarray
    dw_ed: np.ndarray
    # Desired angles of the task's joint components and their derivatives (n_j) (rad,
    # rad/s, rad/s^2): [q3d] for the paper, empty for a pose-only task.
    q_jd: np.ndarray
    q_jd_dot: np.ndarray
    q_jd_ddot: np.ndarray
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
            q_jd=t.q_jd,
            q_jd_dot=t.q_jd_dot,
            q_jd_ddot=t.q_jd_ddot,
            b1d=unpack_heading_reference(heading),
        )


class TaskReference(typing.NamedTuple):
    """The task reference vector's pieces (views into it): y_d, y_d_dot, y_d_ddot of (27)."""

    p_ed: np.ndarray
    R_ed: np.ndarray
    q_jd: np.ndarray
    v_ed: np.ndarray
    w_ed: np.ndarray
    q_jd_dot: np.ndarray
    a_ed: np.ndarray
    dw_ed: np.ndarray
    q_jd_ddot: np.ndarray
    #: y_d_dot = [v_ed; w_ed; q_jd_dot] and y_d_ddot = [a_ed; dw_ed; q_jd_ddot], full task.
    full_dot: np.ndarray
    full_ddot: np.ndarray


def pack_com_reference(sample: ReferenceSample) -> np.ndarray:
    """[x_d and its 1st..4th derivatives] (15,), or (N, 15) for a time-sampled sample."""
    com = np.asarray(sample.com)
    return com.reshape(com.shape[:-2] + (COM_REFERENCE_SIZE,)).copy()


def pack_task_reference(sample: ReferenceSample) -> np.ndarray:
    """[p_ed, R_ed (row-major), q_jd, v_ed, w_ed, q_jd_dot, a_ed, dw_ed, q_jd_ddot]."""
    p_ed = np.asarray(sample.p_ed)
    lead = p_ed.shape[:-1]
    q_jd = np.asarray(sample.q_jd, dtype=float)
    n_joints = q_jd.shape[-1] if q_jd.ndim > len(lead) else 0
    at = TaskReferenceLayout.of(n_joints)
    out = np.empty(lead + (task_reference_size(n_joints),))
    out[..., at.p] = p_ed
    out[..., at.R] = np.asarray(sample.R_ed).reshape(lead + (9,))
    out[..., at.q] = q_jd.reshape(lead + (n_joints,))
    out[..., at.v] = sample.v_ed
    out[..., at.w] = sample.w_ed
    out[..., at.q_dot] = np.asarray(sample.q_jd_dot, float).reshape(lead + (n_joints,))
    out[..., at.a] = sample.a_ed
    out[..., at.dw] = sample.dw_ed
    out[..., at.q_ddot] = np.asarray(sample.q_jd_ddot, float).reshape(lead + (n_joints,))
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
    """The task reference vector's pieces (views into it); the number of joint components
    follows from its size (:func:`task_joint_count`)."""
    vector = np.asarray(vector)
    if vector.ndim == 0:
        raise ValueError(f"A task reference vector has 24 + 3 n_j entries (last axis), got "
                         f"shape {vector.shape}")
    at = TaskReferenceLayout.of(task_joint_count(vector.shape[-1]))
    return TaskReference(
        p_ed=vector[..., at.p],
        R_ed=vector[..., at.R].reshape(vector.shape[:-1] + (3, 3)),
        q_jd=vector[..., at.q],
        v_ed=vector[..., at.v],
        w_ed=vector[..., at.w],
        q_jd_dot=vector[..., at.q_dot],
        a_ed=vector[..., at.a],
        dw_ed=vector[..., at.dw],
        q_jd_ddot=vector[..., at.q_ddot],
        full_dot=vector[..., at.full_dot],
        full_ddot=vector[..., at.full_ddot],
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
