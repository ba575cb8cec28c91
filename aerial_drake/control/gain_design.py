"""Gain design help: the CoM and attitude loops' closed-loop roots from the gains and the
robot, and whether the attitude loop is fast enough against the CoM loop (docs/control.md,
"Gain design help").

Linearised at a hover (docs/analysis.md, section 3), each CoM axis is ``m s^2 + D_x s + K_x``
(``m`` the robot's total mass) and each attitude axis ``J s^2 + k_w s + k_R``, ``J`` the
inertia the attitude law gives that axis: under the paper's (16) the closed loop is
``Lbar2 w~' = -(k_R e_R + k_w w~)``, so ``J`` is ``gains.Lambda2_bar`` (the robot's own
``Lambda_22`` cancels); under the baselines' vehicle law it is the inertia the law assumes
(the robot locked at its start, about its CoM: :func:`.baselines.tuning.locked_inertia`).
Both are the same second-order polynomial, whose roots :func:`.baselines.tuning.
attitude_poles` gives.

The thrust turns only as fast as the attitude loop: when its slowest root is not well left of
the CoM loop's, a push on the vehicle moves the CoM several times ``F / K_x`` before the
thrust follows (docs/control.md, "Table II's attitude root is slower than the CoM's").
:func:`gain_design_message` says so, with the roots and gains that would separate them.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from aerial_drake.control.baselines.tuning import attitude_poles

#: The attitude loop's slowest root must be at least this many times the CoM loop's (in real
#: part) for the check to pass (issue 32, item 5).
ATTITUDE_SEPARATION = 3.0
#: The margin the suggested gains keep past the separation (so rounding them to three
#: significant figures does not land them back on the boundary).
_MARGIN = 1.05


class GainDesignWarning(UserWarning):
    """The scenario's gains leave the attitude loop too slow against the CoM loop."""


@dataclass(frozen=True)
class LoopRoots:
    """The CoM and attitude loops' roots (1/s) at a hover, per axis, the slowest first."""

    mass: float  # the robot's total mass m (kg)
    K_x: np.ndarray  # (3) CoM stiffness (N/m)
    D_x: np.ndarray  # (3) CoM damping (N s/m)
    k_R: float
    k_w: float
    attitude_inertia: np.ndarray  # (3) J per attitude axis (kg m^2)
    com: np.ndarray  # (3, 2) complex: roots of m s^2 + D_x s + K_x, per World axis
    attitude: np.ndarray  # (3, 2) complex: roots of J s^2 + k_w s + k_R, per axis

    @property
    def slowest_com(self) -> complex:
        """The CoM root with the largest real part (the slowest to decay)."""
        return complex(self.com.ravel()[np.argmax(self.com.real)])

    @property
    def slowest_attitude(self) -> complex:
        """The attitude root with the largest real part."""
        return complex(self.attitude.ravel()[np.argmax(self.attitude.real)])

    @property
    def separation(self) -> float:
        """How many times faster the slowest attitude root decays than the slowest CoM root
        (their real parts' ratio); infinite if the CoM loop has a root at zero (K_x = 0)."""
        com = self.slowest_com.real
        return math.inf if com == 0.0 else float(self.slowest_attitude.real / com)

    def fast_enough(self, factor: float = ATTITUDE_SEPARATION) -> bool:
        return self.separation >= factor


def loop_roots(mass: float, K_x, D_x, k_R: float, k_w: float, attitude_inertia,
               ) -> LoopRoots:
    """The roots of each CoM axis (``mass``, the diagonals ``K_x``, ``D_x``) and of each
    attitude axis (``attitude_inertia``, 3 entries, with ``k_R``, ``k_w``)."""
    K_x, D_x = np.asarray(K_x, float), np.asarray(D_x, float)
    J = np.asarray(attitude_inertia, float)
    # inertia s^2 + damping s + stiffness: the one polynomial of both loops (attitude_poles).
    com = np.array([attitude_poles(mass, K_x[i], D_x[i]) for i in range(3)], dtype=complex)
    attitude = np.array([attitude_poles(J[i], k_R, k_w) for i in range(3)], dtype=complex)
    return LoopRoots(mass=float(mass), K_x=K_x, D_x=D_x, k_R=float(k_R), k_w=float(k_w),
                     attitude_inertia=J, com=com, attitude=attitude)


