"""The ``paper_force`` controller's scenario parameters (``controller.force``).

No ``from __future__ import annotations`` here: Drake's ``yaml_load_typed`` needs real type
objects in the dataclass fields.
"""

import math
from dataclasses import dataclass, field

#: ``controller.type`` of the force-task controller.
PAPER_FORCE = "paper_force"


def _finite(value: object) -> bool:
    return (isinstance(value, (int, float)) and not isinstance(value, bool)
            and math.isfinite(value))


@dataclass
class ForceTaskParams:
    """A force task along one World direction (docs/contact.md, "The force task").

    Between ``start`` and ``stop`` the end effector presses along ``direction`` with the
    desired force: 0 at ``start``, ``force`` after ``ramp`` seconds, held, back to 0 at
    ``stop`` (smooth steps). The motion reference keeps the other directions. The pressing
    force is measured by the scenario's ``force_sensor``; an admittance,
    ``M d'' + D d' + K d = F_d - F``, moves the end effector's reference by ``d`` along
    ``direction`` (K = 0 inside the window: the force error is integrated to zero; outside
    it, ``release_stiffness`` brings the reference back to the motion reference's).
    """

    # The direction the tool pushes along, World (normalised at load): into the surface, the
    # opposite of the surface's outward normal. E.g. [1, 0, 0] against a wall facing -x,
    # [0, 0, -1] down on a table.
    direction: list[float] = field(default_factory=list)
    # The desired pressing force during the hold (N, > 0).
    force: float = 10.0
    # The window (s): the force rises from 0 at start over ramp, holds, and is back at 0 at
    # stop.
    start: float = 0.0
    stop: float = 0.0
    # Rise and fall time of the desired force (s, > 0 and at most half the window).
    ramp: float = 0.5
    # The admittance's mass (kg) and damping (N s/m): the reference's response to a force
    # error. The force loop's rate is about K_c / D with K_c the closed loop's contact
    # stiffness (docs/contact.md).
    admittance_mass: float = 20.0
    admittance_damping: float = 600.0
    # The spring (N/m) pulling the reference's shift back to 0 outside the window.
    release_stiffness: float = 400.0
    # Bound on the shift (m): a lost contact does not run the reference away.
    max_shift: float = 0.05
    # Feed the measured contact force forward into f_d of (10) (as paper_plus's F^), so the
    # CoM does not drift by F / K_x while pressing.
    feedforward: bool = True

    def unit_direction(self) -> list[float]:
        """``direction`` normalised."""
        norm = math.sqrt(sum(float(x) ** 2 for x in self.direction))
        return [float(x) / norm for x in self.direction]

    def validate(self, prefix: str = "controller.force") -> "ForceTaskParams":
        """Raise ValueError starting with the field's dotted name. Returns self."""
        d = self.direction
        if (not isinstance(d, (list, tuple)) or len(d) != 3 or not all(map(_finite, d))
                or math.sqrt(sum(float(x) ** 2 for x in d)) < 1e-9):
            raise ValueError(f"{prefix}.direction must be 3 finite numbers, not all zero (the "
                             f"World direction the tool pushes along, e.g. [1, 0, 0]); got "
                             f"{d!r}")
        for name, low in (("force", 0.0), ("ramp", 0.0), ("admittance_mass", 0.0),
                          ("admittance_damping", 0.0), ("max_shift", 0.0)):
            value = getattr(self, name)
            if not (_finite(value) and value > low):
                raise ValueError(f"{prefix}.{name} must be a finite number > {low:g}; got "
                                 f"{value!r}")
        if not (_finite(self.release_stiffness) and self.release_stiffness >= 0):
            raise ValueError(f"{prefix}.release_stiffness must be a finite number >= 0; got "
                             f"{self.release_stiffness!r}")
        if not (_finite(self.start) and _finite(self.stop) and 0 <= self.start < self.stop):
            raise ValueError(f"{prefix}.start and stop must satisfy 0 <= start < stop (s); got "
                             f"start {self.start!r}, stop {self.stop!r}")
        if 2 * self.ramp > self.stop - self.start:
            raise ValueError(f"{prefix}.ramp = {self.ramp:g} s is more than half the window "
                             f"[{self.start:g}, {self.stop:g}] s: shorten the ramp or widen "
                             "the window")
        if not isinstance(self.feedforward, bool):
            raise ValueError(f"{prefix}.feedforward must be true or false; got "
                             f"{self.feedforward!r}")
        return self

    def hold(self) -> tuple[float, float]:
        """The window at the full force: (start + ramp, stop - ramp) (s)."""
        return self.start + self.ramp, self.stop - self.ramp
