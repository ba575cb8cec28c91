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
