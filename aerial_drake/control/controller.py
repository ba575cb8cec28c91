"""The inertially decoupled controller of Section III as a Drake LeafSystem.

``DecoupledController`` is the double instantiation of the scalar-convertible template
``DecoupledController_`` (Drake's ``TemplateSystem``): ``DecoupledController_[AutoDiffXd]`` runs
the same law on an AutoDiffXd copy of the model plant, so Drake's ``Linearize`` applies to a
diagram holding the controller (see :mod:`aerial_drake.analysis`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pydrake.autodiffutils import AutoDiffXd, ExtractGradient
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import Frame
from pydrake.systems.scalar_conversion import TemplateSystem

from aerial_drake.control.base import NONFINITE_STATE, ControllerBase, ControllerBase_
from aerial_drake.control.compiled import (
    ASSUMPTION_1,
    ASSUMPTION_2,
    NONFINITE,
    CompiledLaw,
    pack_gains,
    reference_law_reason,
)
from aerial_drake.control.law import (
    F_D_LIMIT,
    NO_DAMPING,
    SIGMA_MIN_J3_LIMIT,
    AssumptionViolation,
    ControlOutput,
    GainMatrices,
    Gains,
    Reference,
    SingularityRobust,
    TaskKinematics,
    assumption_1_message,
    assumption_2_message,
    compute_control,
    diagnostics_layout,
    diagnostics_slices,
)
from aerial_drake.dynamics.decoupling import DecoupledDynamics, value_of
from aerial_drake.dynamics.kinematic_tree import KinematicTree, UnsupportedTree
from aerial_drake.robots.models import AerialManipulator
from aerial_drake.robots.task import POSE_ROWS, TaskLayout
from aerial_drake.trajectories.reference import (
    unpack_com_reference,
    unpack_heading_reference,
    unpack_task_reference,
)


class _DecoupledControllerBase:
    """The law (10)-(22) on the controller's own model of the plant, on the ports, hold and
    cache of :class:`aerial_drake.control.base.ControllerBase` (its docstring has the ports).

    The ``diagnostics`` port's entries are :func:`aerial_drake.control.law.diagnostics_layout`.
    With ``period`` 0 (continuous feedback, and what ``Linearize`` needs), both outputs come
    from one cached evaluation per context (direct feedthrough). With ``period`` > 0 (the
    paper's 1 kHz controller) the compiled law writes the command and its diagnostics
    straight into the held discrete state at t = k period (:meth:`evaluate_into`), in one
    Python call per sample. ``command`` then holds the sample at t_k over [t_k, t_k+1); so do
    the ``diagnostics``, so a logger at t_k sees those of t_k-1 (the runner re-aligns its
    log, :func:`aerial_drake.simulation.runner.run_scenario`).

    Args:
        plant: the controller's model (a finalized, continuous MultibodyPlant of the system's
            scalar type; usually ``models.make_plant("rigid").plant``), not the simulated
            plant. Scalar conversion converts it (``ToScalarType``).
        end_effector_frame: the task frame E on ``plant``.
        task: the task's rows and joints on ``plant`` (``AerialManipulator.task``).
        gains: Table II gains; validated here (a ValueError names a bad field).
        sigma_min_J3_limit, f_d_limit: thresholds of the Assumption 1 and 2 checks.
        period: the sampling period (s); 0 for continuous feedback.
        singularity: the damped inverse near the singularity of J_3 and when control is
            lost (:class:`aerial_drake.control.law.SingularityRobust`); the default is off.
        kernel: the compiled law's kernel, ``"exact"`` (default: the paper runs' arithmetic,
            bit for bit) or ``"fast"`` (the same law to round-off, faster;
            :mod:`aerial_drake.control.compiled.fast_law`, docs/control.md "The fast
            kernel"). The reference implementation (:meth:`solve`) is the same for both.
    """

    def _setup(self, plant: MultibodyPlant, end_effector_frame: Frame, task: TaskLayout,
               gains: Gains, *,
               sigma_min_J3_limit: float = SIGMA_MIN_J3_LIMIT, f_d_limit: float = F_D_LIMIT,
               period: float = 0.0, singularity: SingularityRobust = NO_DAMPING,
               kernel: str = "exact"):
        nv = plant.num_velocities()
        self._n = nv - 6
        if task.n != self._n:
            raise ValueError(f"the task has {task.n} rows but the plant has {self._n} arm "
                             "velocities: the law needs as many task coordinates as joints")
        self._plant = plant
        self._gains = gains
        self._dynamics = DecoupledDynamics(plant)
        self._dtype = float if isinstance(plant, MultibodyPlant) else object
        self._task = task
        self._K = GainMatrices.from_gains(gains, n_task=self._n)
        self._gravity = self._dynamics.gravity
        self._frame = end_effector_frame
        self._limits: dict[str, Any] = dict(
            sigma_min_J3_limit=sigma_min_J3_limit, f_d_limit=f_d_limit, singularity=singularity)
        # The diagnostics' entry the damped law's check of control reads (evaluate_into).
        self._ee_error_at = diagnostics_slices(self._n)["ee_position_error"].start
        self._plant_context = plant.CreateDefaultContext()
        self.kernel = kernel
        self.not_compiled_reason = ""
        self._compiled = self._make_compiled(gains) if self._dtype is float else None

    def _make_compiled(self, gains: Gains) -> CompiledLaw | None:
        """The compiled law (:mod:`aerial_drake.control.compiled`) on this plant, or None where its
        kernels do not handle the plant's structure (then :meth:`solve` serves, and
        :attr:`not_compiled_reason` says why), or where this process runs the reference
        implementation (:func:`aerial_drake.control.compiled.use_reference_law`)."""
        reason = reference_law_reason()
        if reason is not None:
            self.not_compiled_reason = reason
            return None
        try:
            tree = KinematicTree.from_plant(self._plant, self._dynamics.base_body)
        except UnsupportedTree as err:
            self.not_compiled_reason = str(err)
            return None
        X_BE = self._frame.GetFixedPoseInBodyFrame()
        ee = (tree.index_of(self._frame.body()), X_BE.rotation().matrix(), X_BE.translation())
        return CompiledLaw(tree, self._plant.num_positions(), ee, self._task,
                           pack_gains(self._K, self._gravity), **self._limits,
                           kernel=self.kernel)

    @property
    def compiled(self) -> bool:
        """Whether the simulation evaluates the compiled law (double plants of a supported
        structure) rather than :meth:`solve`."""
        return self._compiled is not None

    def evaluate_into(self, t: float, x: np.ndarray, com: np.ndarray, task: np.ndarray,
                      heading: np.ndarray, command: np.ndarray, diagnostics: np.ndarray,
                      ) -> None:
        """The law at state ``x`` written into ``command`` and ``diagnostics`` (views of the
        held state when sampled): by the compiled law when :attr:`compiled`, else by
        :meth:`solve` (the time is not read: the references carry it).

        Raises:
            AssumptionViolation: as :func:`aerial_drake.control.law.compute_control`.
            FloatingPointError: a non-finite state.
        """
        if self._compiled is None:
            out = self._solve_checked(x, com, task, heading)
            command[0] = out.f
            command[1:4] = out.mu
            command[4:] = out.tau
            diagnostics[:] = out.diagnostics
            return
        # The compiled law writes straight into the arrays given: no copies, and each
        # Python-to-C++ call saved counts at 1 kHz.
        status, f_d_norm, sigma_min = self._compiled(x, com, task, heading, command, diagnostics)
        if status == NONFINITE:
            raise FloatingPointError(NONFINITE_STATE)
        if status == ASSUMPTION_2:
            raise AssumptionViolation(assumption_2_message(f_d_norm, self._limits["f_d_limit"]))
        if status == ASSUMPTION_1:
            raise AssumptionViolation(
                assumption_1_message(sigma_min, self._limits["sigma_min_J3_limit"]))
        singularity = self._limits["singularity"]
        if singularity.damping > 0.0:  # the Assumption 1 stop's replacement
            singularity.check_control_kept(sigma_min, float(diagnostics[self._ee_error_at]))

    def _solve_checked(self, x: np.ndarray, com: np.ndarray, task: np.ndarray,
                       heading: np.ndarray) -> ControlOutput:
        """:meth:`solve` on a finite state, on the references' values (AutoDiffXd)."""
        if not np.all(np.isfinite(value_of(x))):
            raise FloatingPointError(NONFINITE_STATE)
        if self._dtype is object:
            com, task, heading = (_reference_values(r) for r in (com, task, heading))
        return self.solve(x, com, task, heading)

    def solve(self, x: np.ndarray, com: np.ndarray, task: np.ndarray, heading: np.ndarray,
              ) -> ControlOutput:
        """The law at state ``x`` and packed references (no Drake context needed), by the
        reference implementation (:mod:`aerial_drake.dynamics.decoupling`,
        :mod:`aerial_drake.control.law`), with every intermediate quantity."""
        plant, ctx = self._plant, self._plant_context
        plant.SetPositionsAndVelocities(ctx, x)
        d = self._dynamics.compute(ctx)
        J6, J6_dot = self._dynamics.frame_jacobian(d, self._frame)
        J_y, J_y_dot = task_jacobian(self._task, J6, J6_dot, plant.num_velocities(),
                                     self._dtype)
        X_WE = self._frame.CalcPoseInWorld(ctx)
        rows = self._task.rows
        kin = TaskKinematics(p_WE=X_WE.translation(), R_WE=X_WE.rotation().matrix(),
                             q_j=x[list(self._task.joint_positions)], J_y=J_y, J_y_dot=J_y_dot,
                             rows=rows)
        t = unpack_task_reference(task)
        ref = Reference(
            com=unpack_com_reference(com), p_ed=t.p_ed, R_ed=t.R_ed, q_jd=t.q_jd,
            y_d_dot=t.full_dot[list(rows)], y_d_ddot=t.full_ddot[list(rows)],
            b1d=unpack_heading_reference(heading))
        return compute_control(d, kin, ref, self._K, self._gravity, **self._limits)


