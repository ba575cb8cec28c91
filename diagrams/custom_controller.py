"""Your own controller in the closed loop: a subclass of ControllerBase that computes the
command, registered by name and chosen by the scenario's ``controller.type``, then run and
compared with the paper's controller (``aerial_drake.studies.compare``).

    python diagrams/custom_controller.py [SCENARIO] [--duration S] [--out DIR]

The example: the vehicle flies Lee et al.'s geometric law (the baselines' function) on a
body reference, and the arm only holds its posture of t = 0 with a joint-space PD plus
gravity compensation, so the end effector follows the vehicle, not the task: the comparison
shows what that costs.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
from _common import draw_closed_loop, parse_command_line

from aerial_drake.control.base import ControllerBase
from aerial_drake.control.baselines.vehicle import body_reference, geometric_vehicle_law
from aerial_drake.control.law import GainMatrices, rotation_angle
from aerial_drake.control.reference_pose import (
    body_offset_in_heading_frame,
    reference_configuration,
)
from aerial_drake.control.registry import register_controller
from aerial_drake.trajectories.reference import unpack_com_reference, unpack_heading_reference


class JointHoldController(ControllerBase):
    """Lee et al. on the vehicle; the arm held at its posture of t = 0 (PD, gravity
    compensated). Reports the vehicle law's attitude errors and desired force."""

    def __init__(self, scenario, model, kp: float = 200.0, kd: float = 30.0):
        super().__init__(model.plant, model.task, period=scenario.controller_period,
                         diagnostics_layout=(("e_R", 3), ("w_tilde", 3),
                                             ("base_attitude_error", 1), ("f_d_norm", 1)))
        self._model, self._plant = model, model.plant
        self._ctx = model.plant.CreateDefaultContext()
        self._K = GainMatrices.from_gains(scenario.gains, n_task=model.n)
        self._offset = body_offset_in_heading_frame(scenario, model)
        self._arm_q, self._arm_v = model.arm_position_indices, model.arm_velocity_indices
        self._q_hold = reference_configuration(scenario, model)[self._arm_q]
        self._kp, self._kd = kp, kd
        I_B = model.base_body.CalcSpatialInertiaInBodyFrame(self._ctx)
        self._J_v = I_B.CalcRotationalInertia().CopyToFullMatrix3()
        self._m = self._plant.CalcTotalMass(self._ctx)
        self._g = -self._plant.gravity_field().gravity_vector()[2]

    def calc_command(self, t, x, com, task, heading):
        plant, ctx, K = self._plant, self._ctx, self._K
        plant.SetPositionsAndVelocities(ctx, x)
        X_WB = plant.EvalBodyPoseInWorld(ctx, self._model.base_body)
        V_WB = plant.EvalBodySpatialVelocityInWorld(ctx, self._model.base_body)
        R = X_WB.rotation().matrix()
        b1d = unpack_heading_reference(heading)
        body_ref = body_reference(unpack_com_reference(com), b1d, self._offset)
        veh = geometric_vehicle_law(self._m, self._g, self._J_v, body_ref, b1d,
                                    X_WB.translation(), V_WB.translational(), R,
                                    R.T @ V_WB.rotational(), K.K_x, K.D_x, K.k_R, K.k_w)
        q, v = x[:plant.num_positions()], x[plant.num_positions():]
        tau = (self._kp * (self._q_hold - q[self._arm_q]) - self._kd * v[self._arm_v]
               - plant.CalcGravityGeneralizedForces(ctx)[self._arm_v])
        return np.concatenate([[veh.f], veh.mu, tau]), {
            "e_R": veh.e_R, "w_tilde": veh.e_w, "f_d_norm": veh.F_norm,
            "base_attitude_error": rotation_angle(veh.R_d.T @ R)}


def main() -> None:
    from aerial_drake.simulation.scenarios import load_scenario
    from aerial_drake.studies.compare import run_compare

    args = parse_command_line(__doc__)
    # Register once; then any scenario may say `controller: {type: joint_hold}`.
    register_controller("joint_hold", JointHoldController)
    scenario = load_scenario(args.scenario, overrides={"duration": args.duration})
    draw_closed_loop(dataclasses.replace(
        scenario, name=f"{scenario.name}_joint_hold",
        controller=dataclasses.replace(scenario.controller, type="joint_hold")), Path(args.out))
    result = run_compare(args.scenario, ("paper", "joint_hold"), args.out, args.duration, jobs=1)
    print(result.table)


if __name__ == "__main__":
    main()
