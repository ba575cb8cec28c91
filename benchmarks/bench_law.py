"""Median time of one evaluation of the compiled control law (aerial_drake.control.compiled), on the
states and references a short run of a paper scenario visited, in microseconds: the kernel
alone (``CompiledLaw.__call__``, what the simulation's controller calls at each sample) and
through ``DecoupledController.evaluate`` (which adds the output arrays and the status checks).

    python benchmarks/bench_law.py [--scenarios nominal quadrotor_ur3e] [--calls 20000]

One scenario per shipped robot by default, the robots alternating in rounds so their ratio
holds while the machine's speed drifts.

With Pinocchio installed (pip package ``pin``, in the test extra), the same rounds also time
Pinocchio computing, on the same states, the rigid-body quantities the law computes for itself
(:func:`pinocchio_calls`), and print law / Pinocchio per robot. Pinocchio's model is the one the
tests hold the law against (``tests/paper_oracles.PinocchioModel``, built from the Drake plant's
parameters).

The same rounds time the law's fast kernel (``controller.kernel: fast``,
:mod:`aerial_drake.control.compiled.fast_law`: the same law to round-off) on the same inputs,
its rigid-body part and its Section II, and print fast / exact and fast law / Pinocchio.

The machine's speed drifts: compare two versions of the law in one process, alternating
(e.g. with this script's ``time_calls`` on both), not across runs.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

PINOCCHIO = "Pinocchio rigid-body calls"
RIGID_BODY = "the law's rigid-body part"
SECTION_II = "the law's Section II"
FAST = "fast kernel CompiledLaw.__call__"
FAST_RIGID_BODY = "the fast kernel's rigid-body part"
FAST_SECTION_II = "the fast kernel's Section II"
#: Where the Pinocchio model of a Drake plant is built (shared with the oracle tests).
TESTS = Path(__file__).resolve().parent.parent / "tests"


def logged_inputs(scenario_name: str, duration: float, rows: int = 300):
    """The controller and ``rows`` (state, com, task, heading) inputs of a run's log."""
    from aerial_drake.simulation.diagram import build_closed_loop
    from aerial_drake.simulation.runner import run_scenario
    from aerial_drake.simulation.scenarios import load_scenario

    scenario = load_scenario(scenario_name, overrides={"duration": duration})
    log = run_scenario(scenario, progress=False).log
    loop = build_closed_loop(scenario)
    idx = loop.simulated_plant.rigid_state_indices
    picks = np.linspace(0, len(log["t"]) - 1, rows).astype(int)
    inputs = [(np.ascontiguousarray(log["plant_state"][k][idx]), log["com_reference"][k],
               log["task_reference"][k], log["heading_reference"][k]) for k in picks]
    return loop.controller, inputs


def pinocchio_calls(controller, inputs):
    """Pinocchio computing what the law computes of rigid-body dynamics, as one callable on
    the law's inputs, and the inputs in Pinocchio's coordinates; None without Pinocchio.

    The same quantities: the mass matrix M (``crba``), the Christoffel-consistent Coriolis
    matrix C (``computeCoriolisMatrix``, which also leaves every joint's Jacobian and its time
    derivative, in World, in ``data.J`` and ``data.dJ``), the end-effector frame's pose,
    World-aligned Jacobian and its derivative (``updateFramePlacements``, ``getFrameJacobian``,
    ``getFrameJacobianTimeVariation``, from those), and the CoM, its Jacobian J_g and J_g_dot
    (the linear rows of the centroidal map and its derivative, over the mass:
    ``computeCentroidalMapTimeVariation``). Not the generalized gravity (the law never forms
    it: gravity enters (10) at the CoM). Not timed: Drake's state to Pinocchio's (done once per
    state here) and the velocity map between the two libraries' base velocities; the law does
    everything else on top (Section II's T, T^-1, N, N_dot and the law (10)-(22)).

    Until 2026-12-05 (issue 29, item 3) this also called
    ``computeJointJacobiansTimeVariation``, for the exact kernel's every body's Jacobian and
    its derivative: a second pass for what ``computeCoriolisMatrix`` already leaves (the
    frame's Jacobian and derivative are equal to the bit without it), about 0.9 us. The fast
    kernel forms no body Jacobian but the end effector's; both kernels are now held against
    Pinocchio without that call.
    """
    if importlib.util.find_spec("pinocchio") is None:
        return None
    import pinocchio as pin
    from pydrake.common.eigen_geometry import Quaternion

    sys.path.insert(0, str(TESTS))
    from paper_oracles import PinocchioModel

    plant, frame = controller._plant, controller._frame
    pm = PinocchioModel(plant, controller._dynamics.base_body)
    fid = pm.add_frame("end_effector", frame.body(), frame.GetFixedPoseInBodyFrame())
    model, data = pm.model, pm.data
    nq = plant.num_positions()
    world_aligned = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED

    def rigid_body_quantities(q, v):
        pin.crba(model, data, q)
        pin.computeCoriolisMatrix(model, data, q, v)  # and data.J, data.dJ
        pin.updateFramePlacements(model, data)
        pin.getFrameJacobian(model, data, fid, world_aligned)
        pin.getFrameJacobianTimeVariation(model, data, fid, world_aligned)
        pin.computeCentroidalMapTimeVariation(model, data, q, v)

    # Pinocchio's configuration and velocity from Drake's (v_drake = S v_pin), once per state.
    states = []
    for x, *_ in inputs:
        q_drake, v_drake = x[:nq], x[nq:]
        R = Quaternion(q_drake[:4] / np.linalg.norm(q_drake[:4])).rotation()
        S, _ = pm.velocity_map(R, R.T @ v_drake[0:3])
        states.append((pm.configuration(q_drake), np.linalg.solve(S, v_drake)))
    return rigid_body_quantities, states


