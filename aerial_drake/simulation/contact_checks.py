"""Checks of a force task (``controller.type: paper_force``) before anything is simulated
(docs/contact.md, "Checks before the run"); each failure is a ScenarioError naming the
field, the value and the fix (exit status 2).

Along the force window, every :data:`SAMPLE_SPACING` s, at the posture of the controller's
model that realises the reference there (the tool where the motion reference puts it, no
admittance shift):

1. :func:`check_reach`: the tool touches a surface of the environment within
   ``controller.force.max_shift`` along ``controller.force.direction`` (the most the force
   task moves the reference), by sphere tracing on SceneGraph's signed distances
   (:mod:`aerial_drake.simulation.contact_geometry`), and the reference does not put it
   deeper into a surface than that either;
2. :func:`check_stiffness`: on the continuous plant integrated at a fixed step h by an
   explicit scheme, the contact's natural frequency omega = sqrt(k / m_eff) within
   omega h <= :data:`MAX_OMEGA_STEP`; k the tool's and the surface's point contact
   stiffnesses in series (Drake's k1 k2 / (k1 + k2)), m_eff = 1 / (d^T J M^-1 J^T d) the
   apparent mass of the robot at the contact point along d;
3. :func:`check_force` (:mod:`aerial_drake.simulation.contact_loads`): the thrust
   |m (x_d'' + g e3) + F d|, the body torques and the arm's joint torques that hold the
   pressing force F within the command limits;
4. :func:`check_rates` (:mod:`aerial_drake.simulation.contact_rates`): the force loop's
   gain per sample, and friction's regularised damping on an explicit fixed step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from pydrake.math import RigidTransform

from aerial_drake.control.force.admittance import desired_force
from aerial_drake.control.force.params import ForceTaskParams
from aerial_drake.control.reference_pose import mass_and_gravity, realising_targets
from aerial_drake.dynamics.equilibrium import (
    UnreachablePose,
    solve_configuration,
    track_configuration,
)
from aerial_drake.robots.models import AerialManipulator
from aerial_drake.simulation.contact_geometry import Hit, Surfaces, Tool
from aerial_drake.simulation.contact_loads import check_force
from aerial_drake.simulation.contact_rates import (
    apparent_mass,
    check_force_loop,
    check_friction,
    pair_friction,
    tangential_mass,
)
from aerial_drake.simulation.scenarios import Scenario, ScenarioError
from aerial_drake.trajectories.base import ReferenceSource

#: Spacing of the force window's samples (s), as the arm-hold bound's windows
#: (simulation.disturbances.HOLD_CHECK_SPACING): the reference may move along the window.
SAMPLE_SPACING = 0.05
#: How far along the direction a surface is looked for, to name it in a message (m).
SEARCH_DISTANCE = 5.0
#: The largest omega h accepted (docs/contact.md, "Checks before the run"): RK3's stability
#: interval on the imaginary axis is sqrt(3); 1 keeps a factor 1.7 in frequency (3 in
#: stiffness) for the apparent mass's change along the window and the shift, and resolves
#: the contact's oscillation with at least 2 pi steps per period (RK3's amplitude error per
#: step, 1 - |R(i omega h)| = 1 - sqrt(1 - (omega h)^4 / 12 + (omega h)^6 / 36), is 2.8 % at 1).
MAX_OMEGA_STEP = 1.0
#: The integration schemes whose stability needs omega h bounded (explicit); the implicit
#: ones (implicit_euler, radau1, radau3, velocity_implicit_euler) and cenic are not checked.
EXPLICIT_SCHEMES = ("explicit_euler", "runge_kutta2", "runge_kutta3", "bogacki_shampine3",
                    "runge_kutta5", "semi_explicit_euler")


@dataclass
class ContactSample:
    """The robot at the reference posture at time ``t`` of the force window: ``q`` (the
    controller's model), the end-effector body's pose ``X_WB``, the desired force's fraction
    of ``controller.force.force`` there (``share``), the reference's x_d'' (``com_accel``),
    and once traced, the tool that touches first and its ``hit``."""

    t: float
    q: np.ndarray
    X_WB: RigidTransform
    share: float
    com_accel: np.ndarray
    tool: Tool | None = None
    hit: Hit | None = None

    def contact_point(self, direction: np.ndarray) -> np.ndarray:
        """Where the tool touches (World): its sphere's point along ``direction``; without a
        hit, the tool's frame origin."""
        if self.tool is None:
            return self.X_WB.translation()
        return self.X_WB.multiply(self.tool.p_BC) + self.tool.radius * direction


def check_contact(scenario: Scenario, loop) -> None:
    """Raise ScenarioError at the first check of the module docstring that the force task of
    ``loop`` (a :class:`~aerial_drake.simulation.diagram.ClosedLoop`) fails; nothing for a
    controller without a force task."""
    force = getattr(loop.controller, "force_task", None)
    if not isinstance(force, ForceTaskParams):
        return
    direction = np.asarray(force.unit_direction(), float)
    surfaces = Surfaces(loop.simulated_plant)
    samples = window_samples(scenario, loop.controller_model, force, loop.reference.source)
    check_reach(scenario, surfaces, samples, force, direction)
    check_stiffness(scenario, loop.controller_model, surfaces, samples, direction)
    check_force(scenario, loop.controller_model, samples, force, direction)
    check_rates(scenario, loop.controller_model, surfaces, samples, force, direction)


def check_rates(scenario: Scenario, model: AerialManipulator, surfaces: Surfaces,
                samples: list[ContactSample], force: ForceTaskParams,
                direction: np.ndarray) -> None:
    """:mod:`aerial_drake.simulation.contact_rates`' checks at the first sample that touches
    a surface: the force loop's gain, and friction's damping on an explicit fixed step."""
    touching = [s for s in samples if s.tool is not None and s.hit is not None
                and s.hit.found]
    if not touching:
        return
    sample = touching[0]
    tool, hit = sample.tool, sample.hit
    assert tool is not None and hit is not None
    pair = f"'{tool.name}' on '{hit.name}'"
    check_force_loop(scenario, force, series_stiffness(tool.stiffness, hit.stiffness), pair)
    simulator = scenario.simulator
    if (scenario.plant.time_step == 0 and not simulator.use_error_control
            and simulator.integration_scheme in EXPLICIT_SCHEMES):
        mu = pair_friction(surfaces.inspector, tool.geometry, hit.geometry)
        m_t = tangential_mass(model, sample.q, sample.contact_point(direction), direction)
        check_friction(scenario, force, mu, m_t, longest_step(scenario), pair)


def window_samples(scenario: Scenario, model: AerialManipulator, force: ForceTaskParams,
                   reference: ReferenceSource) -> list[ContactSample]:
    """The reference postures along ``force``'s window (its start, its stop and every
    :data:`SAMPLE_SPACING` s between, at most :data:`SAMPLE_SPACING` apart; none if the
    window starts after the run's end), each solved from the last."""
    stop = min(force.stop, scenario.duration)  # (a window past the run's end is cut there)
    if stop <= force.start:
        return []
    steps = max(1, int(math.ceil((stop - force.start) / SAMPLE_SPACING - 1e-9)))
    times = np.linspace(force.start, stop, steps + 1)
    plant = model.plant
    context = plant.CreateDefaultContext()
    mass_gravity = mass_and_gravity(model)
    samples: list[ContactSample] = []
    q = None
    for t in times:
        ref = reference.evaluate(float(t))
        targets = realising_targets(model, ref, mass_gravity)
        q = None if q is None else track_configuration(model, q, context, **targets)
        if q is None:
            try:
                q = solve_configuration(model, **targets, respect_joint_limits=False)
            except UnreachablePose as err:
                raise ScenarioError(
                    f"controller.force: no posture of the robot realises the reference at t = "
                    f"{t:.3f} s, in the force window [{force.start:g}, {force.stop:g}] s: "
                    f"{err}. Move the end-effector reference within the arm's reach there",
                    "trajectory") from None
        plant.SetPositions(context, q)
        samples.append(ContactSample(
            t=float(t), q=np.array(q),
            X_WB=plant.EvalBodyPoseInWorld(context, model.end_effector_body),
            share=desired_force(float(t), force) / force.force,
            com_accel=np.array(ref.com[2])))
    return samples


def check_reach(scenario: Scenario, surfaces: Surfaces, samples: list[ContactSample],
                force: ForceTaskParams, direction: np.ndarray) -> None:
    """Raise ScenarioError unless at every sample inside the window (a desired force > 0)
    a tool sphere touches a surface of the environment within ``force.max_shift`` along
    ``direction``; set those samples' ``tool`` and ``hit`` (the tool that touches first)."""
    where = (f"controller.type {scenario.controller.type} presses the tool along "
             f"controller.force.direction {_show(direction)}")
    if not surfaces.environment:
        raise ScenarioError(
            f"environment: {where} against a surface, but the environment has no collision "
            "geometry (its models are visual only, or there are none): give the surface a "
            "<collision> (e.g. package://aerial_drake/environments/wall.sdf)", "environment")
    if not surfaces.tools:
        raise ScenarioError(
            f"robot: {where}, but the end-effector body "
            f"'{surfaces.sim.end_effector_body.name()}' has no collision geometry, so nothing "
            "of the robot's touches there: give the end-effector link a <collision> tool "
            "(docs/world.md), or choose another controller.type", "robot")
    for sample in samples:
        if sample.share <= 0:  # the window's edges: nothing pressed
            continue
        best: tuple[Tool, Hit] | None = None
        for tool in surfaces.tools:
            hit = surfaces.trace(sample.X_WB.multiply(tool.p_BC), direction, tool.radius,
                                 SEARCH_DISTANCE)
            if best is None or hit.distance < best[1].distance:
                best = (tool, hit)
        assert best is not None
        sample.tool, sample.hit = best
        if best[1].depth > force.max_shift + 1e-9:
            raise ScenarioError(_depth_message(sample, force), "controller.force.max_shift")
        if best[1].distance <= force.max_shift + 1e-9:
            continue
        if surfaces.unmeasured and not best[1].found:
            continue  # a surface the signed distance cannot see may be the one: not refused
        raise ScenarioError(_reach_message(scenario, sample, force, direction),
                            "controller.force.direction")


def _reach_message(scenario: Scenario, sample: ContactSample, force: ForceTaskParams,
                   direction: np.ndarray) -> str:
    tool, hit = sample.tool, sample.hit
    assert tool is not None and hit is not None
    centre = sample.X_WB.multiply(tool.p_BC)
    if hit.found:
        found = (f"the nearest surface along it, '{hit.name}', is {hit.distance:.3f} m "
                 f"ahead of the tool, {hit.distance - force.max_shift:.3f} m more than "
                 f"controller.force.max_shift = {force.max_shift:g} m, the most the force "
                 "task moves the reference")
        fix = (f"bring the end-effector reference (the waypoints) at least "
               f"{hit.distance - force.max_shift:.3f} m closer to the surface along the "
               f"direction over the window ({hit.distance:.3f} m to touch it without the "
               "force task's shift), or move the "
               "window (controller.force.start, stop) to when the reference is there, or "
               "move the environment's surface")
    else:
        found = f"no surface of the environment lies within {SEARCH_DISTANCE:g} m along it"
        fix = ("turn controller.force.direction toward the surface (it points into the "
               "surface, the opposite of the surface's outward normal), or move the "
               "end-effector reference (the waypoints) or the environment so that the "
               "surface is ahead of the tool")
    return (f"controller.force.direction: at t = {sample.t:.3f} s, in the force window "
            f"[{force.start:g}, {force.stop:g}] s, the tool '{tool.name}' (radius "
            f"{tool.radius:g} m) at its reference position {_show(centre)} m presses along "
            f"{_show(direction)}, but {found}: it would press on nothing. Fix: {fix}")


def _depth_message(sample: ContactSample, force: ForceTaskParams) -> str:
    tool, hit = sample.tool, sample.hit
    assert tool is not None and hit is not None
    return (f"controller.force.max_shift: at t = {sample.t:.3f} s, in the force window "
            f"[{force.start:g}, {force.stop:g}] s, the end-effector reference puts the tool "
            f"'{tool.name}' {hit.depth:.3f} m deep into '{hit.name}', more than max_shift = "
            f"{force.max_shift:g} m, the most the force task backs the reference out: the "
            "motion control would press the rest of the way with its own stiffness, whatever "
            f"controller.force.force asks. Fix: end the end-effector reference (the "
            f"waypoints) at or before the surface, or raise max_shift to at least "
            f"{hit.depth:.3f} m")


def check_stiffness(scenario: Scenario, model: AerialManipulator, surfaces: Surfaces,
                    samples: list[ContactSample], direction: np.ndarray) -> None:
    """Raise ScenarioError if the fixed step of an explicit integrator of the continuous
    plant cannot resolve the contact: omega h > :data:`MAX_OMEGA_STEP` at a sample (module
    docstring). Nothing for a discrete plant (its contact solvers are implicit), with error
    control (the integrator shortens its steps), or for a hydroelastic contact."""
    simulator = scenario.simulator
    if (scenario.plant.time_step != 0 or simulator.use_error_control
            or simulator.integration_scheme not in EXPLICIT_SCHEMES):
        return
    h = longest_step(scenario)
    worst: tuple[float, ContactSample, float, float] | None = None
    point: dict[tuple, bool] = {}
    for sample in samples:
        tool, hit = sample.tool, sample.hit
        if tool is None or hit is None or not hit.found:
            continue
        key = (tool.geometry, hit.geometry)
        if key not in point:
            point[key] = surfaces.point_contact(tool, sample.X_WB, direction, hit)
        if not point[key]:
            continue
        k = series_stiffness(tool.stiffness, hit.stiffness)
        m_eff = apparent_mass(model, sample.q, sample.contact_point(direction), direction)
        omega = math.sqrt(k / m_eff)
        if worst is None or omega > worst[0]:
            worst = (omega, sample, k, m_eff)
    if worst is None or worst[0] * h <= MAX_OMEGA_STEP:
        return
    omega, sample, k, m_eff = worst
    tool, hit = sample.tool, sample.hit
    assert tool is not None and hit is not None
    raise ScenarioError(
        f"simulator.max_step_size: the fixed step h = {h:g} s (the shortest of "
        "max_step_size, controller_period and log_period) is too long for the tool's contact: "
        f"at t = {sample.t:.3f} s the tool '{tool.name}' ({tool.stiffness:.3g} N/m) meets "
        f"'{hit.name}' ({hit.stiffness:.3g} N/m), in series k = {k:.3g} N/m, and the robot's "
        f"apparent mass there along {_show(direction)} is m_eff = {m_eff:.3g} kg, so the "
        f"contact rings at omega = sqrt(k / m_eff) = {omega:.4g} rad/s and omega h = "
        f"{omega * h:.3g}, above {MAX_OMEGA_STEP:g}: the explicit "
        f"{simulator.integration_scheme} goes unstable (docs/contact.md). Fix: "
        f"simulator.max_step_size <= {MAX_OMEGA_STEP / omega:.3g} s, or a discrete plant "
        "(plant.time_step: 0.001 with discrete_contact_approximation: sap, implicit), or "
        "simulator.use_error_control: true, or a softer tool (its model file's "
        f"drake:point_contact_stiffness <= {m_eff * (MAX_OMEGA_STEP / h) ** 2:.3g} N/m "
        "in series)", "simulator.max_step_size")


def longest_step(scenario: Scenario) -> float:
    """The longest step the simulator takes (s): ``simulator.max_step_size``, but a step
    also ends at every event of the diagram, the controller's and the loggers' samples
    among them (at multiples of ``controller_period`` and ``log_period``)."""
    periods = (scenario.controller_period, scenario.log_period)
    return min([float(scenario.simulator.max_step_size)] + [p for p in periods if p > 0])


def series_stiffness(k1: float, k2: float) -> float:
    """Two point contact stiffnesses in series, as Drake combines them (N/m)."""
    return k1 * k2 / (k1 + k2)


def _show(v: np.ndarray) -> str:
    """A vector to 4 decimals, round-off (3e-29) and -0 shown as 0."""
    return "[" + ", ".join(f"{x:g}" for x in np.round(np.asarray(v, float), 4) + 0.0) + "]"