def task_jacobian(task: TaskLayout, J6: np.ndarray, J6_dot: np.ndarray, nv: int, dtype=float
                  ) -> tuple[np.ndarray, np.ndarray]:
    """J_y and its derivative: the task's rows of ``[J6; joint rows]``, J6 the end effector's
    World Jacobian ``[v_E; w_E]`` (6, nv) (:mod:`aerial_drake.robots.task`)."""
    J_y = np.zeros((task.n, nv), dtype=dtype)
    J_y_dot = np.zeros((task.n, nv), dtype=dtype)
    for i, r in enumerate(task.rows):
        if r < POSE_ROWS:
            J_y[i], J_y_dot[i] = J6[r], J6_dot[r]
        else:
            J_y[i, task.joint_velocities[r - POSE_ROWS]] = 1.0
    return J_y, J_y_dot


def _reference_values(reference: np.ndarray) -> np.ndarray:
    """An AutoDiffXd reference input's values. The law reads its references as floats, so a
    reference that carries derivatives (linearising with respect to it) is refused."""
    if np.any(ExtractGradient(reference)):
        raise NotImplementedError(
            "DecoupledController_[AutoDiffXd] differentiates with respect to the state only: "
            "its reference inputs must be constant (no derivatives)")
    return value_of(reference)


