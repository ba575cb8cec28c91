"""A run builds its reference once and every reader shares it (issue 26): the generator, the
checks before the run, the start posture, the baselines' body offset and the logs read the
object :func:`~aerial_drake.simulation.diagram.add_closed_loop` built, and its parameters are
checked once per build."""

import dataclasses

import numpy as np
import pytest

from aerial_drake.simulation import runner
from aerial_drake.simulation.scenarios import load_scenario
from aerial_drake.simulation.scenarios import trajectory as scenario_trajectory
from aerial_drake.trajectories import kinds
from aerial_drake.trajectories.params import TrajectoryParams

DURATION = 0.1


class BuildCounter:
    """Counts the reference's builds (through the registry), the builds of the scenario's
    load-time check, and the checks of the section's shared fields, and keeps what was
    built."""

    def __init__(self, monkeypatch, kind: str):
        self.builds, self.load_checks, self.errors = [], 0, 0
        entry = kinds.REFERENCE_KINDS[kind]
        errors, check_build = TrajectoryParams.errors, scenario_trajectory.reference_of

        def build(params, targets):
            self.builds.append(entry.build(params, targets))
            return self.builds[-1]

        def count_errors(params):
            self.errors += 1
            return errors(params)

        def count_check(params, joint_defaults=None):
            self.load_checks += 1
            return check_build(params, joint_defaults)

        monkeypatch.setitem(kinds.REFERENCE_KINDS, kind, dataclasses.replace(entry, build=build))
        monkeypatch.setattr(TrajectoryParams, "errors", count_errors)
        monkeypatch.setattr(scenario_trajectory, "reference_of", count_check)


@pytest.mark.parametrize("controller", ["paper", "uncoupled"])
def test_a_run_builds_its_reference_once_and_checks_it_once_per_build(monkeypatch, controller):
    scenario = load_scenario("nominal", overrides={"duration": DURATION})
    scenario = dataclasses.replace(scenario, controller=dataclasses.replace(
        scenario.controller, type=controller))
    counter = BuildCounter(monkeypatch, "paper")
    seen = []
    result = runner.run_scenario(scenario, progress=False,
                                 configure=lambda builder, loop: seen.append(loop))
    # run_scenario validates the scenario again (its load-time check builds one to test it);
    # the run itself builds one, the generator's, and every reader of the run uses it.
    assert counter.load_checks == 1
    assert len(counter.builds) == 2
    assert seen[0].reference.source is counter.builds[1]
    assert counter.errors == len(counter.builds)
    # The logged references are that source's values at the log's times, to the bit.
    com, task, heading = counter.builds[1].sample(result.log["t"]).to_vectors()
    np.testing.assert_array_equal(result.log["com_reference"], com)
    np.testing.assert_array_equal(result.log["task_reference"], task)
    np.testing.assert_array_equal(result.log["heading_reference"], heading)

