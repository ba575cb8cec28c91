"""x_d planned with margin (trajectories/com_planning.py, option trajectory.com_planning): the
planned x_d's derivatives are the rates of each other, its postures hold the end effector on
y_d with more margin than rule (33)'s on a reference that stretches the arm, the option off
leaves the reference as it was, and a bad option is refused naming the field."""

import dataclasses

import numpy as np
import pytest

from aerial_drake.dynamics.equilibrium import configuration_residual, solve_configuration
from aerial_drake.simulation.scenarios import ScenarioError, load_scenario
from aerial_drake.trajectories import com_planning as dut
from aerial_drake.trajectories.com_margins import level_attitude
from aerial_drake.trajectories.kinds import reference_of, validate_trajectory
from aerial_drake.trajectories.params import ComPlanningParams, TrajectoryParams

#: 1 s of the study base's motion (heading held, agile circle 70 mm, swing 0.2 rad), with the
#: CoM 0.72 m above the end effector instead of 0.62: rule (33) stretches the elbow there.
DURATION = 1.0
STRETCHED = TrajectoryParams(com_offset=[-0.3, 0.0, 0.72], heading_rate=0.0,
                             orientation_amplitudes=[0.2, 0.2, 0.2], agile_amplitude=0.07)


@pytest.fixture(scope="module")
def model():
    return load_scenario("nominal").controller_model()


@pytest.fixture(scope="module")
def planned(model):
    source = reference_of(STRETCHED, model.task_joint_nominal())
    return source, dut.plan_com(source, model, DURATION, sample_period=0.1, knot_period=0.4)


def test_derivatives_are_the_rates_of_the_ones_below(planned):
    source, plan = planned
    h = 1e-4
    times = np.linspace(0.0, DURATION, 41)
    times = np.clip(times, h, DURATION - h)  # central differences inside the plan's span
    com = plan.sample(times).com
    ahead, behind = plan.sample(times + h).com, plan.sample(times - h).com
    # The central difference misses by at most h^2/6 max|x^(k+2)|: the correction's 5th and
    # 6th derivatives (degree 7, from its B-spline) plus the paper kind's, whose terms turn at
    # 3 rad/s with amplitudes below 1 m (3^6 < 1e3); round-off adds ~1e-16 |x^(k-1)| / h.
    top = max(np.abs(plan.delta.MakeDerivative(k).vector_values(list(times))).max()
              for k in (5, 6))
    bound = h ** 2 / 6 * (top + 1e3) + 1e-10
    for k in range(1, 5):
        difference = (ahead[:, k - 1] - behind[:, k - 1]) / (2 * h)
        assert np.abs(difference - com[:, k]).max() < bound, (k, bound)
    # Not vacuous: the correction moves in time (its rates are checked, not only the kind's).
    kind = source.sample(times).com
    assert np.abs(com[:, 1:] - kind[:, 1:]).max() > 1e-3
    # The run starts at rest as with the kind's x_d: the correction's rates vanish at t = 0.
    start, kind_start = plan.evaluate(0.0).com, source.evaluate(0.0).com
    np.testing.assert_allclose(start[1:], kind_start[1:], atol=1e-9)


def test_past_the_plans_span_the_correction_holds_still(planned):
    """After the plan's span (a window or a check sampling past the run) the correction keeps
    its end value with zero rates: x_d stays consistent with its derivatives."""
    _, plan = planned
    end = plan.correction(DURATION)
    after = plan.correction(DURATION + 0.5)
    np.testing.assert_array_equal(after[0], end[0])
    np.testing.assert_array_equal(after[1:], 0.0)
    assert np.abs(end[1:]).max() > 0.0  # not vacuous: the rates at the end are not zero
    np.testing.assert_array_equal(plan.correction(-1.0)[1:], 0.0)


def test_planned_postures_hold_the_task_with_more_margin_than_rule_33(planned, model):
    source, plan = planned
    report = plan.report
    # The end effector on y_d: the postures' largest miss of the task and the CoM, and an
    # independent check by Drake's InverseKinematics at three times.
    assert report.planned.max_residual < 1e-9
    for t in (0.0, 0.45, DURATION):
        ref = plan.evaluate(t)
        targets = dict(p_WG=ref.com[0], R_WB=level_attitude(ref.b1d[0]), p_WE=ref.p_ed,
                       R_WE=ref.R_ed, q_j=ref.q_jd)
        q = solve_configuration(model, **targets, respect_joint_limits=False)
        residual = configuration_residual(model, q, **targets)
        assert residual.ee_position < 1e-6 and residual.ee_orientation < 1e-6
    # The plan moved x_d away from the kind's (rule (33)).
    assert report.max_shift_m > 0.05
    assert np.linalg.norm(plan.evaluate(0.5).com[0] - source.evaluate(0.5).com[0]) > 0.01
    # More margin: sigma_min(J_3) (rule (33): 0.133; planned 0.158), the joint limits
    # (11.5 % -> 12.4 % of range) and |q|/limit (0.770 -> 0.752).
    assert report.planned.sigma_min > 1.15 * report.kind.sigma_min, report.as_dict()
    assert report.planned.limit_fraction > report.kind.limit_fraction
    assert report.planned.max_limit_ratio < report.kind.max_limit_ratio
    assert report.samples == 11
    assert "x_d planned with margin" in report.line()


def test_off_leaves_the_reference_unchanged(model):
    assert TrajectoryParams().com_planning.enabled is False
    source = reference_of(STRETCHED, model.task_joint_nominal())
    assert dut.planned_reference(source, ComPlanningParams(), model, 15.0) is source
    for name in ("nominal", "disturbed", "disturbed_within_limits", "pick_and_place"):
        assert load_scenario(name).trajectory.com_planning.enabled is False


@pytest.mark.parametrize("field, value, words", [
    ("sample_period", -0.1, "'com_planning.sample_period' must be a time in [0.005, 1] s"),
    ("knot_period", float("nan"), "'com_planning.knot_period' must be a time"),
    ("enabled", "yes", "'com_planning.enabled' must be true or false"),
])
def test_a_bad_option_is_refused_naming_it(field, value, words):
    params = dataclasses.replace(
        STRETCHED, com_planning=dataclasses.replace(ComPlanningParams(), **{field: value}))
    with pytest.raises(ValueError, match="Invalid TrajectoryParams") as err:
        validate_trajectory(params)
    assert words in str(err.value) and repr(value) in str(err.value)


def test_knots_closer_than_two_samples_are_refused_with_the_fix():
    params = dataclasses.replace(STRETCHED, com_planning=ComPlanningParams(
        enabled=True, sample_period=0.2, knot_period=0.3))
    with pytest.raises(ValueError, match="raise knot_period or lower sample_period"):
        validate_trajectory(params)


def test_a_scenario_with_a_bad_option_names_the_field():
    with pytest.raises(ScenarioError) as err:
        load_scenario("nominal", overrides={"trajectory.com_planning.sample_period": 0.0})
    assert "com_planning.sample_period" in str(err.value)


def test_a_given_com_and_planning_are_refused_together():
    params = TrajectoryParams(kind="hover", com_planning=ComPlanningParams(enabled=True))
    validate_trajectory(params)  # the hover's CoM by rule (33): the plan may replace it
    params.hover.com = [0.3, 0.0, 1.4]
    with pytest.raises(ValueError, match="'com_planning.enabled' is true but the hover section"):
        validate_trajectory(params)
