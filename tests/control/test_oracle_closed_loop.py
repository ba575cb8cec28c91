"""The closed loop (23a)-(23e) and the Lyapunov function (24)-(26), from the simulated states by
this file's own formulas (issue 22, item 1).

The runs: :func:`aerial_drake.analysis.lyapunov_scenario` (continuous feedback, no disturbance,
no saturation, no lag; Drake's error-controlled runge_kutta3, here at accuracy 1e-7), 0.5 s of
the paper's nominal trajectory and of the shipped ``orbit`` scenario with the compiled law (what
the simulation runs), and 0.3 s of the nominal one with the numpy law (aerial_drake.control,
swapped in through the controller's ``_compiled`` attribute; ``controller.compiled`` is checked).

Nothing below calls the law, the decomposition or the diagnostics code for the quantity checked:
from the logged plant state and the logged references, Drake's MultibodyPlant gives the CoM, its
velocity, R_WB, the end-effector pose, its Jacobian, M and J_g; the Christoffel C comes from
central differences of Drake's M (tests/paper_oracles.py, held against Pinocchio in
test_oracle_pinocchio.py); (10)-(15), (17)-(19), (24)-(25) are written out here; time
derivatives are fourth-order central differences of the 1 kHz log (the first 0.05 s are left
out: the fastest closed-loop modes, -554 and -340 1/s, have decayed by then).

The task error is the package's choice (docs/control.md, math.md section 5): orientation error
e_o = vee(skew(R_E R_ed^T)) and velocity-level y~_dot = J xi - y_d_dot. Its true derivative
differs from y~_dot by w_ed x e_o + O(e_o^2), so the law's z_d_dot (20) is not the derivative
of z_d and (23e) holds only up to Lambda_z K_y (d/dt y~ - y~_dot), nonzero in the orientation
rows (measured: 2.0 % of |K_z z~| on the nominal run). The test checks (23e) with that term
computed here, and checks the term is confined to the orientation rows.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from pydrake.multibody.tree import JacobianWrtVariable

from aerial_drake.analysis import lyapunov_scenario
from aerial_drake.control.law import diagnostics_slices
from aerial_drake.robots.models import make_plant
from aerial_drake.simulation.runner import run_scenario
from aerial_drake.trajectories.reference import (
    unpack_com_reference,
    unpack_heading_reference,
    unpack_task_reference,
)
from paper_oracles import (
    ChristoffelFromMassMatrix,
    central_difference,
    task_jacobian,
    task_space_mobility,
    vee_skew,
)

pytestmark = pytest.mark.slow

ACCURACY = 1e-7  # runge_kutta3's error control
N_TASK = 7  # the paper's task: end-effector pose and q3
SKIP_S = 0.05  # s left out at the start (fast modes), and 4 samples at the end (differences)
RUNS = {"nominal-compiled": ("nominal", "compiled", 0.5),
        "orbit-compiled": ("orbit", "compiled", 0.5),
        "nominal-numpy": ("nominal", "numpy", 0.3)}
E3 = np.eye(3)
e3 = E3[2]


def simulate(name: str, law: str, duration: float):
    scenario = lyapunov_scenario(name, duration=duration, accuracy=ACCURACY)
    assert scenario.controller_period == 0.0 and not scenario.disturbances
    assert not scenario.actuation.saturate and scenario.actuation.lag_rise_time == 0.0

    def configure(builder, loop):
        if law == "numpy":
            assert hasattr(loop.controller, "_compiled"), "the compiled-law switch moved"
            loop.controller._compiled = None
        assert loop.controller.compiled == (law == "compiled")

    result = run_scenario(scenario, progress=False, configure=configure)
    return scenario, result.log


def signals(scenario, log) -> SimpleNamespace:
    """Every quantity of (10)-(25) along the run, from the logged state and references."""
    G = scenario.gains
    K = SimpleNamespace(K_x=np.array(G.K_x), D_x=np.array(G.D_x), k_R=G.k_R, k_w=G.k_w,
                        L2=np.array(G.Lambda2_bar), K_y=np.array(G.K_y), K_z=np.array(G.K_z),
                        g1=G.lyapunov_gamma1, g2=G.lyapunov_gamma2)
    model = make_plant("rigid")
    plant = model.plant
    ctx = plant.CreateDefaultContext()
    m = plant.CalcTotalMass(ctx)
    gravity = -plant.gravity_field().gravity_vector()[2]
    christoffel = ChristoffelFromMassMatrix(make_plant("rigid", floating_base="rpy").plant)
    q3 = model.arm_joints[2]
    world = plant.world_frame()
    nq = plant.num_positions()
    t = log["t"]
    dt = float(t[1] - t[0])
    assert np.allclose(np.diff(t), dt, rtol=1e-9, atol=1e-12)
    rows = []
    for k in range(len(t)):
        q, v = log["plant_state"][k, :nq], log["plant_state"][k, nq:]
        plant.SetPositions(ctx, q)
        plant.SetVelocities(ctx, v)
        com = unpack_com_reference(log["com_reference"][k])  # x_d and 4 derivatives
        task = unpack_task_reference(log["task_reference"][k])
        b1d = unpack_heading_reference(log["heading_reference"][k])[0]
        R = plant.EvalBodyPoseInWorld(ctx, model.base_body).rotation().matrix()
        x_t = plant.CalcCenterOfMassPositionInWorld(ctx) - com[0]
        x_t_dot = plant.CalcCenterOfMassTranslationalVelocityInWorld(ctx) - com[1]
        f_d = m * (com[2] + gravity * e3) - K.K_x * x_t - K.D_x * x_t_dot  # (10)
        b3d = f_d / np.linalg.norm(f_d)  # (12)
        b2d = np.cross(b3d, b1d) / np.linalg.norm(np.cross(b3d, b1d))
        R_d = np.column_stack([np.cross(b2d, b3d), b2d, b3d])  # (13)
        X_WE = model.end_effector_frame.CalcPoseInWorld(ctx)
        J_y = task_jacobian(plant, ctx, model.end_effector_frame, q3.velocity_start())
        y_t = np.concatenate([X_WE.translation() - task.p_ed,
                              vee_skew(X_WE.rotation().matrix() @ task.R_ed.T),
                              q[[q3.position_start()]] - task.q_jd])
        y_d_dot = np.concatenate([task.v_ed, task.w_ed, task.q_jd_dot])
        z_t = J_y @ v - y_d_dot + K.K_y * y_t  # (17)-(18): z~ = y~_dot + K_y y~
        M = plant.CalcMassMatrix(ctx)
        J_g = plant.CalcJacobianCenterOfMassTranslationalVelocity(
            ctx, JacobianWrtVariable.kV, world, world)
        J_z, Lambda_z, M_inv = task_space_mobility(M, J_g, R, J_y)
        w = M_inv @ J_z.T @ Lambda_z @ z_t  # T'^-1 [0; 0; z~], see test_23e
        rows.append(dict(R=R, R_d=R_d, x_t=x_t, x_t_dot=x_t_dot, f_d=f_d, w_b=R.T @ v[:3],
                         e_R=vee_skew(R_d.T @ R),  # (14): 1/2 (R_d^T R - R^T R_d)^vee
                         y_t=y_t, z_t=z_t, Lambda_z=Lambda_z, J_z=J_z, M_inv=M_inv, w=w,
                         C_w=christoffel(q, v) @ w))
    s = SimpleNamespace(**{key: np.array([r[key] for r in rows]) for key in rows[0]})
    s.t, s.dt, s.m, s.K = t, dt, m, K
    s.diagnostics = log["diagnostics"]
    s.window = slice(int(round(SKIP_S / dt)), len(t) - 4)
    # (15): w_d = R^T R_d (R_d^T R_d_dot)^vee, R_d_dot by differences of R_d.
    Omega_d = np.array([vee_skew(Rd.T @ Rd_dot)
                        for Rd, Rd_dot in zip(s.R_d, central_difference(s.R_d, dt))])
    s.w_t = s.w_b - np.einsum("tji,tjk,tk->ti", s.R, s.R_d, Omega_d)
    return s


@pytest.fixture(scope="module", params=list(RUNS))
def run(request):
    name, law, duration = RUNS[request.param]
    scenario, log = simulate(name, law, duration)
    s = signals(scenario, log)
    s.label = request.param
    return s


def relative(residual, *terms, window):
    """max |residual| over the window, relative to the largest of the equation's terms."""
    scale = max(np.abs(term[window]).max() for term in terms)
    return float(np.abs(residual[window]).max() / scale)


