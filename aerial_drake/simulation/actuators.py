"""What turns the controller's command into forces on the plant (Sections II and IV).

- :func:`make_base_actuator`: thrust ``f`` along the body z axis and body torques ``mu`` as a
  body wrench at the helicopter's frame (2), with Drake's ``Propeller`` system.
- :func:`free_body_wrench_map` and :class:`PointWrenchApplier`: external disturbance wrenches
  (World) at the helicopter frame and at the end effector.
- :func:`lag_time_constant` and :class:`ActuatorLag`: the first-order actuator lag of the
  disturbed case (a Drake ``LinearSystem``); the limits are Drake's ``Saturation`` (wired in
  :mod:`aerial_drake.simulation.diagram`).
"""

from __future__ import annotations

import math

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.plant import Propeller, PropellerInfo
from pydrake.multibody.tree import RigidBody
from pydrake.systems.framework import Context, Diagram, DiagramBuilder
from pydrake.systems.primitives import ConstantValueSource, LinearSystem


def lag_time_constant(rise_time: float) -> float:
    """Time constant of a first-order system whose 10-90% rise time is ``rise_time``:
    ``rise_time / ln 9`` (0.1 s -> 0.0455 s)."""
    return rise_time / math.log(9.0)


class ActuatorLag(LinearSystem):
    """A first-order lag with time constant ``time_constant`` on the first ``lagged`` entries
    of its input, the next ``passed`` entries passed through: ``x_dot = (u_l - x) / tau``,
    ``y = [x; u_p]`` (Section IV: thrust and body torques lag, the arm's torques do not).

    One Drake ``LinearSystem`` (C++) instead of a split, a ``FirstOrderLowPassFilter`` and a
    join: the plant asks for it at every integrator stage, and each system there costs
    framework work. Its state is the lagged output; ``x_dot`` is computed as
    ``-x / tau + u / tau``, equal to ``(u - x) / tau`` up to rounding.
    """

    def __init__(self, time_constant: float, lagged: int, passed: int):
        if not time_constant > 0.0:
            raise ValueError(f"ActuatorLag: time_constant must be > 0 (s), got {time_constant}")
        rate = 1.0 / time_constant
        n = lagged + passed
        B = np.zeros((lagged, n))
        B[:, :lagged] = rate * np.eye(lagged)
        C = np.zeros((n, lagged))
        C[:lagged] = np.eye(lagged)
        D = np.zeros((n, n))
        D[lagged:, lagged:] = np.eye(passed)
        super().__init__(-rate * np.eye(lagged), B, C, D)
        self._time_constant = float(time_constant)

    @property
    def time_constant(self) -> float:
        """The lag's time constant (s)."""
        return self._time_constant

    def set_initial_output_value(self, context: Context, value: np.ndarray) -> None:
        """Start the lagged entries at ``value`` (this system's own ``context``)."""
        context.SetContinuousState(np.asarray(value, dtype=float))


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


#: Rotations R_BP whose z axis is the x, y and z axis of B, written out so the products with
#: them are exact (``MakeYRotation(pi / 2)`` leaves 6e-17 in a zero entry).
_AXES = (RotationMatrix(np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])),
         RotationMatrix(np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])),
         RotationMatrix())


class PointWrenchApplier(Diagram):
    """A World wrench ``[torque; force]`` (input ``wrench``, 6) applied at a point fixed on a
    body, as a list of Drake ``ExternallyAppliedSpatialForce`` (output ``spatial_forces``).

    Built from C++ systems only, so the plant's request for it at every integrator stage costs
    no Python call (a Python LeafSystem cost about 7 us per call, three calls per 1 ms step):
    Drake's ``Propeller`` with six "propellers" at the point, three with moment ratio 1 about
    the x, y and z axes and three with thrust ratio 1 along them. ``Propeller`` turns each
    command into a force about its axis, rotated to World by the body's pose from its
    ``body_poses`` input; that input is a constant list of identity poses here, so the axes are
    World's and the commands are the World wrench's six components. The plant applies the
    forces at the point on the body's actual pose (``p_BoBq_B`` is body-fixed).
    """

    def __init__(self, body: RigidBody, p_BoQ_B: np.ndarray, num_bodies: int):
        """``num_bodies``: the plant's ``num_bodies()`` (the length of the pose list)."""
        super().__init__()
        p = np.asarray(p_BoQ_B, dtype=float)
        i = body.index()
        infos = [PropellerInfo(i, RigidTransform(R, p), thrust_ratio=0.0, moment_ratio=1.0)
                 for R in _AXES]
        infos += [PropellerInfo(i, RigidTransform(R, p), thrust_ratio=1.0, moment_ratio=0.0)
                  for R in _AXES]
        builder = DiagramBuilder()
        propeller = builder.AddSystem(Propeller(infos))
        propeller.set_name("world_axes_propellers")
        world_aligned = builder.AddSystem(ConstantValueSource(
            AbstractValue.Make([RigidTransform()] * num_bodies)))
        world_aligned.set_name("world_aligned_poses")
        builder.Connect(world_aligned.get_output_port(), propeller.get_body_poses_input_port())
        builder.ExportInput(propeller.get_command_input_port(), "wrench")
        builder.ExportOutput(propeller.get_spatial_forces_output_port(), "spatial_forces")
        builder.BuildInto(self)
