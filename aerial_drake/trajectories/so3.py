"""SO(3) in exponential coordinates, for orientation segments R(t) = R0 exp(hat(r(t))).

Conventions: ``hat(v) @ u == np.cross(v, u)``; the body angular velocity ``omega`` is defined by
``R^T dR/dt = hat(omega)`` and the world one is ``w = R omega``. With ``R = R0 exp(hat(r))``,
``omega = J_r(r) dr/dt`` where ``J_r`` is the right Jacobian of SO(3)::

    J_r(r) = I - a(t) hat(r) + b(t) hat(r)^2,   a = (1 - cos t) / t^2,   b = (t - sin t) / t^3,

with ``t = |r|``. Every coefficient is an even analytic function of ``t``; below a threshold it
is evaluated from its Taylor series in ``t^2`` (the closed form cancels there), above it from the
closed form. Each threshold is chosen so that the closed form's rounding error above it stays
near 1e-15 relative and the series' truncation below it is under 1e-22; the tests check every
function against 50-digit references and the two branches' agreement at each threshold.

Pure numpy and ``math``: no Drake, no numba (hat and vee are the dynamics layer's).
"""

import math
from fractions import Fraction

import numpy as np

from aerial_drake.dynamics.decoupling import hat as _hat
from aerial_drake.dynamics.decoupling import vee as _vee

__all__ = [
    "hat",
    "vee",
    "exp_so3",
    "log_so3",
    "right_jacobian",
    "right_jacobian_inverse",
    "right_jacobian_dot",
    "rotation_vector_rates",
    "rotation_vector_velocity",
    "rotation_vector_acceleration",
]

#: log_so3 refuses a matrix whose R^T R - I (largest entry) or det R - 1 exceeds this.
ROTATION_TOLERANCE = 1e-9

#: right_jacobian_inverse refuses |r| at or above this. J_r is singular only at |r| = 2 pi, but
#: the segments use principal rotation vectors (|r| <= pi, what log_so3 returns), so a larger
#: |r| is a caller's error; the margin below pi keeps away from the pi <-> -pi ambiguity.
INVERSE_MAX_ANGLE = math.pi - 1e-6

# Number of Taylor terms (powers of t^2) kept in every series: at each threshold below, the
# first omitted term is under 3e-23 of the value (the largest is c's, whose series has radius
# 2 pi, at t = 1); Horner's rule keeps 14 terms cheap.
_TERMS = 14


def _factorial_series(offset: int, scale_by_power: bool = False) -> tuple[float, ...]:
    """Coefficients of t^(2k) in sum_k (-1)^k t^(2k) / (2k + offset)!, or, with
    ``scale_by_power``, of (1/t) d/dt of that sum (the rate coefficients)."""
    if not scale_by_power:
        return tuple(float(Fraction((-1) ** k, math.factorial(2 * k + offset)))
                     for k in range(_TERMS))
    # (1/t) d/dt t^(2k+2) = (2k + 2) t^(2k): the k-th term comes from the (k+1)-th above.
    return tuple(float(Fraction((-1) ** (k + 1) * (2 * k + 2), math.factorial(2 * k + 2 + offset)))
                 for k in range(_TERMS))


def _bernoulli_even(count: int) -> list[Fraction]:
    """|B_2|, |B_4|, ..., |B_(2 count)| exactly (the recurrence sum_k C(m+1, k) B_k = 0)."""
    numbers = [Fraction(1)]
    for m in range(1, 2 * count + 1):
        numbers.append(-sum((math.comb(m + 1, k) * numbers[k] for k in range(m)), Fraction(0))
                       / (m + 1))
    return [abs(numbers[2 * n]) for n in range(1, count + 1)]


# sin t / t, a, b, a'(t)/t, b'(t)/t.
_SINC_SERIES = _factorial_series(1)
_A_SERIES = _factorial_series(2)
_B_SERIES = _factorial_series(3)
_A_RATE_SERIES = _factorial_series(2, scale_by_power=True)
_B_RATE_SERIES = _factorial_series(3, scale_by_power=True)
# c(t) = 1/t^2 - cot(t/2) / (2 t) = sum_n |B_2n| t^(2n-2) / (2n)! (radius 2 pi).
_C_SERIES = tuple(float(b / math.factorial(2 * n))
                  for n, b in enumerate(_bernoulli_even(_TERMS), start=1))

# Series below, closed form at and above. sin t / t and a have no cancellation (a is written
# with sin^2(t/2)): their series only avoid 0/0. For the others the closed form loses about
# eps / t^2 (b, c) or eps / t^4 (the rates) relative, so their thresholds are larger: with these
# the closed forms measure at most 1.1e-15 relative error (50-digit reference, t up to pi).
_SINC_THRESHOLD = 1e-3
_A_THRESHOLD = 1e-3
_B_THRESHOLD = 1.0
_C_THRESHOLD = 1.0
_A_RATE_THRESHOLD = 1.5
_B_RATE_THRESHOLD = 2.0


