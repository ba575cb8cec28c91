"""What the controller measures: the plant's state delayed by whole controller samples and
with Gaussian noise drawn per sample (the scenario's ``sensing`` section).

:class:`StateSensor` sits between the plant's state and the controller's ``state`` input. At
the controller's sample ``t_k = k T`` it gives ``x(t_{k-d}) + n_k``: ``d = delay / T`` samples
held in its discrete state (a ring of the last ``d`` states, updated at the same instants, so
the controller's update at ``t_k`` reads the state of ``t_{k-d}``), and ``n_k`` row ``k`` of a
table drawn before the run from ``default_rng(seed)``. The noise is added per coordinate
group: base position, base attitude (a small rotation ``exp(n)`` applied in World, so a
quaternion stays a unit quaternion; added to the angles of a roll-pitch-yaw base), joint
angles, base angular and linear velocity, joint rates. Sizes come from the model, so any arm
gets the same treatment.

The controller's diagnostics are computed on what it measures, so with noise they include
it; the plant's logged state is the true one, and so are the log's tracking errors and the
metrics read from them (:mod:`aerial_drake.simulation.tracking`).
"""

from __future__ import annotations

import numpy as np
from pydrake.common.eigen_geometry import AngleAxis, Quaternion
from pydrake.math import RotationMatrix
from pydrake.systems.framework import (
    BasicVector,
    Context,
    DiagramBuilder,
    DiscreteValues,
    LeafSystem,
    OutputPort,
)

from aerial_drake.robots.models import AerialManipulator
from aerial_drake.simulation.scenarios.perturbations import Sensing


def noise_table(sensing: Sensing, n_arm: int, samples: int) -> np.ndarray:
    """``(samples, 12 + 2 n_arm)`` noise: [base position 3, attitude 3, joints n, angular
    velocity 3, linear velocity 3, joint rates n] per sample, scaled by the section's stds."""
    sizes = (3, 3, n_arm, 3, 3, n_arm)
    stds = np.concatenate([np.full(size, std) for size, std in zip(sizes, sensing.noise_stds())])
    return np.random.default_rng(sensing.seed).normal(size=(samples, stds.size)) * stds


class StateSensor(LeafSystem):
    """The measured state (module docstring): input ``state``, output ``measured_state``
    (both the model's ``[q; v]``)."""

    def __init__(self, model: AerialManipulator, sensing: Sensing, period: float,
                 duration: float) -> None:
        super().__init__()
        plant = model.plant
        self._nx = plant.num_multibody_states()
        self._nq = plant.num_positions()
        self._period = period
        self._steps = int(round(sensing.delay / period))
        self._base_q = model.base_position_indices
        self._arm_q = model.arm_position_indices
        self._base_v = self._nq + model.base_velocity_indices
        self._arm_v = self._nq + model.arm_velocity_indices
        n = len(model.arm_joints)
        self._noise = noise_table(sensing, n, int(np.floor(duration / period)) + 2)
        self._slices = np.cumsum([0, 3, 3, n, 3, 3, n])
        self._state = self.DeclareVectorInputPort("state", self._nx)
        if self._steps:
            self._buffer = self.DeclareDiscreteState(self._steps * self._nx)
            self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._shift)
        self.DeclareVectorOutputPort("measured_state", self._nx, self._calc_measured)

    def prime(self, context: Context, x0: np.ndarray) -> None:
        """Fill the delay line with ``x0`` (the initial state): before ``d`` samples have
        passed, the controller measures the state at rest at t = 0."""
        if self._steps:
            context.SetDiscreteState(np.tile(x0, self._steps))

    def _shift(self, context: Context, values: DiscreteValues) -> None:
        old = context.get_discrete_state_vector().value()
        x = self._state.Eval(context)
        values.set_value(np.concatenate([x, old[:-self._nx]]))

    def _calc_measured(self, context: Context, output: BasicVector) -> None:
        if self._steps:
            x = context.get_discrete_state_vector().value()[-self._nx:].copy()
        else:
            x = np.array(self._state.Eval(context), dtype=float)
        k = min(int(round(context.get_time() / self._period)), len(self._noise) - 1)
        output.SetFromVector(self._add_noise(x, self._noise[k]))

    def _add_noise(self, x: np.ndarray, n: np.ndarray) -> np.ndarray:
        s = self._slices
        position, attitude = n[s[0]:s[1]], n[s[1]:s[2]]
        q_base = x[self._base_q]
        if len(q_base) == 7:  # quaternion [w x y z], then position
            wxyz = q_base[:4]
            if np.any(attitude):
                R = RotationMatrix(Quaternion(wxyz / np.linalg.norm(wxyz)))
                wxyz = (_rotation_of(attitude) @ R).ToQuaternion().wxyz()
            q_base = np.concatenate([wxyz, q_base[4:] + position])
        else:  # roll, pitch, yaw, then position
            q_base = np.concatenate([q_base[:3] + attitude, q_base[3:] + position])
        x[self._base_q] = q_base
        x[self._arm_q] += n[s[2]:s[3]]
        x[self._base_v] += n[s[3]:s[5]]
        x[self._arm_v] += n[s[5]:s[6]]
        return x


def _rotation_of(rotation_vector: np.ndarray) -> RotationMatrix:
    """exp of ``rotation_vector`` (rad, World axes)."""
    angle = float(np.linalg.norm(rotation_vector))
    return RotationMatrix(AngleAxis(angle, rotation_vector / angle))


def add_state_sensor(builder: DiagramBuilder, sensing: Sensing, model: AerialManipulator,
                     period: float, duration: float, state: OutputPort,
                     ) -> tuple[OutputPort, StateSensor | None]:
    """The port the controller measures: ``state`` itself when sensing is off, else a
    :class:`StateSensor`'s output (and the sensor, to prime at the start)."""
    if not sensing.active():
        return state, None
    sensor = builder.AddSystem(StateSensor(model, sensing, period, duration))
    sensor.set_name("state_sensor")
    builder.Connect(state, sensor.GetInputPort("state"))
    return sensor.GetOutputPort("measured_state"), sensor
