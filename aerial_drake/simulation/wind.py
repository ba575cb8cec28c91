"""Wind on the vehicle: a mean wind plus Dryden turbulence, turned into a drag force at the
base body's origin (its CoM).

Dryden turbulence (MIL-F-8785C, section 3.7.2; the same forms in MIL-HDBK-1797): the gust
velocities along the mean wind (u), across it horizontally (v) and vertically (w) are white
noise of unit power spectral density through the shaping filters

    H_u(s) = sigma_u sqrt(2 L_u / (pi V)) / (1 + (L_u / V) s)
    H_v(s) = sigma_v sqrt(L_v / (pi V)) (1 + sqrt(3) (L_v / V) s) / (1 + (L_v / V) s)^2
    H_w(s) = sigma_w sqrt(L_w / (pi V)) (1 + sqrt(3) (L_w / V) s) / (1 + (L_w / V) s)^2

with intensities sigma, scale lengths L and Taylor's frozen-field airspeed V (the scenario's
``wind`` section; at low altitude h the standard gives L_w = h, L_u = L_v = h / (0.177 +
0.000823 h)^1.2 and sigma_u / sigma_w = 1 / (0.177 + 0.000823 h)^0.4 with sigma_w = 0.1 W20,
in feet). Each filter is written as first-order lags, ``(1 + sqrt(3) T s) / (1 + T s) =
sqrt(3) + (1 - sqrt(3)) / (1 + T s)``, each discretised exactly for a noise held over a sample
(``a = exp(-dt / T)``), driven by ``default_rng(seed)`` normal samples of variance ``pi / dt``:
white noise of unit power spectral density in the standard's convention (spectra over
positive frequencies, Phi(omega) = |H(j omega)|^2), so each output's variance is sigma^2
(tests/simulation/test_wind.py checks it). The gusts are
computed once, before the run, and played by a Drake ``TrajectorySource`` (linear between
samples), so the simulation's cost is one drag evaluation per step.

Drag (body axes B): ``F_B = c_1 v_r + c_2 |v_r| v_r`` per axis, with ``v_r = R_BW (w - v)``
the wind relative to the vehicle's origin; the force in World goes to the closed loop's
``vehicle_wrench`` input beside the disturbance windows.
"""

from __future__ import annotations

import math

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import RigidBody
from pydrake.systems.framework import BasicVector, Context, DiagramBuilder, LeafSystem, OutputPort
from pydrake.systems.primitives import Adder, TrajectorySource
from pydrake.trajectories import PiecewisePolynomial

from aerial_drake.simulation.scenarios.perturbations import Wind

_SQRT3 = math.sqrt(3.0)


def transport_speed(wind: Wind) -> float:
    """Taylor's airspeed V (m/s): the scenario's, else |mean| with at least 1 m/s (hover)."""
    if not math.isnan(wind.airspeed):
        return float(wind.airspeed)
    return max(1.0, float(np.linalg.norm(wind.mean)))


def _lag(x: np.ndarray, a: float) -> np.ndarray:
    """y[k+1] = a y[k] + (1 - a) x[k], y[0] = 0: 1 / (1 + T s) held exactly over a sample."""
    y = np.zeros_like(x)
    for k in range(len(x) - 1):
        y[k + 1] = a * y[k] + (1.0 - a) * x[k]
    return y


def dryden_gusts(wind: Wind, duration: float) -> tuple[np.ndarray, np.ndarray]:
    """Sample times (s) and gusts ``(N, 3)`` [u, v, w] (m/s) over ``[0, duration]``, in the
    wind's own axes (module docstring)."""
    dt = wind.sample_period
    n = int(math.ceil(duration / dt)) + 2
    times = dt * np.arange(n)
    V = transport_speed(wind)
    noise = np.random.default_rng(wind.seed).normal(size=(n, 3)) * math.sqrt(math.pi / dt)
    gusts = np.zeros((n, 3))
    for axis, (sigma, L) in enumerate(zip(wind.sigma, wind.length_scale)):
        if sigma == 0:
            continue
        T = L / V
        a = math.exp(-dt / T)
        first = _lag(noise[:, axis], a)
        if axis == 0:  # H_u: one lag
            gusts[:, 0] = sigma * math.sqrt(2.0 * L / (math.pi * V)) * first
        else:  # H_v, H_w: lead-lag then lag
            lead = _SQRT3 * noise[:, axis] + (1.0 - _SQRT3) * first
            gusts[:, axis] = sigma * math.sqrt(L / (math.pi * V)) * _lag(lead, a)
    return times, gusts


