"""The control law's pure pieces: derivative formulas against finite differences, gain checks."""

import numpy as np
import pytest

from aerial_drake.control.law import (
    GainMatrices,
    Gains,
    desired_attitude,
    diagnostics_layout,
    diagnostics_size,
    diagnostics_slices,
    task_size_of_diagnostics,
    unit_vector_derivatives,
)
from aerial_drake.dynamics.decoupling import hat, vee


def poly(t, coeffs):
    """A smooth test signal and its first two derivatives (coeffs: (k, 3))."""
    out = [np.zeros(3), np.zeros(3), np.zeros(3)]
    for k, c in enumerate(coeffs):
        out[0] = out[0] + c * np.sin((k + 1) * t + k)
        out[1] = out[1] + c * (k + 1) * np.cos((k + 1) * t + k)
        out[2] = out[2] - c * (k + 1) ** 2 * np.sin((k + 1) * t + k)
    return out


COEFFS = np.array([[3.0, -1.0, 20.0], [0.5, 2.0, 0.3], [-0.2, 0.1, 0.4]])
HEAD = np.array([[1.0, 0.2, 0.0], [0.1, 0.9, 0.0], [0.0, 0.05, 0.01]])


@pytest.mark.parametrize("t", [0.0, 0.7, 2.3, 5.1])
def test_unit_vector_derivatives(t):
    h = 1e-5
    b = lambda s: unit_vector_derivatives(*poly(s, COEFFS))  # noqa: E731
    b0, b1, b2 = b(t)
    np.testing.assert_allclose((b(t + h)[0] - b(t - h)[0]) / (2 * h), b1, atol=1e-8)
    np.testing.assert_allclose((b(t + h)[1] - b(t - h)[1]) / (2 * h), b2, atol=1e-7)
    assert abs(np.linalg.norm(b0) - 1) < 1e-14


@pytest.mark.parametrize("t", [0.0, 0.7, 2.3, 5.1])
def test_desired_attitude_derivatives(t):
    h = 1e-5

    def Rd(s):
        b1d = poly(s, HEAD)
        b1d[0] = b1d[0] + np.array([1.0, 0.0, 0.0])  # keep b1d away from f_d
        return desired_attitude(*poly(s, COEFFS), b1d)

    R, R_dot, R_ddot, _ = Rd(t)
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-13)
    assert np.linalg.det(R) == pytest.approx(1.0)
    np.testing.assert_allclose((Rd(t + h)[0] - Rd(t - h)[0]) / (2 * h), R_dot, atol=1e-8)
    np.testing.assert_allclose((Rd(t + h)[1] - Rd(t - h)[1]) / (2 * h), R_ddot, atol=1e-6)
    # R^T R_dot is skew-symmetric (an angular velocity).
    W = R.T @ R_dot
    np.testing.assert_allclose(W + W.T, 0, atol=1e-12)
    # The third column is f_d / |f_d| (12).
    f = poly(t, COEFFS)[0]
    np.testing.assert_allclose(R[:, 2], f / np.linalg.norm(f), atol=1e-14)


def paper_gains(**changes):
    g = Gains(K_x=[800.0] * 3, D_x=[420.0] * 3, k_R=250.0, k_w=200.0,
              Lambda2_bar=[1.46, 0.36, 1.46], K_y=[30.0] * 3 + [10.0] * 3 + [7.0],
              K_z=[30.0] * 7)
    for k, v in changes.items():
        setattr(g, k, v)
    return g


def test_diagnostics_layout_of_the_papers_task():
    """The paper's task (7 rows) keeps the diagnostics vector of 37 entries."""
    assert diagnostics_size(7) == 37
    assert task_size_of_diagnostics(37) == 7
    sl = diagnostics_slices(7)
    assert (sl["y_tilde"], sl["z_tilde"]) == (slice(12, 19), slice(19, 26))
    assert sl["thrust_residual"] == slice(35, 37)
    assert diagnostics_slices(diagnostics_layout(7)) == sl
    with pytest.raises(ValueError, match="36"):
        task_size_of_diagnostics(36)


def test_gains_accept_table_ii():
    K = GainMatrices.from_gains(paper_gains(), n_task=7)
    np.testing.assert_allclose(K.Lambda2_bar_inv, 1 / np.array([1.46, 0.36, 1.46]))


@pytest.mark.parametrize("field,value,match", [
    ("K_x", [800.0, -1.0, 800.0], "gains.K_x .*not positive definite"),
    ("K_z", [30.0] * 6, "gains.K_z must be a list of 7"),
    ("k_R", 0.0, "gains.k_R"),
    ("Lambda2_bar", [1.0, float("nan"), 1.0], "gains.Lambda2_bar"),
    ("D_x", [], "gains.D_x must be a list of 3"),
])
def test_gains_reject_bad_values(field, value, match):
    with pytest.raises(ValueError, match=match):
        paper_gains(**{field: value}).validate(7)


def test_vee_takes_skew_part():
    R = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # 90 deg about z
    # (14): e_R = 1/2 (R_d^T R - R^T R_d)^vee = sin(angle) axis.
    np.testing.assert_allclose(vee(R), [0, 0, 1.0])
    # A symmetric part, with off-diagonal entries, must not leak into vee.
    a = np.array([0.3, -1.2, 2.0])
    S = np.array([[1.0, 0.4, -0.7], [0.4, 2.0, 0.9], [-0.7, 0.9, 3.0]])
    np.testing.assert_allclose(vee(hat(a) + S), a, atol=1e-15)


def test_desired_attitude_refuses_a_heading_along_the_thrust():
    """b1d parallel to f_d leaves (13) undefined: an AssumptionViolation saying so, not NaN
    columns."""
    from aerial_drake.control.law import AssumptionViolation

    zero = np.zeros(3)
    b1d = np.array([[0.0, 0.0, 1.0], zero, zero])
    with pytest.raises(AssumptionViolation, match="heading b1d is parallel"):
        desired_attitude(np.array([0.0, 0.0, 100.0]), zero, zero, b1d)