def _series(coefficients: tuple[float, ...], t2: float) -> float:
    value = 0.0
    for c in reversed(coefficients):
        value = value * t2 + c
    return value


def _sinc(t: float) -> float:
    """sin t / t."""
    if t < _SINC_THRESHOLD:
        return _series(_SINC_SERIES, t * t)
    return math.sin(t) / t


def _coef_a(t: float) -> float:
    """(1 - cos t) / t^2, as 2 sin^2(t/2) / t^2 (no cancellation)."""
    if t < _A_THRESHOLD:
        return _series(_A_SERIES, t * t)
    s = math.sin(0.5 * t) / t
    return 2.0 * s * s


def _coef_b(t: float) -> float:
    """(t - sin t) / t^3."""
    if t < _B_THRESHOLD:
        return _series(_B_SERIES, t * t)
    return (t - math.sin(t)) / t**3


def _coef_a_rate(t: float) -> float:
    """a'(t) / t = (t sin t - 2 (1 - cos t)) / t^4."""
    if t < _A_RATE_THRESHOLD:
        return _series(_A_RATE_SERIES, t * t)
    s = math.sin(0.5 * t)
    return (t * math.sin(t) - 4.0 * s * s) / t**4


def _coef_b_rate(t: float) -> float:
    """b'(t) / t = (3 sin t - 2 t - t cos t) / t^5."""
    if t < _B_RATE_THRESHOLD:
        return _series(_B_RATE_SERIES, t * t)
    return (3.0 * math.sin(t) - 2.0 * t - t * math.cos(t)) / t**5


def _coef_c(t: float) -> float:
    """1/t^2 - (1 + cos t) / (2 t sin t), as 1/t^2 - 1 / (2 t tan(t/2)): exact at t = pi."""
    if t < _C_THRESHOLD:
        return _series(_C_SERIES, t * t)
    return 1.0 / (t * t) - 1.0 / (2.0 * t * math.tan(0.5 * t))


def _vector(v: np.ndarray, name: str) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    if v.shape != (3,):
        raise ValueError(f"{name} must have shape (3,), got {v.shape}")
    return v


def hat(v: np.ndarray) -> np.ndarray:
    """The skew matrix of ``v`` (3,): ``hat(v) @ u == np.cross(v, u)`` (shape-checked
    :func:`aerial_drake.dynamics.decoupling.hat`)."""
    return _hat(_vector(v, "v"))


def vee(S: np.ndarray) -> np.ndarray:
    """The vector (3,) of the skew part (S - S^T)/2 of ``S`` (3, 3); the inverse of :func:`hat`
    (shape-checked :func:`aerial_drake.dynamics.decoupling.vee`)."""
    S = np.asarray(S, dtype=float)
    if S.shape != (3, 3):
        raise ValueError(f"S must have shape (3, 3), got {S.shape}")
    return _vee(S)


def exp_so3(r: np.ndarray) -> np.ndarray:
    """The rotation exp(hat(r)) (Rodrigues), accurate for every |r| including 0."""
    r = _vector(r, "r")
    t = math.sqrt(float(r @ r))
    K = hat(r)
    return np.eye(3) + _sinc(t) * K + _coef_a(t) * (K @ K)


def log_so3(R: np.ndarray) -> np.ndarray:
    """The rotation vector r (3,) with |r| <= pi and exp_so3(r) == R.

    Raises ValueError if ``R`` is not a rotation (R^T R = I and det R = 1 within 1e-9). At
    |r| = pi exactly both r and -r are valid; the sign then follows the rounding of R.
    """
    R = np.asarray(R, dtype=float)
    if R.shape != (3, 3):
        raise ValueError(f"R must have shape (3, 3), got {R.shape}")
    if not np.all(np.isfinite(R)):
        raise ValueError("R is not a rotation matrix: it has non-finite entries")
    orthogonality = float(np.max(np.abs(R.T @ R - np.eye(3))))
    det = float(np.linalg.det(R))
    if orthogonality > ROTATION_TOLERANCE or abs(det - 1.0) > ROTATION_TOLERANCE:
        raise ValueError(
            f"R is not a rotation matrix: max |R^T R - I| = {orthogonality:.3g}, "
            f"det R = {det:.12g} (each must be within {ROTATION_TOLERANCE:g} of I and 1)")
    # R = cos t I + sin t hat(n) + (1 - cos t) n n^T: the skew part gives sin t n, the trace
    # cos t; atan2 of the two keeps t accurate at both ends, where acos or asin alone is not.
    s = vee(R)
    sin_t = math.sqrt(float(s @ s))
    cos_t = 0.5 * (float(np.trace(R)) - 1.0)
    t = math.atan2(sin_t, cos_t)
    if cos_t >= 0.0:
        # t <= pi/2: sin t is well away from 0 relative to t, so s / sin t is an accurate axis.
        return s * (t / sin_t) if sin_t > 0.0 else np.zeros(3)
    # Near pi, sin t -> 0 and s holds only the rounding of R: the axis comes from the symmetric
    # part, (R + R^T)/2 - cos t I = (1 - cos t) n n^T, through its largest column (n_i^2 >= 1/3
    # there); s only gives the sign.
    M = (0.5 * (R + R.T) - cos_t * np.eye(3)) / (1.0 - cos_t)
    i = int(np.argmax(np.diag(M)))
    n = M[:, i] / math.sqrt(M[i, i])
    n /= math.sqrt(float(n @ n))
    if float(n @ s) < 0.0:
        n = -n
    return t * n


