"""Metrics of a run, per phase, from its logs (the keys are documented in the README)."""

from __future__ import annotations

import numpy as np

from aerial_drake.control import diagnostics_slices

INPUT_NAMES = ("thrust", "mu_x", "mu_y", "mu_z") + tuple(f"tau_{i}" for i in range(1, 8))

_ERRORS = {
    # metric name -> diagnostics entry
    "ee_position_error_m": "ee_position_error",
    "ee_orientation_error_rad": "ee_orientation_error",
    "com_position_error_m": "com_error",
    "base_attitude_error_rad": "base_attitude_error",
}


def phase_edges(disturbance_windows: list[tuple[float, float]], duration: float) -> list[float]:
    """Phase boundaries: 0, every window edge inside the run, and the end."""
    inner = sorted({t for w in disturbance_windows for t in w if 0.0 < t < duration})
    return [0.0] + inner + [duration]


def compute_metrics(t: np.ndarray, diagnostics: np.ndarray, applied: np.ndarray,
                    lower: np.ndarray, upper: np.ndarray, edges: list[float],
                    log_period: float, saturation_grace: float = 0.5) -> dict:
    """Per-phase RMS/max errors, assumption margins and saturated time.

    Args:
        t: sample times (N); diagnostics: (N, DIAGNOSTICS_SIZE); applied: (N, 11) inputs that
        reached the plant; lower/upper: (11) input limits; edges: phase boundaries (s).
        saturation_grace: the saturated time after this instant is reported separately, as
        the paper allows saturation only in a short initial interval.
    """
    sl = diagnostics_slices()
    tol = 1e-9 * np.maximum(1.0, np.abs(np.concatenate([lower, upper])).max())
    at_limit = (applied <= lower + tol) | (applied >= upper - tol)
    phases = []
    for k, (a, b) in enumerate(zip(edges[:-1], edges[1:])):
        last = k == len(edges) - 2
        mask = (t >= a) & ((t <= b) if last else (t < b))
        phase = {"start_s": a, "end_s": b, "samples": int(mask.sum())}
        if mask.any():
            for key, diag in _ERRORS.items():
                e = diagnostics[mask, sl[diag]][:, 0]
                phase[key] = {"rms": float(np.sqrt(np.mean(e ** 2))), "max": float(e.max())}
            phase["min_sigma_min_J3"] = float(diagnostics[mask, sl["sigma_min_J3"]].min())
            phase["min_f_d_norm_N"] = float(diagnostics[mask, sl["f_d_norm"]].min())
            phase["saturated_s"] = dict(zip(INPUT_NAMES,
                                            (at_limit[mask].sum(axis=0) * log_period).tolist()))
        phases.append(phase)
    late = t >= saturation_grace
    return {
        "phases": phases,
        "saturated_s_total": dict(zip(INPUT_NAMES,
                                      (at_limit.sum(axis=0) * log_period).tolist())),
        f"saturated_s_after_{saturation_grace:g}s": dict(
            zip(INPUT_NAMES, (at_limit[late].sum(axis=0) * log_period).tolist())),
        "min_sigma_min_J3": float(diagnostics[:, sl["sigma_min_J3"]].min()),
        "min_f_d_norm_N": float(diagnostics[:, sl["f_d_norm"]].min()),
    }


def peak(t: np.ndarray, signal: np.ndarray, a: float, b: float) -> float:
    """max of ``signal`` over ``a <= t <= b``."""
    mask = (t >= a) & (t <= b)
    return float(signal[mask].max())