def law_phases(controller):
    """Four callables on the law's inputs: the exact kernel's rigid-body part (kinematics and
    the body sums: M, C, every body's Jacobian and its derivative, J_g, J_g_dot, the CoM), its
    Section II (that and the transformation (3)-(4): T, T^-1, N, N_dot), the fast kernel's
    rigid-body part (:mod:`aerial_drake.control.compiled.fast_rigid_body`: the recursions for
    M, C, J_g, J_g_dot, the CoM; the end effector's Jacobian is formed later, in the law) and
    its Section II, run alone with the kernels' own functions in a workspace of their own (the
    kernels' arithmetic; the outputs discarded)."""
    from numba import njit

    from aerial_drake.control.compiled.fast_rigid_body import (
        _fast_rb_buffers,
        _fast_rigid_body,
        fast_rigid_body_size,
    )
    from aerial_drake.control.compiled.fast_section2 import _fast_transformation
    from aerial_drake.control.compiled.kernels import (
        _body_sums,
        _law_buffers,
        _transformation,
        _unpack_law,
    )
    from aerial_drake.control.compiled.kinematics import _kinematics

    @njit(cache=True, nogil=True, error_model="numpy")
    def phase(x, model, index, work, kernel, section2):
        tree, p = _unpack_law(model, index)
        nb, nv = tree.parent.shape[0], tree.reflected.shape[0]
        s, _, end = _law_buffers(work, nb, nv)
        q, v = x[:p.nq], x[p.nq:]
        if kernel == 0:
            _kinematics(q, tree, s)
            m, base = _body_sums(v, tree, s)
            if section2:
                _transformation(v, s.R_all[base], s)
        else:
            f, _ = _fast_rb_buffers(work, end, nb, nv)
            m, base = _fast_rigid_body(q, v, tree, s, f)
            if section2:
                _fast_transformation(v, s.R_all[base], s)
        return m

    law = controller._compiled
    # Not the law's workspace (its buffers stay as the law left them); the fast kernel's size.
    work = np.zeros(law._work.size + fast_rigid_body_size(int(law._index[0]),
                                                          int(law._index[1])))

    def call(kernel, section2):
        def run(x, com, task, heading):
            phase(x, law._model, law._index, work, kernel, section2)
        return run

    return call(0, False), call(0, True), call(1, False), call(1, True)


def fast_kernel(controller, command, diagnostics):
    """The law's fast kernel on the controller's model and gains (a CompiledLaw of its own),
    as a callable on the law's inputs."""
    from aerial_drake.control.controller import DecoupledController

    twin = DecoupledController(controller._plant, controller._frame, controller._task,
                               controller._gains, **controller._limits, kernel="fast")
    law = twin._compiled

    def kernel(x, com, task, heading):
        law(x, com, task, heading, command, diagnostics)

    return kernel


