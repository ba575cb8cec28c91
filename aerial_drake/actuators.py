"""What turns the controller's command into forces on the plant (Sections II and IV).

- :class:`BaseWrenchApplier`: thrust ``f`` along the body z axis and body torques ``mu`` as one
  body wrench at the helicopter's frame (2), plus external disturbance wrenches (World) at the
  helicopter and at the end effector, as Drake ``ExternallyAppliedSpatialForce``s.
- :func:`lag_time_constant`: the first-order actuator lag of the disturbed case; the lag itself
  is Drake's ``FirstOrderLowPassFilter`` and the limits Drake's ``Saturation`` (wired in
  :mod:`aerial_drake.diagram`).
"""

from __future__ import annotations

import math

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.multibody.math import SpatialForce
from pydrake.multibody.plant import ExternallyAppliedSpatialForce
from pydrake.multibody.tree import RigidBody
from pydrake.systems.framework import Context, LeafSystem


def lag_time_constant(rise_time: float) -> float:
    """Time constant of a first-order system whose 10-90% rise time is ``rise_time``:
    ``rise_time / ln 9`` (0.1 s -> 0.0455 s)."""
    return rise_time / math.log(9.0)


def quaternion_to_rotation(q: np.ndarray) -> np.ndarray:
    """R_WB from Drake's floating-base quaternion [w, x, y, z] (normalised here)."""
    w, x, y, z = q / np.sqrt(q @ q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


class BaseWrenchApplier(LeafSystem):
    """Spatial forces on the plant from the base command and the disturbance wrenches.

    Input ports:
        - ``base_command``: ``[f, mu_x, mu_y, mu_z]``: thrust (N) along body z, body torques
          (N m) about body axes; applied at the helicopter frame origin (its CoM).
        - ``state``: the simulated plant's state (only the base quaternion ``q[0:4]`` is read).
        - ``helicopter_wrench``: ``[torque (3); force (3)]`` in World at the helicopter frame.
        - ``end_effector_wrench``: ``[torque (3); force (3)]`` in World at the end effector.

    Output port ``spatial_forces``: for the plant's ``applied_spatial_force`` input.
    """

    def __init__(self, base_body: RigidBody, end_effector_body: RigidBody,
                 p_BoE_B: np.ndarray, num_states: int):
        super().__init__()
        self._base_index = base_body.index()
        self._ee_index = end_effector_body.index()
        self._p_BoE_B = np.asarray(p_BoE_B, dtype=float).copy()
        self.DeclareVectorInputPort("base_command", 4)
        self.DeclareVectorInputPort("state", num_states)
        self.DeclareVectorInputPort("helicopter_wrench", 6)
        self.DeclareVectorInputPort("end_effector_wrench", 6)
        self.DeclareAbstractOutputPort(
            "spatial_forces",
            lambda: AbstractValue.Make([ExternallyAppliedSpatialForce()]),
            self._calc)

    def _calc(self, context: Context, output: AbstractValue) -> None:
        cmd = self.get_input_port(0).Eval(context)
        R = quaternion_to_rotation(self.get_input_port(1).Eval(context)[:4])
        heli = self.get_input_port(2).Eval(context)
        ee = self.get_input_port(3).Eval(context)
        # (2): w_b = [f e3; mu] in the body frame, re-expressed in World.
        base = ExternallyAppliedSpatialForce()
        base.body_index = self._base_index
        base.p_BoBq_B = np.zeros(3)
        base.F_Bq_W = SpatialForce(R @ cmd[1:4] + heli[:3], R[:, 2] * cmd[0] + heli[3:])
        tip = ExternallyAppliedSpatialForce()
        tip.body_index = self._ee_index
        tip.p_BoBq_B = self._p_BoE_B
        tip.F_Bq_W = SpatialForce(ee[:3], ee[3:])
        output.set_value([base, tip])
