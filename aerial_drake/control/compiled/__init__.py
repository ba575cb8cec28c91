"""The decomposition of Section II and the law (10)-(22), compiled with numba (double only).

The reference implementation is the numpy code of :mod:`aerial_drake.dynamics.decoupling` and
:mod:`aerial_drake.control.law`, fed by Drake's kinematics; it stays the path for AutoDiffXd
(``Linearize``) and is the oracle the tests hold this package against. This package computes the
same quantities, with the same formulas in the same order, but from its own forward kinematics
(:class:`~aerial_drake.dynamics.kinematic_tree.KinematicTree`), in compiled loops over small
fixed-size arrays: one evaluation of the law costs tens of microseconds instead of about two
milliseconds of numpy calls on 3- to 13-element arrays. See ``docs/performance.md``. (One
quantity takes another route to the same value: sigma_min(J3) of Assumption 1, from the
smallest eigenvalue of J3^T J3 as there, by :func:`.linalg._min_eigenvalue_sym`.)

An evaluation of the law allocates nothing. :class:`CompiledLaw` packs the tree, the
end-effector frame, the gains and the limits into one float and one integer array at
construction and keeps one float workspace, which the kernels see as named views (the
``_*Buffers`` tuples); so a call hands numba nine arrays to unbox (it unboxes each argument of
every call) and none to allocate or free. The law applies Lambda, Gamma and T^-1 to vectors
only, through the columns of T^-1 that the vectors' nonzero entries meet.

The modules, bottom to top: :mod:`.views` (the decorators and the views of flat storage),
:mod:`.linalg` (small dense linear algebra), :mod:`.kinematics` (the packed tree and forward
kinematics), :mod:`.kernels` (Section II, the law and the tracking errors) and :mod:`.law` (the
Python entry points, re-exported here: :class:`CompiledLaw`, :class:`CompiledTracking`,
:func:`decompose`, :func:`pack_gains`, and :func:`compile_law` with :func:`law_cache_is_cold`
for compiling before a run, :func:`aerial_drake.simulation.runner.compile_kernels`, and
:func:`use_reference_law` for a process that must not compile: a cold cache's first run,
:mod:`aerial_drake.simulation.kernel_cache`); the kernels are private.
numba compiles them on first use and caches the machine code next to their files (``cache=True``,
or under ``NUMBA_CACHE_DIR``), so only the first use after installing pays the compile time
(about 35 s to a minute on a 2-core machine; a note on stderr says so); later processes load
the machine code in under a second. The command line's first run does not wait for it: see
:mod:`aerial_drake.simulation.kernel_cache`.
That compile's memory grows with the LLVM IR numba generates, much of it from two constructs the
kernels therefore avoid: array-to-array slice assignment (see :func:`.linalg._copy`) and
numba-level inlining of the functions that build the tuples of views (see
``views._forceinline``).
"""

from aerial_drake.control.compiled.kernels import ASSUMPTION_1, ASSUMPTION_2, NONFINITE, OK
from aerial_drake.control.compiled.law import (
    CompiledLaw,
    CompiledTracking,
    compile_law,
    decompose,
    is_cached,
    law_cache_is_cold,
    pack_gains,
    reference_law_reason,
    use_reference_law,
)

__all__ = ["ASSUMPTION_1", "ASSUMPTION_2", "NONFINITE", "OK", "CompiledLaw", "CompiledTracking",
           "compile_law", "decompose", "is_cached", "law_cache_is_cold", "pack_gains",
           "reference_law_reason", "use_reference_law"]
