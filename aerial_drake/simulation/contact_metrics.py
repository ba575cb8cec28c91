"""Metrics of a run that touched its environment (metrics.json's ``contact``; docs/contact.md).

Read from the log's true contact wrench on the end effector (``contact_wrench``, what Drake
computed; :mod:`aerial_drake.simulation.contact`), not from the force sensor the controller
reads, and from the tracking errors. With a force task (``paper_force``) the force is judged
over the hold's last seconds (``FORCE_EVALUATION_S``, the issue's "last 3 s of the hold"),
and contact over the whole hold:

- ``force_error_max_rel``: the largest |F - F_d| / F_d, F the pressing force along the task's
  direction (minus the contact force's component along it);
- ``contact_lost_s``: time in the hold without contact; ``contact_transitions``: how often
  contact was made or lost in the hold, i.e. how often the pressing force changed sign
  between pushing (> 0) and none (chattering: a force that keeps dropping to zero);
- ``tangential_error_max_m``: the end effector's largest position error across the direction
  (the motion task's), over the hold; ``slip_m``: how far the contact point travelled across
  the direction over the hold (a press should not slide; a slide's is its path);
- ``friction_ratio_max``: the largest |F_t| / F_n in the hold (against the pair's friction
  coefficient: sliding where it reaches it).
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np

from aerial_drake.simulation.contact import contact_slices

#: The length of the hold's end over which the force is judged (s).
FORCE_EVALUATION_S = 3.0


def _float(x: Any) -> float | None:
    value = float(x)
    return value if np.isfinite(value) else None


def _transitions(mask: np.ndarray) -> int:
    return int(np.count_nonzero(np.diff(mask.astype(np.int8)))) if mask.size > 1 else 0


def contact_metrics(t: np.ndarray, wrench: np.ndarray, named: Mapping[str, np.ndarray],
                    task_rows: tuple[int, ...], force_task: Any | None,
                    log_period: float) -> dict:
    """metrics.json's ``contact`` (module docstring).

    Args:
        t: sample times (N); wrench: the log's ``contact_wrench`` (N, 10).
        named: the log's named entries (tracking errors, the controller's diagnostics).
        task_rows: the task's rows of y_full (rows 0-2: the end effector's World position).
        force_task: the ``controller.force`` section of a ``paper_force`` run, else None.
        log_period: the log's sample period (s).
    """
    s = contact_slices()
    force, point = wrench[:, s["force"]], wrench[:, s["point"]]
    touching = wrench[:, s["contacts"]][:, 0] > 0
    out: dict[str, Any] = {
        "contact_time_s": _float(np.count_nonzero(touching) * log_period),
        "first_contact_s": _float(t[np.argmax(touching)]) if touching.any() else None,
        "contact_transitions_run": _transitions(touching),
        "peak_contact_force_N": _float(np.linalg.norm(force, axis=1).max()) if len(t) else None,
    }
    if force_task is None:
        return out
    d = np.asarray(force_task.unit_direction(), float)
    pressing = -force @ d
    h0, h1 = force_task.hold()
    hold = (t >= h0) & (t <= h1)
    judged = hold & (t >= max(h0, h1 - FORCE_EVALUATION_S))
    goal = float(force_task.force)
    tangential = np.eye(3) - np.outer(d, d)
    out.update({
        "force_desired_N": goal,
        "hold_s": [h0, h1],
        "evaluated_s": [max(h0, h1 - FORCE_EVALUATION_S), h1],
        "peak_pressing_force_N": _float(pressing.max()) if len(t) else None,
    })
    if not judged.any():  # the run stopped before the window
        return out
    error = pressing[judged] - goal
    out.update({
        "force_mean_N": _float(pressing[judged].mean()),
        "force_error_max_rel": _float(np.abs(error).max() / goal),
        "force_error_rms_rel": _float(np.sqrt(np.mean(error ** 2)) / goal),
        "contact_lost_s": _float(np.count_nonzero(hold & ~touching) * log_period),
        "contact_transitions": _transitions(touching[hold]),
    })
    rows = [i for i, r in enumerate(task_rows) if r < 3]
    y_tilde = named.get("y_tilde")
    if y_tilde is not None and len(rows) == 3:
        e = y_tilde[:, rows] @ tangential  # the position error across the direction
        out["tangential_error_max_m"] = _float(np.linalg.norm(e[hold], axis=1).max())
        out["tangential_error_rms_m"] = _float(np.sqrt(np.mean(
            np.sum(e[hold] ** 2, axis=1))))
    in_hold = hold & touching
    if in_hold.any():
        p = point[in_hold] @ tangential
        out["slip_m"] = _float(np.linalg.norm(p - p[0], axis=1).max())
        f_t = np.linalg.norm(force[in_hold] @ tangential, axis=1)
        f_n = np.maximum(pressing[in_hold], 1e-9)
        out["friction_ratio_max"] = _float((f_t / f_n).max())
    return out
