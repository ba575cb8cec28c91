"""The scenario fields set from the command line, collected in one place
(aerial_drake.cli.overrides), as each command parses them."""

from aerial_drake.cli import build_parser
from aerial_drake.cli import overrides as dut
from aerial_drake.simulation.scenarios import ScenarioError


def test_run_options_become_scenario_fields():
    args = build_parser().parse_args(["run", "nominal", "--duration", "2", "--max-log-mb", "5"])
    assert dut.scenario_overrides(args) == {"duration": 2.0, "max_log_mb": 5.0}
    assert dut.scenario_overrides(build_parser().parse_args(["run", "nominal"])) == {}


def test_a_command_without_an_option_sets_nothing_for_it():
    args = build_parser().parse_args(["compare", "nominal", "--duration", "0.5"])
    assert not hasattr(args, "max_log_mb")
    assert dut.scenario_overrides(args) == {"duration": 0.5}


def test_an_error_names_the_option_that_set_its_field():
    overrides = {"max_log_mb": -1.0}
    note = dut.option_note(ScenarioError("bad", "max_log_mb"), overrides)
    assert note == " (set by --max-log-mb)"
    assert dut.option_note(ScenarioError("bad", "duration"), overrides) == ""
    assert dut.option_note(ValueError("no field"), overrides) == ""


def test_set_gives_nested_fields_read_as_yaml():
    args = build_parser().parse_args(
        ["run", "nominal", "--set", "gains.k_R=300", "--set",
         "initial.base_position_offset=[0.1, 0, 0]", "--duration", "1"])
    assert dut.scenario_overrides(args) == {
        "gains.k_R": 300, "initial.base_position_offset": [0.1, 0, 0], "duration": 1.0}
    args = build_parser().parse_args(["compare", "nominal", "--set", "controller_period=0.002"])
    assert dut.scenario_overrides(args) == {"controller_period": 0.002}


def test_a_field_set_twice_or_a_bad_assignment_is_refused():
    args = build_parser().parse_args(["run", "nominal", "--duration", "2", "--set",
                                      "duration=3"])
    try:
        dut.scenario_overrides(args)
    except ScenarioError as err:
        assert "--duration" in str(err) and "--set duration" in str(err)
    else:
        raise AssertionError("a field set twice was accepted")
    args = build_parser().parse_args(["run", "nominal", "--set", "gains.k_R"])
    try:
        dut.scenario_overrides(args)
    except ScenarioError as err:
        assert "KEY=VALUE" in str(err)
    else:
        raise AssertionError("an assignment without '=' was accepted")


def test_an_error_names_set_when_set_gave_the_field():
    args = build_parser().parse_args(["run", "nominal", "--set", "duration=-1"])
    overrides = dut.scenario_overrides(args)
    assert dut.option_note(ScenarioError("bad", "duration"), overrides, args) == \
        " (set by --set)"


def test_run_with_a_bad_set_value_exits_2_naming_the_field(capsys):
    from aerial_drake.cli import main
    status = main(["run", "nominal", "--set", "gains.k_R=-5", "--no-plots", "--quiet",
                   "--out", "/nonexistent-never-written"])
    err = capsys.readouterr().err
    assert status == 2, err
    assert "gains.k_R" in err and "-5" in err and "(set by --set)" in err


def test_a_set_field_reaches_the_scenario():
    from aerial_drake.simulation.scenarios import load_scenario
    args = build_parser().parse_args(["run", "nominal", "--set", "gains.k_R=300",
                                      "--set", "trajectory.com_offset=[-0.3, 0.0, 0.6]"])
    scenario = load_scenario("nominal", overrides=dut.scenario_overrides(args))
    assert scenario.gains.k_R == 300.0
    assert list(scenario.trajectory.com_offset) == [-0.3, 0.0, 0.6]
