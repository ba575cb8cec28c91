"""From a model file to a flying scenario (docs/robots.md, "From a URDF to a flying scenario"):
``robot init`` (:func:`init_robot`: the vehicle, the arm and the end effector found, a nominal
posture, the CoM offset, the locked inertia, input limits and gains, written as a robot
description and a hover scenario) and ``robot check`` (:func:`check_robot`: the margins at the
nominal posture)."""

from aerial_drake.analysis.onboarding.errors import OnboardingError
from aerial_drake.analysis.onboarding.init import InitOptions, InitResult, format_init, init_robot

__all__ = ["InitOptions", "InitResult", "OnboardingError", "format_init", "init_robot"]
