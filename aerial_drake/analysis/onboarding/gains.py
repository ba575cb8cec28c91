"""The gains ``robot init`` writes: Table II scaled to the robot by one rule (docs/robots.md,
"robot init", "Gains"). Table II is read from the shipped ``nominal`` scenario and the paper's
robot from its description (one source for every number).

- **CoM** ``K_x``, ``D_x``: Table II's times ``m / m_II`` (``m`` the robot's total mass,
  ``m_II`` the paper robot's): each CoM axis ``m s^2 + D_x s + K_x`` keeps Table II's roots
  (-3.5 and -4.2 1/s).
- **attitude**: ``Lambda2_bar`` the robot's own ``Lambda_22`` at the nominal posture
  (diagonal of the base block of (5)): the attitude law (16) then reshapes no inertia at hover.
  ``k_R``, ``k_w`` by the project's gain design rule
  (:func:`aerial_drake.control.gain_design.suggested_attitude_gains`): every attitude root's
  real part at least 3x the CoM's slowest (Table II's own attitude root is slower than its
  CoM's: docs/control.md, "Gain design help"), so the thrust turns before the CoM drifts.
- **task** ``K_z``: Table II's value of the row's kind (position, orientation, joint),
  lowered where a pole of ``-Lambda_z^-1 K_z`` (the task's inner loop, (23)) would pass
  :data:`TASK_POLE_LIMIT` times the control rate, at the nominal posture or at any of
  :data:`NEARBY_POSTURES` postures about it (each joint within :data:`NEARBY_SPREAD`): a
  light wrist has a small task inertia, and K_z = 30 there would put a pole far past the
  sampling (docs/robots.md, "The quadrotor with the UR3e").
- **task** ``K_y``: Table II's value of the row's kind, but the position rows' on a row whose
  K_z was lowered: the row's error follows ``z~ / K_y`` (23), and a soft row (small K_z) is
  pushed by the stiff rows through ``Lambda_z``'s coupling (measured on a hexacopter with a
  6-joint arm: K_y = 10 on its capped orientation rows let a 10 mrad start offset grow to
  305 mrad; 30 held it to 117 mrad).
"""

from __future__ import annotations

import functools
import warnings
from dataclasses import dataclass

import numpy as np

from aerial_drake.control.gain_design import loop_roots, suggested_attitude_gains
from aerial_drake.control.gains import Gains
from aerial_drake.dynamics.decoupling import DecoupledDynamics
from aerial_drake.dynamics.equilibrium import kinematic_J3
from aerial_drake.robots.description import default_robot
from aerial_drake.robots.models import AerialManipulator, make_plant
from aerial_drake.robots.task import POSE_ROWS

#: The fastest task pole allowed, as a fraction of the control rate 1/period.
TASK_POLE_LIMIT = 0.3
#: How many postures about the nominal the task poles are checked at, and how far each arm
#: joint moves there (rad): the inertia a light wrist shows a task row changes fast with the
#: posture (measured: a pole of 292 1/s at a hexacopter arm's nominal reached 2100 1/s 0.1 rad
#: away, and the sampled loop diverged).
NEARBY_POSTURES = 40
NEARBY_SPREAD = 0.3
#: The posture search's cheaper check: this many nearby postures per candidate.
SEARCH_NEARBY_POSTURES = 8
#: The shipped scenario whose gains are Table II's.
TABLE_II_SCENARIO = "nominal"


@dataclass(frozen=True)
class ScaledGains:
    gains: Gains
    mass: float  # the robot's (kg)
    paper_mass: float  # m_II (kg)
    Lambda_22: np.ndarray  # (3, 3) at the nominal posture
    Lambda_z: np.ndarray  # (n, n) at the nominal posture
    task_poles: np.ndarray  # eigenvalues of -Lambda_z^-1 K_z (1/s)
    capped_rows: tuple[int, ...]  # task rows whose K_z was lowered
    fastest_nearby: float  # the fastest task pole over the nearby postures (1/s)


def _kind(row: int) -> str:
    return "position" if row < 3 else "orientation" if row < POSE_ROWS else "joint"


@functools.cache  # a scenario load and a plant: once per process, not per posture search
def table_ii() -> tuple[Gains, dict[str, tuple[float, float]], float]:
    """Table II's gains, its ``(K_y, K_z)`` per row kind, and the paper robot's mass."""
    from aerial_drake.control.gain_design import GainDesignWarning
    from aerial_drake.simulation.scenarios import load_scenario

    with warnings.catch_warnings():  # Table II's own slow attitude root: known, not this robot's
        warnings.simplefilter("ignore", GainDesignWarning)
        nominal = load_scenario(TABLE_II_SCENARIO)
    paper = make_plant(robot=default_robot())
    assert paper.task is not None
    by_kind: dict[str, tuple[float, float]] = {}
    for i, row in enumerate(paper.task.rows):
        by_kind.setdefault(_kind(row), (nominal.gains.K_y[i], nominal.gains.K_z[i]))
    return nominal.gains, by_kind, paper.total_mass()


def _round(x: float) -> float:
    return float(f"{x:.3g}")


def _floor_2(x: float) -> float:
    """``x`` rounded down to two significant figures (a capped K_z stays under its cap)."""
    scale = 10.0 ** (np.floor(np.log10(x)) - 1)
    return float(np.floor(x / scale) * scale)


