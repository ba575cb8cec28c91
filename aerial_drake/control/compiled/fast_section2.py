"""Section II's transformation (3)-(4) for the fast law (:mod:`.fast_law`): the exact kernel's
quantities T, T_dot and T^-1, by formulas that exploit their structure (so equal to the exact
kernel's to round-off, not to the bit); and the fast law's small solvers (J_3's LU, the
smallest eigenvalue of J_3^T J_3 by Laguerre's iteration).

The exact kernel (:func:`.kernels._transformation`) follows the numpy reference: it factors
Z M Z^T twice (for N and for N_dot) and inverts T (nv x nv) by Gaussian elimination, the
largest single cost of Section II. Here:

- Z M Z^T is symmetric positive definite (M is, Z has full row rank): one Cholesky
  factorisation serves N (4) and N_dot.
- d/dt (Z M Z^T) = Z_dot M Z^T + Z M_dot Z^T + Z M Z_dot^T, and the last term is the first's
  transpose (M is symmetric): one product fewer.
- T^-1 in closed form from T's blocks (docs/control.md, "The fast kernel"). Z's rows span
  the null space of K = [J_g; J_bw] and N Z^T = E_n, so T^-1 = [X, Z^T] with
  X = (E - Z^T N) X0 for any X0 with K X0 = E_6. With J_g = [G_w, E_3, A] (the columns of
  w_WB, v_WBo and the arm; docs/control.md, "Coordinates") and J_bw = [R^T, 0, 0],
  X0 = [[0, R], [E_3, -G_w R], [0, 0]], so with Y = N X0 = [N_v, (N_w - N_v G_w) R]
  (N_w, N_v: N's first two 3-column blocks),
  T^-1 = [[0, R, 0], [E_3 + A Y_1, -G_w R + A Y_2, -A], [-Y_1, -Y_2, E_n]].
"""

from __future__ import annotations

import math

from aerial_drake.control.compiled.kernels import _base_rows_into, _times_zt_into, _z_times_into
from aerial_drake.control.compiled.linalg import _copy, _has_eigenvalue_below, _tridiagonalize
from aerial_drake.control.compiled.views import _jit


@_jit
def _cholesky_into(A, L):
    """The lower-triangular L with L L^T = A (A symmetric positive definite; its lower
    triangle is read); L's upper triangle is not written."""
    n = A.shape[0]
    for j in range(n):
        d = A[j, j]
        for k in range(j):
            d -= L[j, k] * L[j, k]
        d = math.sqrt(d)
        L[j, j] = d
        for i in range(j + 1, n):
            t = A[i, j]
            for k in range(j):
                t -= L[i, k] * L[j, k]
            L[i, j] = t / d


@_jit
def _cholesky_solve(L, B):
    """B <- (L L^T)^-1 B, column by column of B at once (rows of B in the inner loop)."""
    n, m = B.shape
    for i in range(n):
        for k in range(i):
            f = L[i, k]
            for j in range(m):
                B[i, j] -= f * B[k, j]
        d = L[i, i]
        for j in range(m):
            B[i, j] /= d
    for i in range(n - 1, -1, -1):
        for k in range(i + 1, n):
            f = L[k, i]
            for j in range(m):
                B[i, j] -= f * B[k, j]
        d = L[i, i]
        for j in range(m):
            B[i, j] /= d


@_jit
def _structured_inverse(R, J_g, N, Y, T_inv):
    """T^-1 from T's blocks (module docstring); ``Y``: (n, 6) or wider scratch."""
    nv = T_inv.shape[0]
    n = nv - 6
    # Y_1 = N_v, Y_2 = (N_w - N_v G_w) R.
    for i in range(n):
        a0 = N[i, 0] - (N[i, 3] * J_g[0, 0] + N[i, 4] * J_g[1, 0] + N[i, 5] * J_g[2, 0])
        a1 = N[i, 1] - (N[i, 3] * J_g[0, 1] + N[i, 4] * J_g[1, 1] + N[i, 5] * J_g[2, 1])
        a2 = N[i, 2] - (N[i, 3] * J_g[0, 2] + N[i, 4] * J_g[1, 2] + N[i, 5] * J_g[2, 2])
        for c in range(3):
            Y[i, c] = N[i, 3 + c]
            Y[i, 3 + c] = a0 * R[0, c] + a1 * R[1, c] + a2 * R[2, c]
    for i in range(3):
        for j in range(nv):
            T_inv[i, j] = 0.0
        for c in range(3):
            T_inv[i, 3 + c] = R[i, c]
    for i in range(3):
        for c in range(6):  # [E_3, -G_w R] + A Y
            t = 0.0
            if c < 3:
                t = 1.0 if c == i else 0.0
            else:
                t = -(J_g[i, 0] * R[0, c - 3] + J_g[i, 1] * R[1, c - 3]
                      + J_g[i, 2] * R[2, c - 3])
            for k in range(n):
                t += J_g[i, 6 + k] * Y[k, c]
            T_inv[3 + i, c] = t
        for k in range(n):
            T_inv[3 + i, 6 + k] = -J_g[i, 6 + k]
    for i in range(n):
        for c in range(6):
            T_inv[6 + i, c] = -Y[i, c]
        for k in range(n):
            T_inv[6 + i, 6 + k] = 1.0 if k == i else 0.0