def right_jacobian(r: np.ndarray) -> np.ndarray:
    """J_r(r) = I - (1 - cos t)/t^2 hat(r) + (t - sin t)/t^3 hat(r)^2, t = |r|: the map from
    dr/dt to the body angular velocity of R0 exp(hat(r))."""
    r = _vector(r, "r")
    t = math.sqrt(float(r @ r))
    K = hat(r)
    return np.eye(3) - _coef_a(t) * K + _coef_b(t) * (K @ K)


def right_jacobian_inverse(r: np.ndarray) -> np.ndarray:
    """J_r(r)^-1 = I + hat(r)/2 + (1/t^2 - (1 + cos t)/(2 t sin t)) hat(r)^2, t = |r|.

    Raises ValueError for |r| >= pi - 1e-6 (:data:`INVERSE_MAX_ANGLE`): J_r is singular only at
    |r| = 2 pi, but rotation vectors here are principal (|r| <= pi), kept clear of pi.
    """
    r = _vector(r, "r")
    t = math.sqrt(float(r @ r))
    if not t < INVERSE_MAX_ANGLE:
        raise ValueError(
            f"right_jacobian_inverse: |r| = {t!r} is not below pi - 1e-6 ({INVERSE_MAX_ANGLE!r});"
            " rotation vectors must be principal (|r| <= pi) and clear of pi (J_r itself is"
            " singular only at |r| = 2 pi)")
    K = hat(r)
    return np.eye(3) + 0.5 * K + _coef_c(t) * (K @ K)


def right_jacobian_dot(r: np.ndarray, r_dot: np.ndarray) -> np.ndarray:
    """d/dtime J_r(r(time)) at r with dr/dtime = ``r_dot`` (exact; -hat(r_dot)/2 at r = 0)."""
    r = _vector(r, "r")
    r_dot = _vector(r_dot, "r_dot")
    t = math.sqrt(float(r @ r))
    K = hat(r)
    K_dot = hat(r_dot)
    # d a(t)/dtime = a'(t) (r . r_dot) / t: a'(t)/t is analytic, so r = 0 needs no special case.
    rate = float(r @ r_dot)
    return (-_coef_a_rate(t) * rate * K - _coef_a(t) * K_dot
            + _coef_b_rate(t) * rate * (K @ K) + _coef_b(t) * (K @ K_dot + K_dot @ K))


def rotation_vector_rates(r: np.ndarray, r_dot: np.ndarray,
                          r_ddot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(omega, domega): the body angular velocity and acceleration of R0 exp(hat(r)), from r
    and its first two time derivatives."""
    r_dot = _vector(r_dot, "r_dot")
    r_ddot = _vector(r_ddot, "r_ddot")
    J = right_jacobian(r)
    omega = J @ r_dot
    domega = J @ r_ddot + right_jacobian_dot(r, r_dot) @ r_dot
    return omega, domega


def rotation_vector_velocity(r: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """dr/dt = J_r(r)^-1 omega for the body angular velocity ``omega`` (|r| < pi - 1e-6)."""
    return right_jacobian_inverse(r) @ _vector(omega, "omega")


def rotation_vector_acceleration(r: np.ndarray, r_dot: np.ndarray,
                                 domega: np.ndarray) -> np.ndarray:
    """d^2r/dt^2 = J_r(r)^-1 (domega - dJ_r/dt r_dot) for the body angular acceleration
    ``domega`` (|r| < pi - 1e-6)."""
    r_dot = _vector(r_dot, "r_dot")
    rhs = _vector(domega, "domega") - right_jacobian_dot(r, r_dot) @ r_dot
    return right_jacobian_inverse(r) @ rhs
