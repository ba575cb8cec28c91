"""Tracking errors from the plant's state and the references, whichever controller runs.

What the metrics, plots and studies read: the errors of the centre of mass, the end effector
and the base's heading, and the margin of Assumption 1, computed from the rigid state of the
plant (``[q; v]`` of the controller's model, ``AerialManipulator.rigid_state_indices`` of the
simulated plant) and the three references, never from a controller's internals. A
controller's own quantities (the attitude it commands, |f_d|, its Lyapunov function, ...) stay
in its ``diagnostics`` port.

The entries, :func:`tracking_layout` (name, size) pairs, World frame:

- ``x_tilde`` = x_g - x_d, ``x_tilde_dot`` = x_g_dot - x_d_dot: the system CoM of the model
  (the controller model's inertial parameters: with ``model_mismatch`` or a ``payload`` the
  simulated body's CoM differs from it, and x_d is a reference for the model's);
- ``y_tilde``: the task error of :func:`aerial_drake.control.law.task_error` (n rows);
- ``sigma_min_J3``: sigma_min(J_3), J_3 the task Jacobian's arm columns in the decoupled
  coordinates (3): Assumption 1's margin, a property of the posture and the task;
- ``com_error`` = |x_tilde|, ``ee_position_error`` = |p_E - p_ed|, ``ee_orientation_error`` =
  the angle of R_E R_ed^T (rad), of the whole end-effector pose whatever rows the task tracks;
- ``heading_error``: the angle (rad, in [0, pi]) about the base's z axis b3 from its x axis
  to the heading reference b1d projected on the plane normal to b3 (Lee et al.'s b1 of R_d
  (13) with the base's own b3); 0 where b1d is along b3;
- ``base_tilt``: the angle of b3 from World z (rad).

With the paper's controller these equal its diagnostics of the same names to the bit (the
same compiled kernels in the same order, :class:`~aerial_drake.control.compiled.CompiledTracking`)
at the same state (to round-off with ``controller.kernel: fast``, whose arithmetic
differs); with sensing noise or delay they differ, as intended: these are the true errors,
at the simulated plant's state, the diagnostics the controller's view.

:class:`Tracking` computes them for a batch of samples (the runner's, once per run after the
simulation); :class:`TrackingErrors` is the same as a Drake system (output port
``tracking_errors``) for a user's diagram or a live view.
"""

from __future__ import annotations

import numpy as np
from pydrake.systems.framework import BasicVector, Context, LeafSystem

from aerial_drake.control.compiled import CompiledTracking, reference_law_reason
from aerial_drake.control.controller import task_jacobian
from aerial_drake.control.law import diagnostics_slices, rotation_angle, task_error
from aerial_drake.dynamics.decoupling import DecoupledDynamics
from aerial_drake.dynamics.kinematic_tree import KinematicTree, UnsupportedTree
from aerial_drake.robots.models import AerialManipulator
from aerial_drake.trajectories.reference import (
    COM_REFERENCE_SIZE,
    HEADING_REFERENCE_SIZE,
    task_reference_size,
    unpack_task_reference,
)

Layout = tuple[tuple[str, int], ...]


def tracking_layout(n: int) -> Layout:
    """The tracking errors' layout, (name, size) pairs, for a task of ``n`` rows."""
    return (("x_tilde", 3), ("x_tilde_dot", 3), ("y_tilde", n), ("sigma_min_J3", 1),
            ("com_error", 1), ("ee_position_error", 1), ("ee_orientation_error", 1),
            ("heading_error", 1), ("base_tilt", 1))


def entries(array: np.ndarray, layout: Layout | list) -> dict[str, np.ndarray]:
    """``{name: (N, size) columns}`` of a logged ``array`` of ``layout``."""
    return {name: array[:, cols] for name, cols in diagnostics_slices(layout).items()}


def heading_and_tilt(R: np.ndarray, b1d: np.ndarray) -> tuple[float, float]:
    """``heading_error`` and ``base_tilt`` (module docstring) of the base attitude ``R``."""
    proj = b1d - (R[:, 2] @ b1d) * R[:, 2]
    heading = abs(float(np.arctan2(R[:, 1] @ proj, R[:, 0] @ proj)))
    return heading, float(np.arccos(np.clip(R[2, 2], -1.0, 1.0)))


