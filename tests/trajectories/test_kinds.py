"""Every reference kind gives the law derivatives that are the rates of the lower ones, across
every waypoint, and bad sections are refused at load naming the field (issue 18)."""

import dataclasses
import math
import re
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from pydrake.trajectories import PiecewisePolynomial

from aerial_drake.simulation.scenarios import ScenarioError, load_scenario, shipped_scenarios
from aerial_drake.trajectories import paper
from aerial_drake.trajectories.kinds import (
    KINDS,
    REFERENCE_KINDS,
    reference_of,
    validate_trajectory,
)
from aerial_drake.trajectories.params import HoverParams, PythonParams, TrajectoryParams

H = 1e-5  # central-difference step (s)


def pick_and_place() -> TrajectoryParams:
    return load_scenario("pick_and_place").trajectory


def _rate(R_minus, R_plus, h):
    """World angular velocity from R(t - h), R(t + h): vee(log(R+ R-^T)) / 2h (small angle)."""
    D = R_plus @ R_minus.T
    return 0.5 * np.array([D[2, 1] - D[1, 2], D[0, 2] - D[2, 0], D[1, 0] - D[0, 1]]) / (2 * h)


def assert_derivatives_consistent(source, times, rtol=2e-5):
    """Each given derivative equals a central difference of the signal below it."""
    for t in times:
        lo, mid, hi = source.evaluate(t - H), source.evaluate(t), source.evaluate(t + H)
        pairs = [(f"x_d^({k + 1})", (hi.com[k] - lo.com[k]) / (2 * H), mid.com[k + 1])
                 for k in range(4)]
        pairs += [("v_ed", (hi.p_ed - lo.p_ed) / (2 * H), mid.v_ed),
                  ("a_ed", (hi.v_ed - lo.v_ed) / (2 * H), mid.a_ed),
                  ("w_ed", _rate(lo.R_ed, hi.R_ed, H), mid.w_ed),
                  ("dw_ed", (hi.w_ed - lo.w_ed) / (2 * H), mid.dw_ed),
                  ("q_jd'", (hi.q_jd - lo.q_jd) / (2 * H), mid.q_jd_dot),
                  ("q_jd''", (hi.q_jd_dot - lo.q_jd_dot) / (2 * H), mid.q_jd_ddot),
                  ("b1d'", (hi.b1d[0] - lo.b1d[0]) / (2 * H), mid.b1d[1]),
                  ("b1d''", (hi.b1d[1] - lo.b1d[1]) / (2 * H), mid.b1d[2])]
        for name, fd, given in pairs:
            scale = max(1.0, float(np.abs(given).max(initial=0.0)))
            assert np.allclose(fd, given, rtol=0, atol=rtol * scale), \
                f"{name} at t = {t}: finite difference {fd} vs given {given}"
        assert np.allclose(mid.R_ed.T @ mid.R_ed, np.eye(3), atol=1e-12)


def test_waypoints_derivatives_are_rates_everywhere_and_at_every_waypoint():
    params = pick_and_place()
    source = reference_of(params, None)
    knots = np.array([w.time for w in params.waypoints.points])
    inside = (knots[:-1] + knots[1:]) / 2
    times = np.concatenate([np.linspace(0.05, 14.95, 37), inside, knots[1:-1] + 3e-5,
                            knots[1:-1] - 3e-5])
    assert_derivatives_consistent(source, times)


def test_waypoints_no_jump_in_snap_or_angular_acceleration_across_waypoints():
    params = pick_and_place()
    source = reference_of(params, None)
    for w in params.waypoints.points[1:-1]:
        before, after = source.evaluate(w.time - 1e-9), source.evaluate(w.time + 1e-9)
        assert np.allclose(before.com, after.com, atol=1e-6), w.time  # x_d to x_d''''
        assert np.allclose(before.dw_ed, after.dw_ed, atol=1e-6), w.time
        assert np.allclose(before.w_ed, after.w_ed, atol=1e-8), w.time
        # ...and the waypoint is met exactly, at rest.
        at = source.evaluate(w.time)
        assert np.allclose(at.p_ed, w.ee_position, atol=1e-12)
        assert np.allclose(at.v_ed, 0.0, atol=1e-12) and np.allclose(at.w_ed, 0.0, atol=1e-12)


