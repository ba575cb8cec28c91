"""Tests of aerial_drake.trajectories: the paper's trajectory (28)-(33) (paper), its derivatives,
the packed vectors (reference) and the Drake source system (generator)."""

import math

import numpy as np
import pytest
from pydrake.common.yaml import yaml_load_typed
from pydrake.math import RotationMatrix

from aerial_drake.trajectories import generator, paper, reference
from aerial_drake.trajectories.kinds import reference_of, validate_trajectory

# Many times in [0, 15] s, including 0 and the end of the paper's run.
TIMES = np.concatenate([[0.0, 1e-3, 15.0], np.linspace(0.0, 15.0, 37)[1:-1] + 0.0137])

# Central differences: truncation ~ h^2 w^2 / 6 ~ 1e-8 (w <= 3 rad/s), round-off ~ 1e-16 / h.
STEP = 1e-4
RTOL = 1e-7


def generic_params() -> paper.TrajectoryParams:
    """Every constant distinct and non-zero, so a swapped or dropped constant shows up."""
    return paper.TrajectoryParams(
        center=[0.1, -0.2, 1.7],
        basic_amplitude=0.7,
        basic_frequency=0.9,
        basic_climb_rate=-0.03,
        agile_amplitude=0.15,
        agile_frequency=2.3,
        orientation_amplitudes=[0.3, 0.45, 0.6],
        orientation_frequency=1.7,
        joint_targets=[0.25],
        heading_initial=0.4,
        heading_rate=-0.35,
        com_offset=[-0.2, 0.15, 0.5],
    )


PARAMS = [
    pytest.param(paper.TrajectoryParams(), id="paper"),
    pytest.param(generic_params(), id="generic"),
]


def hat(w):
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def derivative_error(f, df, times=TIMES, h=STEP) -> float:
    """max |central difference of f - df| over times, relative to max |df| over times."""
    errors, scales = [], []
    for t in times:
        fd = (np.asarray(f(t + h)) - np.asarray(f(t - h))) / (2 * h)
        exact = np.asarray(df(t))
        errors.append(np.max(np.abs(fd - exact)))
        scales.append(np.max(np.abs(exact)))
    return max(errors) / max(max(scales), 1e-300)


def evaluator(params):
    return lambda t: paper.evaluate_reference(params, t)


# ---- derivatives against central differences ------------------------------------------------


@pytest.mark.parametrize("params", PARAMS)
@pytest.mark.parametrize("order", [1, 2, 3, 4])
def test_com_derivatives(params, order):
    ref = evaluator(params)
    error = derivative_error(lambda t: ref(t).com[order - 1], lambda t: ref(t).com[order])
    assert error < RTOL


@pytest.mark.parametrize("params", PARAMS)
def test_end_effector_translation_derivatives(params):
    ref = evaluator(params)
    assert derivative_error(lambda t: ref(t).p_ed, lambda t: ref(t).v_ed) < RTOL
    assert derivative_error(lambda t: ref(t).v_ed, lambda t: ref(t).a_ed) < RTOL


@pytest.mark.parametrize("params", PARAMS)
def test_orientation_derivatives(params):
    ref = evaluator(params)

    def R_dot(t):
        sample = ref(t)
        return hat(sample.w_ed) @ sample.R_ed

    assert derivative_error(lambda t: ref(t).R_ed, R_dot) < RTOL
    assert derivative_error(lambda t: ref(t).w_ed, lambda t: ref(t).dw_ed) < RTOL


@pytest.mark.parametrize("params", PARAMS)
def test_heading_derivatives(params):
    ref = evaluator(params)
    assert derivative_error(lambda t: ref(t).b1d[0], lambda t: ref(t).b1d[1]) < RTOL
    assert derivative_error(lambda t: ref(t).b1d[1], lambda t: ref(t).b1d[2]) < RTOL


@pytest.mark.parametrize("params", PARAMS)
def test_q3d_is_constant(params):
    # No joint_targets and no joint defaults: the paper's one joint target q3d = 0.
    q3_desired = params.joint_targets or [0.0]
    for t in TIMES:
        sample = paper.evaluate_reference(params, t)
        np.testing.assert_array_equal(sample.q_jd, q3_desired)
        np.testing.assert_array_equal(sample.q_jd_dot, [0.0])
        np.testing.assert_array_equal(sample.q_jd_ddot, [0.0])


