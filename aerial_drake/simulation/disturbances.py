"""External disturbance wrenches as Drake sources: constant windows, as the paper's green
(4-5 s, helicopter) and orange (9-10 s, end effector) areas, the random windows of a
scenario's ``random_disturbances`` section drawn into such windows, and the end-effector
windows bounded by what the arm can hold (:func:`bound_end_effector_windows`)."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np
from pydrake.multibody.tree import JacobianWrtVariable
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource, TrajectorySource
from pydrake.trajectories import PiecewisePolynomial

from aerial_drake.control.reference_pose import reference_configuration
from aerial_drake.robots.models import AerialManipulator
from aerial_drake.simulation.scenarios import Disturbance, Scenario, ScenarioError
from aerial_drake.trajectories.base import ReferenceSource


def wrench_schedule(disturbances: Sequence[Disturbance], target: str,
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Breaks and 6-vector wrenches ``[torque; force]`` (World), piecewise constant, of the
    windows acting on ``target``; overlapping windows add."""
    windows = [d for d in disturbances if d.target == target]
    times = sorted({0.0} | {d.start for d in windows} | {d.stop for d in windows})
    values = []
    for t in times:
        w = np.zeros(6)
        for d in windows:
            if d.start <= t < d.stop:
                w += np.concatenate([d.torque, d.force])
        values.append(w)
    return np.array(times), np.array(values)


def add_wrench_source(builder: DiagramBuilder, disturbances: Sequence[Disturbance],
                      target: str) -> ConstantVectorSource | TrajectorySource:
    """A source system whose output is the disturbance wrench on ``target`` over time."""
    times, values = wrench_schedule(disturbances, target)
    if len(times) == 1:
        source = ConstantVectorSource(np.zeros(6))
    else:
        # Zero-order-hold pieces: value k holds on [times[k], times[k+1]); hold the last.
        breaks = np.append(times, times[-1] + 1.0)
        samples = np.vstack([values, values[-1]]).T
        source = TrajectorySource(PiecewisePolynomial.ZeroOrderHold(breaks, samples))
    source.set_name(f"{target}_disturbance")
    return builder.AddSystem(source)


def _draw(rng: np.random.Generator, interval: list[float]) -> float:
    return float(rng.uniform(interval[0], interval[1]))


def _unit_vector(rng: np.random.Generator) -> np.ndarray:
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def random_windows(scenario: Scenario) -> list[Disturbance]:
    """The scenario's windows after its ``random_disturbances`` section's draws (the
    section's docstring): its own windows, redirected if it asks, then the new ones."""
    r = scenario.random_disturbances
    rng = np.random.default_rng(r.seed)
    windows = list(scenario.disturbances)
    if r.redirect:
        windows = [dataclasses.replace(
            d, force=(np.linalg.norm(d.force) * _unit_vector(rng)).tolist(),
            torque=(np.linalg.norm(d.torque) * _unit_vector(rng)).tolist()) for d in windows]
    for _ in range(int(r.count)):
        start = _draw(rng, r.start)
        length = _draw(rng, r.length)
        force = _draw(rng, r.force) * _unit_vector(rng)
        torque = _draw(rng, r.torque) * _unit_vector(rng)
        windows.append(Disturbance(target=r.target, start=start, stop=start + length,
                                   force=force.tolist(), torque=torque.tolist()))
    return windows


def resolve_random_disturbances(scenario: Scenario) -> Scenario:
    """``scenario`` with its random windows drawn into ``disturbances`` and the random
    section reset (so resolving twice draws nothing more); the same object when it asks for
    none. The input is not modified."""
    r = scenario.random_disturbances
    if not (r.count or r.redirect):
        return scenario
    return dataclasses.replace(
        scenario, disturbances=random_windows(scenario),
        random_disturbances=dataclasses.replace(r, count=0, redirect=False))


#: A window whose scale comes out within this of 1 is left as it is: bounding the resolved
#: scenario again (its windows already at the bound, to round-off) changes nothing.
HOLD_SCALE_TOLERANCE = 1e-9


