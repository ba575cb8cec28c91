"""Why a run failed: one cause per failed run, classified from its log and its failure message
(metrics.json's ``failure_cause``, a study table's ``failure_cause`` column; docs/reliability.md,
"Why a run failed").

:func:`classify_failure` takes numpy arrays (the logged inputs up to the failure, the tracking
errors' sigma_min(J_3)), the input limits and the arm's stretch at the failure
(:func:`arm_stretch`, the one function here that reads a plant) and returns
``{"cause", "detail", ...figures}``, or None for a completed run. The first that holds, in order:

1. ``interrupted``: a signal stopped the run (the message starts "interrupted").
2. ``joint_limit``: the message names a joint limit ("joint limit: ").
3. ``divergence``: a signal became non-finite (the runner's "first non-finite signal", the
   controller's "not finite", Drake's "NaN").
4. ``reach``: a singular-Jacobian stop (Assumption 1, a baseline's "task Jacobian is
   singular", or paper_plus's damped law losing control "near the singularity of J_3") with
   the arm stretched, its elbow's span :data:`STRETCHED` or more of its largest
   (:func:`arm_stretch`), reached by a steady fall of sigma_min(J_3): at least
   :data:`STEADY_SHARE` of its steps over the last :data:`STEADY_WINDOW_S` decreasing. The
   task pulled the arm straight (the elbow under a push that moves the CoM away from the end
   effector), not a shake through a singular posture.
5. ``oscillation``: over the last :data:`OSCILLATION_WINDOW_S`, one frequency of at least
   :data:`OSCILLATION_MIN_HZ` carries :data:`PEAK_SHARE` or more of an applied input's
   detrended power (Hann-windowed FFT, the peak's bin and two either side), with an RMS of at
   least :data:`OSCILLATION_AMPLITUDE` of that input's limit; the input with the largest such
   RMS (relative to its limit) names the frequency (e.g. 13 Hz: an unbalanced rotor). The
   applied inputs (after lag and saturation), not the law's command: what shook the robot;
   a command past a limit is not applied, and it grows without bound as sigma_min(J_3) falls
   (the law's terms in J_3^-1), which no oscillation explains.
6. ``torque_saturation``: inputs at a limit for :data:`SATURATED_SHARE` or more of the last
   :data:`SATURATION_WINDOW_S` (e.g. the wrist's tau_6, tau_7 holding an end-effector wrench,
   or the body torques); all of them named.
7. ``other``: none of these (e.g. an Assumption 2 stop with no such evidence).

Reach comes before the oscillation and the saturation because it is the most specific evidence
(a posture at the stop and a steady approach to it) and a stretched arm may be shaken and
saturated as well; an oscillation as large as these drives inputs into their limits, so it
comes before the saturation it causes. The figures of every test are in the result whatever
the cause (None where not computed: a log too short, a quantity not logged).
"""

from __future__ import annotations

import re
from typing import Any

import numpy as np

CAUSES = ("joint_limit", "divergence", "torque_saturation", "reach", "oscillation",
          "interrupted", "other")