@TemplateSystem.define("DecoupledController_", T_list=(float, AutoDiffXd))
def DecoupledController_(T):
    """The controller for scalar type ``T`` (float or AutoDiffXd); a float controller converts
    to AutoDiffXd (``ToAutoDiffXd``, or inside ``Linearize``) with its model plant."""

    class Impl(_DecoupledControllerBase, ControllerBase_[T]):
        __doc__ = _DecoupledControllerBase.__doc__

        def _construct(self, plant, end_effector_frame, task, gains, *,
                       sigma_min_J3_limit=SIGMA_MIN_J3_LIMIT, f_d_limit=F_D_LIMIT,
                       period=0.0, singularity=NO_DAMPING, kernel="exact", converter=None):
            ControllerBase_[T].__init__(
                self, plant, task, period=period,
                diagnostics_layout=diagnostics_layout(plant.num_velocities() - 6),
                converter=converter)
            self._setup(plant, end_effector_frame, task, gains,
                        sigma_min_J3_limit=sigma_min_J3_limit, f_d_limit=f_d_limit,
                        singularity=singularity, kernel=kernel)

        def _construct_copy(self, other, converter=None):
            plant = other._plant.ToScalarType[T]()
            Impl._construct(self, plant, plant.get_frame(other._frame.index()), other._task,
                            other._gains, **other._limits, period=other.period,
                            kernel=other.kernel, converter=converter)

    return Impl


#: The controller on a double plant (the simulation's); ``DecoupledController_[AutoDiffXd]``
#: is its AutoDiffXd instantiation.
DecoupledController = DecoupledController_[None]


class ZeroController(ControllerBase):
    """The ports of :class:`DecoupledController` with an all-zero command and no
    diagnostics: a benchmark baseline (the plant falls; only the cost of everything but the
    control law is measured: the plant, the reference and the logging). Sampled (``period``
    > 0), it reads its inputs at every sample as the real controller does, so the reference
    is generated."""

    def __init__(self, plant: MultibodyPlant, task: TaskLayout, *, period: float = 0.0):
        super().__init__(plant, task, period=period)

    def evaluate_into(self, t: float, x: np.ndarray, com: np.ndarray, task: np.ndarray,
                      heading: np.ndarray, command: np.ndarray, diagnostics: np.ndarray,
                      ) -> None:
        # Zeros, whatever the state: it computes nothing from it (so a non-finite state is
        # left for the runner to find, as the plant's own).
        command[:] = 0.0


def make_controller(model: AerialManipulator, gains: Gains, *,
                    sigma_min_J3_limit: float = SIGMA_MIN_J3_LIMIT,
                    f_d_limit: float = F_D_LIMIT, period: float = 0.0, zero: bool = False,
                    kernel: str = "exact"):
    """The controller on ``model`` (from :mod:`aerial_drake.robots.models`) and its task,
    sampled every ``period`` s (0: continuous), its compiled law's ``kernel`` ("exact" or
    "fast", :class:`DecoupledController`); ``zero=True`` gives the :class:`ZeroController`
    baseline instead."""
    assert model.task is not None  # a finalized model
    if zero:
        return ZeroController(model.plant, model.task, period=period)
    return DecoupledController(
        model.plant, model.end_effector_frame, model.task, gains,
        sigma_min_J3_limit=sigma_min_J3_limit, f_d_limit=f_d_limit, period=period,
        kernel=kernel)
