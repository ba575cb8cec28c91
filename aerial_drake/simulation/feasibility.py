"""Checks of a scenario against its robot before anything is simulated (exit status 2): the
whole reference (:func:`check_reference`: thrust, reach, Assumption 1 along it, smoothness)
and Assumption 1 at the start state (:func:`check_start_posture`). Each failure is a
ScenarioError naming the time, the cause and the fields to change.

Sampling (docs/control.md, "Checks before a run"):

- thrust, reach and smoothness every :data:`SAMPLE_PERIOD` = 10 ms, vectorised through the
  run's :class:`~aerial_drake.trajectories.base.ReferenceSource` (any reference kind). The
  paper's fastest terms turn at 3 rad/s, so a sampled peak of |f_d| is within
  (3 x 0.01)^2 / 8 = 1e-4 of the true one, and the worst sample is then refined at 0.5 ms; a
  discontinuity is bisected down to microseconds (:mod:`aerial_drake.trajectories.continuity`);
- the posture that realises the task every :data:`POSTURE_PERIOD` = 50 ms (20 Hz), as each
  configuration costs a Newton solve (about a millisecond, from the previous sample's), and
  every sampled local minimum of sigma_min(J_3) below :data:`REFINE_BELOW` margins is
  resampled at 5 ms around it (a singular posture is passed in an instant).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from aerial_drake.control.controller import task_jacobian
from aerial_drake.control.reference_pose import mass_and_gravity, realising_targets
from aerial_drake.dynamics.decoupling import DecoupledDynamics
from aerial_drake.dynamics.equilibrium import (
    UnreachablePose,
    kinematic_J3,
    solve_configuration,
    track_configuration,
)
from aerial_drake.robots.models import AerialManipulator, nominal_end_effector_offset
from aerial_drake.simulation.diagram import input_limits
from aerial_drake.simulation.scenarios import Scenario, ScenarioError
from aerial_drake.trajectories.base import ReferenceSource
from aerial_drake.trajectories.continuity import find_discontinuity
from aerial_drake.trajectories.kinds import reference_of
from aerial_drake.trajectories.reference import ReferenceSample

#: Period of the reference samples for thrust, reach and smoothness (s).
SAMPLE_PERIOD = 0.01
#: Period of the postures solved for Assumption 1 along the reference (s).
POSTURE_PERIOD = 0.05
#: sigma_min(J_3) must stay above this many times the scenario's sigma_min_J3_limit along
#: the reference: the run itself stops at the limit, and the tracked state leaves the
#: reference's posture by the tracking error, so the reference keeps 3x clear of it.
SIGMA_MARGIN_FACTOR = 3.0
#: Sampled local minima of sigma_min(J_3) below this many margins are resampled finely.
REFINE_BELOW = 10.0


def check_reference(scenario: Scenario, model: AerialManipulator,
                    reference: ReferenceSource | None = None) -> None:
    """Raise ScenarioError at the first way the whole reference of ``scenario`` is not
    feasible for ``model`` (the controller's): a discontinuity in a derivative the law needs,
    a thrust above the limit or below Assumption 2's threshold, the end effector out of the
    arm's reach, or Assumption 1 (sigma_min(J_3) above its margin) failing at the posture
    that realises the task. ``reference``: the run's reference (None: built from
    ``scenario.trajectory``). Sampling: the module docstring."""
    reference = _source(scenario, model, reference)
    times = sample_times(scenario.duration, SAMPLE_PERIOD)
    ref = reference.sample(times)
    found = find_discontinuity(reference.sample, times)
    if found is not None:
        raise ScenarioError(
            f"trajectory: the reference is not smooth enough for the law: {found.describe()}. "
            "The law needs x_d up to its 4th derivative, p_ed, R_ed (w_ed, dw_ed) and q_jd up "
            "to the 2nd, b1d up to the 2nd, each continuous and the rate of the one below: "
            "give a smoother reference (splines of higher degree, or correct derivatives)",
            "trajectory")
    check_thrust(scenario, model, ref, times, reference=reference)
    _check_reach(model, ref, times, model.description.workspace_radius)
    check_postures(scenario, model, reference=reference)


def sample_times(duration: float, period: float) -> np.ndarray:
    """[0, period, 2 period, ...] up to ``duration``, with ``duration`` itself last."""
    count = max(int(math.ceil(duration / period - 1e-9)), 3)
    return np.linspace(0.0, duration, count + 1)


def _source(scenario: Scenario, model: AerialManipulator,
            reference: ReferenceSource | None) -> ReferenceSource:
    """``reference``, or (None) the one ``scenario.trajectory`` describes for ``model``."""
    if reference is not None:
        return reference
    return reference_of(scenario.trajectory, model.task_joint_nominal())


def _thrust_needed(m: float, g: float, ref: ReferenceSample) -> np.ndarray:
    """|f_d| = |m (x_d'' + g e3)| of (10) at zero CoM error, per sample (N)."""
    return m * np.linalg.norm(ref.com[:, 2] + np.array([0.0, 0.0, g]), axis=1)


def check_thrust(scenario: Scenario, model: AerialManipulator, ref: ReferenceSample,
                 times: np.ndarray, *, reference: ReferenceSource | None = None) -> None:
    """Raise ScenarioError if the thrust the reference needs, |m (x_d'' + g e3)| (10), leaves
    [max(thrust minimum, f_d_limit), thrust maximum] (the robot's limits or the scenario's
    actuation overrides, as the run saturates them; no upper bound if it does not saturate).
    ``ref``: the reference sampled at ``times``; ``reference``: the one sampled (None: built
    from ``scenario.trajectory``), refined near the extremes."""
    reference = _source(scenario, model, reference)
    m, g = mass_and_gravity(model)
    lower, upper = input_limits(scenario, model)
    thrust_max, thrust_min = float(upper[0]), float(lower[0])
    f = _thrust_needed(m, g, ref)
    worst = _refined_extreme(reference, m, g, times, int(np.argmax(f)), np.max)
    if worst[1] > thrust_max:
        t, need = worst
        raise ScenarioError(
            f"trajectory: the reference needs a thrust of {need:.1f} N at t = {t:.3f} s "
            f"(|m (x_d'' + g e3)|, m = {m:.2f} kg), {need - thrust_max:.1f} N above the "
            f"thrust maximum {thrust_max:g} N (the robot's limits.thrust, or "
            "actuation.thrust_max), with nothing left for feedback: slow the reference's CoM "
            "motion (smaller or slower trajectory amplitudes) or raise actuation.thrust_max",
            "trajectory")
    t, need = _refined_extreme(reference, m, g, times, int(np.argmin(f)), np.min)
    for bound, what in ((scenario.f_d_limit, "Assumption 2's threshold f_d_limit"),
                        (thrust_min, "the thrust minimum (limits.thrust or "
                                     "actuation.thrust_min)")):
        if need < bound:
            raise ScenarioError(
                f"trajectory: the reference needs a thrust of only {need:.3g} N at t = "
                f"{t:.3f} s (|m (x_d'' + g e3)|, m = {m:.2f} kg), {bound - need:.3g} N below "
                f"{what} = {bound:g} N: the CoM reference falls at nearly g there (x_d'' = "
                f"{np.round(ref.com[int(np.argmin(f)), 2], 2).tolist()} m/s^2), so its "
                "attitude (13) is undefined: limit the reference's downward acceleration",
                "trajectory")


def _refined_extreme(reference: ReferenceSource, m: float, g: float, times: np.ndarray,
                     k: int, pick) -> tuple[float, float]:
    """(time, |f_d|) of the extreme (``pick``: np.max or np.min) near sample ``k``, from
    samples 0.5 ms apart over the neighbouring intervals."""
    h = float(times[1] - times[0])
    fine = np.linspace(max(times[k] - h, 0.0), min(times[k] + h, times[-1]), 41)
    f = _thrust_needed(m, g, reference.sample(fine))
    i = int(np.argmax(f)) if pick is np.max else int(np.argmin(f))
    return float(fine[i]), float(f[i])


def check_workspace(scenario: Scenario, model: AerialManipulator, *,
                    radius: float | None = None, rate: float = 50.0,
                    reference: ReferenceSource | None = None) -> None:
    """Raise ScenarioError if the reference leaves the arm's workspace at any sampled time
    (``rate`` samples per second; :func:`check_reference` checks it at 100 Hz).

    The arm holds the end effector at a fixed offset from the system CoM in the heading frame
    (x_d = x_c + R3(phi4) r_o, (33)); the task is feasible while the desired offset
    R3(phi4)^T (p_ed - x_d) stays within ``radius`` of the model's nominal one (default: the
    robot description's ``workspace_radius``). ``reference``: the run's reference (None:
    built from ``scenario.trajectory``).
    """
    radius = model.description.workspace_radius if radius is None else radius
    times = np.linspace(0.0, scenario.duration, int(scenario.duration * rate) + 1)
    _check_reach(model, _source(scenario, model, reference).sample(times), times, radius)


def _check_reach(model: AerialManipulator, ref: ReferenceSample, times: np.ndarray,
                 radius: float) -> None:
    nominal = nominal_end_effector_offset(model)
    offset = ref.p_ed - ref.com[:, 0]
    b1 = ref.b1d[:, 0]  # heading direction (unit, horizontal)
    x_h = np.einsum("ti,ti->t", offset, b1)
    y_h = -offset[:, 0] * b1[:, 1] + offset[:, 1] * b1[:, 0]
    dev = np.linalg.norm(np.column_stack([x_h, y_h, offset[:, 2]]) - nominal, axis=1)
    worst = int(np.argmax(dev))
    if dev[worst] > radius:
        raise ScenarioError(
            f"trajectory: the desired end effector leaves the arm's workspace at t = "
            f"{times[worst]:.2f} s: it is {dev[worst]:.3f} m from its nominal offset "
            f"{np.round(nominal, 3).tolist()} m to the desired CoM (the system's; heading "
            f"frame; limit {radius} m, the robot's workspace_radius). Keep the end-effector "
            "reference near that offset from the CoM reference: trajectory.com_offset near "
            "the nominal offset (the paper and waypoints kinds' rule (33)), a smaller "
            "trajectory.agile_amplitude (paper kind), or CoM waypoints closer to the end "
            "effector's.", "trajectory")


def check_postures(scenario: Scenario, model: AerialManipulator,
                   period: float = POSTURE_PERIOD, *,
                   reference: ReferenceSource | None = None) -> float:
    """Raise ScenarioError if no posture realises the reference at a sampled time (out of
    reach), or if sigma_min(J_3) there is below SIGMA_MARGIN_FACTOR x the scenario's
    sigma_min_J3_limit (Assumption 1 along the reference). Returns the smallest sigma found.

    The postures are tracked: each sample's Newton solve starts from the previous one's
    (:func:`~aerial_drake.dynamics.equilibrium.track_configuration`), with the full solve
    as the fallback; J_3 comes from kinematics alone
    (:func:`~aerial_drake.dynamics.equilibrium.kinematic_J3`). ``reference``: the run's
    reference (None: built from ``scenario.trajectory``)."""
    reference = _source(scenario, model, reference)
    times = sample_times(scenario.duration, period)
    margin = SIGMA_MARGIN_FACTOR * scenario.sigma_min_J3_limit
    tracker = _PostureTracker(model)
    ref = reference.sample(times)
    q = [tracker.solve(float(t), _at(ref, k)) for k, t in enumerate(times)]
    sigma = np.array(tracker.sigmas)
    worst = int(np.argmin(sigma))
    t_worst, s_worst = float(times[worst]), float(sigma[worst])
    inner = (sigma[1:-1] <= sigma[:-2]) & (sigma[1:-1] <= sigma[2:])
    for k in 1 + np.flatnonzero(inner & (sigma[1:-1] < REFINE_BELOW * margin)):
        tracker.restart(q[k - 1])
        fine = np.linspace(times[k - 1], times[k + 1], 21)[1:]
        fine_ref = reference.sample(fine)
        for i, t in enumerate(fine):
            tracker.solve(float(t), _at(fine_ref, i))
            if tracker.sigmas[-1] < s_worst:
                t_worst, s_worst = float(t), tracker.sigmas[-1]
    if not s_worst > margin:
        raise ScenarioError(
            f"trajectory: Assumption 1 fails along the reference at t = {t_worst:.3f} s: at "
            f"the posture that realises the task there, sigma_min(J_3) = {s_worst:.3g}, "
            f"below the margin {margin:.3g} ({SIGMA_MARGIN_FACTOR:g} x sigma_min_J3_limit "
            f"= {scenario.sigma_min_J3_limit:g}): the reference passes (near) a singular "
            "posture of the arm for the task "
            f"{list(model.task.components) if model.task else []}, where the law cannot "
            "control it. Move the end-effector reference (its orientation, its offset from "
            "the CoM) away from that posture, or change the task", "trajectory")
    return s_worst


class _PostureTracker:
    """The postures that realise a reference at increasing times, each solved from the
    last, with sigma_min(J_3) at each (``sigmas``)."""

    def __init__(self, model: AerialManipulator) -> None:
        self.model = model
        self.context = model.plant.CreateDefaultContext()
        self.mass_gravity = mass_and_gravity(model)
        self.q: np.ndarray | None = None
        self.sigmas: list[float] = []

    def restart(self, q: np.ndarray) -> None:
        self.q = q

    def solve(self, t: float, ref: ReferenceSample) -> np.ndarray:
        """The posture that realises ``ref``, the reference at time ``t``."""
        targets = realising_targets(self.model, ref, self.mass_gravity)
        q = None if self.q is None else track_configuration(
            self.model, self.q, self.context, **targets)
        if q is None:
            try:
                q = solve_configuration(self.model, **targets, q_guess=self.q,
                                        respect_joint_limits=False)
            except UnreachablePose as err:
                raise ScenarioError(
                    f"trajectory: no posture of the robot realises the reference at t = "
                    f"{t:.3f} s (CoM on x_d, base at R_d, end effector on its desired pose): "
                    f"the end effector is out of the arm's reach from the CoM reference; "
                    f"{err}", "trajectory") from None
            self.model.plant.SetPositions(self.context, q)
        self.q = q
        J3 = kinematic_J3(self.model, self.context)
        self.sigmas.append(float(np.linalg.svd(J3, compute_uv=False)[-1]))
        return q


def _at(ref: ReferenceSample, k: int) -> ReferenceSample:
    """Sample ``k`` of a time-sampled reference."""
    return ReferenceSample(**{f.name: getattr(ref, f.name)[k]
                              for f in dataclasses.fields(ref)})


def sigma_min_J3(model: AerialManipulator, x: np.ndarray) -> float:
    """sigma_min(J_3) of Assumption 1 at state ``x`` of ``model`` (J = J_y T^-1, (17))."""
    plant = model.plant
    ctx = plant.CreateDefaultContext()
    plant.SetPositionsAndVelocities(ctx, x)
    dynamics = DecoupledDynamics(plant)
    d = dynamics.compute(ctx)
    J6, J6_dot = dynamics.frame_jacobian(d, model.end_effector_frame)
    assert model.task is not None
    J_y, _ = task_jacobian(model.task, J6, J6_dot, plant.num_velocities())
    J3 = (J_y @ d.T_inv)[:, 6:]
    return float(np.linalg.svd(J3, compute_uv=False)[-1])


def check_start_posture(scenario: Scenario, model: AerialManipulator, x0: np.ndarray) -> None:
    """Raise ScenarioError if J_3 is singular (Assumption 1) at the start state ``x0`` of the
    controller's model. A non-finite ``x0`` is left to the run's non-finite check, which
    reports it at t = 0 (Drake's SetPositionsAndVelocities would abort on it here)."""
    if not np.all(np.isfinite(x0)):
        return
    sigma = sigma_min_J3(model, x0)
    limit = scenario.sigma_min_J3_limit
    if not sigma > limit:
        raise ScenarioError(
            f"initial: Assumption 1 fails at the start posture (t = 0): J_3 is singular, "
            f"sigma_min(J_3) = {sigma:.3g} (limit sigma_min_J3_limit = {limit:g}). The task "
            f"{list(model.task.components) if model.task else []} cannot be controlled from "
            "the posture that realises the reference at t = 0: move the reference's start "
            "(trajectory), change the task, or the robot's nominal_posture", "initial")