#: Inputs at a limit for this share of the window or more count as saturated: half the
#: time, so a limit touched by an oscillation's peaks alone does not count.
SATURATED_SHARE = 0.5
#: The window before the failure over which saturation is measured (s): the last half second,
#: what decides a failure, longer than the 0.1 s rise time of the shipped rotor lag.
SATURATION_WINDOW_S = 0.5
#: The window of the applied inputs' spectrum (s): 2 s resolve 0.5 Hz and hold 4 periods
#: of the slowest oscillation counted.
OSCILLATION_WINDOW_S = 2.0
#: The slowest oscillation counted (Hz): above the references' content (the paper's fastest
#: term turns at 3 rad/s, 0.48 Hz), 4 periods in the window.
OSCILLATION_MIN_HZ = 2.0
#: Share of an input's detrended power in the peak (its bin and two either side) for "one
#: peak": more than half, as a sinusoid's Hann-windowed power is 99 % within those bins.
PEAK_SHARE = 0.5
#: The oscillation's RMS relative to the input's limit for "large": a quarter of the limit
#: (50 N m of the paper robot's 200 N m body torques; unperturbed runs show about 4 N m).
OSCILLATION_AMPLITUDE = 0.25
#: The window of sigma_min(J_3)'s approach to the limit (s).
STEADY_WINDOW_S = 0.3
#: Share of sigma_min(J_3)'s steps that decrease over that window for a steady fall (a shake
#: at 13 Hz makes about 65 %; a stretching arm 100 %).
STEADY_SHARE = 0.9
#: Stretch (:func:`arm_stretch`: the elbow's span over its largest) for "stretched": 0.99 is
#: an elbow within 16 degrees of straight between two equal links (cos 8 deg).
STRETCHED = 0.99


def classify_failure(failure: str | None, *, t: np.ndarray, applied: np.ndarray,
                     lower: np.ndarray, upper: np.ndarray, names: tuple[str, ...],
                     sigma_min_J3: np.ndarray | None = None, sigma_limit: float = 1e-3,
                     stretch: float | None = None) -> dict[str, Any] | None:
    """The cause of a failed run (module docstring), or None if ``failure`` is None.

    Args:
        failure: the run's failure message (metrics.json's ``failure``).
        t: the sample times (N) up to the failure; applied: (N, m) the inputs that reached
            the plant (log.npz's ``applied_command``); lower, upper: (m) the inputs' limits
            (finite: the actuators' ratings); names: the m inputs' names.
        sigma_min_J3: (N) Assumption 1's margin at each sample (None: not logged);
            sigma_limit: the scenario's threshold of it.
        stretch: :func:`arm_stretch` at the failure (None: not known).

    The result's ``time_s`` is the failure's time: the message's "t = ... s", else the last
    sample's (None without either).
    """
    if failure is None:
        return None
    message = str(failure)
    t = np.asarray(t, dtype=float)
    stated = re.search(r"t = ([-+0-9.eE]+) s", message)  # the runner's "t = 12.3456 s: ..."
    figures: dict[str, Any] = {"time_s": float(stated.group(1)) if stated else
                               float(t[-1]) if t.size else None}
    if message.startswith("interrupted") or ": interrupted (" in message:
        return _result("interrupted", "a signal stopped the run", figures)
    if "joint limit: " in message:
        joint = message.split("joint limit: ", 1)[1]
        return _result("joint_limit", joint, figures)
    if any(mark in message for mark in ("non-finite", "not finite", "NaN")):
        return _result("divergence", "the simulation diverged (a non-finite signal)", figures)
    applied = np.asarray(applied, float)
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    figures.update(_steadiness(t, sigma_min_J3, stretch))
    figures.update(_oscillation(t, applied, upper - lower, names))
    figures.update(_saturation(t, applied, lower, upper, names))
    if (singular_stop(message) and figures["arm_stretch"] is not None
            and figures["arm_stretch"] >= STRETCHED
            and (figures["sigma_steady_share"] or 0.0) >= STEADY_SHARE):
        return _result("reach", (
            f"the arm stretched, its elbow's span {figures['arm_stretch']:.3f} of its largest, as "
            f"sigma_min(J_3) fell steadily "
            + (f"to the limit {sigma_limit:g} " if "Assumption 1" in message else "") +
            f"({100 * figures['sigma_steady_share']:.0f} % of the last {STEADY_WINDOW_S:g} s' "
            "steps decreasing)"), figures)
    if (figures["oscillation_amplitude_ratio"] or 0.0) >= OSCILLATION_AMPLITUDE:
        return _result("oscillation", (
            f"the applied inputs oscillate at {figures['dominant_frequency_hz']:.1f} Hz "
            f"({figures['oscillation_input']}: RMS {figures['oscillation_amplitude_ratio']:.2f}"
            f" of its limit, {100 * figures['oscillation_peak_share']:.0f} % of its power in "
            f"the peak over the last {OSCILLATION_WINDOW_S:g} s)"), figures)
    if figures["saturated_inputs"]:
        shares = ", ".join(f"{name} {100 * figures['saturated_share'][name]:.0f} %"
                           for name in figures["saturated_inputs"])
        return _result("torque_saturation", (
            f"inputs at their limits over the last {SATURATION_WINDOW_S:g} s: {shares} of "
            "the time"), figures)
    return _result("other", "no joint limit, divergence, stretched arm, oscillation or "
                            "saturation found in the log", figures)


