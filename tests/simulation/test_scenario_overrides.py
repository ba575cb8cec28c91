"""Nested overrides (dotted names into the scenario's sections), the command line's KEY=VALUE
assignments, the deprecated disturbance target, and the gains' one check."""

import warnings

import pytest

import aerial_drake.simulation.scenarios.overrides as dut
from aerial_drake.control.gains import Gains
from aerial_drake.simulation.scenarios import (
    Disturbance,
    RandomDisturbances,
    ScenarioError,
    load_scenario,
    shipped_scenarios,
)


@pytest.fixture(scope="module")
def nominal():
    return load_scenario("nominal")


def test_nested_overrides_set_one_field_and_keep_the_rest(nominal):
    s = dut.apply_overrides(nominal, {
        "gains.k_R": 300, "trajectory.hover.ee_position": [0.5, 0.0, 1.0],
        "simulator.max_step_size": 2e-3, "initial.base_position_offset": (0.1, 0, 0),
        "disturbances": [{"target": "end_effector", "start": 1, "stop": 2}]})
    assert s.gains.k_R == 300.0 and isinstance(s.gains.k_R, float)
    assert s.gains.k_w == nominal.gains.k_w and s.gains.K_x == nominal.gains.K_x
    assert s.trajectory.hover.ee_position == [0.5, 0.0, 1.0]
    assert s.trajectory.center == nominal.trajectory.center
    assert s.simulator.max_step_size == 2e-3
    assert s.simulator.accuracy == nominal.simulator.accuracy
    assert s.initial.base_position_offset == [0.1, 0, 0]
    assert s.disturbances == [Disturbance(target="end_effector", start=1.0, stop=2.0)]
    # The caller's scenario is not modified.
    assert nominal.gains.k_R == 250.0 and nominal.simulator.max_step_size == 1e-3
    assert len(nominal.disturbances) == 2


def test_a_list_replaces_the_list_whole():
    s = load_scenario("pick_and_place", overrides={"trajectory.joint_targets": [0.1]})
    assert s.trajectory.joint_targets == [0.1]


def test_load_scenario_layers_the_overrides_over_the_file():
    s = load_scenario("nominal", overrides={"gains.k_R": 300, "duration": 2})
    assert (s.gains.k_R, s.duration, s.gains.k_w) == (300.0, 2.0, 200.0)


@pytest.mark.parametrize("overrides,match,field", [
    ({"gains.k_X": 1.0}, r"overrides\['gains\.k_X'\]: gains\.k_X is not a field of section "
     r"gains; its fields: K_x, D_x, k_R", "gains.k_X"),
    ({"gainz.k_R": 1.0}, r"gainz is not a field of the scenario; its fields: name", "gainz"),
    ({"gains.k_R": "stiff"}, r"overrides\['gains\.k_R'\]: expected a number, got 'stiff' "
     r"\(e\.g\. gains\.k_R=300", "gains.k_R"),
    ({"gains.k_R": [1.0, 2.0]}, r"overrides\['gains\.k_R'\]: expected a number, got "
     r"\[1\.0, 2\.0\]", "gains.k_R"),
    ({"gains.k_R": True}, r"expected a number, got true", "gains.k_R"),
    ({"gains.K_x": 800.0}, r"overrides\['gains\.K_x'\]: expected a list \(it replaces the "
     r"whole list\), got 800\.0", "gains.K_x"),
    ({"gains.K_x": [1.0, "a"]}, r"gains\.K_x\[1\]: expected a number, got 'a'", "gains.K_x[1]"),
    ({"duration.x": 1.0}, r"overrides\['duration\.x'\]: duration is a value, not a section",
     "duration"),
    ({"trajectory.hover": 1.0}, r"expected a HoverParams \(or set its fields one by one: "
     r"'trajectory\.hover\.<field>'\)", "trajectory.hover"),
    ({"name": 3}, r"overrides\['name'\]: expected text, got 3", "name"),
    ({"wind.seed": 1.5}, r"overrides\['wind\.seed'\]: expected an integer, got 1\.5",
     "wind.seed"),
    ({"disturbances": [{"targt": "vehicle"}]}, r"disturbances\[0\]\.targt \(not a field",
     "disturbances[0].targt"),
    ({"gains..k_R": 1.0}, r"not a field's dotted name", None),
])
def test_bad_overrides_name_the_dotted_field_and_the_fix(nominal, overrides, match, field):
    with pytest.raises(ScenarioError, match=match) as err:
        dut.apply_overrides(nominal, overrides)
    assert err.value.field == field


