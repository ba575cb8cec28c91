"""A run's log from its loggers: the samples cut to one length, the references at the sample
times, a sampled controller's diagnostics re-aligned to their samples, the tracking errors
(:mod:`aerial_drake.simulation.tracking`) and the names of the logged vectors' entries; and
the run's metrics from that log (:func:`run_metrics`)."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
from pydrake.systems.framework import Context

from aerial_drake.control.force.params import PAPER_FORCE
from aerial_drake.control.law import AssumptionViolation, diagnostics_layout
from aerial_drake.control.wrench_observer import observer_layouts
from aerial_drake.simulation.contact_metrics import contact_metrics
from aerial_drake.simulation.diagram import ClosedLoop, input_limits
from aerial_drake.simulation.failure_cause import arm_stretch, classify_failure, singular_stop
from aerial_drake.simulation.joint_limits import ArmLimits, limit_metrics
from aerial_drake.simulation.loggers import PortLog
from aerial_drake.simulation.metrics import (
    compute_metrics,
    disturbance_response,
    input_names,
    limits_by_input,
    phase_edges,
    rotor_metrics,
)
from aerial_drake.simulation.scenarios import Scenario
from aerial_drake.simulation.tracking import Layout, Tracking, entries

REFERENCES = ("com_reference", "task_reference", "heading_reference")


def controller_period(controller) -> float:
    """A controller's sampling period (s); 0 (continuous) for a system without ``period``
    (aerial_drake.control.interface)."""
    return float(getattr(controller, "period", 0.0))


def controller_diagnostics_layout(controller, width: int, n: int) -> Layout:
    """The (name, size) pairs of ``controller``'s ``diagnostics`` port of ``width`` entries:
    its ``diagnostics_layout`` (an attribute or a method) where it has one of that width, else
    the paper law's (:func:`aerial_drake.control.law.diagnostics_layout`, task of ``n``
    rows) where the width is that, else one generic name per entry (``d0``, ``d1``, ...)."""
    own = getattr(controller, "diagnostics_layout", None)
    own = own() if callable(own) else own
    for layout in (own, diagnostics_layout(n)):
        if layout is not None and sum(int(size) for _, size in layout) == width:
            return tuple((str(name), int(size)) for name, size in layout)
    return tuple((f"d{i}", 1) for i in range(width))


def collect_log(scenario: Scenario, loop: ClosedLoop, loggers: dict[str, PortLog],
                context: Context) -> tuple[dict[str, np.ndarray], dict[str, Layout]]:
    """The loggers' samples as ``{"t": times, port: (samples, size)}``, cut to a common
    length, with the references at the sample times (what the reference ports gave there),
    for a sampled controller the diagnostics re-aligned to their sample times, and
    ``tracking``, the tracking errors at each sample's plant state and references; and the
    layouts (name, size pairs) of ``diagnostics`` and ``tracking``."""
    log = {port: logger.FindLog(context) for port, logger in loggers.items()}
    arrays = {"t": log["plant_state"].sample_times()}
    for port, entry in log.items():
        arrays[port] = entry.data().T
    n = min(len(v) for v in arrays.values())
    arrays = {k: v[:n] for k, v in arrays.items()}
    references = loop.reference.source.sample(arrays["t"]).to_vectors()  # the run's own
    arrays.update(zip(REFERENCES, references))
    if controller_period(loop.controller) > 0 and n > 0 and "diagnostics" in arrays:
        arrays = _align_held_diagnostics(arrays, loop)
    # Once, after the simulation (no system in the loop), at the plant's true state: with
    # sensing noise or delay the controller's diagnostics are of what it measured.
    tracking = Tracking(loop.controller_model)
    arrays["tracking"] = tracking(
        arrays["plant_state"][:, loop.simulated_plant.rigid_state_indices],
        *(arrays[k] for k in REFERENCES))
    layouts = {}
    if "diagnostics" in arrays:
        layouts["diagnostics"] = controller_diagnostics_layout(
            loop.controller, arrays["diagnostics"].shape[1], loop.controller_model.n)
    layouts["tracking"] = tracking.layout
    # The wrench observer's estimates (observer.enabled): row k is the update of t_k-1's.
    layouts.update((k, v) for k, v in observer_layouts(loop.controller_model.n).items()
                   if k in arrays)
    return arrays, layouts


def _align_held_diagnostics(arrays: dict[str, np.ndarray], loop: ClosedLoop,
                            ) -> dict[str, np.ndarray]:
    """Each sample's diagnostics at its own time.

    A sampled controller holds the diagnostics of its sample at t_k with the command, and the
    loggers publish at t_k before the update at t_k: the logged row k holds the diagnostics of
    t_k-1 (row 0, the primed hold, those of t_0). So row k is taken from logged row k+1, and
    the last row's from the law at the last logged state and references (what the update at
    that time computes, to the last bit). Where the law refuses that state: an assumption
    violated, the run stopped there, so the row goes (as a failed sample logs nothing); a
    non-finite state, the row stays with NaN diagnostics (the run is cut at that sample).
    """
    held = arrays["diagnostics"]
    x = arrays["plant_state"][-1][loop.simulated_plant.rigid_state_indices]
    try:
        last = loop.controller.evaluate(x, *(arrays[k][-1] for k in REFERENCES),
                                        t=float(arrays["t"][-1]))[1]
    except FloatingPointError:
        last = np.full(held.shape[1], np.nan)
    except AssumptionViolation:
        arrays = {k: v[:-1] for k, v in arrays.items()}
        arrays["diagnostics"] = held[1:]
        return arrays
    arrays["diagnostics"] = np.vstack([held[1:], last])
    return arrays


def layout_json(layouts: dict[str, Layout], task_labels: tuple[str, ...] = ()) -> str:
    """The ``layout`` entry of log.npz: each logged vector's (name, size) pairs by array
    name, and the task's row labels under ``task``."""
    names: dict[str, list] = {k: [list(pair) for pair in v] for k, v in layouts.items()}
    names["task"] = list(task_labels)
    return json.dumps(names)


