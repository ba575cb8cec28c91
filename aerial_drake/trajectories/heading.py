"""The heading angle phi4(t) as the law reads it: b1d and its derivatives (13), and the system's
CoM offset R3(phi4) r_o of (33) with its derivatives up to the 4th (x_d needs C^4).

Both come from z(t) = exp(i phi4(t)) (b1d's xy part), whose derivatives follow from phi4's
by the chain rule (Faa di Bruno up to the 4th order).
"""

from __future__ import annotations

import numpy as np

__all__ = ["unit_phasor_derivatives", "heading_reference", "rotated_offset",
           "heading_and_offset"]


def unit_phasor_derivatives(phi: np.ndarray) -> np.ndarray:
    """d^k/dt^k exp(i phi(t)), k = 0..len(phi)-1 (at most 4), from phi and its derivatives
    ``phi`` = [phi, phi', phi'', ...] (complex array)."""
    phi = np.asarray(phi, dtype=float)
    n = phi.size
    if n > 5:
        raise ValueError("derivatives up to the 4th only")
    d1, d2, d3, d4 = (list(phi[1:]) + [0.0, 0.0, 0.0, 0.0])[:4]
    z = np.exp(1j * phi[0])
    factors = [1.0, 1j * d1, 1j * d2 - d1 ** 2, 1j * d3 - 3 * d1 * d2 - 1j * d1 ** 3,
               1j * d4 - 4 * d1 * d3 - 3 * d2 ** 2 - 6j * d1 ** 2 * d2 + d1 ** 4]
    return np.array(factors[:n]) * z


def heading_reference(phi: np.ndarray) -> np.ndarray:
    """[b1d, b1d', b1d''] (3, 3), b1d = [cos phi4, sin phi4, 0] (32), from phi4 and at least
    its first two derivatives."""
    return _heading_rows(unit_phasor_derivatives(np.asarray(phi, dtype=float)[:3]))


def rotated_offset(phi: np.ndarray, r_o: np.ndarray) -> np.ndarray:
    """d^k/dt^k R3(phi4(t)) r_o, k = 0..4 (5, 3), from phi4 and its first four derivatives:
    R3 turns r_o's xy part by phi4 and keeps its z (33)."""
    return _offset_rows(unit_phasor_derivatives(np.asarray(phi, dtype=float)[:5]), r_o)


def heading_and_offset(phi: np.ndarray, r_o: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`heading_reference` and :func:`rotated_offset` from one evaluation of the
    phasor's derivatives (``phi``: phi4 and its first four derivatives)."""
    z = unit_phasor_derivatives(np.asarray(phi, dtype=float)[:5])
    return _heading_rows(z[:3]), _offset_rows(z, r_o)


def _heading_rows(z: np.ndarray) -> np.ndarray:
    """b1d's derivatives as rows [x, y, 0] from exp(i phi4)'s."""
    return np.column_stack([z.real, z.imag, np.zeros(z.size)])


def _offset_rows(z: np.ndarray, r_o: np.ndarray) -> np.ndarray:
    """R3(phi4) r_o's derivatives from exp(i phi4)'s: the xy part turned, z constant."""
    xy = z * complex(r_o[0], r_o[1])
    out = np.column_stack([xy.real, xy.imag, np.zeros(z.size)])
    out[0, 2] = r_o[2]
    return out
