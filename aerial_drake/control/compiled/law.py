"""The compiled law's Python entry points: :class:`CompiledLaw`, :class:`CompiledTracking`,
:func:`decompose`, :func:`pack_gains`, and :func:`compile_law` with :func:`law_cache_is_cold`
(for compiling before a run: :func:`aerial_drake.simulation.runner.compile_kernels`)."""

from __future__ import annotations

import os
import sys

import numpy as np
from numba import types

from aerial_drake.control.compiled.fast_law import _law_fast
from aerial_drake.control.compiled.fast_rigid_body import fast_rigid_body_size
from aerial_drake.control.compiled.kernels import (
    GAIN_LAYOUT,
    LIMITS_SIZE,
    _decompose,
    _law,
    _packed_gains_size,
    _tracking,
    _workspace_size,
)
from aerial_drake.control.compiled.kinematics import _pack_tree
from aerial_drake.control.law import NO_DAMPING, SingularityRobust, diagnostics_size
from aerial_drake.dynamics.kinematic_tree import KinematicTree
from aerial_drake.robots.task import TaskLayout
from aerial_drake.trajectories.reference import (
    COM_REFERENCE_SIZE,
    HEADING_REFERENCE_SIZE,
    task_reference_size,
    unpack_heading_reference,
    unpack_task_reference,
)

# --- Python entry points ---------------------------------------------------------------------

_DECOMPOSITION_FIELDS = ("m", "R", "p_all", "R_all", "body_J", "body_J_dot", "M", "C", "g",
                         "J_g", "J_g_dot", "p_WG", "N", "N_dot", "T", "T_dot", "T_inv",
                         "Lambda", "Gamma", "xi")


def decompose(tree: KinematicTree, q: np.ndarray, v: np.ndarray) -> dict[str, np.ndarray]:
    """The compiled decomposition at ``(q, v)`` by field name (as in
    :class:`aerial_drake.dynamics.decoupling.Decomposition`; ``p_all``/``R_all``/``body_J``/
    ``body_J_dot`` are per body of ``tree``). For tests and benchmarks."""
    model, index = _pack_tree(tree)
    size = _workspace_size(tree.parent.size, tree.reflected_inertia.size, False)
    values = _decompose(np.ascontiguousarray(q, dtype=float),
                        np.ascontiguousarray(v, dtype=float), model, index, tree.gravity_W,
                        np.zeros(size))
    return dict(zip(_DECOMPOSITION_FIELDS, values))


def pack_gains(K, gravity: float) -> np.ndarray:
    """The gains of a :class:`aerial_drake.control.law.GainMatrices` and gravity in the order
    ``_law`` reads them (:data:`~aerial_drake.control.compiled.kernels.GAIN_LAYOUT`)."""
    parts = [np.ravel(np.asarray(gravity if name == "gravity" else getattr(K, name), float))
             for name, _ in GAIN_LAYOUT]
    n = len(K.K_y)
    for (name, size), part in zip(GAIN_LAYOUT, parts):
        if part.size != (n if size < 0 else size):
            raise ValueError(f"gain {name} has {part.size} entries for a task of {n} rows")
    return np.concatenate(parts)


def law_cache_is_cold(kernels: tuple[str, ...] = ()) -> bool:
    """Whether numba's cache lacks a kernel :func:`compile_law` compiles (the first use after
    installing, or after a change to the kernels' source): :func:`is_cached` of each; with
    ``kernels``, also those law kernels (:data:`LAW_KERNEL_NAMES`, e.g. ``("fast",)``)."""
    return not all(is_cached(kernel, signature)
                   for kernel, signature in _law_kernels(kernels))


def is_cached(kernel, signature: tuple) -> bool:
    """Whether the numba dispatcher ``kernel`` would load ``signature``'s machine code from
    numba's cache rather than compile it: compiled in this process already, or its cache's
    index (valid for the source file as it is now) names a data file that exists for this
    machine's key (numba writes the index before the data, each by a rename: a compile
    stopped between the two leaves an entry without data, which numba compiles again)."""
    if tuple(signature) in kernel.overloads:
        return True
    try:
        # numba's internals (untyped, numba.core.caching): guarded by the except below.
        cache = kernel._cache  # type: ignore[attr-defined]
        key = cache._index_key(tuple(signature), kernel.targetctx.codegen())
        cache_file = cache._cache_file
        name = cache_file._load_index().get(key)
        return name is not None and os.path.exists(os.path.join(cache_file._cache_path, name))
    except (AttributeError, TypeError):  # numba internals moved: say cached (no note)
        return True


def _note_if_cold(kernels: tuple[str, ...] = ()) -> None:
    """Say on stderr that the law is about to compile, if numba's cache is cold."""
    if law_cache_is_cold(kernels):
        print("aerial_drake: compiling the control law with numba (first use after "
              "installing; about a minute, cached afterwards) ...", file=sys.stderr,
              flush=True)


