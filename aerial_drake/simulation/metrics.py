"""Metrics of a run, per phase, from its logs (the keys are documented in the README).

The errors and margins come from named entries (``{name: (N, size) array}``): the run's
tracking errors (:mod:`aerial_drake.simulation.tracking`), and the controller's own
quantities from its diagnostics where it reports them by those names (``base_attitude_error``
against the attitude it commands, ``f_d_norm``); a metric of an entry the controller does not
report is None.
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np


def input_names(n: int) -> tuple[str, ...]:
    """Names of the inputs ``[f, mu, tau]`` of a robot with ``n`` arm joints."""
    return ("thrust", "mu_x", "mu_y", "mu_z") + tuple(f"tau_{i}" for i in range(1, n + 1))

_ERRORS = {
    # metric name -> entry (the tracking errors', but base_attitude_error: the controller's)
    "ee_position_error_m": "ee_position_error",
    "ee_orientation_error_rad": "ee_orientation_error",
    "com_position_error_m": "com_error",
    "base_attitude_error_rad": "base_attitude_error",
}


#: The paper allows saturation "in a very short initial time interval": the saturated time
#: after this instant (s) is reported on its own.
SATURATION_GRACE_S = 0.5


def saturated_after_key(grace: float = SATURATION_GRACE_S) -> str:
    """The metrics.json key of the saturated time after ``grace`` seconds."""
    return f"saturated_s_after_{grace:g}s"


def phase_edges(disturbance_windows: list[tuple[float, float]], duration: float) -> list[float]:
    """Phase boundaries: 0, every window edge inside the run, and the end."""
    inner = sorted({t for w in disturbance_windows for t in w if 0.0 < t < duration})
    return [0.0] + inner + [duration]


def compute_metrics(t: np.ndarray, entries: Mapping[str, np.ndarray], applied: np.ndarray,
                    lower: np.ndarray, upper: np.ndarray, edges: list[float],
                    log_period: float, saturation_grace: float = SATURATION_GRACE_S) -> dict:
    """Per-phase RMS/max errors, assumption margins and saturated time.

    Args:
        t: sample times (N); entries: ``{name: (N, size)}``, the tracking errors and the
        controller's ``base_attitude_error`` and ``f_d_norm`` if it reports them (module
        docstring; a metric of a missing entry is None); applied: (N, 4 + n) inputs that
        reached the plant; lower/upper: (4 + n) input limits; edges: phase boundaries (s).
        saturation_grace: the saturated time after this instant is reported separately, as
        the paper allows saturation only in a short initial interval.
    """
    names = input_names(applied.shape[1] - 4)
    bounds = np.abs(np.concatenate([lower, upper]))
    tol = 1e-9 * max(1.0, bounds[np.isfinite(bounds)].max(initial=1.0))
    at_limit = (applied <= lower + tol) | (applied >= upper - tol)
    phases = []
    for k, (a, b) in enumerate(zip(edges[:-1], edges[1:])):
        last = k == len(edges) - 2
        mask = (t >= a) & ((t <= b) if last else (t < b))
        phase: dict[str, Any] = {"start_s": a, "end_s": b, "samples": int(mask.sum())}
        if mask.any():
            for key, name in _ERRORS.items():
                phase[key] = _rms_and_max(entries.get(name), mask)
            phase["min_sigma_min_J3"] = _min_or_none(entries.get("sigma_min_J3"), mask)
            phase["min_f_d_norm_N"] = _min_or_none(entries.get("f_d_norm"), mask)
            phase["saturated_s"] = dict(zip(names,
                                            (at_limit[mask].sum(axis=0) * log_period).tolist()))
        phases.append(phase)
    late = t >= saturation_grace
    return {
        "phases": phases,
        "saturated_s_total": dict(zip(names,
                                      (at_limit.sum(axis=0) * log_period).tolist())),
        saturated_after_key(saturation_grace): dict(
            zip(names, (at_limit[late].sum(axis=0) * log_period).tolist())),
        # None when nothing was logged (a run stopped at t = 0).
        "min_sigma_min_J3": _min_or_none(entries.get("sigma_min_J3")),
        "min_f_d_norm_N": _min_or_none(entries.get("f_d_norm")),
        # Over the run (the phases keep the keys they had before the tracking errors).
        "heading_error_rad": _rms_and_max(entries.get("heading_error")),
    }


#: Seconds after a disturbance window's end that still count as its response: the CoM error
#: of Table II's gains peaks about 0.2 s after the 4-5 s force ends (the attitude loop, k_R/k_w
#: = 1.25 1/s, tilts the thrust slowly), and the removal of a wrench is a step of its own.
RESPONSE_TAIL_S = 1.0


def disturbance_response(t: np.ndarray, entries: Mapping[str, np.ndarray],
                         windows: list[tuple[str, float, float]],
                         tail: float = RESPONSE_TAIL_S) -> list[dict]:
    """Peak end-effector and CoM position errors in each disturbance's response.

    For each window ``(target, start, stop)`` the peaks are taken over
    ``[start, stop + tail]``, cut at the next window's start (so one response does not see the
    next disturbance). ``ee_to_com_peak_ratio`` tests the paper's claim that a force on the
    helicopter barely moves the end effector (Fig. 3 against Fig. 4). Peaks are None when the
    log does not reach the window; a response whose log ends before ``evaluated_s`` does (a run
    stopped by a failure, or one that ends inside it) has ``"partial": true`` and
    ``"log_end_s"``, its peaks being those of the part logged (the key is absent otherwise).
    ``entries``: the tracking errors by name (``{name: (N,
    size)}``, :mod:`aerial_drake.simulation.tracking`).
    """
    ee = entries["ee_position_error"][:, 0]
    com = entries["com_error"][:, 0]
    starts = sorted(s for _, s, _ in windows)
    out = []
    for target, start, stop in windows:
        later = [s for s in starts if s > start]
        end = min([stop + tail] + later)
        mask = (t >= start) & (t <= end)
        ee_peak: float | None = None
        com_peak: float | None = None
        ratio: float | None = None
        if mask.any():
            ee_peak, com_peak = float(ee[mask].max()), float(com[mask].max())
            ratio = ee_peak / com_peak if com_peak > 0 else None
        response = {"target": target, "window_s": [start, stop], "evaluated_s": [start, end],
                    "ee_position_error_peak_m": ee_peak, "com_error_peak_m": com_peak,
                    "ee_to_com_peak_ratio": ratio}
        if mask.any() and float(t[-1]) < end - 1e-9:  # cut short: say so (not as if complete)
            response.update(partial=True, log_end_s=float(t[-1]))
        out.append(response)
    return out


def rotor_metrics(speeds: np.ndarray, drive_torque: np.ndarray, commanded: np.ndarray,
                  names: tuple[str, ...] = ("left", "right")) -> dict:
    """Speed range and drive torque of each rotor (the "rotors" plant).

    Args:
        speeds: (N, k) rotor joint speeds (rad/s); drive_torque: (N, k) the drive's output
        (N m); commanded: (k) the speeds the drive holds (rad/s).
    """
    out: dict[str, dict] = {}
    if len(speeds) == 0:  # nothing logged (a run stopped at t = 0)
        return out
    for i, name in enumerate(names[:speeds.shape[1]]):
        w, tau = speeds[:, i], drive_torque[:, i]
        out[name] = {
            "commanded_speed_rad_s": float(commanded[i]),
            "speed_min_rad_s": float(w.min()),
            "speed_max_rad_s": float(w.max()),
            "speed_max_deviation_rad_s": float(np.abs(w - commanded[i]).max()),
            "drive_torque_rms_N_m": float(np.sqrt(np.mean(tau ** 2))),
            "drive_torque_max_abs_N_m": float(np.abs(tau).max()),
        }
    return out


def limits_by_input(lower: np.ndarray, upper: np.ndarray) -> dict:
    """``{input name: [lower, upper]}``, None for an unbounded side (JSON has no infinity)."""
    def finite(x):
        return float(x) if np.isfinite(x) else None
    names = input_names(len(lower) - 4)
    return {name: [finite(lo), finite(hi)] for name, lo, hi in zip(names, lower, upper)}


def _rms_and_max(x: np.ndarray | None, mask: np.ndarray | None = None) -> dict | None:
    """RMS and max of the entry ``x`` (N, 1) (at ``mask``); None for an entry not reported
    or nothing logged."""
    if x is None:
        return None
    e = (x if mask is None else x[mask])[:, 0]
    return {"rms": float(np.sqrt(np.mean(e ** 2))), "max": float(e.max())} if e.size else None


def _min_or_none(x: np.ndarray | None, mask: np.ndarray | None = None) -> float | None:
    """The least value of the entry ``x`` (at ``mask``); None for an entry not reported or
    nothing logged (a run stopped at t = 0)."""
    if x is None:
        return None
    x = x if mask is None else x[mask]
    return float(x.min()) if x.size else None