def test_joint_targets_default_to_the_given_joint_defaults():
    params = paper.TrajectoryParams()
    sample = paper.evaluate_reference(params, 1.3, joint_defaults=[0.1, -0.2])
    np.testing.assert_array_equal(sample.q_jd, [0.1, -0.2])
    np.testing.assert_array_equal(sample.q_jd_dot, [0.0, 0.0])
    np.testing.assert_array_equal(sample.q_jd_ddot, [0.0, 0.0])
    assert sample.to_vectors()[1].shape == (reference.task_reference_size(2),) == (30,)
    # The pose part does not depend on the joint components.
    paper_sample = paper.evaluate_reference(params, 1.3)
    for name in ("com", "p_ed", "v_ed", "a_ed", "R_ed", "w_ed", "dw_ed", "b1d"):
        np.testing.assert_array_equal(getattr(sample, name), getattr(paper_sample, name))
    # Given joint_targets win over the defaults.
    generic = paper.evaluate_reference(generic_params(), 1.3, joint_defaults=[0.1])
    np.testing.assert_array_equal(generic.q_jd, [0.25])


@pytest.mark.parametrize(
    "field, row",
    [("com", 4), ("com", 1), ("v_ed", None), ("a_ed", None), ("w_ed", None), ("dw_ed", None)],
)
def test_derivative_check_detects_small_errors(field, row):
    """The tolerance above is tight: a derivative off by 1e-5 (relative) fails the check."""
    params = generic_params()

    def perturbed(t):
        value = np.array(getattr(paper.evaluate_reference(params, t), field))
        if row is not None:
            value = value[row]
        return value * (1 + 1e-5)

    def lower(t):
        sample = paper.evaluate_reference(params, t)
        if field == "com":
            return sample.com[row - 1]
        return {"v_ed": sample.p_ed, "a_ed": sample.v_ed, "w_ed": None, "dw_ed": sample.w_ed}[
            field
        ]

    if field == "w_ed":
        error = derivative_error(
            lambda t: paper.evaluate_reference(params, t).R_ed,
            lambda t: hat(perturbed(t)) @ paper.evaluate_reference(params, t).R_ed,
        )
    else:
        error = derivative_error(lower, perturbed)
    assert error > RTOL


# ---- values: the paper's numbers and an independent implementation of (28)-(33) --------------


def test_paper_values_at_zero():
    sample = paper.evaluate_reference(paper.TrajectoryParams(), 0.0)
    np.testing.assert_allclose(
        sample.p_ed, np.array([0.6, -0.5, 1.3]) + 0.1 * np.array([0, 1, 1]), atol=1e-15
    )
    np.testing.assert_allclose(
        sample.com[0], np.array([0.6, -0.5, 1.3]) + np.array([-0.3, 0, 0.6]), atol=1e-15
    )
    R_expected = (
        RotationMatrix.MakeXRotation(0.0)
        .multiply(RotationMatrix.MakeYRotation(0.5))
        .multiply(RotationMatrix.MakeZRotation(0.5))
        .matrix()
    )
    np.testing.assert_allclose(sample.R_ed, R_expected, atol=1e-15)
    np.testing.assert_allclose(sample.b1d[0], [1.0, 0.0, 0.0], atol=1e-15)
    np.testing.assert_array_equal(sample.q_jd, [0.0])


def straightforward_reference(p: paper.TrajectoryParams, t: float):
    """(28), (29), (31), (32), (33) written out directly, with Drake's rotation matrices."""
    basic = np.array(
        [
            -math.sin(p.basic_frequency * t),
            -math.cos(p.basic_frequency * t),
            math.sin(p.basic_frequency * t) + p.basic_climb_rate * t,
        ]
    )
    agile = np.array(
        [
            math.sin(p.agile_frequency * t),
            math.cos(p.agile_frequency * t),
            math.cos(p.agile_frequency * t),
        ]
    )
    x_c = np.array(p.center) + p.basic_amplitude * basic
    x_ed = x_c + p.agile_amplitude * agile
    a1, a2, a3 = p.orientation_amplitudes
    w_o = p.orientation_frequency
    R_ed = (
        RotationMatrix.MakeXRotation(a1 * math.sin(w_o * t))
        .multiply(RotationMatrix.MakeYRotation(a2 * math.cos(w_o * t)))
        .multiply(RotationMatrix.MakeZRotation(a3 * math.cos(w_o * t)))
        .matrix()
    )
    phi4 = p.heading_initial + p.heading_rate * t
    b1d = np.array([math.cos(phi4), math.sin(phi4), 0.0])
    x_d = x_c + RotationMatrix.MakeZRotation(phi4).multiply(np.array(p.com_offset))
    return x_ed, R_ed, b1d, x_d


@pytest.mark.parametrize("params", PARAMS)
def test_values_match_the_equations(params):
    for t in TIMES:
        sample = paper.evaluate_reference(params, t)
        x_ed, R_ed, b1d, x_d = straightforward_reference(params, t)
        np.testing.assert_allclose(sample.p_ed, x_ed, atol=1e-14)
        np.testing.assert_allclose(sample.R_ed, R_ed, atol=1e-14)
        np.testing.assert_allclose(sample.b1d[0], b1d, atol=1e-14)
        np.testing.assert_allclose(sample.com[0], x_d, atol=1e-14)