def _load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def time_calls(evaluate, inputs, calls: int, block: int = 20) -> np.ndarray:
    """Per-call times (s) of ``evaluate(*inputs[k])``, measured over blocks of ``block``
    consecutive calls (short blocks: a slow moment of the machine spoils few of them)."""
    times = []
    for start in range(0, calls, block):
        t0 = time.perf_counter()
        for k in range(start, start + block):
            evaluate(*inputs[k % len(inputs)])
        times.append((time.perf_counter() - t0) / block)
    return np.array(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenarios", nargs="+", default=["nominal", "quadrotor_ur3e"],
                        help="one scenario per shipped robot by default")
    parser.add_argument("--duration", type=float, default=2.0)
    parser.add_argument("--calls", type=int, default=20000)
    parser.add_argument("--rounds", type=int, default=10,
                        help="the robots alternate in this many rounds (one sitting)")
    args = parser.parse_args()
    subjects = {}
    for name in args.scenarios:
        controller, inputs = logged_inputs(name, args.duration)
        law = controller._compiled
        command, diagnostics = (np.empty_like(a) for a in controller.evaluate(*inputs[0]))

        def kernel(x, com, task, heading, law=law, command=command, diagnostics=diagnostics):
            law(x, com, task, heading, command, diagnostics)

        subjects[name] = (controller, inputs, kernel, pinocchio_calls(controller, inputs),
                          law_phases(controller),
                          fast_kernel(controller, np.empty_like(command),
                                      np.empty_like(diagnostics)))

    print(f"machine: {platform.machine()}, {platform.processor() or platform.platform()}, "
          f"python {platform.python_version()}, load average {_load()}")
    per_round = max(args.calls // args.rounds, 20)
    kinds = ("CompiledLaw.__call__", FAST, "DecoupledController.evaluate", RIGID_BODY,
             SECTION_II, FAST_RIGID_BODY, FAST_SECTION_II, PINOCCHIO)
    times: dict = {(name, kind): [] for name in subjects for kind in kinds}
    for _ in range(args.rounds):  # interleaved: each robot and each subject in every round
        for name, (controller, inputs, kernel, pin_calls, phases, fast) in subjects.items():
            for kind, evaluate, on in (("CompiledLaw.__call__", kernel, inputs),
                                       (FAST, fast, inputs),
                                       ("DecoupledController.evaluate", controller.evaluate,
                                        inputs),
                                       (RIGID_BODY, phases[0], inputs),
                                       (SECTION_II, phases[1], inputs),
                                       (FAST_RIGID_BODY, phases[2], inputs),
                                       (FAST_SECTION_II, phases[3], inputs),
                                       (PINOCCHIO, *(pin_calls or (None, None)))):
                if evaluate is not None:
                    times[name, kind].append(1e6 * time_calls(evaluate, on, per_round))
    for (name, kind), chunks in times.items():
        if not chunks:
            continue
        t = np.concatenate(chunks)
        controller = subjects[name][0]
        print(f"{name} (n = {controller._n}): {kind}: median {np.median(t):.1f} us, "
              f"10th-90th percentile {np.percentile(t, 10):.1f}-{np.percentile(t, 90):.1f} us "
              f"({per_round * args.rounds} calls in {args.rounds} interleaved rounds)")
    if len(subjects) > 1:
        first = next(iter(subjects))
        base = np.median(np.concatenate(times[first, "CompiledLaw.__call__"]))
        for name in list(subjects)[1:]:
            other = np.median(np.concatenate(times[name, "CompiledLaw.__call__"]))
            print(f"kernel time {name} / {first}: {other / base:.3f}")
    for name in subjects:
        exact_chunks, fast_chunks = times[name, "CompiledLaw.__call__"], times[name, FAST]
        ratio = np.median(np.concatenate(fast_chunks)) / np.median(np.concatenate(exact_chunks))
        per_round = [np.median(a) / np.median(b) for a, b in zip(fast_chunks, exact_chunks)]
        print(f"{name}: fast kernel / exact kernel: {ratio:.2f} (per round "
              f"{np.percentile(per_round, 10):.2f}-{np.percentile(per_round, 90):.2f}, "
              "10th-90th percentile)")
    for name in subjects:
        pin_chunks = times[name, PINOCCHIO]
        if not pin_chunks:
            print(f"{name}: law / Pinocchio not measured: Pinocchio (pip package 'pin', in the "
                  "test extra) is not installed")
            continue
        for kind, what in (("CompiledLaw.__call__", "law"), (FAST, "fast law"),
                           (RIGID_BODY, "the law's rigid-body part"),
                           (FAST_RIGID_BODY, "the fast kernel's rigid-body part")):
            law_chunks = times[name, kind]
            # The ratio of the medians, and its spread over the rounds (each round's medians).
            ratio = np.median(np.concatenate(law_chunks)) / np.median(np.concatenate(pin_chunks))
            per_round = [np.median(a) / np.median(b) for a, b in zip(law_chunks, pin_chunks)]
            print(f"{name}: {what} / Pinocchio's rigid-body calls: {ratio:.2f} (per round "
                  f"{np.percentile(per_round, 10):.2f}-{np.percentile(per_round, 90):.2f}, "
                  "10th-90th percentile)")
    print(f"load average after: {_load()}")


if __name__ == "__main__":
    main()
