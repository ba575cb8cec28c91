"""``robot check``'s push margins against simulated pushes (tools/push_margins.py, the tests):
the check's scenario flown as a hover at its hover point (``trajectory.kind: hover``, no
start offsets, no perturbations, its own windows replaced) under a push on the vehicle that
grows as a staircase of :data:`RAMP_STEPS` windows (overlapping windows add; a window is a
step) over :data:`RAMP_TIME_CONSTANTS` time constants of the loop's slowest root, then
holds for :data:`HOLD_TIME_CONSTANTS` more: slowly enough that the robot stays near the
static equilibrium the check predicts (a step push overshoots it: docs/control.md).

A run survives the push, or stops: Assumption 1 or 2, a non-finite value, or a joint past
its position limit (``joint_limits.positions: stop``). For a run that survives a push past
the check's margin, :func:`simulate_push` says why: the limits the run's final state breaks
at rest (:meth:`~.loaded_rest.RestLoop.limits_at`), e.g. the end-effector hold or an input's
saturation, which a run does not stop on."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from pydrake.math import RotationMatrix

from aerial_drake.analysis.onboarding.check_subject import CheckSubject
from aerial_drake.analysis.onboarding.loaded_rest import RestLoop
from aerial_drake.simulation.runner import SimulationFailed, run_scenario
from aerial_drake.simulation.scenarios import Disturbance, Scenario
from aerial_drake.simulation.scenarios.schema import InitialCondition
from aerial_drake.simulation.tracking import entries
from aerial_drake.trajectories.orientation import EeOrientation
from aerial_drake.trajectories.params import HoverParams

#: The push's staircase: this many equal steps over RAMP_TIME_CONSTANTS time constants of the
#: slowest closed-loop root, then held for HOLD_TIME_CONSTANTS; the hover first runs
#: SETTLE_S seconds alone.
RAMP_STEPS = 100
RAMP_TIME_CONSTANTS = 10.0
HOLD_TIME_CONSTANTS = 5.0
SETTLE_S = 0.5
#: What a run's failure names, in order of precedence, and the cause reported.
CAUSES = (("Assumption 1", "Assumption 1"), ("Assumption 2", "Assumption 2"),
          ("joint", "joint limit"), ("non-finite", "non-finite"), ("NaN", "non-finite"))


@dataclass(frozen=True)
class PushRun:
    """One simulated push and what it did."""

    force: np.ndarray  # World, N (the full push)
    survived: bool
    cause: str  # "" if survived; else one of CAUSES' causes or "other"
    failure: str  # the run's failure message ("" if survived)
    stopped_at: float  # s (the duration if survived)
    com_deflection_max: float  # m, max |x_g - x_d| over the run
    com_deflection_end: float  # m, at the end
    ee_error_max: float  # m, max |p_E - p_ed|
    sigma_min_min: float  # smallest sigma_min(J_3)
    violated_at_end: tuple[str, ...]  # the check's limits the final state breaks at rest

    def to_json(self) -> dict:
        return {"force_N": self.force.tolist(), "survived": self.survived,
                "cause": self.cause, "failure": self.failure, "stopped_at_s": self.stopped_at,
                "com_deflection_max_m": self.com_deflection_max,
                "com_deflection_end_m": self.com_deflection_end,
                "ee_error_max_m": self.ee_error_max, "sigma_min_J3_min": self.sigma_min_min,
                "violated_at_end": list(self.violated_at_end)}


def time_constant(subject: CheckSubject) -> float:
    """1 / |real part| of the loop's slowest predicted root at the nominal posture (s): the CoM
    and attitude loops' (:func:`~aerial_drake.control.gain_design.loop_roots`) and the task's,
    ``-K_y`` and the eigenvalues of ``-Lambda_z^-1 K_z`` (docs/analysis.md, section 3). A
    light wrist's task root can be the slowest (0.65 1/s on the hexacopter arm of
    docs/robots.md, against its CoM's 3.5 1/s): a push grown over the CoM's time constants
    only outran it, and the arm left the static path the check follows."""
    from aerial_drake.analysis.onboarding.gains import task_inertia
    from aerial_drake.control.gain_design import loop_roots
    g = subject.scenario.gains
    roots = loop_roots(subject.mass, g.K_x, g.D_x, g.k_R, g.k_w, g.Lambda2_bar)
    _, Lambda_z = task_inertia(subject.model, subject.q0)
    task_z = np.linalg.eigvals(np.linalg.solve(Lambda_z, np.diag(g.K_z))).real
    slowest = min(abs(roots.slowest_com.real), abs(roots.slowest_attitude.real),
                  float(np.min(g.K_y)), float(np.min(task_z)))
    return 1.0 / slowest


def push_scenario(subject: CheckSubject, force: np.ndarray) -> Scenario:
    """The hover scenario of the module docstring under ``force`` (World, N) on the vehicle."""
    s, hover = subject.scenario, subject.hover
    tau = time_constant(subject)
    ramp, hold = RAMP_TIME_CONSTANTS * tau, HOLD_TIME_CONSTANTS * tau
    duration = SETTLE_S + ramp + hold
    b1 = hover.b1d[0]
    params = HoverParams(
        ee_position=hover.p_ed.tolist(),
        ee_orientation=EeOrientation(
            quaternion=RotationMatrix(hover.R_ed).ToQuaternion().wxyz().tolist()),
        heading=math.atan2(b1[1], b1[0]), com=hover.com[0].tolist())
    trajectory = dataclasses.replace(s.trajectory, kind="hover", hover=params,
                                     joint_targets=hover.q_jd.tolist())
    step = np.asarray(force, dtype=float) / RAMP_STEPS
    windows = [Disturbance(target="vehicle", start=SETTLE_S + k * ramp / RAMP_STEPS,
                           stop=duration + 1.0, force=step.tolist(), torque=[0.0, 0.0, 0.0])
               for k in range(RAMP_STEPS)]
    defaults = Scenario()
    return dataclasses.replace(
        s, name=f"{s.name}_push", duration=duration, trajectory=trajectory,
        initial=InitialCondition(), disturbances=windows,
        model_mismatch=defaults.model_mismatch, payload=defaults.payload, wind=defaults.wind,
        sensing=defaults.sensing, random_disturbances=defaults.random_disturbances)


def _cause(failure: str) -> str:
    for key, cause in CAUSES:
        if key in failure:
            return cause
    return "other"


def simulate_push(subject: CheckSubject, force: np.ndarray,
                  loop: RestLoop | None = None) -> PushRun:
    """Fly :func:`push_scenario` (module docstring) and measure it."""
    scenario = push_scenario(subject, force)
    try:
        result = run_scenario(scenario, progress=False)
        failure = ""
    except SimulationFailed as err:
        if err.result is None:  # stopped before a log (an interrupt): nothing to measure
            raise
        result, failure = err.result, str(err)
    log = result.log
    tracking = entries(log["tracking"], result.layouts["tracking"])
    violated: tuple[str, ...] = ()
    if not failure and scenario.plant_variant == "rigid":
        loop = loop or RestLoop(subject)
        q = log["plant_state"][-1, :subject.model.plant.num_positions()]
        violated = loop.limits_at(q).violated
    return PushRun(
        force=np.asarray(force, dtype=float), survived=not failure,
        cause=_cause(failure) if failure else "", failure=failure,
        stopped_at=float(log["t"][-1]),
        com_deflection_max=float(np.max(tracking["com_error"])),
        com_deflection_end=float(tracking["com_error"][-1, 0]),
        ee_error_max=float(np.max(tracking["ee_position_error"])),
        sigma_min_min=float(np.min(tracking["sigma_min_J3"])),
        violated_at_end=violated)
