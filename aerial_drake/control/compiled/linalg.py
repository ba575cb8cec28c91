"""Small dense linear algebra for the compiled kernels: explicit loops over 3- to 13-element
arrays (no BLAS/LAPACK, hence no SciPy), products into given outputs, a linear solve, an
inverse, and the smallest eigenvalue of a symmetric matrix (for sigma_min(J3) of Assumption 1).
"""

from __future__ import annotations

import math

from aerial_drake.control.compiled.views import _inline, _jit

# --- small dense linear algebra (explicit loops: no BLAS/LAPACK, hence no SciPy) -------------

@_jit
def _mm_into(A, B, out):
    """out = A B (zero entries of A skipped)."""
    n, k, m = A.shape[0], A.shape[1], B.shape[1]
    for i in range(n):
        for j in range(m):
            out[i, j] = 0.0
        for p in range(k):
            a = A[i, p]
            if a != 0.0:
                for j in range(m):
                    out[i, j] += a * B[p, j]


@_jit
def _mtm_into(A, B, out):
    """out = A^T B."""
    _mm_into(A.T, B, out)


@_jit
def _mv_into(A, x, out, first=0):
    """out = A[:, first:first + len(x)] x, four rows at a time: four independent sums in
    flight instead of one (the same sums, in the same order)."""
    n, k = A.shape[0], x.shape[0]
    i = 0
    while i + 4 <= n:
        s0, s1, s2, s3 = 0.0, 0.0, 0.0, 0.0
        for p in range(k):
            s0 += A[i, first + p] * x[p]
            s1 += A[i + 1, first + p] * x[p]
            s2 += A[i + 2, first + p] * x[p]
            s3 += A[i + 3, first + p] * x[p]
        out[i], out[i + 1], out[i + 2], out[i + 3] = s0, s1, s2, s3
        i += 4
    for r in range(i, n):
        s0 = 0.0
        for p in range(k):
            s0 += A[r, first + p] * x[p]
        out[r] = s0


@_jit
def _mtv_into(A, x, out, first=0):
    """out = A[:len(x), first:first + len(out)]^T x."""
    k, n = x.shape[0], out.shape[0]
    for i in range(n):
        out[i] = 0.0
    for p in range(k):
        a = x[p]
        for i in range(n):
            out[i] += A[p, first + i] * a


@_jit
def _dot(a, b):
    s = 0.0
    for i in range(a.shape[0]):
        s += a[i] * b[i]
    return s


@_jit
def _norm(a):
    return math.sqrt(_dot(a, a))


@_inline
def _cross_at(a, b, i):
    """Entry i of a x b."""
    j, k = (i + 1) % 3, (i + 2) % 3
    return a[j] * b[k] - a[k] * b[j]


@_jit
def _cross_into(a, b, out):
    for i in range(3):
        out[i] = _cross_at(a, b, i)


@_jit
def _hat_into(a, out):
    out[0, 0], out[1, 1], out[2, 2] = 0.0, 0.0, 0.0
    out[0, 1], out[0, 2] = -a[2], a[1]
    out[1, 0], out[1, 2] = a[2], -a[0]
    out[2, 0], out[2, 1] = -a[1], a[0]


@_jit
def _vee_into(S, out):
    """vee of the skew-symmetric part, as decoupling.vee."""
    out[0] = 0.5 * (S[2, 1] - S[1, 2])
    out[1] = 0.5 * (S[0, 2] - S[2, 0])
    out[2] = 0.5 * (S[1, 0] - S[0, 1])


@_inline
def _zero(A):
    """A = 0 for a matrix (a loop the compiler unrolls or vectorizes, where numba's A[:, :] = 0
    calls memset row by row)."""
    for i in range(A.shape[0]):
        for j in range(A.shape[1]):
            A[i, j] = 0.0


@_inline
def _copy(A, out):
    """out = A for matrices: a loop, where numba's ``out[:, :] = A`` (which checks the two for
    overlap and broadcasts) generates some fifteen times its LLVM IR."""
    for i in range(A.shape[0]):
        for j in range(A.shape[1]):
            out[i, j] = A[i, j]


@_inline
def _copy_vec(a, out):
    """out = a for vectors (see _copy)."""
    for i in range(a.shape[0]):
        out[i] = a[i]


@_jit
def _set_identity(A):
    for i in range(A.shape[0]):
        for j in range(A.shape[1]):
            A[i, j] = 1.0 if i == j else 0.0


@_jit
def _solve_into(A, B):
    """B <- A^-1 B by Gaussian elimination with partial pivoting, overwriting A: the operations
    of an LU factorisation and of its two triangular solves, in their order (the rows of B
    follow the pivoting as they go, so no permutation is kept)."""
    n, m = B.shape
    for k in range(n):
        p = k
        big = abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > big:
                big, p = abs(A[i, k]), i
        if p != k:
            for j in range(k, n):
                A[k, j], A[p, j] = A[p, j], A[k, j]
            for j in range(m):
                B[k, j], B[p, j] = B[p, j], B[k, j]
        d = A[k, k]
        for i in range(k + 1, n):  # the multipliers first: their divisions overlap
            A[i, k] /= d
        for i in range(k + 1, n):
            f = A[i, k]
            if f != 0.0:
                for j in range(k + 1, n):
                    A[i, j] -= f * A[k, j]
                for j in range(m):
                    B[i, j] -= f * B[k, j]
    for i in range(n - 1, -1, -1):
        for k in range(i + 1, n):
            f = A[i, k]
            if f != 0.0:
                for j in range(m):
                    B[i, j] -= f * B[k, j]
        d = A[i, i]
        for j in range(m):
            B[i, j] /= d