@pytest.mark.parametrize("params", PARAMS)
def test_R_ed_is_a_rotation(params):
    for t in TIMES:
        R = paper.evaluate_reference(params, t).R_ed
        np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-14)
        assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-14)


def test_sample_reference_matches_evaluate_reference():
    params = generic_params()
    samples = paper.sample_reference(params, TIMES)
    assert samples.com.shape == (len(TIMES), 5, 3)
    assert samples.R_ed.shape == (len(TIMES), 3, 3)
    assert samples.b1d.shape == (len(TIMES), 3, 3)
    assert samples.q_jd.shape == (len(TIMES), 1)
    for i, t in enumerate(TIMES):
        one = paper.evaluate_reference(params, t)
        for name in ("com", "p_ed", "v_ed", "a_ed", "R_ed", "w_ed", "dw_ed", "b1d"):
            np.testing.assert_allclose(
                getattr(samples, name)[i], getattr(one, name), rtol=0, atol=1e-14, err_msg=name
            )
        np.testing.assert_array_equal(samples.q_jd[i], one.q_jd)
        np.testing.assert_array_equal(samples.q_jd_dot[i], one.q_jd_dot)
        np.testing.assert_array_equal(one.q_jd_dot, [0.0])
    with pytest.raises(ValueError, match="1-D"):
        paper.sample_reference(params, np.zeros((2, 2)))


# ---- packing ----------------------------------------------------------------------------------


def test_packing_layout_and_round_trip():
    sample = paper.evaluate_reference(generic_params(), 2.5)
    com, task, heading = sample.to_vectors()
    assert com.shape == (reference.COM_REFERENCE_SIZE,) == (15,)
    assert task.shape == (reference.task_reference_size(1),) == (27,)
    assert heading.shape == (reference.HEADING_REFERENCE_SIZE,) == (9,)
    # The documented layouts, spelled out once here.
    np.testing.assert_array_equal(com, sample.com.reshape(-1))
    np.testing.assert_array_equal(
        task,
        np.concatenate(
            [
                sample.p_ed, sample.R_ed.reshape(-1), sample.q_jd,
                sample.v_ed, sample.w_ed, sample.q_jd_dot,
                sample.a_ed, sample.dw_ed, sample.q_jd_ddot,
            ]
        ),
    )  # fmt: skip
    np.testing.assert_array_equal(heading, sample.b1d.reshape(-1))

    back = reference.ReferenceSample.from_vectors(com, task, heading)
    for name in ("com", "p_ed", "v_ed", "a_ed", "R_ed", "w_ed", "dw_ed", "b1d"):
        np.testing.assert_array_equal(getattr(back, name), getattr(sample, name))
    for name in ("q_jd", "q_jd_dot", "q_jd_ddot"):
        np.testing.assert_array_equal(getattr(back, name), getattr(sample, name))
        assert getattr(back, name).shape == (1,)

    task_parts = reference.unpack_task_reference(task)
    np.testing.assert_array_equal(task_parts.R_ed, sample.R_ed)
    # The joint pieces are views into the vector, not floats.
    assert np.shares_memory(task_parts.q_jd, task)
    np.testing.assert_array_equal(
        task_parts.full_dot, np.concatenate([sample.v_ed, sample.w_ed, sample.q_jd_dot]))
    np.testing.assert_array_equal(
        task_parts.full_ddot, np.concatenate([sample.a_ed, sample.dw_ed, sample.q_jd_ddot]))
    np.testing.assert_array_equal(reference.unpack_com_reference(com), sample.com)
    np.testing.assert_array_equal(reference.unpack_heading_reference(heading), sample.b1d)
    with pytest.raises(ValueError, match=r"24 \+ 3 n_j .*got 26"):
        reference.unpack_task_reference(np.zeros(26))


def test_packing_over_time_round_trips():
    samples = paper.sample_reference(generic_params(), TIMES)
    com, task, heading = samples.to_vectors()
    assert com.shape == (len(TIMES), 15) and task.shape == (len(TIMES), 27)
    back = reference.ReferenceSample.from_vectors(com, task, heading)
    for name in ("com", "R_ed", "q_jd", "dw_ed", "b1d"):
        np.testing.assert_array_equal(getattr(back, name), getattr(samples, name))


# ---- the Drake system ------------------------------------------------------------------------


