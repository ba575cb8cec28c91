"""The end effector's orientation in an explicit convention (issue 27): ``ee_rpy`` is the
paper's R1 R2 R3 = Rx Ry Rz of (29), not Drake's RollPitchYaw; ``ee_orientation`` names the
convention (rpy_paper, rpy_drake, quaternion) and ambiguity is refused naming the field."""

import dataclasses

import numpy as np
import pytest
from pydrake.common.eigen_geometry import Quaternion
from pydrake.math import RollPitchYaw, RotationMatrix

from aerial_drake.simulation.scenarios import ScenarioError, load_scenario, shipped_scenarios
from aerial_drake.trajectories.kinds import reference_of
from aerial_drake.trajectories.orientation import (
    EeOrientation,
    drake_rpy_rotation,
    paper_angles_rotation,
    quaternion_rotation,
)
from aerial_drake.trajectories.params import HoverParams, TrajectoryParams

ANGLES = [0.3, -0.5, 1.1]  # no two zero: the conventions differ


def _rx(a):
    return RotationMatrix.MakeXRotation(a).matrix()


def test_each_convention_is_the_rotation_it_names():
    a, b, c = ANGLES
    assert np.allclose(paper_angles_rotation(ANGLES), _rx(a) @ RotationMatrix.MakeYRotation(
        b).matrix() @ RotationMatrix.MakeZRotation(c).matrix(), atol=1e-15)
    drake = RollPitchYaw(ANGLES).ToRotationMatrix().matrix()
    assert np.allclose(drake_rpy_rotation(ANGLES), drake, atol=1e-15)
    q = RollPitchYaw(ANGLES).ToQuaternion()
    assert np.allclose(quaternion_rotation([q.w(), q.x(), q.y(), q.z()]), drake, atol=1e-15)
    # The same three numbers are another rotation in the two conventions (why it is named).
    assert np.abs(paper_angles_rotation(ANGLES) - drake).max() > 0.3


def _hover_R(**fields) -> np.ndarray:
    params = TrajectoryParams(kind="hover", hover=HoverParams(**fields))
    return reference_of(params, None).evaluate(0.0).R_ed


@pytest.mark.parametrize("orientation, expected", [
    (EeOrientation(), paper_angles_rotation([0, 0, 0])),
    (EeOrientation(rpy_paper=ANGLES), paper_angles_rotation(ANGLES)),
    (EeOrientation(rpy_drake=ANGLES), RollPitchYaw(ANGLES).ToRotationMatrix().matrix()),
    (EeOrientation(quaternion=[0.5, 0.5, 0.5, 0.5]),
     RotationMatrix(Quaternion([0.5, 0.5, 0.5, 0.5])).matrix()),
])
def test_hover_flies_the_orientation_in_its_convention(orientation, expected):
    assert np.allclose(_hover_R(ee_orientation=orientation), expected, atol=1e-15)


def test_ee_rpy_stays_the_papers_convention():
    assert np.allclose(_hover_R(ee_rpy=ANGLES), paper_angles_rotation(ANGLES), atol=1e-15)


def test_waypoints_in_drake_rpy_match_the_same_rotation_in_paper_angles():
    """pick_and_place's waypoints rewritten in Drake's convention (the same rotations) give
    the same reference, derivatives included."""
    params = load_scenario("pick_and_place").trajectory
    points = []
    for w in params.waypoints.points:
        rpy = RollPitchYaw(RotationMatrix(paper_angles_rotation(w.ee_rpy))).vector()
        points.append(dataclasses.replace(w, ee_rpy=[0.0, 0.0, 0.0],
                                          ee_orientation=EeOrientation(rpy_drake=list(rpy))))
    drake = dataclasses.replace(params, waypoints=dataclasses.replace(params.waypoints,
                                                                      points=points))
    times = np.linspace(0.0, 15.0, 61)
    ours, theirs = reference_of(params, None).sample(times), reference_of(drake, None).sample(
        times)
    for field in ("R_ed", "w_ed", "dw_ed", "p_ed", "com"):
        assert np.allclose(getattr(ours, field), getattr(theirs, field), atol=1e-12), field


@pytest.mark.parametrize("orientation, words", [
    ("{rpy_drake: [0.1, 0.2, 0.3], quaternion: [1, 0, 0, 0]}",
     "gives rpy_drake and quaternion: give one convention only"),
    ("{quaternion: [1, 0, 0, 1]}", "has norm 1.41421: give a unit quaternion"),
    ("{quaternion: [1, 0, 0]}", "must be 4 finite numbers"),
    ("{rpy_drake: [0.1, 0.2]}", "must be 3 finite numbers"),
])
def test_an_ambiguous_or_bad_orientation_is_refused_naming_the_field(tmp_path, orientation,
                                                                     words):
    text = shipped_scenarios()["pick_and_place"].read_text()
    old = "ee_rpy: [0.0, 0.3, 0.0], heading: 0.0}"
    assert old in text
    path = tmp_path / "bad.yaml"
    path.write_text(text.replace(old, f"ee_orientation: {orientation}, heading: 0.0}}", 1))
    with pytest.raises(ScenarioError) as err:
        load_scenario(path)
    assert "waypoints.points[2].ee_orientation" in str(err.value)
    assert words in str(err.value), str(err.value)


def test_ee_rpy_beside_ee_orientation_is_refused(tmp_path):
    text = shipped_scenarios()["pick_and_place"].read_text()
    old = "ee_rpy: [0.0, 0.3, 0.0], heading: 0.0}"
    path = tmp_path / "both.yaml"
    path.write_text(text.replace(
        old, "ee_rpy: [0.0, 0.3, 0.0], ee_orientation: {rpy_drake: [0, 0.3, 0]}, "
        "heading: 0.0}", 1))
    with pytest.raises(ScenarioError, match=r"points\[2\].ee_rpy.*both given: remove ee_rpy"):
        load_scenario(path)


def test_a_misspelt_convention_is_refused(tmp_path):
    text = shipped_scenarios()["pick_and_place"].read_text()
    old = "ee_rpy: [0.0, 0.3, 0.0], heading: 0.0}"
    path = tmp_path / "typo.yaml"
    path.write_text(text.replace(old, "ee_orientation: {rpy: [0, 0.3, 0]}, heading: 0.0}", 1))
    with pytest.raises(ScenarioError, match="rpy"):
        load_scenario(path)