def singular_stop(message: str) -> bool:
    """Whether a failure message is a singular task Jacobian's stop: the paper law's
    Assumption 1 ("J_3 is singular"), a baseline's ("task Jacobian is singular") or the damped
    law's loss of control ("near the singularity of J_3", control.law.control_lost_message)."""
    return ("Assumption 1" in message or "is singular" in message
            or "near the singularity of J_3" in message)


def _result(cause: str, detail: str, figures: dict[str, Any]) -> dict[str, Any]:
    at = figures.get("time_s")
    when = f"t = {at:.4f} s: " if at is not None else ""
    return {"cause": cause, "detail": f"{cause} ({when}{detail})", **figures}


def _last(t: np.ndarray, seconds: float) -> np.ndarray:
    """The mask of the samples in the last ``seconds`` of the log."""
    return t >= t[-1] - seconds if t.size else np.zeros(0, bool)


def _saturation(t: np.ndarray, applied: np.ndarray, lower: np.ndarray, upper: np.ndarray,
                names: tuple[str, ...]) -> dict[str, Any]:
    """The inputs at (or past) a limit for :data:`SATURATED_SHARE` of the last window."""
    if not t.size:
        return {"saturated_inputs": [], "saturated_share": {}}
    recent = applied[_last(t, SATURATION_WINDOW_S)]
    scale = np.maximum(1.0, np.abs(np.concatenate([lower, upper]))[np.isfinite(
        np.concatenate([lower, upper]))].max(initial=1.0))
    tol = 1e-9 * scale  # as metrics.compute_metrics counts "at a limit"
    at_limit = (recent <= lower + tol) | (recent >= upper - tol)
    share = at_limit.mean(axis=0)
    return {"saturated_inputs": [n for n, s in zip(names, share) if s >= SATURATED_SHARE],
            "saturated_share": {n: float(s) for n, s in zip(names, share)}}


def _oscillation(t: np.ndarray, applied: np.ndarray, span: np.ndarray,
                 names: tuple[str, ...]) -> dict[str, Any]:
    """The largest one-peak oscillation of the applied inputs over the last window."""
    found: dict[str, Any] = {"dominant_frequency_hz": None, "oscillation_input": None,
                             "oscillation_amplitude_ratio": None,
                             "oscillation_peak_share": None}
    mask = _last(t, OSCILLATION_WINDOW_S)
    window = t[mask]
    # Too short a log for the slowest counted oscillation's four periods: no spectrum.
    if window.size < 8 or window[-1] - window[0] < 4.0 / OSCILLATION_MIN_HZ * 0.99:
        return found
    dt = float(np.median(np.diff(window)))
    freqs = np.fft.rfftfreq(window.size, dt)
    hann = np.hanning(window.size)
    best = 0.0
    for j, name in enumerate(names):
        if not (np.isfinite(span[j]) and span[j] > 0):
            continue  # no limit to measure it against
        x = applied[mask, j]
        x = x - np.polyval(np.polyfit(window - window[0], x, 1), window - window[0])
        power = np.abs(np.fft.rfft(x * hann)) ** 2
        total = float(power[1:].sum())  # all of the detrended signal's power but the mean
        power[freqs < OSCILLATION_MIN_HZ] = 0.0  # the peak is sought above the references'
        if total <= 0.0:
            continue
        k = int(np.argmax(power))
        if k == int(np.argmax(freqs >= OSCILLATION_MIN_HZ)):
            continue  # the edge of the band: leakage of slower content, not a peak
        peak = float(power[max(k - 2, 0):k + 3].sum()) / total
        # RMS of the part above OSCILLATION_MIN_HZ in the peak, against half the limit span
        # (the limit of a symmetric input).
        ratio = float(np.sqrt(peak * np.mean(x ** 2))) / (span[j] / 2.0)
        if peak >= PEAK_SHARE and ratio > best:
            best = ratio
            found.update(dominant_frequency_hz=float(freqs[k]), oscillation_input=name,
                         oscillation_amplitude_ratio=ratio, oscillation_peak_share=peak)
    return found