def test_waypoints_fixed_axis_fast_path_is_the_general_so3_formula():
    """Rest-to-rest segments turn about a fixed axis and skip the general rates: the same
    reference as the general R_i exp(hat(r)), J_r(r) r' path, to rounding."""
    fast = reference_of(pick_and_place(), None)
    general = reference_of(pick_and_place(), None)
    assert any(term is not None for term in general._axis_terms)
    general._axis_terms = [None] * len(general._axis_terms)
    times = np.linspace(0.0, 15.0, 601)
    a, b = fast.sample(times), general.sample(times)
    for name in ("R_ed", "w_ed", "dw_ed"):
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=0, atol=1e-12)


def test_waypoints_pose_and_heading_at_the_waypoints():
    params = pick_and_place()
    source = reference_of(params, None)
    move = params.waypoints.points[5]
    at = source.evaluate(move.time)
    c = math.cos(move.ee_rpy[2])
    s = math.sin(move.ee_rpy[2])
    assert np.allclose(at.R_ed, [[c, -s, 0], [s, c, 0], [0, 0, 1]], atol=1e-12)
    assert np.allclose(at.b1d[0], [c, s, 0], atol=1e-12)
    # Rule (33): the CoM is the end effector's position plus R3(heading) r_o.
    r_o = np.array(params.com_offset)
    assert np.allclose(at.com[0], at.p_ed + [c * r_o[0] - s * r_o[1], s * r_o[0] + c * r_o[1],
                                             r_o[2]], atol=1e-12)


def test_waypoints_through_given_velocities():
    params = pick_and_place()
    points = [dataclasses.replace(w, heading=math.nan) for w in params.waypoints.points]
    points[5] = dataclasses.replace(points[5], ee_velocity=[-0.1, 0.2, 0.0],
                                    ee_angular_velocity=[0.0, 0.1, 0.3])
    params = dataclasses.replace(params, waypoints=dataclasses.replace(
        params.waypoints, points=points, heading="along_path"))
    source = reference_of(params, None)
    t = points[5].time
    at = source.evaluate(t)
    assert np.allclose(at.v_ed, [-0.1, 0.2, 0.0], atol=1e-12)
    assert np.allclose(at.w_ed, [0.0, 0.1, 0.3], atol=1e-12)
    assert_derivatives_consistent(source, [t - 3e-5, t + 3e-5, t - 0.7, t + 0.4])


def test_hover_is_constant_with_zero_derivatives():
    params = TrajectoryParams(kind="hover", hover=HoverParams(
        ee_position=[0.7, 0.1, 1.0], ee_rpy=[0.1, -0.2, 0.3], heading=0.4))
    ref = reference_of(params, None).sample(np.array([0.0, 3.0, 7.5]))
    assert np.allclose(ref.p_ed, [0.7, 0.1, 1.0]) and np.all(ref.com[:, 1:] == 0)
    assert np.all(ref.w_ed == 0) and np.all(ref.b1d[:, 1:] == 0)
    assert np.allclose(ref.b1d[:, 0], [math.cos(0.4), math.sin(0.4), 0.0])


def test_paper_kind_through_the_entry_point_is_the_paper_kernel_bit_for_bit():
    params = load_scenario("nominal").trajectory
    times = np.linspace(0.0, 15.0, 301)
    a = reference_of(params, None).sample(times).to_vectors()
    b = paper.sample_reference(params, times).to_vectors()
    for x, y in zip(a, b):
        assert np.array_equal(x, y)
    with pytest.raises(ValueError, match="reference_of"):
        paper.sample_reference(pick_and_place(), times)