@_jit
def _inv_into(A, work, out):
    """out = A^-1 (``work``: scratch of A's shape)."""
    _copy(A, work)
    _set_identity(out)
    _solve_into(work, out)


@_jit
def _tridiagonalize(A, d, e, u, p):
    """Householder reduction of the symmetric A (overwritten; its lower triangle is read) to the
    tridiagonal matrix of the same eigenvalues with diagonal ``d`` and off-diagonal ``e``.
    ``u``, ``p``: vectors of A's size, scratch."""
    n = A.shape[0]
    for k in range(n - 2):
        sq = 0.0
        for i in range(k + 1, n):
            sq += A[i, k] * A[i, k]
        d[k] = A[k, k]
        if sq == 0.0:
            e[k] = 0.0
            continue
        x0 = A[k + 1, k]
        alpha = -math.sqrt(sq) if x0 >= 0.0 else math.sqrt(sq)  # no cancellation in x0 - alpha
        e[k] = alpha
        # H = E - beta u u^T, u = x - alpha e_1, maps x = A[k+1:, k] to alpha e_1; the trailing
        # block B = A[k+1:, k+1:] becomes H B H = B - u q^T - q u^T with p = beta B u and
        # q = p - (beta / 2) (u . p) u.
        u[k + 1] = x0 - alpha
        for i in range(k + 2, n):
            u[i] = A[i, k]
        beta = 1.0 / (sq - alpha * x0)  # 2 / (u . u)
        up = 0.0
        for i in range(k + 1, n):
            t = 0.0
            for j in range(k + 1, i + 1):
                t += A[i, j] * u[j]
            for j in range(i + 1, n):
                t += A[j, i] * u[j]
            p[i] = beta * t
            up += u[i] * p[i]
        h = 0.5 * beta * up
        for i in range(k + 1, n):
            p[i] -= h * u[i]
        for i in range(k + 1, n):
            for j in range(k + 1, i + 1):
                A[i, j] -= u[i] * p[j] + p[i] * u[j]
    d[n - 2], d[n - 1] = A[n - 2, n - 2], A[n - 1, n - 1]
    e[n - 2] = A[n - 1, n - 2]


@_jit
def _newton_step(d, e, x):
    """-c(x) / c'(x) for c(x) = det(T - x E) of the tridiagonal T (diagonal d, off-diagonal e),
    by the three-term recurrence of its leading minors."""
    c0, c1 = 1.0, d[0] - x
    g0, g1 = 0.0, -1.0  # their derivatives
    for k in range(1, d.shape[0]):
        b2 = e[k - 1] * e[k - 1]
        c0, c1 = c1, (d[k] - x) * c1 - b2 * c0
        g0, g1 = g1, (d[k] - x) * g1 - c0 - b2 * g0
    return -c1 / g1


@_jit
def _has_eigenvalue_below(d, e, x):
    """Whether the tridiagonal T has an eigenvalue below x (Sylvester: a negative pivot of the
    LDL^T factorisation of T - x E; a zero pivot counts as an eigenvalue at x)."""
    pivot = d[0] - x
    for k in range(1, d.shape[0]):
        if not pivot > 0.0:
            return True
        pivot = (d[k] - x) - e[k - 1] * e[k - 1] / pivot
    return not pivot > 0.0


@_jit
def _min_eigenvalue_sym(S, work):
    """Smallest eigenvalue of a symmetric matrix (overwritten), nan if S is not finite.

    Householder reduction to a tridiagonal matrix, then Newton's method on its characteristic
    polynomial from below the smallest eigenvalue: for a polynomial whose roots are all real,
    the iterates then increase monotonically to the smallest root, quadratically once it is
    simple. Each iteration is a short recurrence, so this costs a fraction of a Jacobi
    solver's sweeps of rotations (square roots and divisions in sequence), with the same
    accuracy: a few units of rounding times the norm of S. ``work``: four vectors of S's size.
    """
    n = S.shape[0]
    for i in range(n):
        for j in range(n):
            if not math.isfinite(S[i, j]):
                return math.nan
    d, e = work[0], work[1]
    _tridiagonalize(S, d, e, work[2], work[3])
    # Start at 0 for a positive semi-definite S (as J3^T J3), else at Gershgorin's bound.
    x = 0.0
    if n > 1 and _has_eigenvalue_below(d, e, 0.0):
        x = min(d[0] - abs(e[0]), d[n - 1] - abs(e[n - 2]))
        for k in range(1, n - 1):
            x = min(x, d[k] - abs(e[k - 1]) - abs(e[k]))
    for _ in range(100):  # (a few iterations; the bound only guards against a double root)
        x_next = x + _newton_step(d, e, x)
        if not x_next > x:  # converged, to rounding (or at the root)
            break
        x = x_next
    return x
