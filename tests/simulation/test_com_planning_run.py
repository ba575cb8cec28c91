"""trajectory.com_planning in a run: the run's one reference is the planned one (the
generator, the logs and the checks read it), and its margins reach metrics.json and the
printed summary."""

import numpy as np

from aerial_drake.simulation import runner
from aerial_drake.simulation.scenarios import load_scenario
from aerial_drake.studies.summary import format_summary
from aerial_drake.trajectories.com_planning import PlannedComReference


def test_a_run_flies_the_planned_com_reference_and_reports_its_margin():
    scenario = load_scenario("nominal", overrides={
        "duration": 0.3, "trajectory.com_planning.enabled": True})
    seen = []
    result = runner.run_scenario(scenario, progress=False,
                                 configure=lambda builder, loop: seen.append(loop))
    assert result.completed
    source = seen[0].reference.source
    assert isinstance(source, PlannedComReference)
    # The logged CoM reference is the planned one, to the bit, and not the kind's.
    com = source.sample(result.log["t"]).to_vectors()[0]
    np.testing.assert_array_equal(result.log["com_reference"], com)
    kind = source.source.sample(result.log["t"]).to_vectors()[0]
    assert np.abs(com - kind).max() > 1e-3
    assert result.metrics["com_planning"] == source.report.as_dict()
    assert "x_d planned with margin" in format_summary(result.metrics)
