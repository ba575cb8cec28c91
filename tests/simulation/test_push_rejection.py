"""Push rejection (issue 32, item 1): the wrench observer's vehicle force estimate fed forward
into paper_plus's CoM law (simulation/diagram.py wires it when ``observer.enabled``), against
the paper's law under the same push; the paper's law untouched by the observer; the
feed-forward without the observer refused."""

import dataclasses

import numpy as np
import pytest

from aerial_drake.control.plus import PlusParams
from aerial_drake.simulation.runner import SimulationFailed, run_scenario
from aerial_drake.simulation.scenarios import ScenarioError, load_scenario
from aerial_drake.simulation.scenarios.schema import Disturbance, Observer
from aerial_drake.simulation.tracking import entries
from aerial_drake.trajectories.params import TrajectoryParams

R = dataclasses.replace
PUSH = [0.0, 50.0, 0.0]  # N, World, on the vehicle over 0.2-1.2 s
WINDOW = (0.2, 1.2)


def _hover(duration: float):
    """The nominal plant (rigid, no lag) hovering at rest on its reference, a 50 N push on
    the vehicle for 1 s."""
    base = load_scenario("nominal")
    initial = R(base.initial, base_position_offset=[0.0] * 3, base_rpy_offset=[0.0] * 3)
    push = Disturbance(target="vehicle", start=WINDOW[0], stop=WINDOW[1], force=PUSH,
                       torque=[0.0] * 3)
    return R(base, duration=duration, disturbances=[push], initial=initial,
             trajectory=TrajectoryParams(kind="hover"))


def _defended(scenario):
    """paper_plus with the observer's vehicle force fed forward (no integral action)."""
    return R(scenario, observer=Observer(enabled=True, bandwidth=20.0),
             controller=R(scenario.controller, type="paper_plus",
                          plus=PlusParams(vehicle_force_feedforward=True)))


def _errors(result):
    tracking = entries(result.log["tracking"], result.layouts["tracking"])
    return tracking["com_error"][:, 0], tracking["ee_position_error"][:, 0]


def test_the_observed_push_fed_forward_keeps_the_com_near_its_reference():
    """The paper's CoM is pushed 248 mm away (peak 0.23 s after the push ends); fed the
    observer's estimate (bandwidth 20 1/s, a sample late), paper_plus's peaks at 49 mm (the
    true force on the port: 35 mm; the rest is the estimate's 50 ms lag) and is at 23 mm at
    2 s (the paper's at 179 mm), and the end effector errs less than under the paper's law
    (0.81 against 1.41 mm). Cost: two 2 s runs."""
    scenario = _hover(2.0)
    paper = run_scenario(scenario, progress=False)
    plus = run_scenario(_defended(scenario), progress=False)
    assert paper.completed and plus.completed
    (com_paper, ee_paper), (com_plus, ee_plus) = _errors(paper), _errors(plus)
    assert 0.22 < com_paper.max() < 0.28  # measured 248.3 mm
    assert com_plus.max() < 0.25 * com_paper.max()  # measured 48.8 mm: 5.1x less
    assert ee_plus.max() < ee_paper.max()  # measured 0.81 mm, the paper's 1.41 mm
    # What was fed forward is the observer's estimate: the push, once the filter has settled.
    t = plus.log["t"]
    fed = entries(plus.log["diagnostics"], plus.layouts["diagnostics"])[
        "vehicle_force_feedforward"]
    settled = (t > WINDOW[0] + 5 / 20.0) & (t < WINDOW[1])
    np.testing.assert_allclose(fed[settled], np.tile(PUSH, (settled.sum(), 1)), atol=0.5)
    assert np.abs(fed[t < WINDOW[0]]).max() < 1e-6


def test_the_observer_does_not_change_the_paper_laws_command():
    """The paper's law does not read the estimate: with the observer on, its command and
    state are the same to the bit (a short run through the push's start)."""
    scenario = _hover(0.3)
    without = run_scenario(scenario, progress=False)
    with_observer = run_scenario(R(scenario, observer=Observer(enabled=True)), progress=False)
    assert "external_wrench_estimate" in with_observer.log
    for name in ("command", "plant_state", "diagnostics"):
        assert np.array_equal(without.log[name], with_observer.log[name]), name


def test_the_feedforward_without_the_observer_is_refused_naming_both_fields():
    scenario = _hover(0.1)
    plus = R(_defended(scenario), observer=Observer(enabled=False))
    with pytest.raises(ScenarioError, match="observer.enabled") as err:
        plus.validate()
    assert err.value.field == "controller.plus.vehicle_force_feedforward"
    assert "vehicle_force_feedforward: false" in str(err.value)


