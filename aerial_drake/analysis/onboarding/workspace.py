"""The workspace radius ``robot init`` writes: :data:`REACH_SHARE` of the smallest reach of the
end effector from the nominal posture along the six heading-frame directions, the CoM, the
base attitude and the end effector's orientation held (:func:`.reach.reach`, what
``robot check`` prints). The description's ``workspace_radius`` is how far a scenario's desired
end effector may stray from its nominal offset to the desired CoM before the scenario is
refused as out of reach: a sphere inside the reach in every direction, with a margin."""

from __future__ import annotations

import math
from pathlib import Path

from aerial_drake.analysis.onboarding.check_subject import load_subject
from aerial_drake.analysis.onboarding.reach import Reach, reach

#: The share of the smallest reach written as the workspace radius.
REACH_SHARE = 0.8


def reach_radius(scenario: Path) -> tuple[float, list[Reach]]:
    """The radius (m, rounded down to three significant figures) for the robot of the
    ``scenario`` file (its hover at the nominal posture), and the reaches it comes from."""
    reaches = reach(load_subject(scenario))
    smallest = min(r.distance for r in reaches)
    if not smallest > 0:
        return 0.0, reaches
    scale = 10.0 ** (math.floor(math.log10(REACH_SHARE * smallest)) - 2)
    return math.floor(REACH_SHARE * smallest / scale) * scale, reaches
