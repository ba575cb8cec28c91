"""From a model file to a flying scenario (docs/robots.md, "From a URDF to a flying scenario"):
``robot init`` (:func:`init_robot`: the vehicle, the arm and the end effector found, a nominal
posture, the CoM offset, the locked inertia, input limits and gains, written as a robot
description and a hover scenario) and ``robot check`` (:func:`check_robot`: the margins at the
nominal posture, :func:`format_check` its text, :class:`RobotCheck` the report)."""

from aerial_drake.analysis.onboarding.check import RobotCheck, check_robot
from aerial_drake.analysis.onboarding.check_text import format_check
from aerial_drake.analysis.onboarding.errors import OnboardingError
from aerial_drake.analysis.onboarding.init import InitOptions, InitResult, format_init, init_robot

__all__ = ["InitOptions", "InitResult", "OnboardingError", "RobotCheck", "check_robot",
           "format_check", "format_init", "init_robot"]
