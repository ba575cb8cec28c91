"""dynamics/equilibrium.py: a configuration solve leaves nothing behind (a study's arm-hold
bound solves dozens of postures per run, in one worker process run after run)."""

import gc

from aerial_drake.control.reference_pose import reference_configuration
from aerial_drake.simulation.scenarios import load_scenario


def _programs() -> int:
    gc.collect()
    return sum(type(o).__name__ in ("InverseKinematics", "MathematicalProgram",
                                    "ComPositionConstraint") for o in gc.get_objects())


def test_a_solve_leaves_no_program_behind():
    # With the CoM constraint on the InverseKinematics' own context, each solve left its
    # program alive (one object per solve on drake 1.51.1, two on 1.58; about 70 KB).
    scenario = load_scenario("nominal")
    model = scenario.controller_model()
    reference_configuration(scenario, model, 0.0)
    before = _programs()
    for k in range(5):
        reference_configuration(scenario, model, 0.01 * k)
    assert _programs() == before
