"""The Lyapunov function along trajectories: the conditions of Lee et al. on ``gamma1``,
``gamma2`` of (25) (:func:`lee_conditions`), and ``V(t)`` of (24)-(25) along the nominal
trajectory without disturbances, continuous feedback, no saturation, an error-controlled
integrator (:func:`lyapunov_study`)."""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass

import numpy as np
from pydrake.systems.analysis import SimulatorConfig

from aerial_drake.analysis.settings import FULL_SETTINGS
from aerial_drake.control.law import Gains, diagnostics_slices, task_size_of_diagnostics
from aerial_drake.simulation.scenarios import Scenario, load_scenario

#: V(0) below this is round-off, not an error (a start within about 1e-7 m and rad of the
#: reference): the run started on its reference and V's decrease shows nothing.
V_ROUND_OFF = 1e-12


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
               "wall_time_s": self.wall_time_s,
               # V(0) is round-off (V_ROUND_OFF): the run started on its reference.
               "started_on_reference": bool(len(self.V) and abs(float(self.V[0])) < V_ROUND_OFF)}
        for name in ("V", "V1", "V_task"):
            x = getattr(self, name)
            rise = self.max_increase(x)
            out[name] = {"initial": float(x[0]), "final": float(x[-1]), "max_increase": rise,
                         "max_increase_relative": rise / float(x[0])
                         if x[0] > 0 and not out["started_on_reference"] else math.nan}
        return out


def lyapunov_study(base: Scenario | str = "nominal", *,
                   duration: float = FULL_SETTINGS.lyapunov_duration,
                   accuracy: float = FULL_SETTINGS.lyapunov_accuracy, gamma1: float | None = None,
                   gamma2: float | None = None) -> LyapunovResult:
    """``V``, ``V1`` and ``V_task`` of (24)-(25) along :func:`lyapunov_scenario`'s run
    (the controller's diagnostics at the log period). ``gamma1``, ``gamma2`` override the
    scenario's ``gains.lyapunov_gamma1/2`` (they change ``V1``, not the control)."""
    from aerial_drake.simulation.runner import (
        run_scenario,  # runner imports much; keep import local
    )

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
    d = result.log["diagnostics"]
    s = diagnostics_slices(task_size_of_diagnostics(d.shape[1]))
    return LyapunovResult(scenario=scenario, t=result.log["t"], V=d[:, s["V"]].ravel(),
                          V1=d[:, s["V1"]].ravel(), V_task=d[:, s["V_task"]].ravel(),
                          wall_time_s=wall)


def trajectory_accel_bound(scenario: Scenario, m: float, samples: int = 2001) -> float:
    """``max |m x_d'' + m g e3|`` over the scenario's trajectory (Assumption 3's bound), g
    from the plant's gravity field."""
    from aerial_drake.trajectories.kinds import sample_reference
    t = np.linspace(0.0, scenario.duration, samples)
    ref = sample_reference(scenario.trajectory, t)
    gravity = scenario.controller_model().plant.gravity_field().gravity_vector()
    acc = np.asarray(ref.com)[:, 2, :] - gravity
    return float(m * np.linalg.norm(acc, axis=1).max())


