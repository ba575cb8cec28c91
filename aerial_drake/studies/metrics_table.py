"""A run's metrics (metrics.json's dict) as flat named numbers, one column each in a study's
table: ``phase{k}.{error}.{rms|max}``, ``phase{k}.min_sigma_min_J3``, ``window{w}.{peak}``,
``saturated_after.{input}`` and the run-wide scalars."""

from __future__ import annotations

import math
from typing import Any

from aerial_drake.simulation.metrics import input_names, phase_edges
from aerial_drake.simulation.scenarios import Scenario, robot_facts

PHASE_ERRORS = ("ee_position_error_m", "ee_orientation_error_rad", "com_position_error_m",
                "base_attitude_error_rad")
PHASE_SCALARS = ("min_sigma_min_J3", "min_f_d_norm_N")
WINDOW_PEAKS = ("ee_position_error_peak_m", "com_error_peak_m", "ee_to_com_peak_ratio")
RUN_SCALARS = ("simulated_time_s", "min_sigma_min_J3", "min_f_d_norm_N")

#: What a study keeps unless its file says otherwise.
DEFAULT_METRICS = ("simulated_time_s", "min_sigma_min_J3", "min_f_d_norm_N",
                   "phase*.ee_position_error_m.*", "phase*.com_position_error_m.*",
                   "phase*.base_attitude_error_rad.max", "phase*.ee_orientation_error_rad.max",
                   "window*.*_peak_m", "saturated_after.*")


#: metrics.json's ``contact`` entries a study's table can keep (``contact.NAME``;
#: aerial_drake.simulation.contact_metrics): the force task's and any run's touch.
CONTACT_SCALARS = ("contact_time_s", "first_contact_s", "contact_transitions_run",
                   "peak_contact_force_N", "peak_pressing_force_N", "force_mean_N",
                   "force_error_max_rel", "force_error_rms_rel", "contact_lost_s",
                   "contact_transitions", "tangential_error_max_m", "tangential_error_rms_m",
                   "slip_m", "friction_ratio_max")


def _number(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value) if math.isfinite(value) else None


def flatten_metrics(metrics: dict) -> dict[str, float | None]:
    """The metrics as ``{column: number or None}`` (module docstring)."""
    flat: dict[str, float | None] = {k: _number(metrics.get(k)) for k in RUN_SCALARS}
    for k, phase in enumerate(metrics.get("phases", [])):
        for name in PHASE_ERRORS:
            for stat in ("rms", "max"):
                flat[f"phase{k}.{name}.{stat}"] = _number((phase.get(name) or {}).get(stat))
        for name in PHASE_SCALARS:
            flat[f"phase{k}.{name}"] = _number(phase.get(name))
    for w, window in enumerate(metrics.get("disturbance_response", [])):
        for name in WINDOW_PEAKS:
            flat[f"window{w}.{name}"] = _number(window.get(name))
    for name, value in (metrics.get("contact") or {}).items():  # an environment's run
        if name in CONTACT_SCALARS:
            flat[f"contact.{name}"] = _number(value)
    late: dict = next((v for k, v in metrics.items() if k.startswith("saturated_s_after")), {})
    for name, value in late.items():
        flat[f"saturated_after.{name}"] = _number(value)
    return flat


def metric_names(scenario: Scenario) -> list[str]:
    """Every column :func:`flatten_metrics` gives for a run of ``scenario`` (its phases from
    its windows; random windows that add phases are not counted)."""
    windows = [(d.start, d.stop) for d in scenario.disturbances]
    n_phases = len(phase_edges(windows, scenario.duration)) - 1
    template = {
        "phases": [{name: {"rms": 0.0, "max": 0.0} for name in PHASE_ERRORS}
                   | {name: 0.0 for name in PHASE_SCALARS} for _ in range(n_phases)],
        "disturbance_response": [{name: 0.0 for name in WINDOW_PEAKS}
                                 for _ in scenario.disturbances],
        "saturated_s_after_": {name: 0.0 for name in input_names(robot_facts(scenario).n)},
    } | {name: 0.0 for name in RUN_SCALARS}
    if scenario.environment.directives:
        template["contact"] = {name: 0.0 for name in CONTACT_SCALARS}
    return list(flatten_metrics(template))
