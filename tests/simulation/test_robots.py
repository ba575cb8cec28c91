"""Every shipped robot: its description builds and its scenarios validate; the second robot's
scenario converges without disturbances and re-converges after each window (docs/robots.md)."""

import numpy as np
import pytest

from aerial_drake.control.law import diagnostics_slices
from aerial_drake.robots.description import load_robot_description, shipped_robots
from aerial_drake.robots.models import make_plant
from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import load_scenario, shipped_scenarios


@pytest.mark.parametrize("name", sorted(shipped_robots()))
def test_every_shipped_robot_builds_in_every_variant(name):
    robot = load_robot_description(name)
    for variant in robot.variant_names():
        model = make_plant(variant, robot=robot)
        assert model.task is not None and model.task.n == model.n
        assert model.plant.num_velocities() == 6 + model.n + len(model.rotor_joints)


def test_every_shipped_robot_has_a_shipped_scenario():
    flown = {load_scenario(name).robot for name in shipped_scenarios()}
    assert flown == set(shipped_robots())


@pytest.fixture(scope="module")
def quadrotor_run():
    result = run_scenario(load_scenario("quadrotor_ur3e"), progress=False)
    assert result.completed, result.failure
    return result


@pytest.mark.parametrize("start, stop", [(3.0, 4.0), (8.0, 9.0), (14.0, 15.0)])
def test_the_quadrotor_ur3e_converges_and_reconverges_after_its_windows(
        quadrotor_run, start, stop):
    """Before the 4-5 s force, after it and after the 9-10 s wrench: below 1 mm, 1 mrad."""
    log = quadrotor_run.log
    d, t = log["diagnostics"], log["t"]
    sl = diagnostics_slices(6)
    window = (t >= start) & (t <= stop)
    assert d[window, sl["ee_position_error"]].max() < 1e-3
    assert d[window, sl["ee_orientation_error"]].max() < 1e-3


def test_the_quadrotor_ur3e_decouples_the_end_effector_from_a_force_on_the_vehicle(
        quadrotor_run):
    """The paper's claim on another robot: the 4-5 s force moves the CoM by over 100 mm and
    the end effector by under 1 mm."""
    response = quadrotor_run.metrics["disturbance_response"][0]
    assert response["com_error_peak_m"] > 0.1
    assert response["ee_position_error_peak_m"] < 1e-3
    assert response["ee_to_com_peak_ratio"] < 0.01
    assert quadrotor_run.log["command"].shape[1] == 4 + 6
    assert np.isfinite(quadrotor_run.log["diagnostics"]).all()
