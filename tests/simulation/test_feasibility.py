"""Feasibility of the whole reference before simulating (aerial_drake.simulation.feasibility,
aerial_drake.trajectories.continuity): each infeasible reference is refused naming the time
and the cause, and the time named is where the cause holds; the shipped scenarios pass."""

import dataclasses
import re

import numpy as np
import pytest

import aerial_drake.simulation.feasibility as dut
from aerial_drake.control.reference_pose import realising_targets
from aerial_drake.dynamics.equilibrium import kinematic_J3, solve_configuration
from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import ScenarioError, load_scenario, shipped_scenarios
from aerial_drake.trajectories.continuity import find_discontinuity
from aerial_drake.trajectories.kinds import reference_of, sample_reference


def named_time(message: str) -> float:
    found = re.search(r"at t = (\d+\.\d+) s", message)
    assert found, message
    return float(found.group(1))


@pytest.fixture(scope="module")
def paper_model():
    return load_scenario("nominal").controller_model()


@pytest.mark.parametrize("name", sorted(shipped_scenarios()))
def test_shipped_scenarios_pass_every_check(name):
    scenario = load_scenario(name)
    model = scenario.controller_model()
    dut.check_reference(scenario, model)
    # And with a margin: the smallest sigma_min(J_3) along each is far above the refusal's.
    assert dut.check_postures(scenario, model) > 10 * dut.SIGMA_MARGIN_FACTOR * \
        scenario.sigma_min_J3_limit


def test_kinematic_J3_is_the_decoupled_dynamics_J3(paper_model):
    # J_3 = J_y Z^T (T^-1's last columns are Z^T): against J_y T^-1 from the mass matrix.
    scenario = load_scenario("nominal")
    model = paper_model
    ctx = model.plant.CreateDefaultContext()
    nv = model.plant.num_velocities()
    for t in (0.0, 2.3, 7.1):
        ref = reference_of(scenario.trajectory, model.task_joint_nominal()).sample(
            np.array([t]))
        q = solve_configuration(model, **realising_targets(model, dut._at(ref, 0)),
                                respect_joint_limits=False)
        model.plant.SetPositions(ctx, q)
        sigma = np.linalg.svd(kinematic_J3(model, ctx), compute_uv=False)[-1]
        assert sigma == pytest.approx(dut.sigma_min_J3(model, np.concatenate(
            [q, np.zeros(nv)])), rel=1e-9)


def thrust_at(scenario, model, t):
    m, g = dut.mass_and_gravity(model)
    ref = sample_reference(scenario.trajectory, np.array([t]), model.task_joint_nominal())
    return m * np.linalg.norm(ref.com[0, 2] + [0.0, 0.0, g])


def test_a_reference_too_fast_for_the_thrust_limit_is_refused_before_simulating():
    # A basic motion at 4.5 rad/s: 0.5 x 4.5^2 = 10.1 m/s^2 up and down, so 54.8 kg needs
    # about 1090 N at the bottom of each swing (limit 980.6 N). Through run_scenario: refused
    # before the simulation starts.
    scenario = load_scenario("nominal", overrides={"duration": 3.0})
    scenario.trajectory.basic_frequency = 4.5
    model = scenario.controller_model()
    with pytest.raises(ScenarioError, match=r"trajectory: the reference needs a thrust of "
                       r"\d+\.\d N at t = .*above the thrust maximum 980\.6 N") as err:
        run_scenario(scenario, progress=False)
    t = named_time(str(err.value))
    need = float(re.search(r"thrust of (\d+\.\d) N", str(err.value)).group(1))
    assert thrust_at(scenario, model, t) == pytest.approx(need, abs=0.05)
    # The peak: no sample of the reference needs more.
    times = np.linspace(0.0, 3.0, 30001)
    m, g = dut.mass_and_gravity(model)
    ref = sample_reference(scenario.trajectory, times, model.task_joint_nominal())
    assert m * np.linalg.norm(ref.com[:, 2] + [0, 0, g], axis=1).max() < need + 0.1


