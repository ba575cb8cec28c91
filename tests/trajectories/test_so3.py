"""Tests of aerial_drake.trajectories.so3 against independent computations: power series of the
matrix exponential and of the right Jacobian (in floats and in 60-digit decimals), Drake's
RotationMatrix(AngleAxis), and finite differences of R(t) = exp(hat(r(t))) along random cubics."""

import math
from decimal import Decimal, localcontext

import numpy as np
import pytest
from pydrake.common.eigen_geometry import AngleAxis
from pydrake.math import RotationMatrix

from aerial_drake.trajectories import so3
from aerial_drake.trajectories.so3 import (
    exp_so3,
    hat,
    log_so3,
    right_jacobian,
    right_jacobian_dot,
    right_jacobian_inverse,
    rotation_vector_acceleration,
    rotation_vector_rates,
    rotation_vector_velocity,
    vee,
)

EPS = np.finfo(float).eps

# Angles |r| at and around every branch threshold of the module (1e-3, 1, 1.5, 2), very small
# and very near pi; each in a random direction.
ANGLES = [0.0, 1e-12, 1e-9, 1e-6, 1e-5, 1e-4, 9.99e-4, 1e-3, 1.001e-3, 0.01, 0.3, 0.5, 0.999,
          1.0, 1.001, 1.499, 1.5, 1.501, 1.999, 2.0, 2.001, 2.5, 3.0, math.pi - 1e-5,
          math.pi - 2e-6]