def test_an_overridden_value_is_validated_with_the_file_named():
    with pytest.raises(ScenarioError, match=r"nominal\.yaml: gains\.k_R must be finite, > 0 "
                       r"and <= 1e\+06; got -1\.0") as err:
        load_scenario("nominal", overrides={"gains.k_R": -1})
    assert err.value.field == "gains.k_R"


def test_assignments_read_yaml_values():
    got = dut.parse_assignments(["gains.k_R=300", "initial.base_position_offset=[0.1,0,0]",
                                 "simulator.integration_scheme = runge_kutta3",
                                 "wind.enabled=true", "name=my run", "duration=1e3"])
    assert got == {"gains.k_R": 300, "initial.base_position_offset": [0.1, 0, 0],
                   "simulator.integration_scheme": "runge_kutta3", "wind.enabled": True,
                   "name": "my run", "duration": "1e3"}
    s = load_scenario("nominal", overrides=dut.parse_assignments(
        ["gains.k_R=300", "initial.base_position_offset=[0.1,0,0]", "duration=2e0"]))
    assert (s.gains.k_R, s.initial.base_position_offset, s.duration) == (
        300.0, [0.1, 0.0, 0.0], 2.0)


@pytest.mark.parametrize("text,match", [
    ("gains.k_R", r"--set 'gains\.k_R': expected KEY=VALUE \(e\.g\. gains\.k_R=300"),
    ("=300", r"--set '=300': '' is not a field's dotted name"),
    ("gains k_R=300", r"--set 'gains k_R=300': 'gains k_R' is not a field's dotted name"),
    ("gains.k_R=", r"--set 'gains\.k_R=': no value after '='"),
    ("gains.K_x=[1, 2", r"--set 'gains\.K_x=\[1, 2': the value '\[1, 2' is not YAML"),
])
def test_bad_assignments_name_the_text(text, match):
    with pytest.raises(ScenarioError, match=match):
        dut.parse_assignments([text])


def test_an_assignment_given_twice_is_refused():
    with pytest.raises(ScenarioError, match=r"gains\.k_R is set twice"):
        dut.parse_assignments(["gains.k_R=1", "gains.k_R=2"])


def test_the_earlier_target_name_reads_as_vehicle_with_one_warning(tmp_path):
    path = tmp_path / "old.yaml"
    text = shipped_scenarios()["nominal"].read_text()
    assert text.count("target: vehicle") == 1
    path.write_text(text.replace("target: vehicle", "target: helicopter"))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("default")  # what a user sees: each warning once per location
        first = load_scenario(path)
        again = load_scenario(path)
    assert first.disturbances[0].target == again.disturbances[0].target == "vehicle"
    messages = [str(w.message) for w in caught if w.category is FutureWarning]
    assert messages == [f"{path}: disturbances[0].target: 'helicopter' is deprecated and "
                        "reads as 'vehicle' (the same frame, renamed for any vehicle): write "
                        "'vehicle'"]


def test_the_earlier_target_name_in_python_and_its_refusal_after_construction(nominal):
    with pytest.warns(FutureWarning, match=r"Disturbance\.target: 'helicopter' is deprecated"):
        assert Disturbance(target="helicopter").target == "vehicle"
    with pytest.warns(FutureWarning, match=r"RandomDisturbances\.target: 'helicopter'"):
        assert RandomDisturbances(target="helicopter").target == "vehicle"
    s = dut.apply_overrides(nominal, {})
    s.disturbances[0].target = "helicopter"
    with pytest.raises(ScenarioError, match=r"disturbances\[0\]\.target: 'helicopter' is the "
                       r"earlier name of 'vehicle': write target: vehicle"):
        s.validate()


def test_the_gains_are_checked_once_with_one_rule_set(monkeypatch):
    calls = []
    validate = Gains.validate

    def counted(self, *args, **kwargs):
        calls.append(args)
        return validate(self, *args, **kwargs)

    monkeypatch.setattr(Gains, "validate", counted)
    load_scenario("nominal")
    assert len(calls) == 1
    with pytest.raises(ScenarioError) as err:
        load_scenario("nominal", overrides={"gains.k_R": 2e6})
    assert err.value.field == "gains.k_R"
    message = str(err.value)
    assert message.count("gains.k_R") == 1 and "got 2000000.0" in message
    assert "> 0 and <= 1e+06" in message
