"""The shipped studies' base scenario (disturbed_within_limits.yaml): the paper's disturbed
case with only the documented trajectory fields and the joint-limit mode changed."""

import dataclasses

from pydrake.common.yaml import yaml_dump_typed

from aerial_drake.simulation.scenarios import load_scenario
from aerial_drake.studies.spec import load_study

SHIPPED_STUDIES = ("robustness", "directions", "directions_plus", "gains", "gains_attitude",
                   "robustness_plus", "gains_plus", "gains_attitude_plus")


def test_study_base_differs_from_disturbed_only_where_documented():
    disturbed = load_scenario("disturbed")
    base = load_scenario("disturbed_within_limits")
    assert base.trajectory.heading_rate == 0.0 and disturbed.trajectory.heading_rate == 0.5
    assert base.trajectory.agile_amplitude == 0.07
    assert list(base.trajectory.orientation_amplitudes) == [0.2, 0.2, 0.2]
    assert list(base.trajectory.com_offset) == [-0.3, 0.0, 0.62]
    assert base.joint_limits.positions == "stop"
    assert disturbed.joint_limits.positions == "report"
    trajectory = dataclasses.replace(
        base.trajectory, heading_rate=disturbed.trajectory.heading_rate,
        agile_amplitude=disturbed.trajectory.agile_amplitude,
        orientation_amplitudes=disturbed.trajectory.orientation_amplitudes,
        com_offset=disturbed.trajectory.com_offset)
    same = dataclasses.replace(base, name=disturbed.name, description=disturbed.description,
                               trajectory=trajectory, joint_limits=disturbed.joint_limits)
    assert yaml_dump_typed(same) == yaml_dump_typed(disturbed)


def test_shipped_studies_run_on_the_base_within_limits():
    for name in SHIPPED_STUDIES:
        loaded = load_study(name)
        assert loaded.study.base == "disturbed_within_limits", name
        assert loaded.base.joint_limits.positions == "stop", name