def wind_axes(mean: list[float]) -> np.ndarray:
    """R_WG: columns u (along the mean wind's horizontal direction; World x when it has
    none), v (horizontal, across it) and w (up)."""
    horizontal = np.array([mean[0], mean[1], 0.0])
    norm = np.linalg.norm(horizontal)
    u = horizontal / norm if norm > 1e-9 else np.array([1.0, 0.0, 0.0])
    w = np.array([0.0, 0.0, 1.0])
    return np.column_stack([u, np.cross(w, u), w])


def wind_velocity(wind: Wind, duration: float) -> tuple[np.ndarray, np.ndarray]:
    """Times and the wind velocity in World ``(N, 3)``: the mean plus the gusts."""
    times, gusts = dryden_gusts(wind, duration)
    return times, np.asarray(wind.mean, dtype=float) + gusts @ wind_axes(wind.mean).T


class WindDrag(LeafSystem):
    """Drag of the relative wind on ``body`` as ``[torque; force]`` in World (torque zero: the
    force acts at the body's origin, its CoM).

    Inputs ``body_poses`` and ``body_spatial_velocities`` (the plant's), ``wind_velocity``
    (World, 3); output ``wrench`` (6).
    """

    def __init__(self, body: RigidBody, linear: list[float], quadratic: list[float]) -> None:
        super().__init__()
        self._index = int(body.index())
        self._linear = np.asarray(linear, dtype=float)
        self._quadratic = np.asarray(quadratic, dtype=float)
        plant = body.GetParentPlant()
        self._poses = self.DeclareAbstractInputPort(
            "body_poses", plant.get_body_poses_output_port().Allocate())
        self._velocities = self.DeclareAbstractInputPort(
            "body_spatial_velocities", plant.get_body_spatial_velocities_output_port().Allocate())
        self._wind = self.DeclareVectorInputPort("wind_velocity", 3)
        self.DeclareVectorOutputPort("wrench", 6, self._calc_wrench)

    def _calc_wrench(self, context: Context, output: BasicVector) -> None:
        X_WB = self._poses.Eval(context)[self._index]
        v_WB = self._velocities.Eval(context)[self._index].translational()
        R_WB = X_WB.rotation().matrix()
        v_r_B = R_WB.T @ (self._wind.Eval(context) - v_WB)
        F_B = self._linear * v_r_B + self._quadratic * np.abs(v_r_B) * v_r_B
        output.SetFromVector(np.concatenate([np.zeros(3), R_WB @ F_B]))


def add_wind(builder: DiagramBuilder, wind: Wind, duration: float, plant: MultibodyPlant,
             body: RigidBody, wrench: OutputPort) -> OutputPort:
    """Add the wind's source and drag on ``body``; returns a port carrying ``wrench`` (the
    disturbance windows' ``[torque; force]``) plus the drag. ``wrench`` itself when the wind
    is off."""
    if not wind.enabled:
        return wrench
    times, velocity = wind_velocity(wind, duration)
    source = builder.AddSystem(TrajectorySource(
        PiecewisePolynomial.FirstOrderHold(times, velocity.T)))
    source.set_name("wind_velocity")
    drag = builder.AddSystem(WindDrag(body, wind.drag_linear, wind.drag_quadratic))
    drag.set_name("wind_drag")
    builder.Connect(plant.get_body_poses_output_port(), drag.GetInputPort("body_poses"))
    builder.Connect(plant.get_body_spatial_velocities_output_port(),
                    drag.GetInputPort("body_spatial_velocities"))
    builder.Connect(source.get_output_port(), drag.GetInputPort("wind_velocity"))
    total = builder.AddSystem(Adder(2, 6))
    total.set_name("vehicle_wrench_with_wind")
    builder.Connect(wrench, total.get_input_port(0))
    builder.Connect(drag.GetOutputPort("wrench"), total.get_input_port(1))
    return total.get_output_port()
