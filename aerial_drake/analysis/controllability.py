"""The open loop at hover: the plant alone with the inputs ``[f, mu, tau]`` linearised
(:func:`linearize_open_loop`), Drake's ``IsControllable`` / ``IsStabilizable``, and where the
rank of the input matrix falls short (underactuation) (:func:`controllability`)."""

from __future__ import annotations

import numpy as np
from pydrake.systems.framework import DiagramBuilder, OutputPortSelection
from pydrake.systems.primitives import (
    ControllabilityMatrix,
    Demultiplexer,
    IsControllable,
    IsStabilizable,
    Linearize,
    LinearSystem,
)

from aerial_drake.analysis.equilibria import HoverEquilibrium
from aerial_drake.analysis.linearization import _actuate
from aerial_drake.robots.models import add_to_builder


# --- The open loop at hover -----------------------------------------------------------------
def linearize_open_loop(eq: HoverEquilibrium) -> LinearSystem:
    """The plant alone, linearised at ``eq`` with its hover inputs; the input is
    ``[f, mu (3), tau (n)]``, the output the full state."""
    model = eq.model
    builder = DiagramBuilder()
    sim = add_to_builder(builder, model.variant, floating_base=model.floating_base,
                         robot=model.description)
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