def test_a_force_at_the_end_effector_is_fed_forward_too():
    """A 40 N force along y at the end effector for 1 s moves the whole robot's CoM as a push
    on the vehicle would (the arm carries it to the vehicle): the observer's
    external_force_estimate, fed to paper_plus, sums the vehicle's and the end effector's
    forces. Measured: CoM peak 196.4 mm under the paper's law, 36.5 mm under paper_plus (the
    end effector's own deflection, 65 / 64 mm, is the arm's, not fed forward). Cost: two 2 s
    runs."""
    base = _hover(2.0)
    window = R(base.disturbances[0], target="end_effector", force=[0.0, 40.0, 0.0])
    scenario = R(base, disturbances=[window])
    paper = run_scenario(scenario, progress=False)
    plus = run_scenario(_defended(scenario), progress=False)
    assert paper.completed and plus.completed
    (com_paper, _), (com_plus, _) = _errors(paper), _errors(plus)
    assert com_plus.max() < 0.25 * com_paper.max()


def _compensated(scenario):
    """_defended, with the observer's generalized force compensated too."""
    plus = _defended(scenario)
    return R(plus, controller=R(plus.controller, plus=R(plus.controller.plus,
                                                        wrench_compensation=True)))


def test_the_compensated_wrench_leaves_the_end_effector_nearly_still():
    """A wrench at the end effector (10 N down, 2 N m about z, 1 s) deflects it through
    (20)'s model accelerations; compensated (the observer's generalized force less its force
    at the CoM, and that force's x_g'' in (20)) it is resisted at the observer's speed.
    Measured: EE peak 12.49 mm under the paper's law, 12.45 mm with the force fed forward
    only, 1.56 mm compensated; under the 50 N push on the vehicle 1.41 mm (paper) and 0.07 mm
    compensated, the CoM's peak as with the feed-forward (47.3 against 48.8 mm). Cost: four
    2 s runs."""
    base = _hover(2.0)
    wrench = R(base.disturbances[0], target="end_effector", force=[0.0, 0.0, -10.0],
               torque=[0.0, 0.0, 2.0])
    at_ee = R(base, disturbances=[wrench])
    fed = run_scenario(_defended(at_ee), progress=False)
    compensated = run_scenario(_compensated(at_ee), progress=False)
    assert fed.completed and compensated.completed
    (_, ee_fed), (_, ee_compensated) = _errors(fed), _errors(compensated)
    assert ee_compensated.max() < 0.2 * ee_fed.max()
    paper = run_scenario(base, progress=False)
    pushed = run_scenario(_compensated(base), progress=False)
    (com_paper, ee_paper), (com_pushed, ee_pushed) = _errors(paper), _errors(pushed)
    assert ee_pushed.max() < 0.1 * ee_paper.max()
    assert com_pushed.max() < 0.25 * com_paper.max()
    moment = entries(pushed.log["diagnostics"], pushed.layouts["diagnostics"])[
        "compensation_moment"]
    assert np.abs(moment[pushed.log["t"] < WINDOW[0]]).max() < 1e-6
    assert np.abs(moment).max() > 1.0  # the push's moment about the CoM, cancelled


def test_the_compensation_without_the_observer_is_refused():
    plus = R(_compensated(_hover(0.1)), observer=Observer(enabled=False))
    plus = R(plus, controller=R(plus.controller, plus=R(plus.controller.plus,
                                                        vehicle_force_feedforward=False)))
    with pytest.raises(ScenarioError, match="observer.enabled") as err:
        plus.validate()
    assert err.value.field == "controller.plus.wrench_compensation"


def test_the_quadrotor_with_the_ur3e_survives_a_50_N_push_it_could_not_before():
    """quadrotor_ur3e on its shipped trajectory, a 50 N push along +y on the vehicle over 4-5 s
    (where its shipped 15 N push acts): the paper's law loses the arm (Assumption 1, the CoM
    dragged ~0.4 m away from the held end effector); paper_plus with the observer's force fed
    forward and its wrench compensated completes, the end effector within 5 mm from 2 s after
    the push began (issue 32's goal). Measured on pushes along +-x and +-y at 4-5 s
    (tools/quadrotor_pushes.py): the paper's law stops in all four, paper_plus completes all
    four with EE peaks of 0.17-0.73 mm and at most 0.09 mm from 6 s. Cost: a 5.2 s and a 6.5 s
    run."""
    base = load_scenario("quadrotor_ur3e")
    push = Disturbance(target="vehicle", start=4.0, stop=5.0, force=[0.0, 50.0, 0.0],
                       torque=[0.0] * 3)
    scenario = R(base, duration=6.5, disturbances=[push])
    with pytest.raises(SimulationFailed, match="Assumption 1"):
        run_scenario(scenario, progress=False)
    plus = run_scenario(_compensated(scenario), progress=False)
    assert plus.completed
    t = plus.log["t"]
    _, ee = _errors(plus)
    assert ee[t >= 6.0].max() < 0.005