def test_23a_com_error_dynamics(run):
    """(23a): m x~'' + K_x x~ + D_x x~' = (R e3 e3^T R^T - E3) f_d (the thrust (11) along
    R e3; x~'' by differences of Drake's CoM velocity). Measured 2.8e-10 (nominal) and 7.0e-10
    (orbit) of the largest term; tolerance 1e-7."""
    err = error_23a(run)
    assert err < 1e-7, (run.label, err)


def error_23a(s):
    K = s.K
    x_t_dd = central_difference(s.x_t_dot, s.dt)
    Re3 = s.R[:, :, 2]
    rhs = Re3 * np.einsum("ti,ti->t", Re3, s.f_d)[:, None] - s.f_d
    residual = s.m * x_t_dd + K.K_x * s.x_t + K.D_x * s.x_t_dot - rhs
    return relative(residual, s.m * x_t_dd, K.K_x * s.x_t, K.D_x * s.x_t_dot, window=s.window)


def test_23c_attitude_error_dynamics(run):
    """(23c): Lbar_2 w~' + k_w w~ + k_R e_R = 0, e_R (14) and w~ (15) from R_d (13) built here.
    Measured 1.9e-8 (nominal) and 4.3e-8 (orbit) of the largest term; tolerance 1e-6."""
    err = error_23c(run)
    assert err < 1e-6, (run.label, err)