def test_a_lowered_thrust_maximum_refuses_the_paper_reference(paper_model):
    scenario = load_scenario("nominal")
    # Hover needs m g = 537.6 N, the paper's reference at most 544.5 N.
    scenario.actuation.thrust_max = 542.0
    with pytest.raises(ScenarioError, match=r"above the thrust maximum 542 N") as err:
        dut.check_reference(scenario, paper_model)
    assert thrust_at(scenario, paper_model, named_time(str(err.value))) > 542.0


def test_a_thrust_below_assumption_2s_threshold_is_refused(paper_model):
    # The threshold above what the reference ever needs at its lightest.
    scenario = load_scenario("nominal", overrides={"f_d_limit": 540.0})
    with pytest.raises(ScenarioError, match=r"at t = \d+\.\d+ s .* below Assumption 2's "
                       r"threshold f_d_limit = 540 N") as err:
        dut.check_reference(scenario, paper_model)
    assert thrust_at(scenario, paper_model, named_time(str(err.value))) < 540.0


def test_an_end_effector_out_of_reach_is_refused(paper_model):
    scenario = load_scenario("nominal")
    scenario.trajectory.agile_amplitude = 0.25
    with pytest.raises(ScenarioError, match=r"trajectory: the desired end effector leaves the "
                       r"arm's workspace at t = \d+\.\d+ s: it is 0\.\d+ m from") as err:
        dut.check_reference(scenario, paper_model)
    dev = float(re.search(r"it is (0\.\d+) m", str(err.value)).group(1))
    assert dev > paper_model.description.workspace_radius


def test_a_reference_through_a_singular_posture_is_refused(paper_model):
    # The end effector pitched through 1.85 rad (phi2 = 2.2 cos(0.5 t)) with the CoM at rest:
    # the wrist's axes align (LWR joints 5 and 7), J_3 loses rank at an instant. At 20 Hz the
    # smallest sampled sigma is 0.013; the refinement finds it down to about 1e-4.
    scenario = load_scenario("nominal", overrides={"duration": 3.0})
    tr = scenario.trajectory
    tr.basic_amplitude, tr.agile_amplitude, tr.heading_rate = 0.0, 0.0, 0.0
    tr.orientation_amplitudes, tr.orientation_frequency = [0.0, 2.2, 0.0], 0.5
    with pytest.raises(ScenarioError, match=r"Assumption 1 fails along the reference at t = "
                       r"\d+\.\d+ s: .*sigma_min\(J_3\) = [\d.e-]+, below the margin 0\.003 "
                       r"\(3 x sigma_min_J3_limit") as err:
        dut.check_reference(scenario, paper_model)
    t = named_time(str(err.value))
    assert t == pytest.approx(1.145, abs=0.01)
    phi2 = 2.2 * np.cos(0.5 * t)
    assert phi2 == pytest.approx(1.85, abs=0.02)


class Patched:
    """A reference built in the test: ``scenario``'s, plus ``extra(times, ref)``; what the
    checks read of a run's reference (its ``sample``)."""

    def __init__(self, scenario, model, extra):
        self.source = reference_of(scenario.trajectory, model.task_joint_nominal())
        self.extra = extra

    def sample(self, times):
        times = np.asarray(times, dtype=float)
        return self.extra(times, self.source.sample(times))


def with_com(ref, add):
    return dataclasses.replace(ref, com=ref.com + add)


def step_in_snap(times, ref):
    # x_d'''' jumps by 2 m/s^4 along x at 1.2345 s: x_d is only C^3 there.
    add = np.zeros_like(ref.com)
    add[:, 4, 0] = 2.0 * (times >= 1.2345)
    return with_com(ref, add)


def kink_in_jerk(times, ref):
    # x_d''' jumps by 0.5 m/s^3 at 2.5 s, with x_d'' a ramp from there (consistent): C^2 only.
    add = np.zeros_like(ref.com)
    after = np.maximum(times - 2.5, 0.0)
    add[:, 0, 2] = 0.5 * after ** 3 / 6
    add[:, 1, 2] = 0.5 * after ** 2 / 2
    add[:, 2, 2] = 0.5 * after
    add[:, 3, 2] = 0.5 * (times >= 2.5)
    return with_com(ref, add)


def wrong_angular_acceleration(times, ref):
    # dw_ed 20 % too large everywhere: not the rate of w_ed.
    return dataclasses.replace(ref, dw_ed=1.2 * ref.dw_ed)


