"""The inertially decoupled controller of Section III as a Drake LeafSystem.

``DecoupledController`` is the double instantiation of the scalar-convertible template
``DecoupledController_`` (Drake's ``TemplateSystem``): ``DecoupledController_[AutoDiffXd]`` runs
the same law on an AutoDiffXd copy of the model plant, so Drake's ``Linearize`` applies to a
diagram holding the controller (see :mod:`aerial_drake.analysis`).
"""

from __future__ import annotations

import typing

import numpy as np
from pydrake.autodiffutils import AutoDiffXd, ExtractGradient
from pydrake.common.value import AbstractValue
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import Frame
from pydrake.systems.framework import BasicVector, Context, LeafSystem, LeafSystem_, ValueProducer
from pydrake.systems.scalar_conversion import TemplateSystem

from aerial_drake.control.compiled import (
    ASSUMPTION_1,
    ASSUMPTION_2,
    NONFINITE,
    CompiledLaw,
    pack_gains,
)
from aerial_drake.control.law import (
    F_D_LIMIT,
    SIGMA_MIN_J3_LIMIT,
    AssumptionViolation,
    ControlOutput,
    GainMatrices,
    Gains,
    Reference,
    TaskKinematics,
    assumption_1_message,
    assumption_2_message,
    compute_control,
    diagnostics_size,
)
from aerial_drake.dynamics.decoupling import DecoupledDynamics, value_of
from aerial_drake.dynamics.kinematic_tree import KinematicTree, UnsupportedTree
from aerial_drake.robots.models import AerialManipulator
from aerial_drake.robots.task import POSE_ROWS, TaskLayout
from aerial_drake.trajectories.reference import (
    COM_REFERENCE_SIZE,
    HEADING_REFERENCE_SIZE,
    task_reference_size,
    unpack_com_reference,
    unpack_heading_reference,
    unpack_task_reference,
)

NONFINITE_STATE = ("the plant state is not finite (the simulation diverged before the "
                   "controller could act)")


# The controllers' mixins are mixed into a LeafSystem: to the type checker they are one.
if typing.TYPE_CHECKING:
    class _LeafSystemMixin(LeafSystem):
        pass
else:
    _LeafSystemMixin = object


class _ControllerPorts(_LeafSystemMixin):
    """Port accessors and the sampled outputs shared by the controllers (same port names and
    sizes)."""

    _period: float

    @property
    def period(self) -> float:
        """The sampling period (s); 0 for continuous feedback."""
        return self._period

    def _declare_held_outputs(self, sizes: tuple[int, int], update) -> tuple:
        """The sampled outputs: ``command`` and ``diagnostics`` (``sizes``) as discrete state,
        read by state output ports and written by ``update`` every :attr:`period` from
        t = 0. Returns the two discrete state indices (as ints)."""
        held = tuple(self.DeclareDiscreteState(size) for size in sizes)
        self.DeclarePeriodicDiscreteUpdateEvent(self._period, 0.0, update)
        for name, index in zip(("command", "diagnostics"), held):
            self.DeclareStateOutputPort(name, index)
        return tuple(int(index) for index in held)

    def get_state_input_port(self):
        return self._state_port

    def get_command_output_port(self):
        return self.GetOutputPort("command")

    def get_diagnostics_output_port(self):
        return self.GetOutputPort("diagnostics")


