"""The scenario's gain design check at load: the CoM and attitude loops' roots on the
scenario's robot (:mod:`aerial_drake.control.gain_design`), and a
:class:`~aerial_drake.control.gain_design.GainDesignWarning` naming them when the attitude
loop is not at least 3x faster than the CoM loop (docs/control.md, "Gain design help").

A warning, not an error: Table II's own gains fail it, and the paper's run must still run.
Python shows a warning once per message, so a scenario validated twice (at load and at
the run) or run many times in a study says it once per process.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from aerial_drake.control.baselines.params import BASELINE_TYPES
from aerial_drake.control.gain_design import (
    GainDesignWarning,
    LoopRoots,
    gain_design_message,
    loop_roots,
)
from aerial_drake.control.registry import PAPER_CONTROLLER

#: The controller types whose attitude loop is the paper's (16), ``gains.Lambda2_bar`` its
#: inertia. Other registered types are not checked (their attitude loop is their own).
LAW_16_TYPES = (PAPER_CONTROLLER, "paper_plus")


def scenario_loop_roots(s: Any, mass: float) -> tuple[LoopRoots, str] | None:
    """The loops' roots of scenario ``s`` (validated gains) on a robot of total ``mass`` (kg),
    and where the attitude inertia comes from; None for a controller type whose attitude
    loop is not known here."""
    g, kind = s.gains, s.controller.type
    if kind in LAW_16_TYPES:
        inertia, source = np.asarray(g.Lambda2_bar, float), "(gains.Lambda2_bar, by (16))"
    elif kind in BASELINE_TYPES:
        found = _baseline_inertia(s)
        if found is None:
            return None
        inertia, source = found
    else:
        return None
    return loop_roots(mass, g.K_x, g.D_x, g.k_R, g.k_w, inertia), source


def _baseline_inertia(s: Any) -> tuple[np.ndarray, str] | None:
    """The principal moments of the inertia the baselines' vehicle law assumes, when given
    (``controller.baseline.vehicle_inertia``); None for the default, the robot locked at its
    start, which needs the run's reference: checked where the registry builds the
    baseline (:mod:`aerial_drake.control.registry`)."""
    given = s.controller.baseline.vehicle_inertia
    if given:
        return np.asarray(given, float), "(controller.baseline.vehicle_inertia)"
    return None


def warn_gain_design(s: Any, mass: float) -> LoopRoots | None:
    """Warn (:class:`GainDesignWarning`) when scenario ``s``'s attitude loop is too slow
    against its CoM loop on a robot of total ``mass``; returns the roots (None where the
    controller type is not checked)."""
    found = scenario_loop_roots(s, mass)
    if found is None:
        return None
    roots, source = found
    message = gain_design_message(roots, source)
    if message is not None:
        warnings.warn(message, GainDesignWarning, stacklevel=2)
    return roots
