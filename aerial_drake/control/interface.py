"""The controller interface: what the closed loop needs of any controller system.

The closed loop (:mod:`aerial_drake.simulation.diagram`) takes any Drake ``LeafSystem`` (or
``Diagram``) with these ports, by name:

Input ports (vector, sizes for the controller's model plant with ``n`` arm joints):
    - ``state``: ``[q; v]`` of the rigid model (``nq + nv``: quaternion base, then the arm).
    - ``com_reference`` (15), ``task_reference`` (24 + 3 n_j, n_j the task's joint
      components: 27 for the paper's task), ``heading_reference`` (9): as
      :class:`aerial_drake.trajectories.generator.ReferenceGenerator` produces them (layouts in
      :mod:`aerial_drake.trajectories.reference`).

Output ports:
    - ``command``: ``[f, mu (3), tau (n)]``, thrust along body z (N), body torques (N m, base
      frame), joint torques (N m): the inputs of (1).
    - ``diagnostics``: :func:`aerial_drake.control.law.diagnostics_layout`. The metrics read
      the errors from the run's tracking errors (:mod:`aerial_drake.simulation.tracking`, of
      the plant's state) and only ``base_attitude_error`` and ``f_d_norm`` from here, by
      name; every controller fills the error entries with the same definitions
      (:func:`error_diagnostics`): ``x_tilde = x_g - x_d`` (system CoM), ``y_tilde`` of
      :func:`aerial_drake.control.law.task_error`, ``com_error = |x_tilde|``,
      ``ee_position_error = |p_E - p_ed|``, ``ee_orientation_error`` = angle of
      ``R_E R_ed^T``, ``base_attitude_error`` = angle of ``R_d^T R_b`` with ``R_d`` the attitude
      the controller itself commands. Entries a controller does not define are NaN.

Optional attributes the runner uses when present: ``period`` (s; > 0 means the outputs are
held samples, as the paper's 1 kHz controller; then also ``hold_sample(context)`` and
``evaluate(x, com, task, heading) -> (command, diagnostics)``, for the log's alignment) and
``evaluations`` (a count, reported in metrics.json). A system without ``period`` is taken as
continuous (direct feedthrough).
"""

from __future__ import annotations

import numpy as np

from aerial_drake.control.law import (
    diagnostics_layout,
    diagnostics_size,
    diagnostics_slices,
    rotation_angle,
    task_error,
)
from aerial_drake.robots.task import TaskLayout
from aerial_drake.trajectories.reference import (
    COM_REFERENCE_SIZE,
    HEADING_REFERENCE_SIZE,
    task_reference_size,
)

INPUT_PORTS = ("state", "com_reference", "task_reference", "heading_reference")
OUTPUT_PORTS = ("command", "diagnostics")
#: The diagnostics entries every controller fills (:func:`error_diagnostics`); the others may
#: be NaN ("not defined by this controller").
REQUIRED_DIAGNOSTICS = ("x_tilde", "x_tilde_dot", "y_tilde", "com_error",
                        "base_attitude_error", "ee_position_error", "ee_orientation_error")


def required_diagnostics_columns(n: int) -> np.ndarray:
    """Column indices of :data:`REQUIRED_DIAGNOSTICS` in the diagnostics vector of a task of
    ``n`` rows."""
    sl = diagnostics_slices(n)
    return np.concatenate([np.arange(diagnostics_size(n))[sl[name]]
                           for name in REQUIRED_DIAGNOSTICS])


def port_sizes(num_states: int, n_arm: int, n_task_joints: int) -> dict[str, int]:
    """Each port's size for a model with ``num_states`` (nq + nv), ``n_arm`` joints and a task
    with ``n_task_joints`` joint components."""
    return {"state": num_states, "com_reference": COM_REFERENCE_SIZE,
            "task_reference": task_reference_size(n_task_joints),
            "heading_reference": HEADING_REFERENCE_SIZE,
            "command": 4 + n_arm, "diagnostics": diagnostics_size(n_arm)}


def check_controller_ports(system, num_states: int, n_arm: int, n_task_joints: int) -> None:
    """Raise ValueError naming the port if ``system`` lacks a port of the interface or has it
    with the wrong size."""
    sizes = port_sizes(num_states, n_arm, n_task_joints)
    name = system.get_name() or type(system).__name__
    for kind, names, has, get in (
            ("input", INPUT_PORTS, system.HasInputPort, system.GetInputPort),
            ("output", OUTPUT_PORTS, system.HasOutputPort, system.GetOutputPort)):
        for port in names:
            if not has(port):
                raise ValueError(
                    f"controller '{name}' has no {kind} port '{port}'; a controller needs the "
                    f"inputs {INPUT_PORTS} and outputs {OUTPUT_PORTS} "
                    "(aerial_drake.control.interface)")
            if get(port).size() != sizes[port]:
                raise ValueError(f"controller '{name}': {kind} port '{port}' has size "
                                 f"{get(port).size()}, the interface needs {sizes[port]}")


def error_diagnostics(*, task: TaskLayout, x_g: np.ndarray, x_g_dot: np.ndarray,
                      com_reference: np.ndarray, p_WE: np.ndarray, R_WE: np.ndarray,
                      q_j: np.ndarray, p_ed: np.ndarray, R_ed: np.ndarray, q_jd: np.ndarray,
                      R_b: np.ndarray, R_d: np.ndarray, **other) -> np.ndarray:
    """A diagnostics vector (:func:`diagnostics_layout`) with the errors the metrics read,
    by the paper controller's definitions, and ``other`` entries by name (``e_R=...``,
    ``sigma_min_J3=...``); the rest NaN.

    ``com_reference`` is the (5, 3) rows of x_d and its derivatives; ``R_b`` the base
    attitude, ``R_d`` the attitude the controller commands.
    """
    x_t = x_g - com_reference[0]
    y_t, R_err = task_error(p_WE, R_WE, q_j, p_ed, R_ed, q_jd, task.rows)
    entries = {"x_tilde": x_t, "x_tilde_dot": x_g_dot - com_reference[1], "y_tilde": y_t,
               "com_error": np.linalg.norm(x_t),
               "base_attitude_error": rotation_angle(R_d.T @ R_b),
               "ee_position_error": np.linalg.norm(p_WE - p_ed),
               "ee_orientation_error": rotation_angle(R_err)}
    layout = diagnostics_layout(task.n)
    unknown = set(other) - {n for n, _ in layout}
    if unknown:
        raise KeyError(f"no diagnostics entries {sorted(unknown)}; the layout has "
                       f"{[n for n, _ in layout]}")
    entries.update(other)
    out = np.full(diagnostics_size(task.n), np.nan)
    for key, sl in diagnostics_slices(task.n).items():
        if key in entries:
            out[sl] = entries[key]
    return out