USER_MODULE = '''
import numpy as np
from pydrake.trajectories import PiecewisePolynomial
from aerial_drake.trajectories.reference import ReferenceSample

W = 0.8

def circle(t, wrong=False):
    """The end effector on a circle of 0.2 m, CoM 0.5 m above it; analytic derivatives."""
    c, s = np.cos(W * t), np.sin(W * t)
    com = np.zeros((5, 3))
    for k in range(5):
        # d^k/dt^k [0.2 cos, 0.2 sin] = 0.2 W^k [cos(Wt + k pi/2), sin(Wt + k pi/2)]
        a = W * t + k * np.pi / 2
        com[k, :2] = 0.2 * W ** k * np.array([np.cos(a), np.sin(a)])
    com[0] += [0.6, 0.0, 1.8]
    p = com[:3].copy()
    p[0, 2] = 1.3
    if wrong:
        com[4] *= 1.5  # a snap that is not the jerk's rate
    return ReferenceSample(com=com, p_ed=p[0], v_ed=p[1], a_ed=p[2], R_ed=np.eye(3),
                           w_ed=np.zeros(3), dw_ed=np.zeros(3), q_jd=np.zeros(1),
                           q_jd_dot=np.zeros(1), q_jd_ddot=np.zeros(1),
                           b1d=np.array([[1.0, 0, 0], [0, 0, 0], [0, 0, 0]]))

def breaks_later(t):
    if t > 2.0:
        raise ZeroDivisionError("no path after 2 s")
    return circle(t)

def wrong_snap(t):
    return circle(t, wrong=True)

def drake_paths():
    times = np.linspace(0.0, 20.0, 21)
    x = np.vstack([0.6 + 0.1 * np.sin(0.3 * times), 0.1 * np.cos(0.3 * times), 1.8 + 0 * times])
    # Cubic splines: their jerk and snap jump at the knots.
    return {"com": PiecewisePolynomial.CubicShapePreserving(times, x),
            "ee_position": PiecewisePolynomial.FirstOrderHold(times, x - [[0], [0], [0.5]])}

def smooth_paths():
    # Polynomials of degree 6 through time: every derivative smooth.
    from pydrake.trajectories import BsplineTrajectory
    from pydrake.math import BsplineBasis, KnotVectorType
    basis = BsplineBasis(7, 14, KnotVectorType.kClampedUniform, 0.0, 20.0)
    pts = [np.array([[0.6 + 0.05 * np.sin(i)], [0.05 * np.cos(i)], [1.8]]) for i in range(14)]
    rot = [np.array([[0.1 * np.sin(i)], [0.05 * i / 14], [0.2]]) for i in range(14)]
    q = [np.array([[0.1 * np.sin(0.5 * i)]]) for i in range(14)]
    head = [np.array([[0.02 * i]]) for i in range(14)]
    return {"com": BsplineTrajectory(basis, pts),
            "ee_position": BsplineTrajectory(basis, [p - [[0], [0], [0.5]] for p in pts]),
            "ee_rotation_vector": BsplineTrajectory(basis, rot),
            "joints": BsplineTrajectory(basis, q), "heading": BsplineTrajectory(basis, head)}
'''


@pytest.fixture
def user_module(tmp_path):
    (tmp_path / "user_paths.py").write_text(textwrap.dedent(USER_MODULE))
    yield tmp_path
    sys.modules.pop("user_paths", None)
    if str(tmp_path) in sys.path:
        sys.path.remove(str(tmp_path))


def _python_scenario(tmp_path, function: str):
    """The nominal scenario with its trajectory section replaced by a python kind's."""
    base = shipped_scenarios()["nominal"].read_text()
    start = base.index("trajectory:")
    end = base.index("\n# The start")
    section = ("trajectory:\n  kind: python\n  joint_targets: [0.0]\n  python:\n"
               f"    function: '{function}'\n    path: .\n")
    path = tmp_path / "user_scenario.yaml"
    path.write_text(base[:start] + section + base[end:])
    return path


