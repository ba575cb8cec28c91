"""Finding where a run went non-finite, and guessing why, after the run (no cost in the loop).

The loop itself stops at the first non-finite value: the controller refuses a non-finite
state at each evaluation (``FloatingPointError``), Drake refuses a NaN force on a body, and
the runner checks the plant state at each progress pause. What stopped it is then located in
the log here: the first sample holding a non-finite value, in which signal, and the
scenario's numbers that likely caused it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

#: The logged signals searched for the first non-finite value, in the loop's order (the
#: references are computed from the time alone and finite by construction; a controller's
#: diagnostics are its own extras, which may be NaN where it does not define them).
CHECKED_SIGNALS = ("plant_state", "command", "applied_command", "rotor_drive_torque")


def first_non_finite_sample(arrays: dict[str, np.ndarray]) -> tuple[int, str] | None:
    """Index of the first logged sample with a non-finite value, and the signal holding it
    (the plant state first at equal index), if any. Scans the log once, after the run: no cost
    during the simulation."""
    first: tuple[int, str] | None = None
    for name in CHECKED_SIGNALS:
        if name not in arrays or arrays[name].size == 0:
            continue
        bad = ~np.all(np.isfinite(arrays[name]), axis=1)
        if bad.any() and (first is None or int(np.argmax(bad)) < first[0]):
            first = (int(np.argmax(bad)), name)
    return first


def cut_at_divergence(arrays: dict[str, np.ndarray], index: int, signal_name: str,
                      cause: str) -> tuple[dict[str, np.ndarray], float, str]:
    """The log up to its first non-finite sample (at ``index``, in ``signal_name``), that
    sample's time and the failure message. The first non-finite sample is where the run went
    wrong, whatever stopped it later, so the log ends there, as the message says."""
    arrays = {k: v[:index + 1] for k, v in arrays.items()}
    t = float(arrays["t"][index])
    return arrays, t, (f"t = {t:.4f} s: {SIGNAL_MEANING[signal_name]} (first non-finite "
                       f"signal: '{signal_name}'); {cause}")


def likely_cause(scenario: Any) -> str:
    """A guess at why a run went non-finite, from the scenario's numbers far above the
    shipped scenarios' (the checks' ranges allow them; the dynamics may not)."""
    suspects = []
    g = scenario.gains
    for name in ("K_x", "D_x", "Lambda2_bar", "K_y", "K_z"):
        if max(getattr(g, name)) > 1e4:
            suspects.append(f"gains.{name}")
    if max(g.k_R, g.k_w) > 1e4:
        suspects.append("gains.k_R/k_w")
    for i, d in enumerate(scenario.disturbances):
        if max(abs(x) for x in [*d.force, *d.torque]) > 1e3:
            suspects.append(f"disturbances[{i}]")
    if scenario.rotors.drive_gain > 1e3 or abs(scenario.rotors.speed) > 1e3:
        suspects.append("rotors")
    if scenario.simulator.max_step_size > 1e-2:
        suspects.append("simulator.max_step_size")
    if suspects:
        return (f"likely cause: {', '.join(suspects)} far above the shipped scenarios' values "
                "(the closed loop is too stiff or too strongly pushed for the integrator)")
    return ("likely cause: the closed loop diverged (an unstable or saturated loop, or an "
            "integration step too long for its stiffness: try a smaller "
            "simulator.max_step_size)")


def first_non_finite_output(loop: Any, root_context: Any) -> str | None:
    """The first of the loop's checked signals whose value at ``root_context`` (where a Drake
    error stopped the run, between two logged samples) is not finite, if any."""
    for name in CHECKED_SIGNALS:
        if not loop.has_output_port(name):
            continue
        port = loop.output_port(name)
        try:
            value = port.Eval(port.get_system().GetMyContextFromRoot(root_context))
        except Exception:  # the value itself cannot be computed there: that one
            return name
        if not np.all(np.isfinite(np.asarray(value))):
            return name
    return None


#: What a first non-finite signal most often means.
SIGNAL_MEANING = {
    "plant_state": "the plant state became non-finite (diverged)",
    "command": "the control law's command became non-finite",
    "applied_command": "the command applied to the plant (after lag and saturation) became "
                       "non-finite",
    "rotor_drive_torque": "the rotor drive's torque became non-finite",
}