def error_23c(s):
    K = s.K
    w_t_dot = central_difference(s.w_t, s.dt)
    residual = K.L2 * w_t_dot + K.k_w * s.w_t + K.k_R * s.e_R
    return relative(residual, K.L2 * w_t_dot, K.k_w * s.w_t, K.k_R * s.e_R, window=s.window)


def test_23e_task_velocity_error_dynamics(run):
    """(23e): Lambda_z z~' + (Gamma_z + K_z) z~ = 0, written without T^-1 or Gamma_z:
    for T' = [J_g; J_bw; J_z] (z = J_z v, tests/paper_oracles.task_space_mobility) and
    w = T'^-1 [0; 0; z~] = M^-1 J_z^T Lambda_z z~, the third block of Lambda' zeta' + Gamma' zeta
    is Lambda_z J_z (w' + M^-1 C w), C the Christoffel matrix. With the package's orientation
    error the law's (20) leaves Lambda_z K_y (d/dt y~ - y~_dot) (module docstring): measured
    2.5e-8 (nominal) and 5.6e-8 (orbit) of |K_z z~| after it; tolerance 1e-6. The term
    itself is 2.0 % of |K_z z~| and lives in the orientation rows: its position and q3 rows of
    d/dt y~ - y~_dot measured 1.2e-8 m/s and rad/s (tolerance 1e-6)."""
    err, off_rows = error_23e(run)
    assert err < 1e-6, (run.label, err)
    assert off_rows < 1e-6, (run.label, off_rows)


def error_23e(s):
    """(residual relative to |K_z z~|, largest position/q3 row of d/dt y~ - y~_dot)."""
    K = s.K
    w_dot = central_difference(s.w, s.dt)
    lhs = np.einsum("tij,tjk,tk->ti", s.Lambda_z, s.J_z,
                    w_dot + np.einsum("tij,tj->ti", s.M_inv, s.C_w))
    y_t_dot_true = central_difference(s.y_t, s.dt)
    y_t_dot_velocity = s.z_t - K.K_y * s.y_t
    gap = y_t_dot_true - y_t_dot_velocity
    orientation_term = np.einsum("tij,tj->ti", s.Lambda_z, K.K_y * gap)
    residual = lhs + K.K_z * s.z_t - orientation_term
    return (relative(residual, K.K_z * s.z_t, window=s.window),
            float(np.abs(gap[s.window][:, [0, 1, 2, 6]]).max()))


def V1_of(s):
    """(25) with k_R/2 tr(E3 - R_d^T R_b) (docs/control.md: the print drops the 1/2)."""
    K = s.K
    return (0.5 * s.m * np.sum(s.x_t_dot ** 2, 1) + 0.5 * np.sum(K.K_x * s.x_t ** 2, 1)
            + K.g1 * np.sum(s.x_t * s.x_t_dot, 1) + 0.5 * np.sum(K.L2 * s.w_t ** 2, 1)
            + 0.5 * K.k_R * (3.0 - np.einsum("tji,tji->t", s.R_d, s.R))
            + K.g2 * np.sum(s.e_R * s.w_t, 1))