class Tracking:
    """The tracking errors on ``model`` (the controller's model, a finalized rigid
    :class:`AerialManipulator`): ``tracking(x, com, task, heading)`` gives one row of
    :func:`tracking_layout` per sample (rows of ``x`` and the references), or one vector for
    1-D inputs. By the compiled kernels where they serve the model, else by the reference
    implementation (:mod:`aerial_drake.dynamics.decoupling` and Drake's kinematics), or by
    that with ``compiled=False`` or where this process runs the reference law
    (:func:`aerial_drake.control.compiled.use_reference_law`)."""

    def __init__(self, model: AerialManipulator, *, compiled: bool = True):
        if model.task is None:
            raise ValueError("Tracking needs a finalized model (its task resolved)")
        self.model, self.task = model, model.task
        self.n = model.n
        self.layout = tracking_layout(self.n)
        self.width = sum(size for _, size in self.layout)
        frame = model.end_effector_frame
        self._compiled: CompiledTracking | None = None
        try:
            if compiled and reference_law_reason() is None:
                tree = KinematicTree.from_plant(model.plant, model.base_body)
                X_BE = frame.GetFixedPoseInBodyFrame()
                ee = (tree.index_of(frame.body()), X_BE.rotation().matrix(),
                      X_BE.translation())
                self._compiled = CompiledTracking(tree, model.plant.num_positions(), ee,
                                                  self.task)
        except UnsupportedTree:
            pass
        if self._compiled is None:
            self._dynamics = DecoupledDynamics(model.plant, model.base_body)
            self._context = model.plant.CreateDefaultContext()

    def __call__(self, x: np.ndarray, com: np.ndarray, task: np.ndarray,
                 heading: np.ndarray) -> np.ndarray:
        single = np.ndim(x) == 1
        X, C, T, H = (np.atleast_2d(np.asarray(a, dtype=float))
                      for a in (x, com, task, heading))
        if not len(X) == len(C) == len(T) == len(H):
            raise ValueError(f"the state and the references have {len(X)}, {len(C)}, "
                             f"{len(T)}, {len(H)} samples: give one row of each per sample")
        if self._compiled is not None:
            out = self._compiled(X, C, T, H, self.width)
        else:
            out = np.array([self._row(*sample) for sample in zip(X, C, T, H)]).reshape(
                -1, self.width)
        return out[0] if single else out

    def _row(self, x: np.ndarray, com: np.ndarray, task: np.ndarray,
             heading: np.ndarray) -> np.ndarray:
        """One sample by the reference implementation (what the compiled kernel computes)."""
        if not np.all(np.isfinite(x)):
            return np.full(self.width, np.nan)
        plant, ctx, frame = self.model.plant, self._context, self.model.end_effector_frame
        plant.SetPositionsAndVelocities(ctx, x)
        d = self._dynamics.compute(ctx)
        J6, J6_dot = self._dynamics.frame_jacobian(d, frame)
        J_y, _ = task_jacobian(self.task, J6, J6_dot, plant.num_velocities())
        J3 = (J_y @ d.T_inv)[:, 6:]
        X_WE = frame.CalcPoseInWorld(ctx)
        ref = unpack_task_reference(task)
        y_t, R_err = task_error(X_WE.translation(), X_WE.rotation().matrix(),
                                x[list(self.task.joint_positions)], ref.p_ed, ref.R_ed,
                                ref.q_jd, self.task.rows)
        x_t, x_t_dot = d.p_WG - com[0:3], d.xi[:3] - com[3:6]
        heading_error, tilt = heading_and_tilt(d.R, heading[0:3])
        return np.concatenate([
            x_t, x_t_dot, y_t,
            [np.linalg.svd(J3, compute_uv=False)[-1], np.linalg.norm(x_t),
             np.linalg.norm(X_WE.translation() - ref.p_ed), rotation_angle(R_err),
             heading_error, tilt]])


class TrackingErrors(LeafSystem):
    """The tracking errors (:func:`tracking_layout`) as a Drake system, for a diagram or a
    live view; the runner computes the same from its log instead (no system in the loop).

    Input ports: ``state`` (the rigid state ``[q; v]`` of ``model``, e.g. a simulated plant's
    state through ``rigid_state_indices``), ``com_reference``, ``task_reference``,
    ``heading_reference`` (as the reference generator gives them). Output port:
    ``tracking_errors``.
    """

    def __init__(self, model: AerialManipulator):
        super().__init__()
        self._tracking = Tracking(model)
        self.layout = self._tracking.layout
        plant = model.plant
        assert model.task is not None  # (Tracking checked)
        self._inputs = [
            self.DeclareVectorInputPort("state",
                                        plant.num_positions() + plant.num_velocities()),
            self.DeclareVectorInputPort("com_reference", COM_REFERENCE_SIZE),
            self.DeclareVectorInputPort("task_reference",
                                        task_reference_size(model.task.n_joints)),
            self.DeclareVectorInputPort("heading_reference", HEADING_REFERENCE_SIZE)]
        self.DeclareVectorOutputPort("tracking_errors", self._tracking.width, self._calc)

    def _calc(self, context: Context, output: BasicVector) -> None:
        output.SetFromVector(self._tracking(*(port.Eval(context) for port in self._inputs)))