@pytest.mark.parametrize("extra, signal, time, kind", [
    (step_in_snap, "x_d''''", 1.2345, "jumps"),
    (kink_in_jerk, "x_d'''", 2.5, "jumps"),
    (wrong_angular_acceleration, "dw_ed", None, "is not the rate"),
])
def test_a_discontinuity_is_refused_naming_the_signal_and_time(paper_model, extra, signal,
                                                              time, kind):
    scenario = load_scenario("nominal", overrides={"duration": 4.0})
    with pytest.raises(ScenarioError, match=r"the reference is not smooth enough for the "
                       rf"law: {re.escape(signal)} (at t = |)") as err:
        dut.check_reference(scenario, paper_model,
                            reference=Patched(scenario, paper_model, extra))
    message = str(err.value)
    assert kind in message
    if time is not None:
        assert re.search(rf"{re.escape(signal)} jumps at t = (\d+\.\d+)", message)
        assert float(re.search(r"t = (\d+\.\d+)", message).group(1)) == \
            pytest.approx(time, abs=1e-5)


def test_a_fast_but_smooth_feature_is_not_a_discontinuity(paper_model):
    # A Gaussian bump of 20 ms width in x_d (all four derivatives exact): at 10 ms samples its
    # snap changes by far more over one interval than over the next, but bisection shows it
    # shrinking with the interval, so it passes.
    scenario = load_scenario("nominal", overrides={"duration": 2.0})
    w, t0, a = 0.02, 1.003, 1e-5

    def bump(times, ref):
        u = (times - t0) / w
        e = np.exp(-u ** 2 / 2)
        hermite = (1, u, u ** 2 - 1, u ** 3 - 3 * u, u ** 4 - 6 * u ** 2 + 3)
        add = np.zeros_like(ref.com)
        for n, he in enumerate(hermite):
            add[:, n, 0] = a * (-1) ** n * he * e / w ** n
        return with_com(ref, add)

    times = dut.sample_times(2.0, dut.SAMPLE_PERIOD)
    found = find_discontinuity(Patched(scenario, paper_model, bump).sample, times)
    assert found is None
    # The same bump made a step (its snap cut at t0) is found.
    cut = Patched(scenario, paper_model, lambda t, ref: step_in_snap(t, bump(t, ref)))
    found = find_discontinuity(cut.sample, times)
    assert found is not None and found.signal == "x_d''''"


@pytest.mark.parametrize("heading", [0.7, -2.3])
def test_the_reach_check_reads_the_offset_in_the_heading_frame(tmp_path, heading):
    """A robot whose nominal end-effector offset has a sideways part (its roll joint at 0.3
    rad), held at that offset plus 40 mm, rotated with a heading that is not 0: the check
    finds 40 mm, whatever the heading (a wrong sign or a transposed R3 does not: issue 27)."""
    from aerial_drake.robots.description import load_robot_description
    from aerial_drake.robots.models import make_plant, nominal_end_effector_offset
    from aerial_drake.trajectories.params import HoverParams, TrajectoryParams
    from own_robot import write_robot

    description, _ = write_robot(tmp_path, posture="[0.3, 0.8, -0.8, 0.0]")
    model = make_plant(robot=load_robot_description(description))
    nominal = nominal_end_effector_offset(model)
    assert abs(nominal[1]) > 0.05 and abs(nominal[0]) > 0.05  # sideways and forward parts
    delta = np.array([0.02, -0.03, 0.0])  # 36 mm, in the heading frame
    # Rule (33): the CoM is ee_position + R3(heading) com_offset, so the offset of E from the
    # CoM in the heading frame is -com_offset.
    params = TrajectoryParams(kind="hover", joint_targets=[0.0], com_offset=list(
        -(nominal + delta)), hover=HoverParams(ee_position=[0.3, -0.2, 1.0], heading=heading))
    reference = reference_of(params, None)
    scenario = load_scenario("nominal")
    dut.check_workspace(scenario, model, radius=0.037, reference=reference)
    with pytest.raises(ScenarioError, match=r"it is 0\.036 m from its nominal offset"):
        dut.check_workspace(scenario, model, radius=0.035, reference=reference)
