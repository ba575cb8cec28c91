"""The baselines' scenario parameters (``controller.baseline``).

No ``from __future__ import annotations`` here: Drake's ``yaml_load_typed`` needs real type
objects in the dataclass fields.
"""

from dataclasses import dataclass, field

import numpy as np

#: The baselines by scenario name (``controller.type``).
BASELINE_TYPES = ("uncoupled", "static_compensation")


@dataclass
class BaselineParams:
    """Parameters of the baselines (scenario ``controller.baseline``); their gains are the
    scenario's ``gains`` (Table II), used as docs/baselines.md says."""

    # The inertia the vehicle's attitude law assumes, diagonal (kg m^2); empty: the whole
    # robot's, locked at the reference configuration of t = 0, about its centre of mass,
    # from the model (baselines.tuning.locked_inertia; docs/baselines.md, "Tuning").
    # [1.46, 0.36, 1.46] is the helicopter body's alone (Table I), the default before.
    vehicle_inertia: list[float] = field(default_factory=list)
    # The run stops when the arm's fixed-base task Jacobian's smallest singular value falls
    # below this (the analogue of Assumption 1).
    sigma_min_limit: float = 1e-3

    def validate(self, prefix: str = "controller.baseline") -> "BaselineParams":
        """Raise ValueError naming the field. Returns self."""
        try:
            inertia = np.asarray(self.vehicle_inertia, dtype=float)
        except (TypeError, ValueError):
            inertia = np.full(1, np.nan)  # not a list of numbers: refused below
        if not isinstance(self.vehicle_inertia, (list, tuple)) or (inertia.size and (
                inertia.shape != (3,) or not np.all(np.isfinite(inertia))
                or np.any(inertia <= 0))):
            raise ValueError(f"{prefix}.vehicle_inertia must be empty (the model's) or 3 "
                             f"finite entries > 0 (kg m^2); got {self.vehicle_inertia!r}")
        limit = self.sigma_min_limit
        if isinstance(limit, bool) or not isinstance(limit, (int, float)) \
                or not (np.isfinite(limit) and limit > 0):
            raise ValueError(f"{prefix}.sigma_min_limit must be a finite number > 0; got "
                             f"{limit!r}")
        return self
