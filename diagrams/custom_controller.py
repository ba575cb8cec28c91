"""Your own controller in the closed loop: a LeafSystem with the interface's ports
(aerial_drake.control.interface), registered by name and chosen by the scenario's
``controller.type``, then run and measured like the paper's controller.

    python diagrams/custom_controller.py [SCENARIO] [--duration S] [--out DIR]

The example: the vehicle flies Lee et al.'s geometric law (the baselines' function) on a
body reference, and the arm only holds its posture of t = 0 with a joint-space PD plus
gravity compensation, so the end effector follows the vehicle, not the task: the metrics show
what that costs.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np
from _common import write_graphviz
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import LeafSystem, ValueProducer

from aerial_drake.control.baselines.vehicle import body_reference, geometric_vehicle_law
from aerial_drake.control.interface import error_diagnostics
from aerial_drake.control.law import GainMatrices, diagnostics_size
from aerial_drake.simulation.controllers import body_offset_in_heading_frame, register_controller
from aerial_drake.simulation.diagram import build_closed_loop
from aerial_drake.simulation.runner import reference_configuration, run_scenario
from aerial_drake.simulation.scenarios import load_scenario
from aerial_drake.trajectories.reference import (
    task_reference_size,
    unpack_com_reference,
    unpack_heading_reference,
    unpack_task_reference,
)


class JointHoldController(LeafSystem):
    """Lee et al. on the vehicle; the arm held at ``q_hold`` (PD, gravity compensated)."""

    def __init__(self, scenario, model, kp: float = 200.0, kd: float = 30.0):
        super().__init__()
        self._model, self._plant = model, model.plant
        self._ctx = model.plant.CreateDefaultContext()
        self._K = GainMatrices.from_gains(scenario.gains, n_task=model.n)
        self._offset = body_offset_in_heading_frame(scenario, model)
        self._arm_q = model.arm_position_indices
        self._arm_v = model.arm_velocity_indices
        self._q_hold = reference_configuration(scenario, model)[self._arm_q]
        self._kp, self._kd = kp, kd
        I_B = model.base_body.CalcSpatialInertiaInBodyFrame(self._ctx)
        self._J_v = I_B.CalcRotationalInertia().CopyToFullMatrix3()
        self._ports = [self.DeclareVectorInputPort(name, size) for name, size in (
            ("state", model.plant.num_multibody_states()), ("com_reference", 15),
            ("task_reference", task_reference_size(model.task.n_joints)),
            ("heading_reference", 9))]
        n = len(model.arm_joints)
        # The law once per input change, both outputs read from it (a cache entry): not
        # once per output port.
        self._solution = self.DeclareCacheEntry(
            description="law", value_producer=ValueProducer(
                allocate=AbstractValue.Make(object()).Clone,
                calc=lambda c, value: value.set_value(self._law(c))),
            prerequisites_of_calc={self.all_input_ports_ticket()})
        for i, (name, size) in enumerate((("command", 4 + n),
                                          ("diagnostics", diagnostics_size(n)))):
            self.DeclareVectorOutputPort(
                name, size, lambda c, o, i=i: o.SetFromVector(self._solution.Eval(c)[i]),
                prerequisites_of_calc={self._solution.ticket()})

    def _law(self, context):
        x, com, task, heading = (p.Eval(context) for p in self._ports)
        plant, ctx, K = self._plant, self._ctx, self._K
        plant.SetPositionsAndVelocities(ctx, x)
        X_WB = plant.EvalBodyPoseInWorld(ctx, self._model.base_body)
        V_WB = plant.EvalBodySpatialVelocityInWorld(ctx, self._model.base_body)
        R = X_WB.rotation().matrix()
        com_ref, b1d = unpack_com_reference(com), unpack_heading_reference(heading)
        m = plant.CalcTotalMass(ctx)
        g = -plant.gravity_field().gravity_vector()[2]
        veh = geometric_vehicle_law(m, g, self._J_v, body_reference(com_ref, b1d, self._offset),
                                    b1d, X_WB.translation(), V_WB.translational(), R,
                                    R.T @ V_WB.rotational(), K.K_x, K.D_x, K.k_R, K.k_w)
        q, v = x[:plant.num_positions()], x[plant.num_positions():]
        tau = (self._kp * (self._q_hold - q[self._arm_q]) - self._kd * v[self._arm_v]
               - plant.CalcGravityGeneralizedForces(ctx)[self._arm_v])
        X_WE = self._model.end_effector_frame.CalcPoseInWorld(ctx)
        t = unpack_task_reference(task)
        diagnostics = error_diagnostics(
            task=self._model.task, x_g=plant.CalcCenterOfMassPositionInWorld(ctx),
            x_g_dot=plant.CalcCenterOfMassTranslationalVelocityInWorld(ctx),
            com_reference=com_ref, p_WE=X_WE.translation(), R_WE=X_WE.rotation().matrix(),
            q_j=q[list(self._model.task.joint_positions)], p_ed=t.p_ed, R_ed=t.R_ed,
            q_jd=t.q_jd, R_b=R, R_d=veh.R_d, e_R=veh.e_R, w_tilde=veh.e_w,
            f_d_norm=veh.F_norm, sigma_min_J3=1.0)
        return np.concatenate([[veh.f], veh.mu, tau]), diagnostics


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario", nargs="?", default="nominal")
    parser.add_argument("--duration", type=float, default=2.0)
    parser.add_argument("--out", default="out/diagrams")
    args = parser.parse_args()
    # Register once; then any scenario may say `controller: {type: joint_hold}`.
    register_controller("joint_hold", JointHoldController)
    scenario = load_scenario(args.scenario, overrides={"duration": args.duration})
    scenario = dataclasses.replace(
        scenario, name=f"{scenario.name}_joint_hold",
        controller=dataclasses.replace(scenario.controller, type="joint_hold"))
    out = Path(args.out)
    for path in write_graphviz(build_closed_loop(scenario).diagram,
                               out / f"{scenario.name}_closed_loop"):
        print(f"wrote {path}")
    result = run_scenario(scenario, out_dir=out / scenario.name)
    last = result.metrics["phases"][-1]
    print(f"ran {result.metrics['simulated_time_s']:.2f} s; max end-effector error in the "
          f"last phase {1e3 * last['ee_position_error_m']['max']:.1f} mm; logs in "
          f"{result.out_dir}")


if __name__ == "__main__":
    main()