def test_python_function_kind_loads_and_its_derivatives_are_rates(user_module):
    params = TrajectoryParams(kind="python", python=PythonParams(
        function="user_paths:circle", path=str(user_module)))
    source = reference_of(params, None)
    assert_derivatives_consistent(source, np.linspace(0.1, 9.0, 13))
    scenario = load_scenario(_python_scenario(user_module, "user_paths:circle"))
    assert scenario.trajectory.python.path == str(user_module)


def test_python_function_with_a_wrong_derivative_is_refused_at_load(user_module):
    with pytest.raises(ScenarioError) as err:
        load_scenario(_python_scenario(user_module, "user_paths:wrong_snap"))
    message = str(err.value)
    assert "x_d''''" in message and "t = " in message and "user_paths:wrong_snap" in message
    assert "is not the rate of the signal below it" in message


def test_python_drake_trajectories_of_too_low_a_degree_are_refused_at_load(user_module):
    with pytest.raises(ScenarioError) as err:
        load_scenario(_python_scenario(user_module, "user_paths:drake_paths"))
    message = str(err.value)
    assert "jumps at t = " in message, message


def test_python_drake_trajectories_smooth_enough_load_with_consistent_derivatives(user_module):
    params = TrajectoryParams(kind="python", python=PythonParams(
        function="user_paths:smooth_paths", path=str(user_module)))
    source = reference_of(params, None)
    assert_derivatives_consistent(source, np.linspace(0.3, 19.0, 11))
    load_scenario(_python_scenario(user_module, "user_paths:smooth_paths"))


@pytest.mark.parametrize("edit, field, words", [
    (("time: 5.0", "time: 3.0"), "trajectory.waypoints.points[3].time", "later than"),
    (("kind: waypoints", "kind: spline"), "trajectory.kind", "one of"),
    (("heading: 1.5708}", "}"), "trajectory.waypoints.points[5].heading", "heading: given"),
    (("ee_rpy: [0.0, 0.0, 1.5708], heading: 1.5708}\n      # descend",
      "ee_rpy: [0.0, 0.0, 3.1], heading: 1.5708}\n      # descend"),
     "trajectory", "insert a waypoint between"),
])
def test_bad_waypoints_are_refused_at_load_naming_the_field(tmp_path, edit, field, words):
    text = shipped_scenarios()["pick_and_place"].read_text()
    assert edit[0] in text
    path = tmp_path / "bad.yaml"
    path.write_text(text.replace(edit[0], edit[1], 1))
    with pytest.raises(ScenarioError) as err:
        load_scenario(path)
    assert err.value.field == field, str(err.value)
    assert words in str(err.value) and str(path) in str(err.value)


def test_a_user_function_returning_wrong_shapes_is_named(tmp_path):
    (tmp_path / "bad_paths.py").write_text("def f(t):\n    return 3.0\n")
    params = TrajectoryParams(kind="python", python=PythonParams(function="bad_paths:f",
                                                                 path=str(tmp_path)))
    try:
        with pytest.raises(ValueError, match="bad_paths:f.*not a ReferenceSample"):
            reference_of(params, None)
    finally:
        sys.modules.pop("bad_paths", None)


def test_drake_trajectory_dict_rows_checked():
    with pytest.raises(ValueError, match="'com' is 2 x 1, expected 3 x 1"):
        from aerial_drake.trajectories.python_kind import DrakeTrajectoriesReference
        DrakeTrajectoriesReference(
            {"com": PiecewisePolynomial(np.zeros((2, 1))),
             "ee_position": PiecewisePolynomial(np.zeros((3, 1)))}, np.zeros(1))


def test_python_function_that_raises_during_the_run_is_refused_at_load(user_module):
    with pytest.raises(ScenarioError) as err:
        load_scenario(_python_scenario(user_module, "user_paths:breaks_later"))
    message = str(err.value)
    assert "ZeroDivisionError: no path after 2 s" in message and "failed while sampled" in message
    assert err.value.field == "trajectory.python.function"


