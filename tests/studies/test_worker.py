"""A study run's row (aerial_drake.studies.worker.run_planned): a run that fails in simulation
names its cause in ``failure_cause`` (metrics.json's), a completed one leaves it empty."""

from pydrake.common.yaml import yaml_dump_typed

from aerial_drake.simulation.scenarios import load_scenario
from aerial_drake.studies import worker as dut


def _text(**overrides):
    return yaml_dump_typed(load_scenario("nominal", overrides={"duration": 0.2, **overrides}))


def test_a_failed_runs_row_names_its_cause(monkeypatch):
    # Assumption 1's threshold raised to stop a calm run at about 0.135 s (the check of the
    # whole reference, which would refuse it before simulating, bypassed).
    monkeypatch.setattr("aerial_drake.simulation.runner.check_reference", lambda *a: None)
    row = dut.run_planned(_text(sigma_min_J3_limit=0.2))
    assert row["completed"] is False and row["failure_kind"] == "simulation"
    assert row["failure_cause"] == "other"


def test_a_completed_runs_row_has_no_cause():
    row = dut.run_planned(_text(duration=0.05))
    assert row["completed"] is True and row["failure_cause"] == ""


def test_a_run_that_cannot_be_built_has_no_cause():
    row = dut.run_planned(_text(sigma_min_J3_limit=5.0))  # refused before simulating
    assert row["failure_kind"] == "error" and row["failure_cause"] == ""