def V_task_of(s):
    """(24) without V1: 1/2 z~^T Lambda_z z~ + y~^T K_y K_z y~."""
    K = s.K
    return (0.5 * np.einsum("ti,tij,tj->t", s.z_t, s.Lambda_z, s.z_t)
            + np.sum(K.K_y * K.K_z * s.y_t ** 2, 1))


def test_lyapunov_diagnostics_are_24_25(run):
    """The law's logged V1, V_task, V equal (24)-(25) computed here: measured 4e-13 / 6e-12
    (V1, nominal / orbit), 1e-14 (V_task), 2e-12 (V) of the logged value's largest magnitude;
    tolerance 1e-9. (The gamma_2 term e_R . w~ alone is 1.7e-3 of V1 on these runs.)"""
    for name, err in errors_24_25(run).items():
        assert err < 1e-9, (run.label, name, err)


def errors_24_25(s):
    sl = diagnostics_slices(N_TASK)
    out = {}
    mine = {"V1": V1_of(s), "V_task": V_task_of(s)}
    mine["V"] = mine["V1"] + mine["V_task"]
    w = s.window
    for name, value in mine.items():
        logged = s.diagnostics[:, sl[name]][:, 0]
        out[name] = float(np.abs(logged[w] - value[w]).max() / np.abs(logged[w]).max())
    return out


def test_lyapunov_derivative_is_26(run):
    """dV/dt along the run (differences of V computed here) against (26), with V1_dot from
    (23a)-(23c): with X = (R e3 e3^T R^T - E3) f_d and
    C(R) = 1/2 (tr(R^T R_d) E3 - R^T R_d) (e_R' = C(R) w~, Lee et al.),
    V1' = -x~'^T D_x x~' + g1 |x~'|^2 - g1/m (x~^T K_x x~ + x~^T D_x x~') + (x~' + g1/m x~) . X
          - k_w |w~|^2 + g2 w~^T C(R) w~ - g2 e_R^T Lbar_2^-1 (k_w w~ + k_R e_R),
    and the task part of (26) with the orientation error's term of test_23e added back
    (y~' in the y~ term, Lambda_z K_y (d/dt y~ - y~_dot) in the z~ term). Measured 7.9e-9 / 9.8e-9
    (V1, nominal / orbit) and 6.8e-9 / 2.5e-8 (task) of the derivative's largest magnitude;
    tolerance 1e-6. (26) as printed misses the task part by 0.7 % here (the orientation
    error's derivative)."""
    err_1, err_task = errors_26(run)
    assert err_1 < 1e-6, (run.label, err_1)
    assert err_task < 1e-6, (run.label, err_task)


def errors_26(s):
    K = s.K
    Re3 = s.R[:, :, 2]
    X = Re3 * np.einsum("ti,ti->t", Re3, s.f_d)[:, None] - s.f_d
    C_R = 0.5 * (np.einsum("tji,tji->t", s.R, s.R_d)[:, None, None] * E3
                 - np.einsum("tji,tjk->tik", s.R, s.R_d))
    V1_dot = (-np.sum(K.D_x * s.x_t_dot ** 2, 1) + K.g1 * np.sum(s.x_t_dot ** 2, 1)
              - K.g1 / s.m * (np.sum(K.K_x * s.x_t ** 2, 1) + np.sum(K.D_x * s.x_t * s.x_t_dot, 1))
              + np.sum((s.x_t_dot + K.g1 / s.m * s.x_t) * X, 1) - K.k_w * np.sum(s.w_t ** 2, 1)
              + K.g2 * np.einsum("ti,tij,tj->t", s.w_t, C_R, s.w_t)
              - K.g2 * np.sum(s.e_R / K.L2 * (K.k_w * s.w_t + K.k_R * s.e_R), 1))
    gap = central_difference(s.y_t, s.dt) - (s.z_t - K.K_y * s.y_t)
    V_task_dot = (-np.sum(K.K_z * s.z_t ** 2, 1)
                  - 2 * np.sum(s.y_t * K.K_y * K.K_z * (K.K_y * s.y_t - s.z_t), 1)  # (26)
                  + 2 * np.sum(s.y_t * K.K_y * K.K_z * gap, 1)
                  + np.sum(s.z_t * np.einsum("tij,tj->ti", s.Lambda_z, K.K_y * gap), 1))
    w = s.window
    err_1 = relative(central_difference(V1_of(s), s.dt) - V1_dot, V1_dot, window=w)
    err_task = relative(central_difference(V_task_of(s), s.dt) - V_task_dot, V_task_dot,
                        window=w)
    return err_1, err_task
