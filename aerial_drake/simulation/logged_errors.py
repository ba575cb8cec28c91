"""The tracking errors of a run computed from its log, for a controller other than the paper's.

A controller reports only its own diagnostics (:mod:`aerial_drake.control.interface`); the
metrics, plots and studies read the paper law's layout
(:func:`aerial_drake.control.law.diagnostics_layout`). For any other controller the runner
builds that layout here, after the run, from the logged plant state and references: the
errors (``x_tilde``, ``x_tilde_dot``, ``y_tilde``, ``com_error``, ``ee_position_error``,
``ee_orientation_error``) by the paper controller's definitions on the controller's rigid
model, the controller's own entries of the same name and size copied in (``e_R``,
``base_attitude_error``, ...), the rest NaN. A stand-in until the tracking errors are
measured in the loop by a simulation-side system for every controller alike (issue 26).
"""

from __future__ import annotations

import numpy as np

from aerial_drake.control.interface import diagnostics_layout_of
from aerial_drake.control.law import (
    diagnostics_layout,
    diagnostics_size,
    diagnostics_slices,
    rotation_angle,
    task_error,
)
from aerial_drake.robots.models import AerialManipulator
from aerial_drake.simulation.diagram import ClosedLoop
from aerial_drake.trajectories.reference import unpack_com_reference, unpack_task_reference

#: The entries computed here from the state and the references.
STATE_ERRORS = ("x_tilde", "x_tilde_dot", "y_tilde", "com_error", "ee_position_error",
                "ee_orientation_error")


def with_paper_layout(arrays: dict[str, np.ndarray], loop: ClosedLoop,
                      ) -> dict[str, np.ndarray]:
    """The run's log ``arrays`` with ``diagnostics`` in the paper law's layout: as logged for
    the paper controller; for another, its own under ``controller_diagnostics`` and
    ``diagnostics`` from :func:`paper_layout_diagnostics`."""
    own_layout = diagnostics_layout_of(loop.controller)
    if own_layout == diagnostics_layout(loop.n_arm):
        return arrays
    arrays = dict(arrays, controller_diagnostics=arrays["diagnostics"])
    rigid = arrays["plant_state"][:, loop.simulated_plant.rigid_state_indices]
    arrays["diagnostics"] = paper_layout_diagnostics(
        loop.controller_model, rigid, arrays["com_reference"], arrays["task_reference"],
        arrays["controller_diagnostics"], own_layout)
    return arrays


def paper_layout_diagnostics(model: AerialManipulator, rigid_states: np.ndarray,
                             com_reference: np.ndarray, task_reference: np.ndarray,
                             own: np.ndarray, own_layout: tuple[tuple[str, int], ...],
                             ) -> np.ndarray:
    """(N, diagnostics_size(n)) rows in the paper law's layout (module docstring).

    Args:
        model: the controller's rigid model (its task gives n and the rows).
        rigid_states: (N, nq + nv) the model's state at each logged sample.
        com_reference, task_reference: (N, ...) the logged packed references.
        own: (N, k) the controller's own diagnostics, named by ``own_layout``.
    """
    task = model.task
    assert task is not None  # a finalized model
    n = task.n
    out = np.full((len(rigid_states), diagnostics_size(n)), np.nan)
    paper = diagnostics_slices(n)
    sizes = dict(diagnostics_layout(n))
    for name, sl in diagnostics_slices(own_layout).items():
        if name in paper and name not in STATE_ERRORS and sizes[name] == sl.stop - sl.start:
            out[:, paper[name]] = own[:, sl]
    plant, frame = model.plant, model.end_effector_frame
    ctx = plant.CreateDefaultContext()
    joints = list(task.joint_positions)
    for k, x in enumerate(rigid_states):
        if not np.all(np.isfinite(x)):
            continue  # the run diverged here: the errors stay NaN
        plant.SetPositionsAndVelocities(ctx, x)
        x_d = unpack_com_reference(com_reference[k])
        ref = unpack_task_reference(task_reference[k])
        X_WE = frame.CalcPoseInWorld(ctx)
        x_t = plant.CalcCenterOfMassPositionInWorld(ctx) - x_d[0]
        y_t, R_err = task_error(X_WE.translation(), X_WE.rotation().matrix(), x[joints],
                                ref.p_ed, ref.R_ed, ref.q_jd, task.rows)
        row = out[k]
        row[paper["x_tilde"]] = x_t
        row[paper["x_tilde_dot"]] = (plant.CalcCenterOfMassTranslationalVelocityInWorld(ctx)
                                     - x_d[1])
        row[paper["y_tilde"]] = y_t
        row[paper["com_error"]] = np.linalg.norm(x_t)
        row[paper["ee_position_error"]] = np.linalg.norm(X_WE.translation() - ref.p_ed)
        row[paper["ee_orientation_error"]] = rotation_angle(R_err)
    return out
