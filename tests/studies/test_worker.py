"""A study run's row (aerial_drake.studies.worker.run_planned): a run that fails in simulation
names its cause in ``failure_cause`` (metrics.json's), a completed one leaves it empty; a
worker on a cold numba cache compiles in a child process (ensure_warm)."""

import contextlib

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


def test_a_cold_worker_compiles_in_a_child_then_loads(monkeypatch):
    # The worker process must not keep the compile's memory: the compile goes to a child
    # process (compile_in_child), then the worker loads the cache (compile_kernels); warm,
    # it only loads. Both under the cache's lock.
    calls = []
    cold = {"now": True}

    def compile_in_child():
        calls.append("child")
        cold["now"] = False

    @contextlib.contextmanager
    def compile_lock():
        calls.append("lock")
        yield True

    monkeypatch.setattr(dut, "kernels_cache_is_cold", lambda: cold["now"])
    monkeypatch.setattr(dut, "compile_in_child", compile_in_child)
    monkeypatch.setattr(dut, "compile_kernels", lambda: calls.append("load"))
    monkeypatch.setattr(dut, "compile_lock", compile_lock)
    monkeypatch.setattr(dut, "_warm", [])
    dut.ensure_warm()
    dut.ensure_warm()  # once per process
    assert calls == ["lock", "child", "load"]
    monkeypatch.setattr(dut, "_warm", [])
    dut.ensure_warm()  # a warm cache: loaded only
    assert calls[3:] == ["lock", "load"]
