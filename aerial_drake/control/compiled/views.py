"""The kernels' numba decorators and their views of flat storage.

The kernels of this package see the packed inputs (tree, gains, limits) and their one float
workspace as named views into flat arrays (:func:`_vec`, :func:`_mat`, :func:`_mats`), built by
:func:`_view`: no slices, no reference counting, nothing allocated. Every kernel module of the
package takes its decorator from here (``_jit``, ``_inline``, ``_forceinline``), so the compiled
law keeps one set of compile options.
"""

from __future__ import annotations

from numba import njit, types
from numba.core import cgutils
from numba.core.imputils import impl_ret_untracked
from numba.extending import intrinsic
from numba.np.arrayobj import make_array, populate_array

# error_model="numpy": a division by zero gives inf/nan as in the numpy path (and the checks
# of Assumptions 1 and 2 report it) instead of raising ZeroDivisionError mid-law.
_jit = njit(cache=True, nogil=True, error_model="numpy")
# For the few-line kernels called in inner loops: a call passes each array as its whole
# descriptor, which costs more than these kernels' own work; numba inlines them instead.
_inline = njit(cache=True, nogil=True, error_model="numpy", inline="always")
# For the functions that build the tuples of views: inline="always" would copy their tuple
# handling into the caller's IR, where numba writes out each reference count of each view
# field by field (most of the law kernel's IR, and of the compile's peak memory). Compiled once
# and inlined by LLVM instead, they still leave it the views' null meminfos to fold away.
_forceinline = njit(cache=True, nogil=True, error_model="numpy", forceinline=True)


# --- flat storage: packed inputs and the workspace, as views ---------------------------------

@intrinsic
def _view(typingctx, buf, at, shape):
    """``buf[at:at + prod(shape)]`` of a flat C-contiguous ``buf`` as a C-contiguous array of
    ``shape`` (a tuple of integers), unchecked and not reference-counted.

    A slice or ``reshape`` would cost tens of nanoseconds for each of the hundred or so views
    of a call, and more for each view taken of them in a loop: numba's ``reshape`` checks the
    shape through a C helper, and each view holds a reference to ``buf``'s memory, taken and
    released by atomic operations in a function call. This view and the views taken of it
    carry no reference (as numba's ``carray`` of a pointer), so they are valid while ``buf``
    is, which the kernels' callers guarantee (they keep the packed arrays and the workspace
    for the call); they must not outlive the call. The caller also checks that the views fit
    (see :func:`_law`)."""
    if not (isinstance(buf, types.Array) and buf.ndim == 1 and buf.layout == "C"
            and isinstance(at, types.Integer) and isinstance(shape, types.BaseTuple)
            and all(isinstance(d, types.Integer) for d in shape)):
        return None

    def codegen(context, builder, sig, args):
        src = make_array(sig.args[0])(context, builder, args[0])
        dims = [context.cast(builder, d, t, types.intp)
                for d, t in zip(cgutils.unpack_tuple(builder, args[2]), sig.args[2])]
        strides, stride = [], src.itemsize
        for d in reversed(dims):  # C order: the last index contiguous
            strides.insert(0, stride)
            stride = builder.mul(stride, d)
        start = context.cast(builder, args[1], sig.args[1], types.intp)
        view = make_array(sig.return_type)(context, builder)
        populate_array(view, data=builder.gep(src.data, [start]), shape=dims, strides=strides,
                       itemsize=src.itemsize, meminfo=None)
        return impl_ret_untracked(context, builder, sig.return_type, view._getvalue())

    return types.Array(buf.dtype, len(shape), "C")(buf, at, shape), codegen


@_inline
def _vec(buf, at, size):
    """The ``size`` entries of the flat ``buf`` from offset ``at`` (a :func:`_view`), and the
    offset after them. (Inlined: compiled apart, these three took a compile per signature, some
    thirty.)"""
    return _view(buf, at, (size,)), at + size


@_inline
def _mat(buf, at, rows, cols):
    """As :func:`_vec`, a rows x cols matrix."""
    return _view(buf, at, (rows, cols)), at + rows * cols


@_inline
def _mats(buf, at, count, rows, cols):
    """As :func:`_vec`, ``count`` rows x cols matrices."""
    return _view(buf, at, (count, rows, cols)), at + count * rows * cols