class _DecoupledControllerBase(_ControllerPorts):
    """The law (10)-(22) on the controller's own model of the plant.

    Input ports:
        - ``state``: the model plant's state ``[q; v]`` (its floating base, quaternion or rpy,
          then the n arm joints).
        - ``com_reference`` (15), ``task_reference`` (24 + 3 n_j), ``heading_reference`` (9): as
          produced by :class:`aerial_drake.trajectories.generator.ReferenceGenerator`.

    Output ports:
        - ``command``: ``[f, mu (3), tau (n)]``, the inputs of (1).
        - ``diagnostics``: see :func:`aerial_drake.control.law.diagnostics_layout`.

    With ``period`` 0 (continuous feedback, and what ``Linearize`` needs), both outputs come
    from one cached evaluation per context (direct feedthrough). With ``period`` > 0 (the
    paper's 1 kHz controller) the law runs in a periodic discrete update at t = k period that
    writes the command and its diagnostics into the controller's discrete state, and the
    outputs are that state (Drake's state output ports): a sample-and-hold, in one Python
    call per sample. ``command`` then holds the sample at t_k over [t_k, t_k+1); so do the
    ``diagnostics``, so a logger at t_k sees those of t_k-1 (the runner re-aligns its log,
    :func:`aerial_drake.simulation.runner.run_scenario`). Set the held values at the initial
    state with :meth:`hold_sample` (or leave the first update to do it at t = 0).

    Args:
        plant: the controller's model (a finalized, continuous MultibodyPlant of the system's
            scalar type; usually ``models.make_plant("rigid").plant``), not the simulated
            plant. Scalar conversion converts it (``ToScalarType``).
        end_effector_frame: the task frame E on ``plant``.
        task: the task's rows and joints on ``plant`` (``AerialManipulator.task``).
        gains: Table II gains; validated here (a ValueError names a bad field).
        sigma_min_J3_limit, f_d_limit: thresholds of the Assumption 1 and 2 checks.
        period: the sampling period (s); 0 for continuous feedback.
    """

    def _setup(self, plant: MultibodyPlant, end_effector_frame: Frame, task: TaskLayout,
               gains: Gains, *,
               sigma_min_J3_limit: float = SIGMA_MIN_J3_LIMIT, f_d_limit: float = F_D_LIMIT,
               period: float = 0.0):
        if not period >= 0.0:
            raise ValueError(f"period must be >= 0 (s; 0 = continuous feedback), got {period}")
        self._plant = plant
        self._gains = gains
        self._dynamics = DecoupledDynamics(plant)
        self._dtype = float if isinstance(plant, MultibodyPlant) else object
        nv = plant.num_velocities()
        self._n = nv - 6
        if task.n != self._n:
            raise ValueError(f"the task has {task.n} rows but the plant has {self._n} arm "
                             "velocities: the law needs as many task coordinates as joints")
        self._task = task
        self._diagnostics_size = diagnostics_size(self._n)
        self._K = GainMatrices.from_gains(gains, n_task=self._n)
        self._gravity = self._dynamics.gravity
        self._frame = end_effector_frame
        self._limits = dict(sigma_min_J3_limit=sigma_min_J3_limit, f_d_limit=f_d_limit)
        self._plant_context = plant.CreateDefaultContext()
        self._period = float(period)
        self.evaluations = 0  # number of control law evaluations (for tests and benchmarks)
        self.not_compiled_reason = ""
        self._compiled = self._make_compiled(gains) if self._dtype is float else None

        nx = plant.num_positions() + nv
        self._state_port = self.DeclareVectorInputPort("state", nx)
        self._com_port = self.DeclareVectorInputPort("com_reference", COM_REFERENCE_SIZE)
        self._task_port = self.DeclareVectorInputPort(
            "task_reference", task_reference_size(task.n_joints))
        self._heading_port = self.DeclareVectorInputPort("heading_reference",
                                                         HEADING_REFERENCE_SIZE)
        if self._period > 0.0:
            self._held = self._declare_held_outputs((4 + self._n, self._diagnostics_size),
                                                    self._sample)
            return
        self._solution = self.DeclareCacheEntry(
            description="control law solution",
            value_producer=ValueProducer(
                allocate=AbstractValue.Make(object()).Clone, calc=self._calc_solution),
            prerequisites_of_calc={self.all_input_ports_ticket(), self.time_ticket()})
        self.DeclareVectorOutputPort(
            "command", 4 + self._n, self._calc_command,
            prerequisites_of_calc={self._solution.ticket()})
        self.DeclareVectorOutputPort(
            "diagnostics", self._diagnostics_size, self._calc_diagnostics,
            prerequisites_of_calc={self._solution.ticket()})

    def _make_compiled(self, gains: Gains) -> CompiledLaw | None:
        """The compiled law (:mod:`aerial_drake.control.compiled`) on this plant, or None where its
        kernels do not handle the plant's structure (then :meth:`solve` serves, and
        :attr:`not_compiled_reason` says why)."""
        try:
            tree = KinematicTree.from_plant(self._plant, self._dynamics.base_body)
        except UnsupportedTree as err:
            self.not_compiled_reason = str(err)
            return None
        X_BE = self._frame.GetFixedPoseInBodyFrame()
        ee = (tree.index_of(self._frame.body()), X_BE.rotation().matrix(), X_BE.translation())
        return CompiledLaw(tree, self._plant.num_positions(), ee, self._task,
                           pack_gains(self._K, self._gravity), **self._limits)

    @property
    def compiled(self) -> bool:
        """Whether the simulation evaluates the compiled law (double plants of a supported
        structure) rather than :meth:`solve`."""
        return self._compiled is not None

    def evaluate(self, x: np.ndarray, com: np.ndarray, task: np.ndarray, heading: np.ndarray,
                 ) -> tuple[np.ndarray, np.ndarray]:
        """``(command, diagnostics)`` of the law at state ``x``: what the output ports give,
        by the compiled law when :attr:`compiled`, else by :meth:`solve`.

        Raises:
            AssumptionViolation: as :func:`aerial_drake.control.law.compute_control`.
        """
        if self._compiled is None:
            out = self.solve(x, com, task, heading)
            return np.concatenate([[out.f], out.mu, out.tau]), out.diagnostics
        command, diagnostics = np.empty(4 + self._n), np.empty(self._diagnostics_size)
        self._evaluate_into(x, com, task, heading, command, diagnostics)
        return command, diagnostics

    def _evaluate_into(self, x: np.ndarray, com: np.ndarray, task: np.ndarray,
                       heading: np.ndarray, command: np.ndarray, diagnostics: np.ndarray,
                       ) -> None:
        """The compiled law, written into ``command`` and ``diagnostics`` (which may be views
        of a context's discrete state); raises as :meth:`evaluate`."""
        assert self._compiled is not None  # evaluate and the update call this only then
        status, f_d_norm, sigma_min = self._compiled(x, com, task, heading, command, diagnostics)
        self.evaluations += 1
        if status == NONFINITE:
            raise FloatingPointError(NONFINITE_STATE)
        if status == ASSUMPTION_2:
            raise AssumptionViolation(assumption_2_message(f_d_norm, self._limits["f_d_limit"]))
        if status == ASSUMPTION_1:
            raise AssumptionViolation(
                assumption_1_message(sigma_min, self._limits["sigma_min_J3_limit"]))

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
        self.evaluations += 1
        return compute_control(d, kin, ref, self._K, self._gravity, **self._limits)

    def law_at(self, context: Context) -> tuple[np.ndarray, np.ndarray]:
        """``(command, diagnostics)`` of the law at this system's ``context``: its input ports
        and time, as the outputs (continuous) or the next sample (sampled) would give them.

        Raises:
            AssumptionViolation, FloatingPointError: naming the context's time.
        """
        x, com, task, heading = self._inputs(context)
        try:
            if self._compiled is not None:
                return self.evaluate(x, com, task, heading)
            if not np.all(np.isfinite(value_of(x))):
                raise FloatingPointError(NONFINITE_STATE)
            if self._dtype is object:
                com, task, heading = (_reference_values(r) for r in (com, task, heading))
            out = self.solve(x, com, task, heading)
        except (AssumptionViolation, FloatingPointError) as err:
            raise _at_time(err, context) from None
        return np.concatenate([[out.f], out.mu, out.tau]), out.diagnostics

    def _inputs(self, context: Context
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The state and the three references at ``context``."""
        return (self._state_port.Eval(context), self._com_port.Eval(context),
                self._task_port.Eval(context), self._heading_port.Eval(context))

    def hold_sample(self, context: Context) -> None:
        """Sampled controller: run the law at ``context`` and hold its result, as the periodic
        update does (e.g. at the initial state, so the hold starts at the first command)."""
        if self._period <= 0.0:
            raise RuntimeError("hold_sample: this controller is continuous (period 0); it "
                               "holds nothing")
        self._sample(context, context.get_mutable_discrete_state())

    def _sample(self, context: Context, discrete_state) -> None:
        command_index, diagnostics_index = self._held
        if self._compiled is None:
            command, diagnostics = self.law_at(context)
            discrete_state.set_value(command_index, command)
            discrete_state.set_value(diagnostics_index, diagnostics)
            return
        # The compiled law writes straight into the update's state (numpy views of Drake's
        # vectors): no copies, and each Python-to-C++ call saved counts at 1 kHz. On a
        # failure the update is abandoned, so a partial write never reaches the context.
        try:
            self._evaluate_into(*self._inputs(context),
                                discrete_state.get_mutable_value(command_index),
                                discrete_state.get_mutable_value(diagnostics_index))
        except (AssumptionViolation, FloatingPointError) as err:
            raise _at_time(err, context) from None

    def _calc_solution(self, context: Context, value: AbstractValue) -> None:
        value.set_value(self.law_at(context))

    def _calc_command(self, context: Context, output: BasicVector) -> None:
        output.SetFromVector(self._solution.Eval(context)[0])

    def _calc_diagnostics(self, context: Context, output: BasicVector) -> None:
        output.SetFromVector(self._solution.Eval(context)[1])


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


def _at_time(err: Exception, context: Context) -> Exception:
    """``err`` again, its message prefixed by the context's time."""
    return type(err)(f"t = {context.get_time():.4f} s: {err}")


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

    class Impl(_DecoupledControllerBase, LeafSystem_[T]):
        __doc__ = _DecoupledControllerBase.__doc__

        def _construct(self, plant, end_effector_frame, task, gains, *,
                       sigma_min_J3_limit=SIGMA_MIN_J3_LIMIT, f_d_limit=F_D_LIMIT,
                       period=0.0, converter=None):
            LeafSystem_[T].__init__(self, converter)
            self._setup(plant, end_effector_frame, task, gains,
                        sigma_min_J3_limit=sigma_min_J3_limit,
                        f_d_limit=f_d_limit, period=period)

        def _construct_copy(self, other, converter=None):
            plant = other._plant.ToScalarType[T]()
            Impl._construct(self, plant, plant.get_frame(other._frame.index()), other._task,
                            other._gains, **other._limits, period=other._period,
                            converter=converter)

    return Impl


#: The controller on a double plant (the simulation's); ``DecoupledController_[AutoDiffXd]``
#: is its AutoDiffXd instantiation.
DecoupledController = DecoupledController_[None]


class ZeroController(_ControllerPorts, LeafSystem):
    """The ports of :class:`DecoupledController` with all-zero outputs: a benchmark baseline
    (the plant falls; only the cost of everything but the control law is measured: the
    plant, the reference and the logging). Sampled (``period`` > 0), it reads its inputs at
    every sample as the real controller does, so the reference is generated, and its outputs
    are a zero discrete state."""

    def __init__(self, plant: MultibodyPlant, end_effector_frame: Frame, task: TaskLayout,
                 gains: Gains, *,
                 sigma_min_J3_limit: float = SIGMA_MIN_J3_LIMIT, f_d_limit: float = F_D_LIMIT,
                 period: float = 0.0):
        super().__init__()
        nv = plant.num_velocities()
        self.evaluations = 0
        self._period = float(period)
        self._sizes = (4 + nv - 6, diagnostics_size(nv - 6))
        self._state_port = self.DeclareVectorInputPort(
            "state", plant.num_positions() + nv)
        self.DeclareVectorInputPort("com_reference", COM_REFERENCE_SIZE)
        self.DeclareVectorInputPort("task_reference", task_reference_size(task.n_joints))
        self.DeclareVectorInputPort("heading_reference", HEADING_REFERENCE_SIZE)
        if self._period > 0.0:
            self._declare_held_outputs(self._sizes, self._sample)
        else:
            for name, size in zip(("command", "diagnostics"), self._sizes):
                self.DeclareVectorOutputPort(name, size, self._calc_zero)

    def evaluate(self, x: np.ndarray, com: np.ndarray, task: np.ndarray, heading: np.ndarray,
                 ) -> tuple[np.ndarray, np.ndarray]:
        """Zeros, as the outputs."""
        self.evaluations += 1
        return np.zeros(self._sizes[0]), np.zeros(self._sizes[1])

    def hold_sample(self, context: Context) -> None:
        """Nothing to hold: the state is zero."""

    def _sample(self, context: Context, discrete_state) -> None:
        # Read every input, as DecoupledController.law_at does; the held zeros stay.
        for i in range(self.num_input_ports()):
            self.get_input_port(i).Eval(context)
        self.evaluations += 1

    def _calc_zero(self, context: Context, output: BasicVector) -> None:
        self.evaluations += 1
        output.SetZero()


def make_controller(model: AerialManipulator, gains: Gains, *,
                    sigma_min_J3_limit: float = SIGMA_MIN_J3_LIMIT,
                    f_d_limit: float = F_D_LIMIT, period: float = 0.0, zero: bool = False):
    """The controller on ``model`` (from :mod:`aerial_drake.robots.models`) and its task,
    sampled every ``period`` s (0: continuous); ``zero=True`` gives the
    :class:`ZeroController` baseline instead."""
    controller_type = ZeroController if zero else DecoupledController
    assert model.task is not None  # a finalized model
    return controller_type(
        model.plant, model.end_effector_frame, model.task, gains,
        sigma_min_J3_limit=sigma_min_J3_limit, f_d_limit=f_d_limit, period=period)