# ---- the registry of kinds ---------------------------------------------------------------------


def test_every_kind_is_one_registry_entry_and_the_docs_list_each():
    """The registry names the kinds validation accepts, the section each reads, and the docs'
    table lists exactly those."""
    assert KINDS == tuple(REFERENCE_KINDS) == ("paper", "hover", "waypoints", "python")
    for name, kind in REFERENCE_KINDS.items():
        assert kind.section is None or dataclasses.is_dataclass(
            getattr(TrajectoryParams(), kind.section)), name
    docs = (Path(__file__).parents[2] / "docs" / "trajectories.md").read_text()
    listed = re.findall(r"^\| `(\w+)`", docs, flags=re.MULTILINE)
    assert tuple(listed) == KINDS


def test_an_unknown_kind_is_refused_listing_the_registry():
    with pytest.raises(ValueError, match="'kind' must be one of.*'paper', 'hover', 'waypoints', "
                                         "'python'.*got 'spline'"):
        reference_of(TrajectoryParams(kind="spline"), None)


def test_a_kind_reads_only_its_own_section():
    """A bad section of another kind does not stop the paper kind (each reads its own)."""
    params = TrajectoryParams(hover=HoverParams(heading=math.nan))
    validate_trajectory(params)
    with pytest.raises(ValueError, match="'hover.heading'"):
        validate_trajectory(dataclasses.replace(params, kind="hover"))


def test_reference_of_builds_by_the_registry_and_validates_once(monkeypatch):
    """One build: the section checked once (the constructors do not check again), the
    registry's constructor called once with the joint targets."""
    calls = {"errors": 0, "section": 0, "build": []}
    hover = REFERENCE_KINDS["hover"]
    shared_errors, section_errors = TrajectoryParams.errors, HoverParams.errors

    def count_shared(self):
        calls["errors"] += 1
        return shared_errors(self)

    def count_section(self, n_joints=None, prefix="hover."):
        calls["section"] += 1
        return section_errors(self, n_joints, prefix)

    def build(params, targets):
        calls["build"].append(targets.copy())
        return hover.build(params, targets)

    monkeypatch.setattr(TrajectoryParams, "errors", count_shared)
    monkeypatch.setattr(HoverParams, "errors", count_section)
    monkeypatch.setitem(REFERENCE_KINDS, "hover", dataclasses.replace(hover, build=build))
    source = reference_of(TrajectoryParams(kind="hover"), np.array([0.25, -0.5]))
    assert calls["errors"] == 1 and calls["section"] == 1
    assert len(calls["build"]) == 1
    np.testing.assert_array_equal(calls["build"][0], [0.25, -0.5])
    np.testing.assert_array_equal(source.evaluate(3.0).q_jd, [0.25, -0.5])


def test_waypoint_joints_are_checked_against_the_task_once():
    """The task's joint count reaches the one validation: a waypoint's joints of the wrong
    length are named there, not by the constructor afterwards."""
    params = pick_and_place()
    points = [dataclasses.replace(w, joints=[0.0, 0.0]) for w in params.waypoints.points]
    params = dataclasses.replace(params, joint_targets=[], waypoints=dataclasses.replace(
        params.waypoints, points=points))
    with pytest.raises(ValueError, match=r"Invalid TrajectoryParams: 'waypoints.points\[0\]."
                                         r"joints' must be a list of 1 floats"):
        reference_of(params, [0.0])
    reference_of(params, [0.1, 0.2])


@pytest.mark.parametrize("kind", [["paper"], {"a": 1}, 3, None])
def test_a_kind_that_is_not_text_is_named_not_a_crash(kind):
    params = dataclasses.replace(TrajectoryParams(), kind=kind)
    with pytest.raises(ValueError, match="'kind' must be one of"):
        validate_trajectory(params)
