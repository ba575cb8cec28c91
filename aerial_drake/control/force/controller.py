"""``paper_force``: ``paper_plus`` (:mod:`aerial_drake.control.plus`) with a force task
along one direction (docs/contact.md, "The force task").

At each sample, the measured contact force (input ``contact_force``, the wrist sensor's, N,
World) gives the pressing force along the task's direction; the admittance
(:mod:`aerial_drake.control.force.admittance`) turns its error against the desired force
into a shift ``d`` of the end effector's reference along that direction, handed to the paper
law with its derivatives. The law's impedance, (18)-(21) with K_y and K_z, then presses the
tool on the surface with the force the admittance settles at; the other directions track
the motion reference. With ``feedforward`` the measured force also enters f_d of (10) as
paper_plus's F^, so the CoM holds its reference while the vehicle leans against the push.
"""

from __future__ import annotations

import numpy as np
from pydrake.systems.framework import Context

from aerial_drake.control.force.admittance import (
    admittance_acceleration,
    admittance_step,
    desired_force,
    pressing_force,
    shifted_task,
)
from aerial_drake.control.force.params import PAPER_FORCE, ForceTaskParams
from aerial_drake.control.plus.controller import PaperPlusController
from aerial_drake.robots.models import AerialManipulator

#: The admittance's discrete state group (d, d'), after paper_plus's integrators.
_ADMITTANCE = 3
#: paper_force's diagnostics after paper_plus's: the desired and the measured pressing force
#: (N), the reference's shift along the direction (m).
FORCE_DIAGNOSTICS = (("force_desired", 1), ("force_measured", 1), ("force_shift", 1))


class PaperForceController(PaperPlusController):
    """``paper_plus`` with the force task of ``force`` (module docstring). Input ports:
    ``paper_plus``'s and ``contact_force`` (3, N, World; unconnected: zero, no contact)."""

    def __init__(self, model: AerialManipulator, gains, plus, force: ForceTaskParams,
                 limits: tuple[np.ndarray, np.ndarray], **kwargs) -> None:
        force.validate()
        task = model.task
        assert task is not None
        if not any(r < 3 for r in task.rows):
            raise ValueError(f"controller.type {PAPER_FORCE} needs a task with the end "
                             "effector's position (its force task moves the position "
                             f"reference); the task is {list(task.labels)}")
        super().__init__(model, gains, plus, limits, extra_diagnostics=FORCE_DIAGNOSTICS,
                         **kwargs)
        self._force = force
        self._direction = np.asarray(force.unit_direction(), float)
        self._contact_port = self.DeclareVectorInputPort("contact_force", 3)
        # y~'s entries of the end effector's World x, y, z (all three, or None).
        position = {r: i for i, r in enumerate(task.rows) if r < 3}
        self._position_rows = ([position[r] for r in range(3)] if len(position) == 3
                               else None)
        self.DeclareDiscreteState(2)  # group _ADMITTANCE: (d, d')
        # (d, d') and the measured force this sample runs on; the latest sample's, for
        # evaluate_into.
        self._pending = self._latest_force = (np.zeros(2), np.zeros(3))

    @property
    def force_task(self) -> ForceTaskParams:
        return self._force

    def _run(self, t, x, com, task, heading, state, force, tau_hat, command, diagnostics):
        adm, measured = self._pending
        pressing = pressing_force(measured, self._direction)
        accel = admittance_acceleration(t, adm, pressing, self._force)
        task = shifted_task(task, self._direction, adm, accel)
        if self._force.feedforward:
            # The surface's push back along the direction, the force the task commands; the
            # friction across it answers the motion task's own push (feeding the whole
            # measured force gave the same force and path errors, UR3e wall press).
            force = force - pressing * self._direction
        super()._run(t, x, com, task, heading, state, force, tau_hat, command, diagnostics)
        d = self._slices
        diagnostics[d["force_desired"]] = desired_force(t, self._force)
        diagnostics[d["force_measured"]] = pressing
        diagnostics[d["force_shift"]] = adm[0]
        self._accel = accel

    def _integrated_task_error(self, y_tilde: np.ndarray) -> np.ndarray:
        """paper_plus's task integral (``controller.plus.task_integral_gain``) across the push
        only: along it the force loop is the integral (the admittance integrates the force
        error), and a second integral there winds up while the force builds (measured: a
        touch overshooting to 11.3 N for 10 N). Needs the task's three position rows; with
        fewer, y~ as it is."""
        rows = self._position_rows
        if rows is None:
            return y_tilde
        out = np.array(y_tilde, dtype=float)
        out[rows] -= (out[rows] @ self._direction) * self._direction
        return out

    def evaluate_into(self, t, x, com, task, heading, command, diagnostics) -> None:
        self._pending = self._latest_force
        super().evaluate_into(t, x, com, task, heading, command, diagnostics)

    def _step(self, context: Context, discrete_state, *, advance: bool) -> None:
        adm = np.array(context.get_discrete_state(_ADMITTANCE).value())
        measured = (np.array(self._contact_port.Eval(context), dtype=float)
                    if self._contact_port.HasValue(context) else np.zeros(3))
        self._pending = (adm, measured)
        super()._step(context, discrete_state, advance=advance)
        if advance:
            adm = admittance_step(adm, self._accel, self._h, self._force.max_shift)
            discrete_state.get_mutable_value(_ADMITTANCE)[:] = adm
        self._latest_force = (adm, measured)


def make_paper_force(scenario, model: AerialManipulator,
                     limits: tuple[np.ndarray, np.ndarray]) -> PaperForceController:
    """``paper_force`` on ``model`` from a scenario's fields (gains, controller.plus,
    controller.force, controller_period, the assumption limits) and the command ``limits``."""
    return PaperForceController(
        model, scenario.gains, scenario.controller.plus, scenario.controller.force, limits,
        sigma_min_J3_limit=scenario.sigma_min_J3_limit, f_d_limit=scenario.f_d_limit,
        period=scenario.controller_period, kernel=scenario.controller.kernel)
