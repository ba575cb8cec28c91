"""The closed loop at hover linearised: Drake's ``Linearize`` of the continuous closed loop (no
sampling, lag or saturation) at an equilibrium, on an ``RpyFloatingJoint`` base, with the
controller converted to AutoDiffXd (``DecoupledController_[AutoDiffXd]``); its eigenvalues
beside the predicted ones (docs/analysis.md, section 3) (:func:`predicted_eigenvalues`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from pydrake.systems.framework import (
    Diagram,
    DiagramBuilder,
    InputPortSelection,
    OutputPortSelection,
)
from pydrake.systems.primitives import ConstantVectorSource, Demultiplexer, Linearize

from aerial_drake.analysis.equilibria import HoverEquilibrium
from aerial_drake.control.controller import DecoupledController, make_controller
from aerial_drake.control.law import Gains
from aerial_drake.robots.models import AerialManipulator, add_to_builder
from aerial_drake.simulation.diagram import connect_actuation


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
    sim = add_to_builder(builder, model.variant, floating_base=model.floating_base,
                         robot=model.description)
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
    """``Linearize`` of the hover loop, and its eigenvalues beside the predicted ones
    (docs/analysis.md, section 3)."""

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
    """The closed loop's 2 (6 + n) eigenvalues at a hover, each with its origin, as predicted
    in docs/analysis.md, section 3.

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
        rows.append({"group": "unpredicted", "label": "not predicted",
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