def test_reference_generator_outputs():
    params = generic_params()
    system = generator.ReferenceGenerator(params)
    assert system.num_input_ports() == 0
    context = system.CreateDefaultContext()
    assert context.num_total_states() == 0
    ports = {
        "com_reference": system.get_com_reference_output_port(),
        "task_reference": system.get_task_reference_output_port(),
        "heading_reference": system.get_heading_reference_output_port(),
    }
    for name, port in ports.items():
        assert port.get_name() == name
        assert system.GetOutputPort(name) is port
    # Increasing, then a decreasing time: the cache must follow the context's time.
    for t in [0.0, 0.7, 4.2, 15.0, 3.3]:
        context.SetTime(t)
        expected = paper.evaluate_reference(params, t).to_vectors()
        for port, vector in zip(ports.values(), expected):
            np.testing.assert_allclose(port.Eval(context), vector, rtol=0, atol=1e-15)


def test_reference_generator_keeps_its_own_params():
    params = generic_params()
    system = generator.ReferenceGenerator(params)
    params.center[0] = 100.0  # The caller's later edits do not reach the system.
    context = system.CreateDefaultContext()
    com = reference.unpack_com_reference(system.get_com_reference_output_port().Eval(context))
    np.testing.assert_allclose(com, paper.evaluate_reference(generic_params(), 0.0).com)
    assert system.params() == generic_params()


def test_reference_generator_outputs_the_source_it_is_given():
    """Built from a ReferenceSource (the run's), the generator outputs that very object's
    values and holds it as ``source``: nothing is rebuilt."""
    source = reference_of(generic_params(), [0.1])
    system = generator.ReferenceGenerator(source)
    assert system.source is source and system.params() is None
    context = system.CreateDefaultContext()
    for t in [0.0, 2.5, 9.1]:
        context.SetTime(t)
        outputs = [system.GetOutputPort(name).Eval(context) for name in (
            "com_reference", "task_reference", "heading_reference")]
        for port, vector in zip(outputs, source.evaluate(t).to_vectors()):
            np.testing.assert_array_equal(port, vector)


def test_reference_generator_validates():
    with pytest.raises(ValueError, match="'com_offset'"):
        generator.ReferenceGenerator(paper.TrajectoryParams(com_offset=[0.0, 0.0]))


def test_reference_generator_is_double_only():
    with pytest.raises(RuntimeError):
        generator.ReferenceGenerator(paper.TrajectoryParams()).ToAutoDiffXd()


# ---- parameters --------------------------------------------------------------------------------


def test_params_load_from_yaml():
    params = yaml_load_typed(
        schema=paper.TrajectoryParams,
        data="""
center: [0.5, 0.1, 1.0]
agile_frequency: 2
orientation_amplitudes: [0.1, 0.2, 0.3]
heading_rate: -0.25
""",
    )
    validate_trajectory(params)
    assert params.center == [0.5, 0.1, 1.0]
    assert params.agile_frequency == 2.0
    assert params.orientation_amplitudes == [0.1, 0.2, 0.3]
    assert params.heading_rate == -0.25
    # Absent keys keep the paper's values.
    assert params.basic_amplitude == 0.5 and params.com_offset == [-0.3, 0.0, 0.6]
    assert yaml_load_typed(schema=paper.TrajectoryParams, data="{}") == paper.TrajectoryParams()


def test_yaml_typo_is_an_error():
    with pytest.raises(RuntimeError, match="heading_rat"):
        yaml_load_typed(schema=paper.TrajectoryParams, data="heading_rat: 0.5")


def test_paper_defaults_are_valid():
    validate_trajectory(paper.TrajectoryParams())
    validate_trajectory(generic_params())


@pytest.mark.parametrize(
    "changes, field",
    [
        (dict(center=[0.6, 0.0]), "center"),
        (dict(orientation_amplitudes=[0.5, 0.5, 0.5, 0.5]), "orientation_amplitudes"),
        (dict(com_offset=[-0.3, float("nan"), 0.6]), "com_offset"),
        (dict(orientation_amplitudes=[0.5, -0.5, 0.5]), "orientation_amplitudes"),
        (dict(basic_frequency=-0.5), "basic_frequency"),
        (dict(agile_amplitude=-0.1), "agile_amplitude"),
        (dict(orientation_frequency=float("inf")), "orientation_frequency"),
        (dict(heading_rate=float("nan")), "heading_rate"),
        (dict(joint_targets=[0.1, float("inf")]), "joint_targets"),
    ],
)
def test_validate_names_the_field(changes, field):
    params = paper.TrajectoryParams(**changes)
    with pytest.raises(ValueError, match=f"'{field}'"):
        validate_trajectory(params)
    with pytest.raises(ValueError, match=f"'{field}'"):
        paper.evaluate_reference(params, 0.0)


def test_validate_reports_length_and_fix():
    with pytest.raises(ValueError, match=r"'center' must be a list of 3 floats .*exactly three"):
        validate_trajectory(paper.TrajectoryParams(center=[0.6, 0.0]))