@_jit
def _fast_transformation(v, R, s):
    """T of (3) with N of (4) as its last rows, its derivative (N_dot last), and T^-1, into
    ``s.T``, ``s.T_dot``, ``s.T_inv`` (Section II's buffers, as the exact
    :func:`.kernels._transformation`); leaves Z M Z^T = Lambda_33 in ``s.ZZ[0]``."""
    T, T_dot, J_g, J_g_dot = s.T, s.T_dot, s.J_g, s.J_g_dot
    _copy(J_g, T[:3])
    _copy(J_g_dot, T_dot[:3])
    # J_bw = [R^T, 0, 0], J_bw_dot = [-hat(R^T w) R^T, 0, 0] (w = v[:3] in World).
    _base_rows_into(v, R, T[3:6], T_dot[3:6])
    nv = T.shape[0]

    ZM, ZdM, ZMd = s.Z[0], s.Z[1], s.Z[2]
    ZMZ, L, a, b = s.ZZ[0], s.ZZ[1], s.ZZ[2], s.ZZ[3]
    N, N_dot = T[6:], T_dot[6:]
    _z_times_into(J_g, s.M, True, ZM)
    _times_zt_into(ZM, J_g, True, ZMZ)
    _cholesky_into(ZMZ, L)
    _copy(ZM, N)
    _cholesky_solve(L, N)  # (4)
    _z_times_into(J_g_dot, s.M, False, ZdM)
    M_dot, C = s.M_dot, s.C
    for i in range(nv):
        for j in range(nv):
            M_dot[i, j] = C[i, j] + C[j, i]
    _z_times_into(J_g, M_dot, True, ZMd)
    _times_zt_into(ZdM, J_g, True, a)  # Z_dot M Z^T; Z M Z_dot^T is its transpose
    _times_zt_into(ZMd, J_g, True, b)  # Z M_dot Z^T
    n = N.shape[0]
    for i in range(n):
        for j in range(nv):
            N_dot[i, j] = ZdM[i, j] + ZMd[i, j]
        for k in range(n):
            f = (a[i, k] + b[i, k]) + a[k, i]
            for j in range(nv):
                N_dot[i, j] -= f * N[k, j]
    _cholesky_solve(L, N_dot)
    _structured_inverse(R, J_g, N, ZdM, s.T_inv)


# --- J_3's LU factorisation, for the fast law's solves with J_3 -----------------------------

@_jit
def _lu_factor(A, piv):
    """P A = L U in place (L unit lower, below the diagonal; U on and above it) by Gaussian
    elimination with partial pivoting; ``piv[k]``: the row swapped with row k at step k (as
    a float: the workspace is one float array)."""
    n = A.shape[0]
    for k in range(n):
        p = k
        big = abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > big:
                big, p = abs(A[i, k]), i
        piv[k] = p
        if p != k:
            for j in range(n):
                A[k, j], A[p, j] = A[p, j], A[k, j]
        d = A[k, k]
        for i in range(k + 1, n):
            A[i, k] /= d
        for i in range(k + 1, n):
            f = A[i, k]
            if f != 0.0:
                for j in range(k + 1, n):
                    A[i, j] -= f * A[k, j]


@_jit
def _lu_solve(LU, piv, b, out):
    """out = A^-1 b from :func:`_lu_factor`'s ``LU``, ``piv`` of A."""
    n = b.shape[0]
    for i in range(n):
        out[i] = b[i]
    for k in range(n):
        p = int(piv[k])
        if p != k:
            out[k], out[p] = out[p], out[k]
    for i in range(n):
        t = out[i]
        for k in range(i):
            t -= LU[i, k] * out[k]
        out[i] = t
    for i in range(n - 1, -1, -1):
        t = out[i]
        for k in range(i + 1, n):
            t -= LU[i, k] * out[k]
        out[i] = t / LU[i, i]


# --- sigma_min(J_3) for the fast law ------------------------------------------------------------

@_jit
def _laguerre_step(d, e, x):
    """Laguerre's step at x for c(x) = det(T - x E) of the tridiagonal T (diagonal d,
    off-diagonal e), from the three-term recurrence of its leading minors and their first two
    derivatives. From below the smallest eigenvalue it moves up to it, cubically: a handful
    of steps where Newton's (linalg._min_eigenvalue_sym) takes ten on J_3^T J_3's clustered
    smallest eigenvalues."""
    n = d.shape[0]
    c0, c1 = 1.0, d[0] - x
    g0, g1 = 0.0, -1.0  # c'
    h0, h1 = 0.0, 0.0  # c''
    for k in range(1, n):
        b2 = e[k - 1] * e[k - 1]
        c2 = (d[k] - x) * c1 - b2 * c0
        g2 = (d[k] - x) * g1 - c1 - b2 * g0
        h2 = (d[k] - x) * h1 - 2.0 * g1 - b2 * h0
        c0, c1, g0, g1, h0, h1 = c1, c2, g1, g2, h1, h2
    if c1 == 0.0:
        return 0.0
    G = g1 / c1
    H = G * G - h1 / c1
    root = math.sqrt(max((n - 1) * (n * H - G * G), 0.0))
    den = G - root if G < 0.0 else G + root
    return -n / den if den != 0.0 else 0.0


@_jit
def _min_eigenvalue_laguerre(S, work):
    """As :func:`.linalg._min_eigenvalue_sym` (S overwritten, nan if not finite; ``work``: four
    vectors of S's size), Laguerre's iteration in place of Newton's (the same root, to
    rounding)."""
    n = S.shape[0]
    for i in range(n):
        for j in range(n):
            if not math.isfinite(S[i, j]):
                return math.nan
    d, e = work[0], work[1]
    if n == 1:
        return S[0, 0]
    _tridiagonalize(S, d, e, work[2], work[3])
    x = 0.0
    if _has_eigenvalue_below(d, e, 0.0):
        x = min(d[0] - abs(e[0]), d[n - 1] - abs(e[n - 2]))
        for k in range(1, n - 1):
            x = min(x, d[k] - abs(e[k - 1]) - abs(e[k]))
    for _ in range(100):
        x_next = x + _laguerre_step(d, e, x)
        if not x_next > x:
            break
        x = x_next
    return x
