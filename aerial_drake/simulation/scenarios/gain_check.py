"""The scenario's gain design check at load: the CoM and attitude loops' roots on the
scenario's robot (:mod:`aerial_drake.control.gain_design`), and a
:class:`~aerial_drake.control.gain_design.GainDesignWarning` naming them when the attitude
loop is not at least 3x faster than the CoM loop (docs/control.md, "Gain design help").

A warning, not an error: Table II's own gains fail it, and the paper's run must still run.
Python shows a warning once per message, so a scenario validated twice (at load and at
the run) or run many times in a study says it once per process.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from aerial_drake.control.baselines.params import BASELINE_TYPES
from aerial_drake.control.gain_design import LoopRoots, warn_if_slow
from aerial_drake.control.registry import PAPER_CONTROLLER

#: The controller types whose attitude loop is the paper's (16), ``gains.Lambda2_bar`` its
#: inertia. Other registered types are not checked (their attitude loop is their own).
LAW_16_TYPES = (PAPER_CONTROLLER, "paper_plus")


def attitude_inertia(s: Any) -> tuple[np.ndarray, str] | None:
    """The inertia per attitude axis that scenario ``s``'s attitude law assumes, and where it
    comes from; None where it is not known at load: a controller type whose attitude loop
    is its own, or a baseline's default inertia, the robot locked at its start, which needs
    the run's reference (checked where the registry builds the baseline,
    :mod:`aerial_drake.control.registry`)."""
    if s.controller.type in LAW_16_TYPES:
        return np.asarray(s.gains.Lambda2_bar, float), "(gains.Lambda2_bar, by (16))"
    given = s.controller.baseline.vehicle_inertia
    if s.controller.type in BASELINE_TYPES and given:
        return np.asarray(given, float), "(controller.baseline.vehicle_inertia)"
    return None


def warn_gain_design(s: Any, mass: float) -> LoopRoots | None:
    """Warn (:class:`GainDesignWarning`) when scenario ``s``'s attitude loop is too slow
    against its CoM loop on a robot of total ``mass``; returns the roots (None where the
    inertia is not known at load, :func:`attitude_inertia`)."""
    found = attitude_inertia(s)
    if found is None:
        return None
    return warn_if_slow(mass, s.gains, *found, stacklevel=4)