# The law's one signature: every argument a C-contiguous 1-D array, float but the index.
_F64 = types.Array(types.float64, 1, "C")
_LAW_SIGNATURE = (_F64,) * 7 + (types.Array(types.int64, 1, "C"), _F64)
# The tracking errors': the states, references and output as C-contiguous 2-D float arrays.
_F64_2D = types.Array(types.float64, 2, "C")
_TRACKING_SIGNATURE = (_F64_2D,) * 5 + (_F64, types.Array(types.int64, 1, "C"), _F64)
#: Every ``(kernel, signature)`` a run calls from Python, in the order compile_law compiles
#: them (the law first: it is most of the time).
LAW_KERNELS = ((_law, _LAW_SIGNATURE), (_tracking, _TRACKING_SIGNATURE),
               (_workspace_size, (types.int64, types.int64, types.boolean)))
#: The law's kernels by the name of the scenario's ``controller.kernel``: ``exact`` (the
#: default, the paper runs') and ``fast`` (:mod:`.fast_law`: the same law to round-off,
#: compiled only where chosen: the first controller built on it compiles it).
LAW_KERNEL_NAMES = {"exact": _law, "fast": _law_fast}


def _law_kernels(kernels: tuple[str, ...]) -> tuple:
    """:data:`LAW_KERNELS` and the law kernels named in ``kernels`` beyond them."""
    extra = tuple((LAW_KERNEL_NAMES[name], _LAW_SIGNATURE) for name in kernels
                  if LAW_KERNEL_NAMES[name] is not _law)
    return LAW_KERNELS + extra


def compile_law(kernels: tuple[str, ...] = ()) -> None:
    """Compile the law (and the workspace's size) into numba's cache, or load them from it,
    without a model: their argument types are the same for every tree
    (``simulation.runner.compile_kernels``; a test holds these signatures to what a run calls);
    with ``kernels``, also those law kernels (:data:`LAW_KERNEL_NAMES`)."""
    _note_if_cold(kernels)
    for kernel, signature in _law_kernels(kernels):
        kernel.compile(signature)


#: Set by :func:`use_reference_law`: controllers built afterwards in this process run the
#: reference implementation (``control.controller``), and the tracking errors too.
_REFERENCE_LAW: list[str] = []


def use_reference_law(reason: str | None) -> None:
    """From now on in this process, build controllers on the reference implementation (numpy
    and Drake; the compiled law's results to round-off, not to the bit) and say ``reason``
    (e.g. that numba's cache is cold); ``None``: the compiled law again."""
    _REFERENCE_LAW.clear()
    if reason is not None:
        _REFERENCE_LAW.append(reason)


def reference_law_reason() -> str | None:
    """Why this process runs the reference implementation (:func:`use_reference_law`), or
    None: the compiled law where it serves."""
    return _REFERENCE_LAW[0] if _REFERENCE_LAW else None


def _pack_law(tree: KinematicTree, num_positions: int,
              end_effector: tuple[int, np.ndarray, np.ndarray], task: TaskLayout,
              gains: np.ndarray, limits: tuple[float, ...]) -> tuple[np.ndarray, np.ndarray]:
    """The float and integer arrays the law's kernels unpack (``kernels._unpack_law``): the
    tree, then the end-effector frame, the gains and the ``LIMITS_SIZE`` limits (in
    ``kernels.LIMITS_SIZE``'s order); the task's layout."""
    if len(limits) != LIMITS_SIZE:
        raise ValueError(f"{len(limits)} limits for the law's {LIMITS_SIZE}")
    body, R_BE, p_BE = end_effector
    nv = tree.reflected_inertia.size
    if task.n != nv - 6:
        raise ValueError(f"a task of {task.n} rows for {nv - 6} arm velocities")
    floats, ints = _pack_tree(tree)
    model = np.concatenate([floats, np.ravel(R_BE), np.ravel(p_BE), gains, limits]
                           ).astype(float)
    index = np.concatenate([ints, [num_positions, body, task.n_joints], task.rows,
                            task.joint_positions, task.joint_velocities]).astype(np.int64)
    return model, index


