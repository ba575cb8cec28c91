"""Scenario files mean the same run on every supported Drake release (drake_compat)."""

import dataclasses

import pytest
from pydrake.common.yaml import yaml_load_data

from aerial_drake import drake_compat as dut
from aerial_drake.simulation.scenarios import ScenarioError, load_scenario, shipped_scenarios


def _with_simulator_line(tmp_path, line: str):
    """The shipped nominal scenario with one more line in its ``simulator:`` section."""
    text = shipped_scenarios()["nominal"].read_text()
    assert "\nsimulator:\n" in text
    path = tmp_path / "user.yaml"
    path.write_text(text.replace("\nsimulator:\n", f"\nsimulator:\n  {line}\n"))
    return path


@pytest.mark.parametrize("name", sorted(shipped_scenarios()))
def test_shipped_scenarios_use_no_field_some_release_lacks(name):
    data = yaml_load_data(shipped_scenarios()[name].read_text())
    present = set(data.get("simulator", {})) & set(dut._REMOVED_SIMULATOR_FIELDS)
    assert not present, f"{name}.yaml writes {present}, which some Drake release lacks"


def test_user_file_with_the_old_default_loads_as_without_it(tmp_path):
    path = _with_simulator_line(tmp_path, "publish_every_time_step: false")
    loaded = load_scenario(path)
    plain = load_scenario("nominal")
    assert repr(loaded.simulator) == repr(plain.simulator)
    # Compared by repr: the unset limits are NaN, and since Python 3.13 a dataclass's
    # __eq__ compares field by field, where nan != nan (3.12 and earlier compared tuples,
    # whose identity shortcut made the shared NaN default equal to itself).
    assert repr(dataclasses.replace(loaded, simulator=plain.simulator)) == \
        repr(dataclasses.replace(plain, simulator=plain.simulator))


@pytest.mark.parametrize("value", ["true", "'no'", "1"])
def test_user_file_asking_per_step_publishing_says_remove_the_field(tmp_path, value):
    path = _with_simulator_line(tmp_path, f"publish_every_time_step: {value}")
    with pytest.raises(ScenarioError) as err:
        load_scenario(path)
    message = str(err.value)
    assert str(path) in message
    assert "simulator.publish_every_time_step" in message
    assert "Remove the field" in message
    assert "1.58.0" in message


def test_other_unknown_simulator_fields_still_fail_by_name(tmp_path):
    path = _with_simulator_line(tmp_path, "publish_every_tme_step: false")
    with pytest.raises(ScenarioError, match="publish_every_tme_step"):
        load_scenario(path)


def test_translation_leaves_other_fields_alone():
    section = {"publish_every_time_step": False, "accuracy": 1e-6}
    assert dut.translate_simulator_section(section, "simulator")
    assert section == {"accuracy": 1e-6}
    assert not dut.translate_simulator_section(section, "simulator")
    assert not dut.translate_simulator_section(None, "simulator")