def suggested_attitude_gains(roots: LoopRoots, factor: float = ATTITUDE_SEPARATION,
                             ) -> tuple[float, float]:
    """``(k_R, k_w)`` that put every attitude root's real part at or left of ``-a``,
    ``a = factor |Re slowest CoM root|`` (with a 5 % margin): ``k_w = 2 J_max a`` puts the
    largest inertia's pair at real part ``-a``, and ``k_R = (2 J_max - J_min) a^2`` makes
    ``J a^2 - k_w a + k_R >= 0`` for every ``J`` in ``[J_min, J_max]``, so no root lies in
    ``(-a, 0)``. Rounded up to three significant figures."""
    a = _MARGIN * factor * abs(roots.slowest_com.real)
    J_max, J_min = float(roots.attitude_inertia.max()), float(roots.attitude_inertia.min())
    k_w = 2.0 * J_max * a
    k_R = (2.0 * J_max - J_min) * a * a
    return _round_up(k_R), _round_up(k_w)


def suggested_com_gains(roots: LoopRoots, factor: float = ATTITUDE_SEPARATION,
                        ) -> tuple[float, float]:
    """``(K_x, D_x)``, the same on each axis, that put the CoM loop's double root at
    ``-b``, ``b = |Re slowest attitude root| / factor`` (with a 5 % margin): critically
    damped, ``K_x = m b^2``, ``D_x = 2 m b``. Rounded down to three significant figures."""
    b = abs(roots.slowest_attitude.real) / (factor * _MARGIN)
    return _round_down(roots.mass * b * b), _round_down(2.0 * roots.mass * b)


def _round_up(x: float) -> float:
    scale = 10.0 ** (np.floor(np.log10(abs(x))) - 2)
    return float(np.ceil(x / scale) * scale)


def _round_down(x: float) -> float:
    scale = 10.0 ** (np.floor(np.log10(abs(x))) - 2)
    return float(np.floor(x / scale) * scale)


def _show_roots(pairs: np.ndarray) -> str:
    return "; ".join(", ".join(f"{s.real:.4g}" if abs(s.imag) < 1e-12 else
                               f"{s.real:.4g}{s.imag:+.4g}j" for s in pair) for pair in pairs)


def gain_design_message(roots: LoopRoots, inertia_source: str,
                        factor: float = ATTITUDE_SEPARATION) -> str | None:
    """None when the attitude loop's slowest root is at least ``factor`` times the CoM
    loop's (in real part); else a message naming both loops' roots and what to change
    (``inertia_source`` says where the attitude inertia comes from)."""
    if roots.fast_enough(factor):
        return None
    att, com = roots.slowest_attitude, roots.slowest_com
    k_R, k_w = suggested_attitude_gains(roots, factor)
    K_x, D_x = suggested_com_gains(roots, factor)
    return (
        f"gains: the attitude loop's slowest root, {att.real:.4g} 1/s, is not {factor:g}x "
        f"faster than the CoM loop's slowest, {com.real:.4g} 1/s (it is {roots.separation:.2f}"
        f"x). CoM roots (m s^2 + D_x s + K_x, m = {roots.mass:.4g} kg, per World axis): "
        f"{_show_roots(roots.com)}; attitude roots (J s^2 + k_w s + k_R, J = "
        f"{np.round(roots.attitude_inertia, 4).tolist()} kg m^2 {inertia_source}, per axis): "
        f"{_show_roots(roots.attitude)}. The slow attitude root is about -k_R / k_w = "
        f"{-roots.k_R / roots.k_w:.4g} 1/s: a push on the vehicle then moves the CoM several "
        f"times F / K_x before the thrust turns (docs/control.md, \"Gain design help\"). "
        f"Make the attitude loop faster, e.g. k_R = {k_R:g}, k_w = {k_w:g} (every attitude "
        f"root at or left of {-factor * abs(com.real):.3g} 1/s), or the CoM loop slower, "
        f"e.g. K_x = {K_x:g}, D_x = {D_x:g} on each axis (a double root at "
        f"{-abs(att.real) / factor:.3g} 1/s)")


def warn_if_slow(mass: float, gains, attitude_inertia, inertia_source: str,
                 stacklevel: int = 3) -> LoopRoots:
    """Warn (:class:`GainDesignWarning`, with :func:`gain_design_message`) when ``gains``'
    attitude loop, of ``attitude_inertia``, is too slow against their CoM loop on a robot of
    ``mass``; returns the roots."""
    roots = loop_roots(mass, gains.K_x, gains.D_x, gains.k_R, gains.k_w, attitude_inertia)
    message = gain_design_message(roots, inertia_source)
    if message is not None:
        warnings.warn(message, GainDesignWarning, stacklevel=stacklevel)
    return roots