def log_entries(log: dict[str, np.ndarray], layouts: dict[str, Layout]
                ) -> dict[str, np.ndarray]:
    """``{name: (N, size)}`` of a run's log: the controller's diagnostics entries by their
    names, then the tracking errors (which take a name both have: the metrics read the errors
    at the plant's state, and only the controller's own quantities from its diagnostics)."""
    named: dict[str, np.ndarray] = {}
    for array in ("diagnostics", "tracking"):
        if array in log and array in layouts:
            named.update(entries(log[array], layouts[array]))
    return named


def run_metrics(scenario: Scenario, loop: ClosedLoop, log: dict[str, np.ndarray],
                layouts: dict[str, Layout], wall: float, sim_time: float,
                failure: str | None = None) -> dict:
    """metrics.json's content (README) of a run's log (:func:`collect_log`); ``failure``:
    the run's failure message (None: it completed), classified in ``failure_cause``."""
    lower, upper = input_limits(scenario, loop.controller_model)
    windows = [(d.start, d.stop) for d in scenario.disturbances]
    edges = phase_edges(windows, scenario.duration)
    named = log_entries(log, layouts)
    metrics = compute_metrics(log["t"], named, log["applied_command"], lower, upper, edges,
                              scenario.log_period)
    metrics.update({
        "scenario": scenario.name,
        "simulated_time_s": sim_time,
        "wall_time_s": wall,
        "real_time_factor": sim_time / wall if wall > 0 else None,
        "controller_evaluations": getattr(loop.controller, "evaluations", None),
        "input_limits": limits_by_input(lower, upper),
        "disturbance_response": disturbance_response(
            log["t"], named, [(d.target, d.start, d.stop) for d in scenario.disturbances]),
    })
    sim = loop.simulated_plant
    # Past the arm's joint limits, whatever the scenario's joint_limits do (docs/reliability.md).
    metrics.update(limit_metrics(log["plant_state"], ArmLimits.of(sim)))
    if sim.rotor_joints and "rotor_drive_torque" in log:
        nq = sim.plant.num_positions()
        metrics["rotors"] = rotor_metrics(
            log["plant_state"][:, nq + sim.rotor_velocity_indices], log["rotor_drive_torque"],
            scenario.rotors.speed * np.array(sim.rotor_directions))
    if "contact_wrench" in log:  # an environment: what touched it (docs/contact.md)
        force_task = (scenario.controller.force if scenario.controller.type == PAPER_FORCE
                      else None)
        task = loop.controller_model.task
        assert task is not None  # a finalized model
        metrics["contact"] = contact_metrics(
            log["t"], log["contact_wrench"], named, task.rows,
            force_task, scenario.log_period)
    metrics["failure_cause"] = failure_cause(scenario, loop, log, named, failure)
    if getattr(loop.controller, "compiled", True) is False:  # absent: the compiled law ran
        metrics["control_law"] = ("reference implementation (numpy): "
                                  f"{getattr(loop.controller, 'not_compiled_reason', '')}")
    plan = getattr(loop.reference.source, "report", None)  # trajectory.com_planning's
    if plan is not None:
        metrics["com_planning"] = plan.as_dict()
    return metrics


def failure_cause(scenario: Scenario, loop: ClosedLoop, log: dict[str, np.ndarray],
                  named: dict[str, np.ndarray], failure: str | None) -> dict | None:
    """:func:`aerial_drake.simulation.failure_cause.classify_failure` of a run's log: the
    inputs against the actuators' ratings (the limits the run saturates at, or would with
    ``actuation.saturate``), the arm's stretch at the last logged state (singular-Jacobian
    stops only: the one posture it needs)."""
    if failure is None:
        return None
    model = loop.controller_model
    rated = dataclasses.replace(scenario, actuation=dataclasses.replace(
        scenario.actuation, saturate=True))
    lower, upper = input_limits(rated, model)
    stretch = None
    x = log["plant_state"][-1][loop.simulated_plant.rigid_state_indices] if len(log["t"]) \
        else None
    if singular_stop(failure) and x is not None and np.all(np.isfinite(x)):
        stretch = arm_stretch(model, x[:model.plant.num_positions()])
    return classify_failure(
        failure, t=log["t"], applied=log["applied_command"], lower=lower, upper=upper,
        names=input_names(model.n), sigma_min_J3=named.get("sigma_min_J3"),
        sigma_limit=scenario.sigma_min_J3_limit, stretch=stretch)
