"""The controller interface: what the closed loop needs of any controller system.

The closed loop (:mod:`aerial_drake.simulation.diagram`) takes any Drake ``LeafSystem`` (or
``Diagram``) with these ports, by name:

Input ports (vector, sizes for the controller's model plant with ``n`` arm joints):
    - ``state``: ``[q; v]`` of the rigid model (``nq + nv``: quaternion base, then the arm).
    - ``com_reference`` (15), ``task_reference`` (24 + 3 n_j, n_j the task's joint
      components: 27 for the paper's task), ``heading_reference`` (9): as
      :class:`aerial_drake.trajectories.generator.ReferenceGenerator` produces them (layouts in
      :mod:`aerial_drake.trajectories.reference`).

Output ports:
    - ``command``: ``[f, mu (3), tau (n)]``, thrust along body z (N), body torques (N m, base
      frame), joint torques (N m): the inputs of (1).
    - ``diagnostics``: the controller's own extra entries, named by its
      ``diagnostics_layout`` attribute ((name, size) pairs in order; the paper controller's is
      :func:`aerial_drake.control.law.diagnostics_layout`); any size, 0 for none. A system
      without ``diagnostics_layout`` has one unnamed entry (:func:`diagnostics_layout_of`).
      The tracking errors (end effector, CoM, attitude) are not a controller's business: the
      simulation measures them for every controller alike.

:class:`aerial_drake.control.base.ControllerBase` gives all of this to a subclass that
computes the command. Optional attributes the runner uses when present: ``period`` (s; > 0
means the outputs are held samples, as the paper's 1 kHz controller; then also
``hold_sample(context)`` and ``evaluate(x, com, task, heading, t) -> (command,
diagnostics)``, for the log's alignment) and ``evaluations`` (a count, reported in
metrics.json). A system without ``period`` is taken as continuous (direct feedthrough).
"""

from __future__ import annotations

from typing import Any

from aerial_drake.trajectories.reference import (
    COM_REFERENCE_SIZE,
    HEADING_REFERENCE_SIZE,
    task_reference_size,
)

INPUT_PORTS = ("state", "com_reference", "task_reference", "heading_reference")
OUTPUT_PORTS = ("command", "diagnostics")


def diagnostics_layout_of(system: Any) -> tuple[tuple[str, int], ...]:
    """The names and sizes of ``system``'s ``diagnostics`` port, in order: its
    ``diagnostics_layout``, or one entry ``("diagnostics", size)`` for a system without one."""
    layout = getattr(system, "diagnostics_layout", None)
    if layout is not None:
        return tuple((str(name), int(size)) for name, size in layout)
    return (("diagnostics", system.GetOutputPort("diagnostics").size()),)


def port_sizes(num_states: int, n_arm: int, n_task_joints: int) -> dict[str, int]:
    """Each fixed-size port's size for a model with ``num_states`` (nq + nv), ``n_arm``
    joints and a task with ``n_task_joints`` joint components (``diagnostics`` is the
    controller's own)."""
    return {"state": num_states, "com_reference": COM_REFERENCE_SIZE,
            "task_reference": task_reference_size(n_task_joints),
            "heading_reference": HEADING_REFERENCE_SIZE, "command": 4 + n_arm}


def check_controller_ports(system, num_states: int, n_arm: int, n_task_joints: int) -> None:
    """Raise ValueError naming the port if ``system`` lacks a port of the interface or has it
    with the wrong size (``diagnostics``: the sum of its layout's sizes)."""
    sizes = port_sizes(num_states, n_arm, n_task_joints)
    name = system.get_name() or type(system).__name__
    for kind, names, has, get in (
            ("input", INPUT_PORTS, system.HasInputPort, system.GetInputPort),
            ("output", OUTPUT_PORTS, system.HasOutputPort, system.GetOutputPort)):
        for port in names:
            if not has(port):
                raise ValueError(
                    f"controller '{name}' has no {kind} port '{port}'; a controller needs the "
                    f"inputs {INPUT_PORTS} and outputs {OUTPUT_PORTS} "
                    "(aerial_drake.control.interface)")
            if port in sizes and get(port).size() != sizes[port]:
                raise ValueError(f"controller '{name}': {kind} port '{port}' has size "
                                 f"{get(port).size()}, the interface needs {sizes[port]}")
    declared = sum(size for _, size in diagnostics_layout_of(system))
    if system.GetOutputPort("diagnostics").size() != declared:
        raise ValueError(f"controller '{name}': output port 'diagnostics' has size "
                         f"{system.GetOutputPort('diagnostics').size()} but its "
                         f"diagnostics_layout sums to {declared}")
