"""What turns the controller's command into forces on the plant (Sections II and IV).

- :func:`make_base_actuator`: thrust ``f`` along the body z axis and body torques ``mu`` as a
  body wrench at the helicopter's frame (2), with Drake's ``Propeller`` system.
- :func:`free_body_wrench_map` and :class:`PointWrenchApplier`: external disturbance wrenches
  (World) at the helicopter frame and at the end effector.
- :func:`lag_time_constant`: the first-order actuator lag of the disturbed case; the lag itself
  is Drake's ``FirstOrderLowPassFilter`` and the limits Drake's ``Saturation`` (wired in
  :mod:`aerial_drake.diagram`).
"""

from __future__ import annotations

import math

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.multibody.math import SpatialForce
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.plant import ExternallyAppliedSpatialForce, Propeller, PropellerInfo
from pydrake.multibody.tree import RigidBody
from pydrake.systems.framework import Context, LeafSystem


def lag_time_constant(rise_time: float) -> float:
    """Time constant of a first-order system whose 10-90% rise time is ``rise_time``:
    ``rise_time / ln 9`` (0.1 s -> 0.0455 s)."""
    return rise_time / math.log(9.0)


def make_base_actuator(base_body: RigidBody) -> Propeller:
    """The helicopter's thrust and body torques (2) as Drake's ``Propeller`` system.

    Four "propellers" on the base body, all at its frame origin: one with thrust ratio 1 along
    body z (the thrust f), and three with thrust ratio 0 and moment ratio 1 whose axes are the
    body x, y and z axes (the torques mu). Its ``command`` input is ``[f, mu_x, mu_y, mu_z]``;
    its ``spatial_forces`` output goes to the plant. Being C++, it costs next to nothing at each
    integrator stage, and it keeps the wrench body-fixed as the base rotates.
    """
    i = base_body.index()
    axes = (RotationMatrix(),  # thrust along z
            RotationMatrix.MakeYRotation(np.pi / 2),  # P's z = body x
            RotationMatrix.MakeXRotation(-np.pi / 2),  # P's z = body y
            RotationMatrix())  # P's z = body z
    infos = [PropellerInfo(i, RigidTransform(axes[0]), thrust_ratio=1.0, moment_ratio=0.0)]
    infos += [PropellerInfo(i, RigidTransform(R), thrust_ratio=0.0, moment_ratio=1.0)
              for R in axes[1:]]
    return Propeller(infos)


def free_body_wrench_map(nv: int) -> np.ndarray:
    """Generalized force of a World wrench ``[torque; force]`` applied at the base frame origin,
    for a plant whose first six velocities are the base's ``[w_WB; v_WBo]`` (World): it is the
    wrench itself (``J^T`` of the free joint at that point is the identity)."""
    G = np.zeros((nv, 6))
    G[:6, :6] = np.eye(6)
    return G


class PointWrenchApplier(LeafSystem):
    """A World wrench ``[torque; force]`` (input ``wrench``, 6) applied at a point fixed on a
    body, as a Drake ``ExternallyAppliedSpatialForce`` list (output ``spatial_forces``).

    The output depends on the input alone. Its input usually depends on time (a disturbance
    schedule), so the plant asks for it at every integrator stage: the calculation keeps the
    last force list and rebuilds it only when the wrench changes (a piecewise-constant
    disturbance changes at its window edges only).
    """

    def __init__(self, body: RigidBody, p_BoQ_B: np.ndarray):
        super().__init__()
        self._body_index = body.index()
        self._p_BoQ_B = np.asarray(p_BoQ_B, dtype=float).copy()
        self._wrench_port = self.DeclareVectorInputPort("wrench", 6)
        # The last wrench (as bytes) and its force list: a pure function of the input, so it
        # is shared by every context.
        self._last_wrench, self._last_forces = None, None
        self.DeclareAbstractOutputPort(
            "spatial_forces", lambda: AbstractValue.Make([self._force(np.zeros(6))]),
            self._calc,
            prerequisites_of_calc={self.input_port_ticket(self._wrench_port.get_index())})

    def _force(self, wrench: np.ndarray) -> ExternallyAppliedSpatialForce:
        """The World ``wrench`` [torque; force] at this applier's point of its body."""
        force = ExternallyAppliedSpatialForce()
        force.body_index = self._body_index
        force.p_BoBq_B = self._p_BoQ_B
        force.F_Bq_W = SpatialForce(wrench[:3], wrench[3:])
        return force

    def _calc(self, context: Context, output: AbstractValue) -> None:
        wrench = self._wrench_port.Eval(context)
        key = wrench.tobytes()
        if key != self._last_wrench:
            self._last_wrench, self._last_forces = key, [self._force(wrench)]
        output.set_value(self._last_forces)
