"""A waypoints section's given velocities (com_velocity, heading_rate, joint_velocities) and
its mode are refused when wrong, each message naming the field with its waypoint's index,
the value and the fix; a velocity at the first or last waypoint must be zero (issue 28)."""

import dataclasses
import math

import pytest

from aerial_drake.simulation.scenarios import ScenarioError, load_scenario, shipped_scenarios
from aerial_drake.trajectories.params import Waypoint, WaypointsParams


def _section(com="waypoints", heading="given", mode="through", **middle):
    """Three waypoints, the middle one with ``middle``'s fields."""
    def point(t, **extra):
        fields = dict(time=t, ee_position=[0.6 + 0.1 * t, 0.0, 1.0], joints=[0.1 * t])
        if com == "waypoints":
            fields["com"] = [0.3 + 0.1 * t, 0.0, 1.6]
        if heading == "given":
            fields["heading"] = 0.2 * t
        return Waypoint(**{**fields, **extra})
    return WaypointsParams(points=[point(0.0), point(1.0, **middle), point(2.0)], com=com,
                           heading=heading, mode=mode)


def _only_error(section, n_joints=1):
    errors = section.errors(n_joints)
    assert len(errors) == 1, errors
    return errors[0]


def test_a_valid_section_with_every_given_velocity_has_no_error():
    section = _section(com_velocity=[0.1, 0.0, 0.0], heading_rate=0.2, joint_velocities=[0.1],
                       ee_velocity=[0.1, 0.0, 0.0], ee_angular_velocity=[0.0, 0.0, 0.2])
    assert section.errors(1) == []
    assert dataclasses.replace(section, mode="stop").errors(1) == []


@pytest.mark.parametrize("section, words", [
    (_section(mode="smooth"), ["'waypoints.mode' must be one of ('stop', 'through')",
                               "'smooth'"]),
    (_section(com_velocity=[0.1, 0.0]),
     ["'waypoints.points[1].com_velocity' must be a list of 3 floats", "[0.1, 0.0]"]),
    (_section(com_velocity=[0.1, math.inf, 0.0]),
     ["'waypoints.points[1].com_velocity' must hold finite numbers", "inf"]),
    (_section(com="offset", com_velocity=[0.1, 0.0, 0.0]),
     ["'waypoints.points[1].com_velocity' is set but the CoM follows rule (33)",
      "set com: waypoints, or remove it"]),
    (_section(heading_rate=math.inf),
     ["'waypoints.points[1].heading_rate' must be a finite rate (rad/s), got inf"]),
    (_section(heading="along_path", heading_rate=0.3),
     ["'waypoints.points[1].heading_rate' = 0.3 is set but heading is 'along_path'",
      "set heading: given"]),
    (_section(joint_velocities=[0.1, 0.2]),
     ["'waypoints.points[1].joint_velocities' must be a list of 1 floats", "[0.1, 0.2]"]),
    (_section(joint_velocities=[math.nan]),
     ["'waypoints.points[1].joint_velocities' must hold finite numbers", "nan"]),
])
def test_a_bad_given_velocity_or_mode_is_named_with_its_value_and_fix(section, words):
    message = _only_error(section)
    for word in words:
        assert word in message, message


def test_joint_velocities_without_joints_is_named():
    section = _section(joint_velocities=[0.1])
    points = [dataclasses.replace(w, joints=[]) for w in section.points]
    points[1] = dataclasses.replace(points[1], joint_velocities=[0.1])
    message = _only_error(dataclasses.replace(section, points=points))
    assert "'waypoints.points[1].joint_velocities' is set but 'waypoints.points[1].joints' " \
           "is not" in message, message


@pytest.mark.parametrize("end", [0, 2])
@pytest.mark.parametrize("field, value", [("com_velocity", [0.0, 0.1, 0.0]),
                                          ("heading_rate", 0.25),
                                          ("joint_velocities", [-0.2]),
                                          ("ee_velocity", [0.1, 0.0, 0.0])])
def test_a_velocity_at_the_first_or_last_waypoint_must_be_zero(end, field, value):
    section = _section()
    points = list(section.points)
    points[end] = dataclasses.replace(points[end], **{field: value})
    message = _only_error(dataclasses.replace(section, points=points))
    assert f"'waypoints.points[{end}].{field}' = {value!r} must be zero" in message, message
    assert "holds still before the first and after the last waypoint" in message
    zero = 0.0 if field == "heading_rate" else [0.0] * len(value)
    points[end] = dataclasses.replace(points[end], **{field: zero})
    assert dataclasses.replace(section, points=points).errors(1) == []


def test_a_bad_given_velocity_in_a_scenario_is_refused_at_load_naming_the_field(tmp_path):
    text = shipped_scenarios()["pick_and_place"].read_text()
    old = "ee_rpy: [0.0, 0.0, 1.5708], heading: 1.5708}\n      # descend"
    assert old in text
    path = tmp_path / "bad.yaml"
    path.write_text(text.replace(old, old.replace("heading: 1.5708}",
                                                  "heading: 1.5708, heading_rate: .inf}"), 1))
    with pytest.raises(ScenarioError) as err:
        load_scenario(path)
    assert err.value.field == "trajectory.waypoints.points[5].heading_rate", str(err.value)
    assert "finite rate" in str(err.value) and str(path) in str(err.value)