class CompiledLaw:
    """The law (10)-(22) on ``tree``, compiled: ``law(x, com, task, heading, command,
    diagnostics)`` fills the two output arrays and returns ``(status, f_d_norm, sigma_min)``
    (status :data:`OK`, :data:`ASSUMPTION_1`, :data:`ASSUMPTION_2` or :data:`NONFINITE`).

    The law works in a buffer of this object's: one call at a time per CompiledLaw (each
    controller has its own).

    Args:
        tree: the controller model's tree (:meth:`KinematicTree.from_plant`).
        num_positions: size of q in the state ``x = [q; v]``.
        end_effector: ``(index of the body in tree, R_BE, p_BE)`` of the task frame E.
        task: the task's rows and its joints' indices (:class:`TaskLayout`).
        gains: packed by :func:`pack_gains`.
        sigma_min_J3_limit, f_d_limit: the Assumption 1 and 2 thresholds.
        singularity: the damped inverse near the singularity of J_3 (damping 0: off, the
            paper's law; with it on, no Assumption 1 status: the caller checks that control
            is kept, :meth:`SingularityRobust.check_control_kept`).
        kernel: ``"exact"`` (the paper runs' arithmetic, bit for bit) or ``"fast"`` (the same
            law to round-off, faster: :mod:`.fast_law`); see :data:`LAW_KERNEL_NAMES`.
    """

    def __init__(self, tree: KinematicTree, num_positions: int,
                 end_effector: tuple[int, np.ndarray, np.ndarray], task: TaskLayout,
                 gains: np.ndarray, sigma_min_J3_limit: float,
                 f_d_limit: float, singularity: SingularityRobust = NO_DAMPING,
                 kernel: str = "exact"):
        if kernel not in LAW_KERNEL_NAMES:
            raise ValueError(f"kernel '{kernel}' is not one of {tuple(LAW_KERNEL_NAMES)}")
        self.kernel = kernel
        self._kernel = LAW_KERNEL_NAMES[kernel]
        nb, nv = tree.parent.size, tree.reflected_inertia.size
        gains = np.ravel(gains).astype(float)
        # The kernel's own count run as Python (py_func): nothing compiles outside compile_law.
        if gains.size != _packed_gains_size.py_func(nv - 6):
            raise ValueError(f"{gains.size} gains for {nv} velocities: see pack_gains")
        self._model, self._index = _pack_law(tree, num_positions, end_effector, task, gains,
                                             (sigma_min_J3_limit, f_d_limit,
                                              singularity.damping, singularity.threshold))
        self._n_joints = task.n_joints
        # The fast kernel's recursions work after the exact law's buffers.
        extra = fast_rigid_body_size(nb, nv) if kernel == "fast" else 0
        self._work = np.zeros(_workspace_size(nb, nv, True) + extra)
        self._nq, self._nv = int(num_positions), nv
        self._compile()

    def _compile(self) -> None:
        """Compile (or load from numba's cache) now, at construction, rather than in the
        middle of the first simulation step: one evaluation at rest, outputs discarded."""
        if self._kernel.signatures:
            return
        _note_if_cold((self.kernel,))
        x = np.zeros(self._nq + self._nv)
        x[0] = 1.0  # unit quaternion, all else zero
        com, task = np.zeros(COM_REFERENCE_SIZE), np.zeros(task_reference_size(self._n_joints))
        heading = np.zeros(HEADING_REFERENCE_SIZE)
        unpack_task_reference(task).R_ed[:] = np.eye(3)  # views into the vectors
        unpack_heading_reference(heading)[0, 0] = 1.0  # b1d = e_x
        self(x, com, task, heading, np.empty(4 + self._nv - 6),
             np.empty(diagnostics_size(self._nv - 6)))

    def __call__(self, x: np.ndarray, com: np.ndarray, task: np.ndarray, heading: np.ndarray,
                 command: np.ndarray, diagnostics: np.ndarray) -> tuple[int, float, float]:
        return self._kernel(x, com, task, heading, command, diagnostics, self._model,
                            self._index, self._work)


class CompiledTracking:
    """The tracking errors of :mod:`aerial_drake.simulation.tracking`, compiled:
    ``tracking(X, com, task, heading)`` gives one row per row of the states ``X`` (the law's
    ``x``) and of the references. The same kernels as :class:`CompiledLaw`'s in the same
    order, so each entry equals the law's diagnostic of the same name to the bit.

    Args: as :class:`CompiledLaw`'s first four.
    """

    def __init__(self, tree: KinematicTree, num_positions: int,
                 end_effector: tuple[int, np.ndarray, np.ndarray], task: TaskLayout):
        nb, nv = tree.parent.size, tree.reflected_inertia.size
        self.n = nv - 6
        # The law's packing; the kernel reads no gain or limit, so zeros stand for them.
        self._model, self._index = _pack_law(tree, num_positions, end_effector, task,
                                             np.zeros(17 + 2 * self.n),
                                             (0.0,) * LIMITS_SIZE)
        self._work = np.zeros(_workspace_size(nb, nv, True))

    def __call__(self, X: np.ndarray, com: np.ndarray, task: np.ndarray, heading: np.ndarray,
                 width: int) -> np.ndarray:
        """(N, ``width``) rows of the tracking errors (``width`` of the layout)."""
        out = np.empty((len(X), width))
        X, com, task, heading = (np.ascontiguousarray(a, dtype=float)
                                 for a in (X, com, task, heading))
        _tracking(X, com, task, heading, out, self._model, self._index, self._work)
        return out