def task_inertia(manip: AerialManipulator, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(Lambda_22, Lambda_z)`` at positions ``q`` ((5) and (19))."""
    plant = manip.plant
    ctx = plant.CreateDefaultContext()
    plant.SetPositions(ctx, q)
    d = DecoupledDynamics(plant, manip.base_body).compute(ctx)
    J3_inv = np.linalg.inv(kinematic_J3(manip, ctx))
    return d.Lambda[3:6, 3:6], J3_inv.T @ d.Lambda[6:, 6:] @ J3_inv  # (19)


def _fastest(K: np.ndarray, inertias: list[np.ndarray]) -> float:
    return max(float(np.max(np.linalg.eigvals(np.linalg.solve(L, np.diag(K))).real))
               for L in inertias)


def _capped_K_z(K_z: np.ndarray, inertias: list[np.ndarray], limit: float
                ) -> tuple[np.ndarray, tuple[int, ...]]:
    """``K_z`` with every eigenvalue of ``Lambda_z^-1 K_z`` at most ``limit`` for each
    ``Lambda_z`` of ``inertias`` (the first the nominal posture's): each row first at most
    ``limit`` times the smallest inertia that row sees alone, ``1 / (Lambda_z^-1)_ii`` (the
    row's own pole), then the rows so lowered scaled together until the coupled poles are
    under the limit too."""
    row_inertia = np.min([1.0 / np.diag(np.linalg.inv(L)) for L in inertias], axis=0)
    K = np.minimum(K_z, limit * row_inertia)
    capped = np.flatnonzero(K < K_z)
    for _ in range(100):
        fastest = _fastest(K, inertias)
        if fastest <= limit * (1 + 1e-9):
            break
        scale = np.ones_like(K)
        scale[capped if capped.size else np.arange(K.size)] = 0.98 * limit / fastest
        K = K * scale
    return K, tuple(int(i) for i in capped)


def nearby_positions(manip: AerialManipulator, q: np.ndarray, count: int = NEARBY_POSTURES,
                     spread: float = NEARBY_SPREAD, seed: int = 0) -> list[np.ndarray]:
    """``q`` and ``count`` positions with each arm joint moved uniformly within ``spread``
    rad (inside its limits): the postures a run near the nominal visits."""
    rng = np.random.default_rng(seed)
    lower, upper = manip.arm_position_limits()
    arm = manip.arm_position_indices
    out = [q]
    for _ in range(count):
        moved = q.copy()
        moved[arm] = np.clip(q[arm] + rng.uniform(-spread, spread, arm.size), lower, upper)
        out.append(moved)
    return out


def table_ii_K_z(manip: AerialManipulator) -> np.ndarray:
    """Table II's K_z for each of ``manip``'s task rows, by the row's kind."""
    _, by_kind, _ = table_ii()
    assert manip.task is not None
    return np.array([by_kind.get(_kind(r), by_kind["position"])[1] for r in manip.task.rows],
                    float)


def slowest_task_pole(manip: AerialManipulator, q: np.ndarray, K_z0: np.ndarray,
                      controller_period: float, nearby: int = SEARCH_NEARBY_POSTURES) -> float:
    """The slowest task pole (1/s, positive) at positions ``q`` with ``K_z0`` capped as
    :func:`scaled_gains` caps it, over ``nearby`` postures about ``q`` (the posture search's
    cheaper version of the rule); 0 where J_3 is singular."""
    try:
        inertias = [task_inertia(manip, p)[1] for p in nearby_positions(manip, q, nearby)]
    except np.linalg.LinAlgError:
        return 0.0
    K, _ = _capped_K_z(K_z0, inertias, TASK_POLE_LIMIT / controller_period)
    return float(np.min(np.linalg.eigvals(np.linalg.solve(inertias[0], np.diag(K))).real))


def scaled_gains(manip: AerialManipulator, q: np.ndarray, controller_period: float
                 ) -> ScaledGains:
    """The gains of the module docstring for ``manip`` at positions ``q`` (the nominal
    posture, vehicle level)."""
    II, by_kind, m_II = table_ii()
    m = manip.total_mass()
    ratio = m / m_II
    K_x = [_round(k * ratio) for k in II.K_x]
    D_x = [_round(d * ratio) for d in II.D_x]
    Lambda_22, Lambda_z = task_inertia(manip, q)
    Lambda2_bar = [_round(x) for x in np.diag(Lambda_22)]
    roots = loop_roots(m, K_x, D_x, II.k_R, II.k_w, Lambda2_bar)
    k_R, k_w = suggested_attitude_gains(roots)
    assert manip.task is not None
    kinds = [_kind(r) for r in manip.task.rows]
    K_z0 = table_ii_K_z(manip)
    inertias = [Lambda_z] + [task_inertia(manip, p)[1] for p in nearby_positions(manip, q)[1:]]
    K_z, capped = _capped_K_z(K_z0, inertias, TASK_POLE_LIMIT / controller_period)
    # A row with a lowered K_z takes the position rows' K_y: its stiffness K_y K_z falls less
    # and its error follows z~ / K_y closer (the shipped quadrotor_ur3e's choice).
    K_y = [by_kind["position"][0] if i in capped else by_kind.get(k, by_kind["position"])[0]
           for i, k in enumerate(kinds)]
    K_z = np.array([_floor_2(k) if i in capped else k for i, k in enumerate(K_z)])
    gains = Gains(K_x=K_x, D_x=D_x, k_R=k_R, k_w=k_w, Lambda2_bar=Lambda2_bar,
                  K_y=[float(k) for k in K_y], K_z=[float(k) for k in K_z])
    poles = -np.linalg.eigvals(np.linalg.solve(Lambda_z, np.diag(K_z)))
    return ScaledGains(gains=gains, mass=m, paper_mass=m_II, Lambda_22=Lambda_22,
                       Lambda_z=Lambda_z, task_poles=poles, capped_rows=capped,
                       fastest_nearby=_fastest(K_z, inertias))