def _steadiness(t: np.ndarray, sigma: np.ndarray | None, stretch: float | None
                ) -> dict[str, Any]:
    """sigma_min(J_3) at the failure and the share of its last steps that decrease."""
    out: dict[str, Any] = {"sigma_min_J3": None, "sigma_steady_share": None,
                           "arm_stretch": stretch}
    if sigma is None or not t.size:
        return out
    sigma = np.asarray(sigma, dtype=float).reshape(len(t), -1)[:, 0]
    out["sigma_min_J3"] = float(sigma[-1])
    steps = np.diff(sigma[_last(t, STEADY_WINDOW_S)])
    if steps.size:
        out["sigma_steady_share"] = float(np.mean(steps < 0.0))
    return out


def arm_stretch(model: Any, q: np.ndarray) -> float | None:
    """How straight the elbow of ``model``'s arm (an
    :class:`~aerial_drake.robots.models.AerialManipulator`) is at the positions ``q`` of its
    plant, 1 fully stretched; None for an arm without two links.

    The points are the arm joints' origins then the end effector's; the links, the distances
    between successive points (fixed by the model). The elbow is the pair of successive
    non-zero links with the largest summed length, the upper arm and the forearm (the LWR's
    0.40 and 0.39 m, the UR3e's 0.24 and 0.21 m): the stretch is the distance between their
    far ends over its largest value as the joints between them turn (each swept over a full
    turn, twice in turn), so 1 whatever offsets the arm's links have."""
    plant = model.plant
    context = plant.CreateDefaultContext()
    frames = [j.frame_on_child() for j in model.arm_joints] + [model.end_effector_frame]
    positions = np.array(q, dtype=float)
    plant.SetPositions(context, positions)
    points = np.array([f.CalcPoseInWorld(context).translation() for f in frames])
    links = np.linalg.norm(np.diff(points, axis=0), axis=1)
    solid = [k for k, length in enumerate(links) if length > 1e-6]  # link k: point k to k+1
    pairs = [(k, m) for k, m in zip(solid[:-1], solid[1:])]
    if not pairs:
        return None
    first, second = max(pairs, key=lambda pair: links[pair[0]] + links[pair[1]])
    a, b = frames[first], frames[second + 1]

    def span(values: np.ndarray) -> float:
        plant.SetPositions(context, values)
        return float(np.linalg.norm(b.CalcPoseInWorld(context).translation()
                                    - a.CalcPoseInWorld(context).translation()))

    now = span(positions)
    # The joints whose angles change that distance: those strictly between the two ends.
    bends = [model.arm_position_indices[k] for k in range(first + 1, second + 1)]
    widest, best = positions.copy(), now
    for _ in range(2 if len(bends) > 1 else 1):
        for index in bends:
            for angle in np.linspace(-np.pi, np.pi, 361):
                trial = widest.copy()
                trial[index] = angle
                length = span(trial)
                if length > best:
                    widest, best = trial, length
    return now / best if best > 0 else None