def bound_end_effector_windows(scenario: Scenario, model: AerialManipulator,
                               reference: ReferenceSource | None = None) -> Scenario:
    """``scenario`` with each of its end-effector windows scaled to what the arm can hold
    (``random_disturbances.arm_hold_fraction``, its docstring; :func:`hold_scale`), on
    ``model`` (the controller's) along the run's ``reference``; the same object when the
    bound is off or no window exceeds it. The fraction is kept: the windows already within
    it, bounding the result again changes nothing. The input is not modified.

    Raises ScenarioError naming ``random_disturbances.arm_hold_fraction`` when gravity alone
    takes more than the fraction of a joint's limit at a posture along a window
    (:func:`hold_times`)."""
    fraction = scenario.random_disturbances.arm_hold_fraction
    if fraction == 0 or not any(d.target == "end_effector" for d in scenario.disturbances):
        return scenario
    arm = ArmLoads(scenario, model, reference)
    windows, changed = [], False
    for i, d in enumerate(scenario.disturbances):
        if d.target == "end_effector":
            s = hold_scale(arm, d, fraction, f"disturbances[{i}]")
            if s < 1.0 - HOLD_SCALE_TOLERANCE:
                d = dataclasses.replace(d, force=(s * np.asarray(d.force)).tolist(),
                                        torque=(s * np.asarray(d.torque)).tolist())
                changed = True
        windows.append(d)
    return dataclasses.replace(scenario, disturbances=windows) if changed else scenario


class ArmLoads:
    """The arm joints' gravity torques and the end effector's Jacobian at the reference
    posture, per time (each posture solved once)."""

    def __init__(self, scenario: Scenario, model: AerialManipulator,
                 reference: ReferenceSource | None) -> None:
        self.scenario, self.model, self.reference = scenario, model, reference
        self.context = model.plant.CreateDefaultContext()
        self.limits = model.arm_effort_limits()
        self.names = [j.name() for j in model.arm_joints]
        self._cache: dict[float, tuple[np.ndarray, np.ndarray]] = {}

    def at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """``(tau_g, J_arm^T)`` at the reference posture at ``t``: the arm joints' gravity
        generalized forces (N m) and the rows of J^T that map a World wrench ``[torque;
        force]`` at the end-effector frame's origin to them (n x 6)."""
        if t not in self._cache:
            model, plant = self.model, self.model.plant
            q = reference_configuration(self.scenario, model, t, reference=self.reference)
            plant.SetPositions(self.context, q)
            arm = model.arm_velocity_indices
            tau_g = plant.CalcGravityGeneralizedForces(self.context)[arm]
            # The wrench acts at E's origin (diagram.py's PointWrenchApplier at X_BE's
            # translation); Drake's spatial velocity is [w; v], so J^T [torque; force] is the
            # generalized force the wrench applies.
            J = plant.CalcJacobianSpatialVelocity(
                self.context, JacobianWrtVariable.kV, model.end_effector_frame, np.zeros(3),
                plant.world_frame(), plant.world_frame())
            self._cache[t] = (tau_g, J[:, arm].T)
        return self._cache[t]


#: The spacing (s) of the reference postures along a window at which the arm must hold it: the
#: posture moves during a window (the paper's agile circle at 3 Hz), so the edges alone are
#: not enough (a window held at both edges needed 108.6 % of joint 7's limit at mid-window;
#: docs/studies.md).
HOLD_CHECK_SPACING = 0.05


def hold_times(window: Disturbance) -> list[float]:
    """The times at which :func:`hold_scale` checks ``window``: its start, its stop and
    every :data:`HOLD_CHECK_SPACING` s between (evenly spaced, at most that far apart)."""
    steps = max(1, int(np.ceil((window.stop - window.start) / HOLD_CHECK_SPACING - 1e-9)))
    return [float(t) for t in np.linspace(window.start, window.stop, steps + 1)]


def hold_scale(arm: ArmLoads, window: Disturbance, fraction: float, where: str) -> float:
    """The largest ``s`` in [0, 1] with ``|tau_g,i + s (J^T w)_i| <= fraction tau_max,i`` for
    every arm joint ``i`` at the reference postures along the window (:func:`hold_times`:
    both edges and every :data:`HOLD_CHECK_SPACING` s between; ``w = [torque; force]``,
    tau_max the model's effort limits): the statics of the arm holding its own weight and
    the wrench. ``where`` names the window in errors."""
    w = np.concatenate([window.torque, window.force])
    limit = fraction * arm.limits
    s = 1.0
    for t in hold_times(window):
        tau_g, JT = arm.at(t)
        over = np.abs(tau_g) > limit
        if over.any():
            i = int(np.argmax(np.abs(tau_g) / arm.limits))
            raise ScenarioError(
                f"random_disturbances.arm_hold_fraction = {fraction:g}: at t = {t:g} s "
                f"({where}) gravity alone takes {abs(tau_g[i]):.3g} N m of joint "
                f"'{arm.names[i]}''s limit {arm.limits[i]:g} N m "
                f"({abs(tau_g[i]) / arm.limits[i]:.3g} of it), more than the fraction: "
                "raise arm_hold_fraction", "random_disturbances.arm_hold_fraction")
        a = JT @ w
        for g_i, a_i, c_i in zip(tau_g, a, limit):
            if a_i > 0:
                s = min(s, (c_i - g_i) / a_i)
            elif a_i < 0:
                s = min(s, (-c_i - g_i) / a_i)
    return float(max(s, 0.0))