def unit(rng: np.random.Generator) -> np.ndarray:
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def vectors_of_norms(norms, seed: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    return [t * unit(rng) for t in norms]


# --- 60-digit references: plain power series, no closed form, no threshold -----------------

PREC = 60


def d_vec(v) -> list[Decimal]:
    return [Decimal(float(x)) for x in v]


def d_hat(v: list[Decimal]) -> list[list[Decimal]]:
    x, y, z = v
    zero = Decimal(0)
    return [[zero, -z, y], [z, zero, -x], [-y, x, zero]]


def d_mul(A, B):
    return [[sum(A[i][k] * B[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def d_identity():
    return [[Decimal(int(i == j)) for j in range(3)] for i in range(3)]


def d_power_series(K, coefficient) -> list[list[Decimal]]:
    """sum_{k >= 1} coefficient(k) K^k, until the terms are below 1e-70."""
    total = [[Decimal(0)] * 3 for _ in range(3)]
    power = d_identity()
    k = 1
    while True:
        power = d_mul(power, K)
        term = [[coefficient(k) * x for x in row] for row in power]
        total = [[a + b for a, b in zip(ra, rb)] for ra, rb in zip(total, term)]
        if k > 5 and max(abs(x) for row in term for x in row) < Decimal(10) ** -70:
            return total
        k += 1


def d_exp_minus_identity(r: list[Decimal]):
    """exp(hat(r)) - I = sum_{k >= 1} hat(r)^k / k!."""
    return d_power_series(d_hat(r), lambda k: Decimal(1) / math.factorial(k))


def d_jr_minus_identity(r: list[Decimal]):
    """J_r(r) - I = sum_{k >= 1} (-hat(r))^k / (k + 1)!  (J_r = int_0^1 exp(-s hat(r)) ds)."""
    return d_power_series(d_hat(r), lambda k: Decimal((-1) ** k) / math.factorial(k + 1))


def d_add_identity(A):
    return [[x + (1 if i == j else 0) for j, x in enumerate(row)] for i, row in enumerate(A)]


def d_inverse(A):
    """Adjugate over determinant (3x3)."""
    cof = [[A[(i + 1) % 3][(j + 1) % 3] * A[(i + 2) % 3][(j + 2) % 3]
            - A[(i + 1) % 3][(j + 2) % 3] * A[(i + 2) % 3][(j + 1) % 3] for j in range(3)]
           for i in range(3)]
    det = sum(A[0][j] * cof[0][j] for j in range(3))
    return [[cof[j][i] / det for j in range(3)] for i in range(3)]


def d_vee_of_product_transpose(A, B):
    """vee(A^T B) for 3x3 decimals."""
    P = [[sum(A[k][i] * B[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    half = Decimal("0.5")
    return [half * (P[2][1] - P[1][2]), half * (P[0][2] - P[2][0]), half * (P[1][0] - P[0][1])]


def to_float(A) -> np.ndarray:
    return np.array([[float(x) for x in row] for row in A]) if isinstance(A[0], list) \
        else np.array([float(x) for x in A])


def ref_exp_minus_identity(r) -> np.ndarray:
    with localcontext() as ctx:
        ctx.prec = PREC
        return to_float(d_exp_minus_identity(d_vec(r)))


def ref_jr_minus_identity(r) -> np.ndarray:
    with localcontext() as ctx:
        ctx.prec = PREC
        return to_float(d_jr_minus_identity(d_vec(r)))


def ref_jr_inverse_minus_identity(r) -> np.ndarray:
    with localcontext() as ctx:
        ctx.prec = PREC
        inverse = d_inverse(d_add_identity(d_jr_minus_identity(d_vec(r))))
        return to_float([[x - (1 if i == j else 0) for j, x in enumerate(row)]
                         for i, row in enumerate(inverse)])


def ref_jr_dot(r, r_dot) -> np.ndarray:
    """Central difference of the series J_r along r + s r_dot: with h = 1e-25 at 60 digits the
    truncation is ~1e-50 and the rounding ~1e-35."""
    with localcontext() as ctx:
        ctx.prec = PREC
        h = Decimal("1e-25")
        r0, v = d_vec(r), d_vec(r_dot)
        plus = d_jr_minus_identity([a + h * b for a, b in zip(r0, v)])
        minus = d_jr_minus_identity([a - h * b for a, b in zip(r0, v)])
        return to_float([[(p - m) / (2 * h) for p, m in zip(rp, rm)]
                         for rp, rm in zip(plus, minus)])


def ref_rates(r, r_dot, r_ddot) -> tuple[np.ndarray, np.ndarray]:
    """(omega, domega) from exp's series along r(s) = r + s r_dot + s^2/2 r_ddot, by central
    differences at 60 digits: omega = vee(R^T dR/ds) with h = 1e-20 (error ~1e-40), domega its
    difference with h = 1e-12 (truncation ~1e-24, rounding of omega ~1e-28)."""
    with localcontext() as ctx:
        ctx.prec = PREC
        r0, v, a = d_vec(r), d_vec(r_dot), d_vec(r_ddot)

        def rotation(s: Decimal):
            point = [x + s * y + s * s / 2 * z for x, y, z in zip(r0, v, a)]
            return d_add_identity(d_exp_minus_identity(point))

        def omega(s: Decimal) -> list[Decimal]:
            h = Decimal("1e-20")
            R, plus, minus = rotation(s), rotation(s + h), rotation(s - h)
            dR = [[(p - m) / (2 * h) for p, m in zip(rp, rm)] for rp, rm in zip(plus, minus)]
            return d_vee_of_product_transpose(R, dR)

        h2 = Decimal("1e-12")
        w0, wp, wm = omega(Decimal(0)), omega(h2), omega(-h2)
        return to_float(w0), to_float([(p - m) / (2 * h2) for p, m in zip(wp, wm)])


def relative_error(value: np.ndarray, reference: np.ndarray, scale: float | None = None) -> float:
    scale = float(np.linalg.norm(reference)) if scale is None else scale
    error = float(np.linalg.norm(value - reference))
    return error / scale if scale > 0.0 else error


def assert_near_identity_matches(value: np.ndarray, reference_minus_identity: np.ndarray):
    """``value`` (a matrix I + X) against I + reference: each entry to 4 eps absolute (the most
    a float near 1 can hold) plus 1e-14 relative; and its skew part, which carries the first
    order in |r|, to 1e-14 relative plus 4 eps of the off-diagonal entries it is the difference
    of (those are ~|r| for small r, so tiny |r| is held to 1e-14 relative too)."""
    error = np.abs(value - np.eye(3) - reference_minus_identity)
    assert np.all(error <= 4 * EPS + 1e-14 * np.abs(reference_minus_identity)), error
    off_diagonal = float(np.max(np.abs(reference_minus_identity - np.diag(
        np.diag(reference_minus_identity)))))
    skew = vee(reference_minus_identity)
    skew_error = float(np.linalg.norm(vee(value) - skew))
    assert skew_error <= 1e-14 * float(np.linalg.norm(skew)) + 4 * EPS * off_diagonal


# --- hat and vee ---------------------------------------------------------------------------


def test_hat_is_the_cross_product_and_vee_inverts_it():
    rng = np.random.default_rng(1)
    for _ in range(20):
        v, u = rng.normal(size=3), rng.normal(size=3)
        assert np.allclose(hat(v) @ u, np.cross(v, u), rtol=0, atol=1e-15)
        assert np.array_equal(hat(v), -hat(v).T)
        assert np.array_equal(vee(hat(v)), v)
        # vee reads the skew part only.
        S = rng.normal(size=(3, 3))
        assert np.allclose(vee(S + S.T), 0.0, atol=1e-15)
        assert np.allclose(hat(vee(S)), 0.5 * (S - S.T), rtol=0, atol=1e-15)


def test_hat_and_vee_refuse_wrong_shapes():
    with pytest.raises(ValueError, match=r"shape \(3,\)"):
        hat(np.zeros(4))
    with pytest.raises(ValueError, match=r"shape \(3, 3\)"):
        vee(np.zeros((3, 2)))


# --- exp and log ---------------------------------------------------------------------------


def float_power_series_exp(r: np.ndarray, terms: int = 60) -> np.ndarray:
    """sum_k hat(r)^k / k! in floats (|r| <= pi: the largest term is below 5, so ~1e-15)."""
    K = hat(r)
    total, term = np.eye(3), np.eye(3)
    for k in range(1, terms):
        term = term @ K / k
        total = total + term
    return total


@pytest.mark.parametrize("r", vectors_of_norms(ANGLES, seed=2), ids=[f"{t:.6g}" for t in ANGLES])
def test_exp_matches_power_series_and_drake(r):
    t = float(np.linalg.norm(r))
    R = exp_so3(r)
    assert np.allclose(R.T @ R, np.eye(3), rtol=0, atol=4 * EPS)
    assert abs(np.linalg.det(R) - 1.0) < 4 * EPS
    assert np.allclose(R, float_power_series_exp(r), rtol=0, atol=4 * EPS)
    if t > 0.0:
        drake = RotationMatrix(AngleAxis(t, r / t)).matrix()
        assert np.allclose(R, drake, rtol=0, atol=4 * EPS)
    assert_near_identity_matches(R, ref_exp_minus_identity(r))


@pytest.mark.parametrize("t", [1e-9, 1e-5, 1e-3, 1.0, 2.0, 3.0, math.pi - 1e-7])
def test_log_inverts_exp(t):
    rng = np.random.default_rng(3)
    for _ in range(20):
        r = t * unit(rng)
        # R from the 60-digit series, so the round trip does not share exp_so3's rounding.
        R = np.eye(3) + ref_exp_minus_identity(r)
        assert relative_error(log_so3(R), r) < 1e-13


def test_log_of_random_rotations():
    """Half from Drake's AngleAxis, half from random unit quaternions."""
    rng = np.random.default_rng(4)
    for i in range(200):
        if i % 2:
            R = RotationMatrix(AngleAxis(rng.uniform(0.0, math.pi), unit(rng))).matrix()
        else:
            R = _quaternion_matrix(rng.normal(size=4))
        r = log_so3(R)
        assert np.linalg.norm(r) <= math.pi * (1 + 2 * EPS)
        assert np.allclose(exp_so3(r), R, rtol=0, atol=8 * EPS)


def _quaternion_matrix(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


@pytest.mark.parametrize("gap", [1e-5, 1e-7, 1e-9, 1e-12, 1e-15, 0.0])
def test_log_near_pi_keeps_the_principal_angle(gap):
    rng = np.random.default_rng(5)
    for _ in range(20):
        n = unit(rng)
        t = math.pi - gap
        R = RotationMatrix(AngleAxis(t, n)).matrix()
        r = log_so3(R)
        assert np.linalg.norm(r) <= math.pi * (1 + 2 * EPS)
        assert np.allclose(exp_so3(r), R, rtol=0, atol=8 * EPS)
        # The axis, up to the sign that a rotation by pi leaves free (fixed once gap >> eps).
        assert abs(abs(float(r @ n)) - t) < 1e-14
        if gap >= 1e-9:
            assert np.allclose(r, t * n, rtol=0, atol=1e-14)


def test_log_of_the_exact_half_turn():
    for n in np.eye(3):
        R = 2.0 * np.outer(n, n) - np.eye(3)
        r = log_so3(R)
        assert np.allclose(np.abs(r), math.pi * n, rtol=0, atol=1e-15)
        assert np.allclose(exp_so3(r), R, rtol=0, atol=4 * EPS)


def test_log_refuses_what_is_not_a_rotation():
    R = exp_so3(np.array([0.3, -0.2, 0.5]))
    log_so3(R + 1e-11)  # within the tolerance: accepted
    for bad, why in [(R + 1e-7, "R\\^T R - I"), (-R, "det R"), (np.diag([1.0, 1.0, -1.0]),
                     "det R"), (2 * R, "R\\^T R - I"), (np.zeros((3, 3)), "not a rotation")]:
        with pytest.raises(ValueError, match=why):
            log_so3(bad)
    with pytest.raises(ValueError, match="non-finite"):
        log_so3(np.full((3, 3), np.nan))
    with pytest.raises(ValueError, match=r"shape \(3, 3\)"):
        log_so3(np.eye(4))


# --- right Jacobian, its inverse and its rate -----------------------------------------------


@pytest.mark.parametrize("r", vectors_of_norms(ANGLES, seed=6), ids=[f"{t:.6g}" for t in ANGLES])
def test_right_jacobian_and_inverse_match_the_series(r):
    J = right_jacobian(r)
    assert_near_identity_matches(J, ref_jr_minus_identity(r))
    J_inv = right_jacobian_inverse(r)
    assert_near_identity_matches(J_inv, ref_jr_inverse_minus_identity(r))
    assert np.allclose(J_inv @ J, np.eye(3), rtol=0, atol=8 * EPS)
    assert np.allclose(J @ r, r, rtol=0, atol=4 * EPS * (1 + np.linalg.norm(r)))
    # J_r(-r) = J_r(r)^T: the left Jacobian.
    assert np.allclose(right_jacobian(-r), J.T, rtol=0, atol=2 * EPS)


@pytest.mark.parametrize("r", vectors_of_norms(ANGLES, seed=7), ids=[f"{t:.6g}" for t in ANGLES])
def test_right_jacobian_dot_matches_the_series_rate(r):
    rng = np.random.default_rng(8)
    direction = r / np.linalg.norm(r) if np.linalg.norm(r) > 0 else unit(rng)
    # A generic rate, one along r (only |r| changes) and one across it (only the axis turns).
    across = np.cross(direction, unit(rng))
    for r_dot in [rng.normal(size=3), 0.7 * direction, across]:
        J_dot = right_jacobian_dot(r, r_dot)
        assert relative_error(J_dot, ref_jr_dot(r, r_dot)) < 1e-13


def test_right_jacobian_dot_at_zero_is_half_hat():
    v = np.array([0.3, -1.2, 0.8])
    assert np.array_equal(right_jacobian_dot(np.zeros(3), v), -0.5 * hat(v))


def test_right_jacobian_inverse_refuses_angles_at_pi():
    right_jacobian_inverse(np.array([0.0, 0.0, math.pi - 2e-6]))
    for t in [math.pi - 1e-6, math.pi, 4.0, 2 * math.pi]:
        with pytest.raises(ValueError, match="pi - 1e-6"):
            right_jacobian_inverse(np.array([0.0, t, 0.0]))
    with pytest.raises(ValueError, match="pi - 1e-6"):
        rotation_vector_velocity(np.array([math.pi, 0.0, 0.0]), np.ones(3))


# The coefficient functions, series and closed form, on both sides of every threshold: the two
# branches agree to ~1e-15 (measured), and each matches the 60-digit closed form.
COEFFICIENTS = [
    (so3._sinc, so3._SINC_THRESHOLD, lambda t, s, c: s / t),
    (so3._coef_a, so3._A_THRESHOLD, lambda t, s, c: (1 - c) / t**2),
    (so3._coef_b, so3._B_THRESHOLD, lambda t, s, c: (t - s) / t**3),
    (so3._coef_a_rate, so3._A_RATE_THRESHOLD, lambda t, s, c: (t * s - 2 * (1 - c)) / t**4),
    (so3._coef_b_rate, so3._B_RATE_THRESHOLD, lambda t, s, c: (3 * s - 2 * t - t * c) / t**5),
    (so3._coef_c, so3._C_THRESHOLD, lambda t, s, c: 1 / t**2 - (1 + c) / (2 * t * s)),
]


def d_sin_cos(t: Decimal) -> tuple[Decimal, Decimal]:
    s, c, term, k = Decimal(0), Decimal(0), Decimal(1), 0
    while abs(term) > Decimal(10) ** -75 or k < 4:
        if k % 2 == 0:
            c += term if k % 4 == 0 else -term
        else:
            s += term if k % 4 == 1 else -term
        k += 1
        term = term * t / k
    return s, c


@pytest.mark.parametrize("function, threshold, closed_form", COEFFICIENTS,
                         ids=[f[0].__name__ for f in COEFFICIENTS])
def test_coefficients_agree_across_thresholds_and_with_60_digits(function, threshold,
                                                                 closed_form):
    below = np.nextafter(threshold, 0.0)
    assert abs(function(below) - function(threshold)) <= 2e-15 * abs(function(threshold))
    with localcontext() as ctx:
        ctx.prec = PREC
        grid = np.concatenate([np.geomspace(1e-8, math.pi - 1e-6, 300),
                               threshold * (1 + np.array([-1e-3, -1e-12, 0.0, 1e-12, 1e-3]))])
        for t in grid:
            d = Decimal(float(t))
            reference = float(closed_form(d, *d_sin_cos(d)))
            assert abs(function(float(t)) - reference) <= 4e-15 * abs(reference), t


# --- rates, velocity and acceleration -------------------------------------------------------


@pytest.mark.parametrize("r", vectors_of_norms(ANGLES, seed=9), ids=[f"{t:.6g}" for t in ANGLES])
def test_rates_match_60_digit_differences_of_exp(r):
    rng = np.random.default_rng(10)
    for _ in range(3):
        r_dot, r_ddot = rng.normal(size=3), rng.normal(size=3)
        omega, domega = rotation_vector_rates(r, r_dot, r_ddot)
        omega_ref, domega_ref = ref_rates(r, r_dot, r_ddot)
        assert relative_error(omega, omega_ref) < 1e-14
        # domega = J r_ddot + (r_dot-squared terms): scaled by both, as either may cancel.
        scale = float(np.linalg.norm(r_ddot) + np.linalg.norm(r_dot) ** 2)
        assert relative_error(domega, domega_ref, scale) < 1e-14


def cubic(coefficients: np.ndarray):
    """r(t) = c0 + c1 t + c2 t^2 + c3 t^3 (coefficients (4, 3)) and its first two derivatives."""
    c0, c1, c2, c3 = coefficients

    def at(t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return (c0 + t * (c1 + t * (c2 + t * c3)), c1 + t * (2 * c2 + 3 * t * c3),
                2 * c2 + 6 * t * c3)
    return at


def random_cubics(rng: np.random.Generator) -> list[tuple[str, np.ndarray, float]]:
    """(kind, coefficients, scale of r): generic ones, ones through r ~ 1e-8 at t = 0.2 and
    small-angle ones (|r| ~ 1e-4); each redrawn until |r| < 3 on [-1.1, 1.1] (principal
    rotation vectors, and the derivatives stay moderate)."""

    def through_zero() -> np.ndarray:
        # c(t) = p(t - 0.2) + 1e-8 u: 1e-8 from r = 0 at t = 0.2.
        p = 0.8 * rng.normal(size=(4, 3))
        p[0] = 1e-8 * unit(rng)
        s = -0.2
        return np.array([p[0] + s * p[1] + s**2 * p[2] + s**3 * p[3],
                         p[1] + 2 * s * p[2] + 3 * s**2 * p[3], p[2] + 3 * s * p[3], p[3]])

    draws = [("generic", lambda: 0.6 * rng.normal(size=(4, 3)), 1.0),
             ("through zero", through_zero, 1.0),
             ("small angle", lambda: 1e-4 * rng.normal(size=(4, 3)), 1e-4)]
    curves = []
    for kind, draw, scale in draws:
        while sum(k == kind for k, _, _ in curves) < 6:
            c = draw()
            if max(np.linalg.norm(cubic(c)(t)[0]) for t in np.linspace(-1.1, 1.1, 45)) < 3.0:
                curves.append((kind, c, scale))
    return curves


TIMES = [-1.0, -0.61, -0.2, 0.0, 0.2 - 3e-5, 0.2, 0.2 + 1e-6, 0.37, 0.8, 1.0]


def test_rates_match_finite_differences_of_the_rotation():
    """omega against vee(R^T dR/dt), dR/dt by central differences with h = 1e-5: truncation
    h^2/6 |d3R/dt3| <~ 2e-11 * 200 on these curves, rounding ~eps/h ~ 2e-11; tolerance 1e-8
    (measured 4e-9). On the small-angle curves everything is 1e-4 times smaller and vee reads
    off-diagonal entries ~1e-4 (rounding ~1e-4 eps/h ~ 2e-15); tolerance 1e-12 (measured 3e-14).
    domega against the central difference of omega with h = 1e-4: truncation
    h^2/6 |d3omega/dt3| <~ 2e-9 * 200, rounding ~eps |omega| / h; tolerance 1e-6 (measured
    3e-7); small-angle 1e-12 (measured 2e-15). The world velocity R omega against
    vee(dR/dt R^T) the same way."""
    rng = np.random.default_rng(11)
    worst = {"omega": 0.0, "domega": 0.0}
    for kind, coefficients, scale in random_cubics(rng):
        at = cubic(coefficients)
        tol_omega, tol_domega = (1e-8, 1e-6) if scale == 1.0 else (1e-12, 1e-12)
        for t in TIMES:
            r, r_dot, r_ddot = at(t)
            omega, domega = rotation_vector_rates(r, r_dot, r_ddot)
            h = 1e-5
            R, R_plus, R_minus = exp_so3(r), exp_so3(at(t + h)[0]), exp_so3(at(t - h)[0])
            dR = (R_plus - R_minus) / (2 * h)
            omega_fd = vee(R.T @ dR)
            assert np.linalg.norm(omega - omega_fd) < tol_omega, (kind, t)
            assert np.linalg.norm(R @ omega - vee(dR @ R.T)) < tol_omega, (kind, t)
            h = 1e-4
            domega_fd = (rotation_vector_rates(*at(t + h))[0]
                         - rotation_vector_rates(*at(t - h))[0]) / (2 * h)
            assert np.linalg.norm(domega - domega_fd) < tol_domega, (kind, t)
            worst["omega"] = max(worst["omega"], np.linalg.norm(omega - omega_fd) / tol_omega)
            worst["domega"] = max(worst["domega"],
                                  np.linalg.norm(domega - domega_fd) / tol_domega)
    # The tolerances are not loose by orders of magnitude: some error uses a fair part of them.
    assert worst["omega"] > 1e-4 and worst["domega"] > 1e-4, worst


def test_right_jacobian_dot_matches_finite_differences_along_cubics():
    """Central difference of right_jacobian along r(t), h = 1e-5: truncation h^2/6 |d3J/dt3|
    <~ 2e-11 * 100, rounding ~eps/h ~ 2e-11 (J's diagonal is near 1 at every angle); tolerance
    1e-8 (measured 2e-9), 1e-10 on small-angle curves (measured 7e-12)."""
    rng = np.random.default_rng(12)
    for kind, coefficients, scale in random_cubics(rng):
        at = cubic(coefficients)
        tol = 1e-8 if scale == 1.0 else 1e-10
        for t in TIMES:
            r, r_dot, _ = at(t)
            h = 1e-5
            fd = (right_jacobian(at(t + h)[0]) - right_jacobian(at(t - h)[0])) / (2 * h)
            assert np.linalg.norm(right_jacobian_dot(r, r_dot) - fd) < tol, (kind, t)


def test_velocity_and_acceleration_invert_the_rates():
    rng = np.random.default_rng(13)
    for r in vectors_of_norms(ANGLES, seed=14):
        for _ in range(5):
            r_dot, r_ddot = rng.normal(size=3), rng.normal(size=3)
            omega, domega = rotation_vector_rates(r, r_dot, r_ddot)
            back = rotation_vector_velocity(r, omega)
            assert np.allclose(back, r_dot, rtol=0, atol=1e-14 * np.linalg.norm(r_dot))
            back_ddot = rotation_vector_acceleration(r, r_dot, domega)
            scale = np.linalg.norm(r_ddot) + np.linalg.norm(r_dot) ** 2
            assert np.allclose(back_ddot, r_ddot, rtol=0, atol=1e-14 * scale)


def test_public_names():
    assert sorted(so3.__all__) == sorted([
        "hat", "vee", "exp_so3", "log_so3", "right_jacobian", "right_jacobian_inverse",
        "right_jacobian_dot", "rotation_vector_rates", "rotation_vector_velocity",
        "rotation_vector_acceleration"])
