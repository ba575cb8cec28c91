"""Back-compatible names for the controller registry, which lives in the control layer now
(:mod:`aerial_drake.control.registry`: registering a controller needs no simulation), and for
:func:`~aerial_drake.control.reference_pose.body_offset_in_heading_frame`. Kept while code
written against ``aerial_drake.simulation.controllers`` (scripts, the scenario schema) moves
to those modules; new code imports from them.
"""

from aerial_drake.control.reference_pose import body_offset_in_heading_frame
from aerial_drake.control.registry import (
    PAPER_CONTROLLER,
    ControllerFactory,
    controller_factory,
    controller_types,
    make_controller_system,
    register_controller,
    zero_controller,
)

__all__ = ["PAPER_CONTROLLER", "ControllerFactory", "body_offset_in_heading_frame",
           "controller_factory", "controller_types", "make_controller_system",
           "register_controller", "zero_controller"]
