"""The closed loop analysed with Drake's tools (docs/analysis.md).

- :func:`hover_equilibrium`: a hover configuration (Drake's ``InverseKinematics`` through
  :func:`aerial_drake.equilibrium.solve_configuration`) and the inputs that hold it.
- :func:`linearize_closed_loop`: Drake's ``Linearize`` of the continuous closed loop (no
  sampling, lag or saturation) at that equilibrium, on an ``RpyFloatingJoint`` base, with the
  controller converted to AutoDiffXd (``DecoupledController_[AutoDiffXd]``); its eigenvalues
  beside the ones design note 6 predicts (:func:`predicted_eigenvalues`).
- :func:`linearize_open_loop` and :func:`controllability`: the plant alone at hover with the
  inputs ``[f, mu, tau]``, Drake's ``IsControllable`` / ``IsStabilizable``, and where the
  rank of the input matrix falls short (underactuation).
- :func:`lee_conditions`: the conditions of Lee et al. on ``gamma1``, ``gamma2`` of (25).
- :func:`lyapunov_study`: ``V(t)`` of (24)-(25) along the nominal trajectory without
  disturbances, continuous feedback, no saturation, an error-controlled integrator.
- :func:`region_of_attraction`: the fraction of runs that converge from sampled initial
  offsets of growing size.
- :func:`analyze`: all of it, written to a folder as ``analysis.json`` and plots.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pydrake.math import RollPitchYaw, RotationMatrix
from pydrake.systems.analysis import SimulatorConfig
from pydrake.systems.framework import (
    Diagram, DiagramBuilder, InputPortSelection, OutputPortSelection)
from pydrake.systems.primitives import (
    ConstantVectorSource, ControllabilityMatrix, Demultiplexer, IsControllable, IsStabilizable,
    Linearize, LinearSystem)

from aerial_drake.control import Gains, diagnostics_slices
from aerial_drake.controller import DecoupledController, make_controller
from aerial_drake.diagram import connect_actuation
from aerial_drake.equilibrium import UnreachablePose, solve_configuration
from aerial_drake.models import (
    AerialManipulator, add_to_builder, make_plant, nominal_end_effector_offset)
from aerial_drake.reference import ReferenceSample
from aerial_drake.scenarios import Scenario, load_scenario

__all__ = [
    "HoverEquilibrium", "UnreachablePose", "hover_equilibrium", "hover_inputs",
    "default_equilibria", "HoverLoop", "build_hover_loop", "linearize_closed_loop",
    "ClosedLoopLinearization", "predicted_eigenvalues", "compare_eigenvalues",
    "linearize_open_loop", "controllability", "unactuated_directions", "lee_conditions",
    "trajectory_accel_bound", "lyapunov_scenario", "lyapunov_study", "LyapunovResult",
    "ROA_UNIT", "region_of_attraction", "RegionOfAttraction", "analyze", "figure_eigenvalues",
    "figure_lyapunov", "figure_region_of_attraction", "format_eigenvalue_table",
    "format_report", "cli_analyze", "AnalysisSettings", "FULL_SETTINGS", "FAST_SETTINGS",
]


# --- Settings -------------------------------------------------------------------------------
@dataclass(frozen=True)
class AnalysisSettings:
    """The Lyapunov and region-of-attraction studies' settings. The defaults are the full
    study (``aerial-drake analyze``, about 3 minutes on two cores) and the defaults of
    :func:`lyapunov_scenario`, :func:`lyapunov_study` and :func:`region_of_attraction`;
    :meth:`fast` is ``--fast`` (a smoke test: the error-controlled integrator's first 0.1 s
    at 1e-8 alone costs ~10 s)."""

    lyapunov_duration: float = 2.0  # s
    lyapunov_accuracy: float = 1e-8  # runge_kutta3's error-control accuracy
    roa_scales: tuple[float, ...] = (1.0, 2.0, 4.0, 6.0, 8.0)  # offset sizes (ROA_UNIT)
    roa_samples: int = 6  # runs per size
    roa_duration: float = 1.0  # s, per run

    @classmethod
    def fast(cls) -> AnalysisSettings:
        return cls(lyapunov_duration=0.1, lyapunov_accuracy=1e-6, roa_scales=(1.0, 6.0),
                   roa_samples=1, roa_duration=0.2)


FULL_SETTINGS = AnalysisSettings()
FAST_SETTINGS = AnalysisSettings.fast()


# --- Hover equilibrium ----------------------------------------------------------------------
@dataclass(frozen=True)
class HoverEquilibrium:
    """A hover: the robot at rest with the CoM at ``p_WG``, the base level with heading
    ``yaw``, the end effector at ``(p_WE, R_WE)`` and joint 3 at ``q3``, and the inputs that
    hold it (static balance ``F = g(q)`` through ``[J_b^T Q^T]``)."""

    model: AerialManipulator  # the plant ``q`` belongs to (quaternion or rpy base)
    q: np.ndarray
    p_WG: np.ndarray  # m, World
    yaw: float  # rad, heading of the base x axis about World z
    p_WE: np.ndarray  # m, World
    R_WE: np.ndarray
    q3: float  # rad
    thrust: float  # f (N), along the base z axis
    body_torques: np.ndarray  # mu (N m), base frame
    joint_torques: np.ndarray  # tau (N m)
    horizontal_force_residual: float  # |base-frame x, y force| of the static balance (N)

    @property
    def R_WB(self) -> np.ndarray:
        return RotationMatrix.MakeZRotation(self.yaw).matrix()

    @property
    def state(self) -> np.ndarray:
        """``[q; v]`` with ``v = 0``."""
        return np.concatenate([self.q, np.zeros(self.model.plant.num_velocities())])

    @property
    def inputs(self) -> np.ndarray:
        """``[f, mu (3), tau (7)]``, the command layout of the controller."""
        return np.concatenate([[self.thrust], self.body_torques, self.joint_torques])

    def reference(self) -> ReferenceSample:
        """The constant reference that has this hover as its equilibrium: ``x_d = p_WG`` with
        zero derivatives, the task at ``(p_WE, R_WE, q3)`` at rest, ``b1d`` along the heading."""
        z3 = np.zeros(3)
        b1d = np.zeros((3, 3))
        b1d[0] = [math.cos(self.yaw), math.sin(self.yaw), 0.0]
        return ReferenceSample(
            com=np.vstack([self.p_WG, np.zeros((4, 3))]), p_ed=self.p_WE.copy(), v_ed=z3,
            a_ed=z3, R_ed=self.R_WE.copy(), w_ed=z3, dw_ed=z3, q3d=float(self.q3),
            q3d_dot=0.0, q3d_ddot=0.0, b1d=b1d)

    def summary(self) -> dict:
        return {
            "p_WG_m": self.p_WG.tolist(), "yaw_rad": self.yaw, "p_WE_m": self.p_WE.tolist(),
            "rpy_WE_rad": RollPitchYaw(RotationMatrix(self.R_WE)).vector().tolist(),
            "q3_rad": self.q3, "q": self.q.tolist(),
            "base_position_coordinates": self.model.floating_base,
            "thrust_N": self.thrust, "body_torques_Nm": self.body_torques.tolist(),
            "joint_torques_Nm": self.joint_torques.tolist(),
            "horizontal_force_residual_N": self.horizontal_force_residual,
        }


def hover_inputs(model: AerialManipulator, q: np.ndarray) -> tuple[float, np.ndarray,
                                                                       np.ndarray, float]:
    """The inputs that hold configuration ``q`` at rest: ``g(q) = J_b^T [f e3; mu] + Q^T tau``.

    The base's generalized forces are the World torque and force at the base origin (design
    note 1), so ``mu = R^T g[0:3]``, ``[f_x, f_y, f] = R^T g[3:6]``, ``tau = g[arm]``. Returns
    ``(f, mu, tau, |(f_x, f_y)|)``; the last is zero only when the base is level (a helicopter
    cannot push sideways).
    """
    plant = model.plant
    ctx = plant.CreateDefaultContext()
    plant.SetPositions(ctx, q)
    g = -plant.CalcGravityGeneralizedForces(ctx)
    R = plant.EvalBodyPoseInWorld(ctx, model.base_body).rotation().matrix()
    base = model.base_velocity_indices
    mu = R.T @ g[base[:3]]
    force_b = R.T @ g[base[3:]]
    tau = g[model.arm_velocity_indices]
    return float(force_b[2]), mu, tau, float(np.linalg.norm(force_b[:2]))


def hover_equilibrium(p_WG: np.ndarray, p_WE: np.ndarray, R_WE: np.ndarray | None = None, *,
                      yaw: float = 0.0, q3: float = 0.0,
                      model: AerialManipulator | None = None,
                      q_guess: np.ndarray | None = None) -> HoverEquilibrium:
    """The hover with the CoM at ``p_WG`` (m), the base level with heading ``yaw`` (rad), the
    end effector at ``p_WE`` (m) with orientation ``R_WE`` (default: the heading's yaw) and
    joint 3 at ``q3`` (rad), on ``model`` (default: the rigid model with an rpy base).

    Raises:
        UnreachablePose: no configuration realises the pose; the message names the failing
            constraints (CoM, end-effector position or orientation, q3) and what was asked.
    """
    model = model if model is not None else make_plant("rigid", floating_base="rpy")
    p_WG = np.asarray(p_WG, dtype=float).copy()
    p_WE = np.asarray(p_WE, dtype=float).copy()
    R_WB = RotationMatrix.MakeZRotation(yaw).matrix()
    if isinstance(R_WE, RotationMatrix):
        R_WE = R_WE.matrix()
    R_WE = R_WB if R_WE is None else np.asarray(R_WE, dtype=float)
    try:
        q = solve_configuration(model, p_WG=p_WG, R_WB=R_WB, p_WE=p_WE, R_WE=R_WE, q3=q3,
                                q_guess=q_guess)
    except UnreachablePose as err:
        raise UnreachablePose(
            f"no hover equilibrium with the CoM at {p_WG.round(4).tolist()} m, heading "
            f"{yaw:g} rad, end effector at {p_WE.round(4).tolist()} m (rpy "
            f"{RollPitchYaw(RotationMatrix(R_WE)).vector().round(4).tolist()} rad), "
            f"q3 = {q3:g} rad: {err}") from None
    f, mu, tau, residual = hover_inputs(model, q)
    return HoverEquilibrium(model=model, q=q, p_WG=p_WG, yaw=float(yaw), p_WE=p_WE,
                            R_WE=np.array(R_WE), q3=float(q3), thrust=f, body_torques=mu,
                            joint_torques=tau, horizontal_force_residual=residual)


def default_equilibria(model: AerialManipulator | None = None) -> dict[str, HoverEquilibrium]:
    """Two hovers used by the analysis and the tests: ``"nominal"`` (the end effector at the
    model's nominal offset from the CoM, :func:`nominal_end_effector_offset`: 0.3 m ahead
    and 0.6 m below, R_WE = I, the mount's design pose) and ``"turned"``
    (heading 0.7 rad, the end effector moved and tilted, q3 = 0.2 rad)."""
    model = model if model is not None else make_plant("rigid", floating_base="rpy")
    p_WG = np.array([0.0, 0.0, 2.0])
    yaw = 0.7
    R_yaw = RotationMatrix.MakeZRotation(yaw)
    turned_R_WE = (R_yaw @ RotationMatrix(RollPitchYaw(0.3, -0.2, 0.1))).matrix()
    return {
        "nominal": hover_equilibrium(p_WG, p_WG + nominal_end_effector_offset(model),
                                     np.eye(3), model=model),
        "turned": hover_equilibrium(p_WG, p_WG + R_yaw.matrix() @ [0.35, 0.1, -0.55],
                                    turned_R_WE, yaw=yaw, q3=0.2, model=model),
    }


# --- The closed loop at hover ---------------------------------------------------------------
@dataclass
class HoverLoop:
    """The continuous closed loop around a hover: plant (continuous, base as in the
    equilibrium's model), the controller on ``equilibrium.model``, constant references, the
    base actuator (Drake ``Propeller``) and joint torques straight to the actuators."""

    diagram: Diagram
    plant: AerialManipulator  # the simulated plant inside ``diagram``
    controller: DecoupledController
    equilibrium: HoverEquilibrium

    def context_at_equilibrium(self):
        context = self.diagram.CreateDefaultContext()
        self.plant.plant.SetPositionsAndVelocities(
            self.plant.plant.GetMyMutableContextFromRoot(context), self.equilibrium.state)
        return context


def _actuate(builder: DiagramBuilder, sim: AerialManipulator, command) -> None:
    """``command`` = [f, mu, tau] to the plant, with no hold, lag or saturation."""
    split = builder.AddSystem(Demultiplexer([4, len(sim.arm_joints)]))
    split.set_name("split_command")
    builder.Connect(command, split.get_input_port())
    forces = connect_actuation(builder, sim, split.get_output_port(0), split.get_output_port(1))
    builder.Connect(forces, sim.plant.get_applied_spatial_force_input_port())


def build_hover_loop(eq: HoverEquilibrium, gains: Gains) -> HoverLoop:
    """The closed loop of :class:`HoverLoop` (continuous feedback: no hold, lag, saturation)."""
    model = eq.model
    builder = DiagramBuilder()
    sim = add_to_builder(builder, model.variant, floating_base=model.floating_base)
    sim.plant.set_name("plant")
    if sim.plant.num_positions() != model.plant.num_positions():
        raise ValueError("the equilibrium's model and the simulated plant differ in coordinates")
    controller = builder.AddSystem(make_controller(model, gains))
    controller.set_name("controller")
    for name, value in zip(("com_reference", "task_reference", "heading_reference"),
                           eq.reference().to_vectors()):
        source = builder.AddSystem(ConstantVectorSource(value))
        source.set_name(name)
        builder.Connect(source.get_output_port(), controller.GetInputPort(name))
    builder.Connect(sim.plant.get_state_output_port(), controller.get_state_input_port())
    _actuate(builder, sim, controller.get_command_output_port())
    diagram = builder.Build()
    diagram.set_name("hover_loop")
    return HoverLoop(diagram=diagram, plant=sim, controller=controller, equilibrium=eq)


@dataclass
class ClosedLoopLinearization:
    """``Linearize`` of the hover loop, and its eigenvalues beside design note 6's."""

    equilibrium: HoverEquilibrium
    A: np.ndarray  # (2 (6 + n)) square, state [q (rpy base); v]
    eigenvalues: np.ndarray
    derivative_residual: float  # |x_dot| at the equilibrium (should be round-off)
    predicted: list[dict]  # from predicted_eigenvalues()
    table: list[dict]  # from compare_eigenvalues()
    max_relative_mismatch: float
    Lambda_z: np.ndarray
    command_at_equilibrium: np.ndarray  # the controller's [f, mu, tau] at zero error

    def summary(self) -> dict:
        return {
            "equilibrium": self.equilibrium.summary(),
            "states": int(self.A.shape[0]),
            "derivative_residual": self.derivative_residual,
            "command_at_equilibrium": self.command_at_equilibrium.tolist(),
            "command_minus_static_balance": float(np.abs(
                self.command_at_equilibrium - self.equilibrium.inputs).max()),
            "max_relative_mismatch": self.max_relative_mismatch,
            "eigenvalues": self.table,
        }


def predicted_eigenvalues(m: float, gains: Gains, Lambda_z: np.ndarray) -> list[dict]:
    """Design note 6: the closed loop's 2 (6 + n) eigenvalues at a hover, each with its origin.

    - CoM, each axis i: ``m s^2 + D_x[i] s + K_x[i] = 0``;
    - attitude, each body axis i: ``Lbar2[i] s^2 + k_w s + k_R = 0``;
    - task: ``-K_y`` and the eigenvalues of ``-Lambda_z^{-1} K_z``.
    """
    out = []
    for i, axis in enumerate("xyz"):
        for s in np.roots([m, gains.D_x[i], gains.K_x[i]]):
            out.append({"group": "com", "label": f"CoM {axis}: m s^2 + D_x s + K_x",
                        "value": complex(s)})
    for i in range(3):
        for s in np.roots([gains.Lambda2_bar[i], gains.k_w, gains.k_R]):
            out.append({"group": "attitude",
                        "label": f"attitude b{i + 1}: Lbar2 s^2 + k_w s + k_R",
                        "value": complex(s)})
    for i, k in enumerate(gains.K_y):
        out.append({"group": "task_y", "label": f"task -K_y[{i}]", "value": complex(-k)})
    modes = np.linalg.eigvals(-np.linalg.solve(Lambda_z, np.diag(gains.K_z)))
    for i, s in enumerate(sorted(modes, key=lambda s: s.real)):
        out.append({"group": "task_z", "label": f"task eig(-Lambda_z^-1 K_z) #{i}",
                    "value": complex(s)})
    return out


def compare_eigenvalues(computed: np.ndarray, predicted: list[dict]) -> tuple[list[dict], float]:
    """Pair each predicted eigenvalue with the nearest unused computed one (predicted taken in
    order of magnitude) and return the table rows and the largest relative mismatch
    ``|computed - predicted| / |predicted|``. Unpaired computed eigenvalues (if the counts
    differ) appear as rows with ``predicted`` None and mismatch inf."""
    remaining = list(np.asarray(computed, dtype=complex))
    rows = []
    for p in sorted(predicted, key=lambda p: abs(p["value"])):
        if not remaining:
            rows.append({**_row(p, None), "relative_mismatch": math.inf})
            continue
        k = int(np.argmin([abs(c - p["value"]) for c in remaining]))
        c = remaining.pop(k)
        rows.append({**_row(p, c), "relative_mismatch": abs(c - p["value"]) / abs(p["value"])})
    for c in remaining:
        rows.append({"group": "unpredicted", "label": "not in design note 6",
                     "predicted": None, "computed": [c.real, c.imag],
                     "relative_mismatch": math.inf})
    worst = max(r["relative_mismatch"] for r in rows) if rows else math.inf
    return rows, float(worst)


def _row(p: dict, c) -> dict:
    v = p["value"]
    return {"group": p["group"], "label": p["label"], "predicted": [v.real, v.imag],
            "computed": None if c is None else [c.real, c.imag]}


def linearize_closed_loop(eq: HoverEquilibrium, gains: Gains, *,
                          equilibrium_tolerance: float = 1e-6) -> ClosedLoopLinearization:
    """Drake's ``Linearize`` of :func:`build_hover_loop` at ``eq`` (no inputs, no outputs).

    The whole diagram converts to AutoDiffXd, the controller included
    (``DecoupledController_[AutoDiffXd]`` on an AutoDiffXd copy of its model plant), so ``A``
    is the exact Jacobian of the closed loop's time derivatives. ``Linearize`` itself checks
    that ``eq`` is an equilibrium to ``equilibrium_tolerance``.
    """
    loop = build_hover_loop(eq, gains)
    context = loop.context_at_equilibrium()
    xdot = loop.diagram.EvalTimeDerivatives(context).CopyToVector()
    sol = loop.controller.solve(eq.state, *eq.reference().to_vectors())
    command = np.concatenate([[sol.f], sol.mu, sol.tau])
    linear = Linearize(loop.diagram, context, InputPortSelection.kNoInput,
                       OutputPortSelection.kNoOutput,
                       equilibrium_check_tolerance=equilibrium_tolerance)
    A = linear.A()
    eigenvalues = np.linalg.eigvals(A)
    m = eq.model.plant.CalcTotalMass(eq.model.plant.CreateDefaultContext())
    predicted = predicted_eigenvalues(m, gains, sol.Lambda_z)
    table, worst = compare_eigenvalues(eigenvalues, predicted)
    return ClosedLoopLinearization(
        equilibrium=eq, A=A, eigenvalues=eigenvalues,
        derivative_residual=float(np.abs(xdot).max()), predicted=predicted, table=table,
        max_relative_mismatch=worst, Lambda_z=sol.Lambda_z, command_at_equilibrium=command)


# --- The open loop at hover -----------------------------------------------------------------
def linearize_open_loop(eq: HoverEquilibrium) -> LinearSystem:
    """The plant alone, linearised at ``eq`` with its hover inputs; the input is
    ``[f, mu (3), tau (7)]`` (11), the output the full state."""
    model = eq.model
    builder = DiagramBuilder()
    sim = add_to_builder(builder, model.variant, floating_base=model.floating_base)
    sim.plant.set_name("plant")
    inputs = builder.AddSystem(Demultiplexer([4 + len(sim.arm_joints)]))
    inputs.set_name("inputs")
    _actuate(builder, sim, inputs.get_output_port(0))
    builder.ExportInput(inputs.get_input_port(), "inputs")
    diagram = builder.Build()
    diagram.set_name("open_loop")
    context = diagram.CreateDefaultContext()
    sim.plant.SetPositionsAndVelocities(sim.plant.GetMyMutableContextFromRoot(context),
                                        eq.state)
    diagram.get_input_port(0).FixValue(context, eq.inputs)
    return Linearize(diagram, context, diagram.get_input_port(0).get_index(),
                     OutputPortSelection.kNoOutput)


def controllability(system: LinearSystem, *, rank_tolerance: float = 1e-9) -> dict:
    """Drake's ``IsControllable`` and ``IsStabilizable``, the rank of ``B`` and of the
    controllability matrices ``[B, AB, ..., A^k B]`` as ``k`` grows, and the PBH test
    ``rank [A - s I, B]`` at each open-loop eigenvalue ``s`` (numerical ranks by SVD,
    relative ``rank_tolerance``).

    ``IsControllable`` is Kalman's rank test on ``[B, AB, ..., A^{n-1} B]``, whose columns
    grow like ``|A|^k``: for the 26-state plant its condition number reaches 1e16 and the
    test cannot tell rank in double precision. It is therefore also run on the time-scaled
    system ``(A, B) / |A|`` (``t' = |A| t``, the same controllability matrix up to column
    scaling), reported as ``IsControllable_time_scaled`` with that matrix's
    ``sigma_min / sigma_max``.
    """
    A, B = system.A(), system.B()
    n = A.shape[0]
    a = float(np.linalg.norm(A, 2))
    scaled = LinearSystem(A / a, B / a, np.zeros((0, n)), np.zeros((0, B.shape[1])))
    sv_raw = np.linalg.svd(ControllabilityMatrix(system), compute_uv=False)
    sv_scaled = np.linalg.svd(ControllabilityMatrix(scaled), compute_uv=False)

    def rank(X):
        sv = np.linalg.svd(X, compute_uv=False)
        return int(np.sum(sv > rank_tolerance * sv[0]))

    growth, blocks, AkB = [], [], B
    for _ in range(n):
        blocks.append(AkB)
        growth.append(rank(np.hstack(blocks)))
        if growth[-1] == n or (len(growth) > 1 and growth[-1] == growth[-2]):
            break
        AkB = A @ AkB
    open_loop = np.linalg.eigvals(A)
    pbh = [n - rank(np.hstack([A - s * np.eye(n), B])) for s in open_loop]
    return {
        "states": n, "inputs": int(B.shape[1]),
        "IsControllable": bool(IsControllable(system)),
        "controllability_matrix_conditioning": float(sv_raw[-1] / sv_raw[0]),
        "IsControllable_time_scaled": bool(IsControllable(scaled)),
        "time_scaled_conditioning": float(sv_scaled[-1] / sv_scaled[0]),
        "IsStabilizable": bool(IsStabilizable(system)),
        "rank_B": rank(B),
        "controllability_rank_growth": growth,  # rank of [B .. A^k B], k = 0, 1, ...
        "pbh_max_rank_deficiency": int(max(pbh)),
        "open_loop_eigenvalues": [[s.real, s.imag] for s in sorted(open_loop,
                                                                    key=lambda s: -s.real)],
        "unstable_open_loop_eigenvalues": int(np.sum(open_loop.real > 1e-6 * a)),
    }


def unactuated_directions(eq: HoverEquilibrium, system: LinearSystem,
                          tol: float = 1e-9) -> np.ndarray:
    """The generalized forces the inputs cannot produce at ``eq``: an orthonormal basis (rows)
    of the left null space of ``M B_v`` (``B_v``: the velocity rows of the open loop's ``B``,
    so ``M B_v = [J_b^T [e3; 0], J_b^T [0; E3], Q^T]``)."""
    plant = eq.model.plant
    ctx = plant.CreateDefaultContext()
    plant.SetPositions(ctx, eq.q)
    S = plant.CalcMassMatrix(ctx) @ system.B()[plant.num_positions():]
    U, sv, _ = np.linalg.svd(S)
    return U[:, int(np.sum(sv > tol * sv[0])):].T


# --- Lyapunov function along trajectories ---------------------------------------------------
def lee_conditions(gains: Gains, m: float, *, accel_bound: float, psi1: float = 0.05,
                   e_x_max: float = 0.1) -> dict:
    """The conditions Lee, Leok and McClamroch (CDC 2010, the paper's [14]) put on the
    cross-term constants ``c1 = gamma1``, ``c2 = gamma2`` of ``V1`` (25), for the gains, with
    ``J`` replaced by ``Lambda2_bar`` (docs/analysis.md derives them):

    - CoM, ``alpha = sqrt(psi1 (2 - psi1))``:
      ``c1 < min(sqrt(k_x m), k_v (1 - alpha),
      4 m k_x k_v (1 - alpha)^2 / (k_v^2 (1 + alpha)^2 + 4 m k_x (1 - alpha)))``;
    - attitude: ``c2 < min(sqrt(k_R l_min), k_w, 4 k_w k_R l_min^2 / (k_w^2 l_max + 4 k_R
      l_min^2))``, and per body axis, near the equilibrium,
      ``c2 < 4 k_w k_R l_i / (k_w^2 + 4 k_R l_i)``;
    - coupling: ``lambda_min(W2) > 4 |W12|^2 / lambda_min(W1)`` with
      ``B = accel_bound`` bounding ``|m x_d'' + m g e3|`` (Assumption 3) and ``e_x_max`` the
      CoM error considered.
    """
    k_x, k_v = min(gains.K_x), min(gains.D_x)
    k_R, k_w = float(gains.k_R), float(gains.k_w)
    lam = np.asarray(gains.Lambda2_bar, dtype=float)
    l_min, l_max = float(lam.min()), float(lam.max())
    c1, c2 = float(gains.lyapunov_gamma1), float(gains.lyapunov_gamma2)
    alpha = math.sqrt(psi1 * (2.0 - psi1))
    c1_bounds = {
        "sqrt(k_x m)": math.sqrt(k_x * m),
        "k_v (1 - alpha)": k_v * (1 - alpha),
        "4 m k_x k_v (1-alpha)^2 / (k_v^2 (1+alpha)^2 + 4 m k_x (1-alpha))":
            4 * m * k_x * k_v * (1 - alpha) ** 2
            / (k_v ** 2 * (1 + alpha) ** 2 + 4 * m * k_x * (1 - alpha)),
    }
    c2_bounds = {
        "sqrt(k_R l_min)": math.sqrt(k_R * l_min),
        "k_w": k_w,
        "4 k_w k_R l_min^2 / (k_w^2 l_max + 4 k_R l_min^2)":
            4 * k_w * k_R * l_min ** 2 / (k_w ** 2 * l_max + 4 * k_R * l_min ** 2),
    }
    per_axis = [4 * k_w * k_R * li / (k_w ** 2 + 4 * k_R * li) for li in lam]
    B = float(accel_bound)
    W1 = np.array([[c1 * k_x * (1 - alpha) / m, -c1 * k_v * (1 + alpha) / (2 * m)],
                   [-c1 * k_v * (1 + alpha) / (2 * m), k_v * (1 - alpha) - c1]])
    W2 = np.array([[c2 * k_R / l_max, -c2 * k_w / (2 * l_min)],
                   [-c2 * k_w / (2 * l_min), k_w - c2]])
    W12 = np.array([[c1 * B / m, 0.0], [B + k_x * e_x_max, 0.0]])
    lmin_W1 = float(np.linalg.eigvalsh(W1)[0])
    lmin_W2 = float(np.linalg.eigvalsh(W2)[0])
    needed = 4 * float(np.linalg.norm(W12, 2)) ** 2 / lmin_W1 if lmin_W1 > 0 else math.inf
    # The best any c2 can do for the coupling: lambda_min(W2) <= c2 k_R / l_max with c2 below
    # its attitude bound, and |W12| >= B, lambda_min(W1) <= k_v.
    best_W2 = min(c2_bounds.values()) * k_R / l_max
    return {
        "gamma1": c1, "gamma2": c2, "psi1": psi1, "alpha": alpha, "B_N": B,
        "e_x_max_m": e_x_max,
        "gamma1_bounds": c1_bounds, "gamma1_ok": c1 < min(c1_bounds.values()),
        "gamma2_bounds": c2_bounds, "gamma2_ok": c2 < min(c2_bounds.values()),
        "gamma2_per_axis_bounds": per_axis, "gamma2_per_axis_ok": c2 < min(per_axis),
        "lambda_min_W1": lmin_W1, "lambda_min_W2": lmin_W2,
        "coupling_needed_lambda_min_W2": needed,
        "coupling_ok": lmin_W2 > needed,
        "coupling_possible_for_some_gammas": best_W2 > 4 * B ** 2 / k_v,
    }


def lyapunov_scenario(base: Scenario | str = "nominal", *,
                      duration: float = FULL_SETTINGS.lyapunov_duration,
                      accuracy: float = FULL_SETTINGS.lyapunov_accuracy,
                      max_step_size: float = 1e-3) -> Scenario:
    """``base`` without disturbances, with continuous feedback (``controller_period: 0``), no
    lag, no saturation, and Drake's error-controlled ``runge_kutta3`` at ``accuracy``."""
    scenario = load_scenario(base) if isinstance(base, str) else base
    return dataclasses.replace(
        scenario, name=f"{scenario.name}_lyapunov", duration=duration, controller_period=0.0,
        disturbances=[],
        actuation=dataclasses.replace(scenario.actuation, saturate=False, lag_rise_time=0.0),
        simulator=SimulatorConfig(
            integration_scheme="runge_kutta3", max_step_size=max_step_size,
            accuracy=accuracy, use_error_control=True, target_realtime_rate=0.0)).validate()


@dataclass
class LyapunovResult:
    scenario: Scenario
    t: np.ndarray
    V: np.ndarray
    V1: np.ndarray
    V_task: np.ndarray
    wall_time_s: float

    @staticmethod
    def max_increase(x: np.ndarray) -> float:
        """``max_{s <= t} (x(t) - x(s))``: the largest rise above an earlier value."""
        return float(np.max(x - np.minimum.accumulate(x))) if len(x) else 0.0

    def summary(self) -> dict:
        sim = self.scenario.simulator
        out = {"duration_s": self.scenario.duration, "samples": int(len(self.t)),
               "integrator": {"scheme": sim.integration_scheme, "accuracy": sim.accuracy,
                              "use_error_control": sim.use_error_control,
                              "max_step_size_s": sim.max_step_size},
               "gamma1": self.scenario.gains.lyapunov_gamma1,
               "gamma2": self.scenario.gains.lyapunov_gamma2,
               "wall_time_s": self.wall_time_s}
        for name in ("V", "V1", "V_task"):
            x = getattr(self, name)
            rise = self.max_increase(x)
            out[name] = {"initial": float(x[0]), "final": float(x[-1]), "max_increase": rise,
                         "max_increase_relative": rise / float(x[0]) if x[0] > 0 else math.nan}
        return out


def lyapunov_study(base: Scenario | str = "nominal", *,
                   duration: float = FULL_SETTINGS.lyapunov_duration,
                   accuracy: float = FULL_SETTINGS.lyapunov_accuracy, gamma1: float | None = None,
                   gamma2: float | None = None) -> LyapunovResult:
    """``V``, ``V1`` and ``V_task`` of (24)-(25) along :func:`lyapunov_scenario`'s run
    (the controller's diagnostics at the log period). ``gamma1``, ``gamma2`` override the
    scenario's ``gains.lyapunov_gamma1/2`` (they change ``V1``, not the control)."""
    from aerial_drake.runner import run_scenario  # runner imports much; keep import local

    scenario = lyapunov_scenario(base, duration=duration, accuracy=accuracy)
    gains = dataclasses.replace(scenario.gains)
    if gamma1 is not None:
        gains.lyapunov_gamma1 = gamma1
    if gamma2 is not None:
        gains.lyapunov_gamma2 = gamma2
    scenario = dataclasses.replace(scenario, gains=gains).validate()
    start = time.perf_counter()
    result = run_scenario(scenario, progress=False)
    wall = time.perf_counter() - start
    d, s = result.log["diagnostics"], diagnostics_slices()
    return LyapunovResult(scenario=scenario, t=result.log["t"], V=d[:, s["V"]].ravel(),
                          V1=d[:, s["V1"]].ravel(), V_task=d[:, s["V_task"]].ravel(),
                          wall_time_s=wall)


def trajectory_accel_bound(scenario: Scenario, m: float, samples: int = 2001) -> float:
    """``max |m x_d'' + m g e3|`` over the scenario's trajectory (Assumption 3's bound), g
    from the plant's gravity field."""
    from aerial_drake.reference import sample_reference
    t = np.linspace(0.0, scenario.duration, samples)
    ref = sample_reference(scenario.trajectory, t)
    gravity = make_plant("rigid").plant.gravity_field().gravity_vector()
    acc = np.asarray(ref.com)[:, 2, :] - gravity
    return float(m * np.linalg.norm(acc, axis=1).max())


# --- Region of attraction -------------------------------------------------------------------
#: Offsets of size 1: base position (m), base roll-pitch-yaw (rad), arm joints (rad), as
#: vector norms; a run of size s draws each from the sphere of radius s times these.
ROA_UNIT = {"base_position_offset": 0.1, "base_rpy_offset": 0.1, "arm_offset": 0.1}


@dataclass
class RegionOfAttraction:
    scales: list[float]
    runs: list[dict]  # scale, offsets, completed, failure, V0, VT, converged
    duration: float
    min_decay_rate: float
    wall_time_s: float

    @property
    def fractions(self) -> list[float]:
        out = []
        for s in self.scales:
            runs = [r for r in self.runs if r["scale"] == s]
            out.append(sum(r["converged"] for r in runs) / len(runs) if runs else math.nan)
        return out

    def summary(self) -> dict:
        return {"scales": self.scales, "unit": ROA_UNIT, "duration_s": self.duration,
                "criterion": f"run completes and V(T) <= exp(-{self.min_decay_rate:g} T) V(0)",
                "converged_fraction": self.fractions,
                "runs_per_scale": [sum(r["scale"] == s for r in self.runs)
                                   for s in self.scales],
                "wall_time_s": self.wall_time_s, "runs": self.runs}


def _unit_vector(rng: np.random.Generator, n: int) -> np.ndarray:
    u = rng.normal(size=n)
    return u / np.linalg.norm(u)


def region_of_attraction(base: Scenario | str = "nominal", *,
                         scales=FULL_SETTINGS.roa_scales,
                         samples: int = FULL_SETTINGS.roa_samples,
                         duration: float = FULL_SETTINGS.roa_duration,
                         min_decay_rate: float = 1.0, seed: int = 0,
                         ) -> RegionOfAttraction:
    """Run ``base`` (its sampling, saturation and integrator; disturbances removed) from
    ``samples`` random initial offsets at each scale s: base position, base roll-pitch-yaw
    and arm joint offsets, each a random direction times ``s * ROA_UNIT``. A run converges
    if it completes (no assumption violated, no divergence) and V decays on average at least
    at ``min_decay_rate`` (1/s): ``V(T) <= exp(-min_decay_rate T) V(0)`` (at hover the
    slowest closed-loop pole, about -1.2/s, makes V decay at about 2.4/s). Draws come from
    ``numpy.random.default_rng(seed)``."""
    from aerial_drake.runner import SimulationFailed, run_scenario

    scenario = load_scenario(base) if isinstance(base, str) else base
    scenario = dataclasses.replace(scenario, duration=duration, disturbances=[])
    rng = np.random.default_rng(seed)
    V = diagnostics_slices()["V"]
    runs, start = [], time.perf_counter()
    for s in scales:
        for _ in range(samples):
            offsets = {
                "base_position_offset": s * ROA_UNIT["base_position_offset"] * _unit_vector(rng, 3),
                "base_rpy_offset": s * ROA_UNIT["base_rpy_offset"] * _unit_vector(rng, 3),
                "arm_offset": s * ROA_UNIT["arm_offset"] * _unit_vector(rng, 7),
            }
            initial = dataclasses.replace(scenario.initial,
                                          **{k: v.tolist() for k, v in offsets.items()})
            run = dataclasses.replace(scenario, initial=initial).validate()
            row = {"scale": s, **{k: v.tolist() for k, v in offsets.items()},
                   "completed": True, "failure": None, "V0": math.nan, "VT": math.nan}
            try:
                log = run_scenario(run, progress=False).log["diagnostics"][:, V].ravel()
                row["V0"], row["VT"] = float(log[0]), float(log[-1])
            except SimulationFailed as err:
                row["completed"], row["failure"] = False, str(err)
            row["converged"] = bool(row["completed"] and
                                    row["VT"] <= math.exp(-min_decay_rate * duration) * row["V0"])
            runs.append(row)
    return RegionOfAttraction(scales=list(scales), runs=runs, duration=duration,
                              min_decay_rate=min_decay_rate,
                              wall_time_s=time.perf_counter() - start)


# --- Everything, to a folder ----------------------------------------------------------------
def _nan_to_none(x):
    """``x`` with every float NaN (also inside numpy arrays) replaced by None."""
    if isinstance(x, dict):
        return {k: _nan_to_none(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_nan_to_none(v) for v in x]
    if isinstance(x, np.ndarray):
        return _nan_to_none(x.tolist())
    if isinstance(x, (float, np.floating)) and math.isnan(x):
        return None
    return x


def _json_default(x):
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, (np.floating, np.integer, np.bool_)):
        return x.item()
    if isinstance(x, complex):
        return [x.real, x.imag]
    raise TypeError(f"not JSON serialisable: {type(x)}")


def analyze(out_dir: str | Path = "out/analysis", *, scenario: str = "nominal",
            settings: AnalysisSettings = FULL_SETTINGS, seed: int = 0,
            stream=None) -> dict:
    """Equilibria, linearisations, eigenvalue tables, open-loop controllability, Lee's
    conditions, the Lyapunov study and the region-of-attraction study (``settings``) of
    ``scenario``'s gains;
    writes ``analysis.json``, ``eigenvalues.png``, ``lyapunov.png`` and
    ``region_of_attraction.png`` to ``out_dir`` and returns the JSON content."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)

    def say(msg):
        if stream is not None:
            stream.write(msg + "\n")
            stream.flush()

    sc = load_scenario(scenario)
    report: dict = {"scenario": sc.name, "equilibria": {}}
    lins = {}
    for name, eq in default_equilibria().items():
        say(f"linearising the closed loop at hover '{name}'")
        lin = linearize_closed_loop(eq, sc.gains)
        lins[name] = lin
        open_loop = linearize_open_loop(eq)
        report["equilibria"][name] = {
            "closed_loop": lin.summary(),
            "open_loop": {**controllability(open_loop), "unactuated_generalized_forces":
                          unactuated_directions(eq, open_loop).round(12).tolist()}}
        say(f"  max relative eigenvalue mismatch {lin.max_relative_mismatch:.2e}")
    m = make_plant("rigid").total_mass()
    report["lee_conditions"] = lee_conditions(sc.gains, m,
                                              accel_bound=trajectory_accel_bound(sc, m))
    st = settings
    say(f"Lyapunov study: {st.lyapunov_duration:g} s, continuous feedback, runge_kutta3 "
        f"{st.lyapunov_accuracy:g}")
    lyap = lyapunov_study(sc, duration=st.lyapunov_duration, accuracy=st.lyapunov_accuracy)
    report["lyapunov"] = lyap.summary()
    say(f"region of attraction: {len(st.roa_scales)} sizes x {st.roa_samples} runs of "
        f"{st.roa_duration:g} s")
    roa = region_of_attraction(sc, scales=st.roa_scales, samples=st.roa_samples,
                               duration=st.roa_duration, seed=seed)
    report["region_of_attraction"] = roa.summary()
    figures = {"eigenvalues.png": figure_eigenvalues(lins), "lyapunov.png": figure_lyapunov(lyap),
               "region_of_attraction.png": figure_region_of_attraction(roa)}
    report["figures"] = []
    for name, fig in figures.items():
        fig.savefig(out / name, dpi=120)
        report["figures"].append(name)
    # JSON has no NaN: undefined numbers are written as null.
    (out / "analysis.json").write_text(
        json.dumps(_nan_to_none(report), indent=2, default=_json_default, allow_nan=False))
    say(f"wrote {out / 'analysis.json'} and {', '.join(figures)}")
    return report


# --- Figures (matplotlib's object API: no pyplot state, no display needed) ------------------
_GROUP_STYLE = {"com": ("tab:blue", "CoM"), "attitude": ("tab:orange", "attitude"),
                "task_y": ("tab:green", "task, -K_y"),
                "task_z": ("tab:red", "task, eig(-Lambda_z^-1 K_z)"),
                "unpredicted": ("k", "not predicted")}


def figure_eigenvalues(linearizations: dict[str, ClosedLoopLinearization]):
    """Computed (crosses) and predicted (circles) closed-loop eigenvalues, one panel per
    equilibrium, against -Re(s) on a log axis (all are real and negative)."""
    from matplotlib.figure import Figure
    fig = Figure(figsize=(8, 2.2 * len(linearizations) + 0.6), layout="constrained")
    axes = fig.subplots(len(linearizations), 1, squeeze=False)[:, 0]
    for ax, (name, lin) in zip(axes, linearizations.items()):
        for k, group in enumerate(_GROUP_STYLE):
            rows = [r for r in lin.table if r["group"] == group]
            if not rows:
                continue
            color, label = _GROUP_STYLE[group]
            pred = np.array([r["predicted"] for r in rows if r["predicted"] is not None])
            comp = np.array([r["computed"] for r in rows if r["computed"] is not None])
            if len(pred):
                ax.scatter(-pred[:, 0], np.full(len(pred), k), s=70, facecolors="none",
                           edgecolors=color, label=f"{label} (predicted)")
            if len(comp):
                ax.scatter(-comp[:, 0], np.full(len(comp), k), marker="x", color=color)
        ax.set_xscale("log")
        ax.set_yticks(range(len(_GROUP_STYLE) - 1),
                      [v[1] for k, v in _GROUP_STYLE.items() if k != "unpredicted"])
        ax.set_ylim(-0.6, len(_GROUP_STYLE) - 1.4)
        ax.set_title(f"hover '{name}': {lin.A.shape[0]} eigenvalues, max relative mismatch "
                     f"{lin.max_relative_mismatch:.1e} (o predicted, x Linearize)", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
    axes[-1].set_xlabel("-Re(s) (1/s)")
    return fig


def figure_lyapunov(result: LyapunovResult):
    """V, V1 and V_task of (24)-(25) against time (log scale)."""
    from matplotlib.figure import Figure
    fig = Figure(figsize=(8, 3.6), layout="constrained")
    ax = fig.subplots()
    for name, style in (("V", "k-"), ("V1", "C0--"), ("V_task", "C3:")):
        ax.semilogy(result.t, getattr(result, name), style, label=name)
    s = result.summary()
    ax.set_title(f"(24)-(25) along the nominal trajectory, no disturbances, continuous "
                 f"feedback;\nmax increase of V: {s['V']['max_increase']:.2e}, of V_task: "
                 f"{s['V_task']['max_increase']:.2e}", fontsize=9)
    ax.set_xlabel("t (s)")
    ax.legend()
    ax.grid(True, which="both", alpha=0.3)
    return fig


def figure_region_of_attraction(result: RegionOfAttraction):
    """Fraction of converged runs against the size of the initial offsets."""
    from matplotlib.figure import Figure
    fig = Figure(figsize=(6, 3.6), layout="constrained")
    ax = fig.subplots()
    ax.plot(result.scales, result.fractions, "o-")
    ax.set_ylim(-0.05, 1.05)
    ax.set_xlabel(f"offset size s: base {ROA_UNIT['base_position_offset']:g} s m, attitude "
                  f"{ROA_UNIT['base_rpy_offset']:g} s rad, joints {ROA_UNIT['arm_offset']:g} s rad")
    ax.set_ylabel("fraction converged")
    ax.set_title(f"{len(result.runs)} runs of {result.duration:g} s; converged: completed "
                 f"and V(T) <= exp(-{result.min_decay_rate:g} T) V(0)", fontsize=9)
    ax.grid(True, alpha=0.3)
    return fig


# --- Command line ---------------------------------------------------------------------------


def format_eigenvalue_table(rows: list[dict]) -> str:
    """A :func:`compare_eigenvalues` table as text, slowest first."""
    lines = [f"{'eigenvalue':<46}{'predicted':>14}{'Linearize':>14}{'rel. err':>10}"]
    for r in sorted(rows, key=lambda r: -r["computed"][0] if r["predicted"] is None
                    else -r["predicted"][0]):
        p = "-" if r["predicted"] is None else f"{r['predicted'][0]:.6f}"
        c = "-" if r["computed"] is None else f"{r['computed'][0]:.6f}"
        lines.append(f"{r['label']:<46}{p:>14}{c:>14}{r['relative_mismatch']:10.1e}")
    return "\n".join(lines)


def format_report(report: dict) -> str:
    """The terminal summary of :func:`analyze`'s result."""
    lines = []
    for name, e in report["equilibria"].items():
        cl, ol = e["closed_loop"], e["open_loop"]
        eq = cl["equilibrium"]
        lines.append(f"hover '{name}': CoM {eq['p_WG_m']} m, yaw {eq['yaw_rad']:g} rad, end "
                     f"effector {np.round(eq['p_WE_m'], 3).tolist()} m, q3 {eq['q3_rad']:g}; "
                     f"thrust {eq['thrust_N']:.1f} N")
        lines.append(f"  closed loop: {cl['states']} states, |x_dot| at equilibrium "
                     f"{cl['derivative_residual']:.1e}, max relative eigenvalue mismatch "
                     f"{cl['max_relative_mismatch']:.1e}")
        lines += ["  " + line for line in format_eigenvalue_table(cl["eigenvalues"]).split("\n")]
        lines.append(f"  open loop: IsStabilizable {ol['IsStabilizable']}, IsControllable "
                     f"{ol['IsControllable']} (Kalman matrix sigma ratio "
                     f"{ol['controllability_matrix_conditioning']:.1e}), time-scaled "
                     f"{ol['IsControllable_time_scaled']}; rank B {ol['rank_B']} of "
                     f"{ol['states'] // 2} velocities; rank [B .. A^k B]: "
                     f"{ol['controllability_rank_growth']}")
    lee = report["lee_conditions"]
    lines.append(f"Lee et al.: gamma1 = {lee['gamma1']:g} < "
                 f"{min(lee['gamma1_bounds'].values()):.3g}"
                 f" {'ok' if lee['gamma1_ok'] else 'VIOLATED'}; gamma2 = {lee['gamma2']:g} < "
                 f"{min(lee['gamma2_bounds'].values()):.3g} "
                 f"{'ok' if lee['gamma2_ok'] else 'VIOLATED'} (per axis < "
                 f"{min(lee['gamma2_per_axis_bounds']):.3g}: "
                 f"{'ok' if lee['gamma2_per_axis_ok'] else 'VIOLATED'}); coupling condition "
                 f"{'ok' if lee['coupling_ok'] else 'not met'}")
    ly = report["lyapunov"]
    lines.append(f"Lyapunov ({ly['duration_s']:g} s, {ly['integrator']['scheme']} accuracy "
                 f"{ly['integrator']['accuracy']:g}): V {ly['V']['initial']:.4g} -> "
                 f"{ly['V']['final']:.4g}, max increase {ly['V']['max_increase']:.2e}; V_task max "
                 f"increase {ly['V_task']['max_increase']:.2e}")
    roa = report["region_of_attraction"]
    lines.append("region of attraction (" + roa["criterion"] + "): " + ", ".join(
        f"s = {s:g}: {f:.2f}" for s, f in zip(roa["scales"], roa["converged_fraction"])))
    return "\n".join(lines)


def cli_analyze(args: argparse.Namespace) -> int:
    """``aerial-drake analyze [--out DIR] [--scenario NAME] [--fast] [--seed N] [--quiet]``."""
    import sys

    from aerial_drake.scenarios import ScenarioError
    settings = FAST_SETTINGS if args.fast else FULL_SETTINGS
    try:
        report = analyze(args.out, scenario=args.scenario, settings=settings, seed=args.seed,
                         stream=None if args.quiet else sys.stdout)
    except (ScenarioError, UnreachablePose) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    print(format_report(report))
    return 0
