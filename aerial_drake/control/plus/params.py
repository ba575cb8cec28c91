"""The ``paper_plus`` controller's scenario parameters (``controller.plus``).

No ``from __future__ import annotations`` here: Drake's ``yaml_load_typed`` needs real type
objects in the dataclass fields. Every default means "off": with them ``paper_plus`` gives
the paper law's command (docs/control.md, "paper_plus").
"""

import math
from dataclasses import dataclass, field
from typing import Any

from aerial_drake.control.law import SingularityRobust

#: ``controller.type`` of the extended controller.
PAPER_PLUS = "paper_plus"


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


@dataclass
class PlusParams:
    """Options of ``paper_plus`` (docs/control.md, "paper_plus"); the other gains are the
    scenario's ``gains`` (Table II)."""

    # Integral gain on the CoM error, per World axis: f_d of (10) gets - K_I,x int(x~) dt
    # (N/(m s)); empty or zeros: off.
    com_integral_gain: list[float] = field(default_factory=list)
    # Integral gain on the task error, per task row: z_d of (18) gets - K_I,y int(y~) dt
    # (1/s^2); empty or zeros: off.
    task_integral_gain: list[float] = field(default_factory=list)
    # Bound on each entry of the CoM integral's term as an acceleration, |K_I,x int(x~)| / m
    # (m/s^2): the integral state is clamped there.
    com_integral_limit: float = 3.0
    # Bound on each entry of the task integral's term, |K_I,y int(y~)| (m/s for position rows,
    # rad/s for orientation and joint rows): the integral state is clamped there.
    task_integral_limit: float = 2.0
    # Feed the input port ``vehicle_force_estimate`` (an estimate of the external force on
    # the vehicle, World, N; unconnected = zero) forward into f_d of (10).
    vehicle_force_feedforward: bool = False
    # Cancel the observer's estimate of the external generalized force (input port
    # ``generalized_force_estimate``) but for its total force (vehicle_force_feedforward's):
    # the moment about the CoM through the vehicle moment, the rest through the arm torques,
    # i.e. (16) and (20) with observer-corrected accelerations (docs/control.md, "Wrench
    # compensation").
    wrench_compensation: bool = False

    # --- Graceful degradation near the singularity of J_3 (docs/control.md, "Graceful
    # degradation"; control.law.SingularityRobust) ---
    # lambda_max of the damped inverse of J_3 (units of sigma_min(J_3)); 0: off, the paper's
    # Assumption 1 stop.
    singularity_damping: float = 0.0
    # eps: the inverse is damped where sigma_min(J_3) < eps.
    singularity_threshold: float = 0.05
    # With the damping on, control is lost (the run stops) when the inverse is damped and
    # the end effector's position error exceeds this (m).
    singularity_lost_error: float = 0.1

    def singularity(self) -> SingularityRobust:
        """The damped inverse's parameters, for the law."""
        return SingularityRobust(damping=float(self.singularity_damping),
                                 threshold=float(self.singularity_threshold),
                                 lost_error=float(self.singularity_lost_error))

    def _validate_singularity(self, prefix: str) -> None:
        """:meth:`validate`'s checks of the singularity fields."""
        for name in ("singularity_damping", "singularity_threshold", "singularity_lost_error"):
            value = getattr(self, name)
            zero_is_off = name == "singularity_damping"
            if not (_is_number(value) and math.isfinite(value)
                    and (value >= 0 if zero_is_off else value > 0)):
                bound = ">= 0 (0: off)" if zero_is_off else "> 0"
                raise ValueError(f"{prefix}.{name} must be a finite number {bound}; got "
                                 f"{value!r}")

    def com_gain(self) -> list[float]:
        """The CoM integral gain as 3 entries (zeros when empty)."""
        return [float(k) for k in self.com_integral_gain] or [0.0] * 3

    def task_gain(self, n: int) -> list[float]:
        """The task integral gain as ``n`` entries (zeros when empty)."""
        return [float(k) for k in self.task_integral_gain] or [0.0] * n

    def integrates(self) -> bool:
        """Whether any integral gain is nonzero."""
        return any(k != 0 for k in list(self.com_integral_gain) + list(self.task_integral_gain))

    def com_gain_error(self, m: float, K_x: Any, D_x: Any, prefix: str = "controller.plus"
                       ) -> str:
        """Why the CoM integral gain destabilises the CoM loop of a robot of mass ``m``
        (kg) under (10)'s diagonals ``K_x``, ``D_x``; empty if it does not. Per axis,
        m s^3 + D_x s^2 + K_x s + K_I (23a with the integral) is Hurwitz iff
        K_I < K_x D_x / m (Routh)."""
        for i, (k, K, D) in enumerate(zip(self.com_gain(), K_x, D_x)):
            if not k * m < K * D:
                return (f"{prefix}.com_integral_gain[{i}] = {k:g} makes the CoM loop "
                        f"unstable: m s^3 + D_x s^2 + K_x s + K_I needs K_I < K_x D_x / m = "
                        f"{K * D / m:.4g} N/(m s) (m = {m:.4g} kg, gains.K_x and gains.D_x)")
        return ""

    def validate(self, n: int, prefix: str = "controller.plus") -> "PlusParams":
        """Raise ValueError starting with the field's dotted name (``n``: the task's rows).
        Returns self."""
        for name, size in (("com_integral_gain", 3), ("task_integral_gain", n)):
            value = getattr(self, name)
            if not isinstance(value, (list, tuple)) or (value and (
                    len(value) != size or not all(_is_number(k) and math.isfinite(k)
                                                  and 0 <= k <= 1e6 for k in value))):
                raise ValueError(f"{prefix}.{name} must be empty (off) or {size} numbers in "
                                 f"[0, 1e6] (0: off on that entry); got {value!r}")
        for name in ("com_integral_limit", "task_integral_limit"):
            value = getattr(self, name)
            if not _is_number(value) or not (math.isfinite(value) and value > 0):
                raise ValueError(f"{prefix}.{name} must be a finite number > 0; got "
                                 f"{value!r}")
        for name in ("vehicle_force_feedforward", "wrench_compensation"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"{prefix}.{name} must be true or false; got "
                                 f"{getattr(self, name)!r}")
        self._validate_singularity(prefix)
        return self
