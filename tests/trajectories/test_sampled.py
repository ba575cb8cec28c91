"""The python kind sampled once onto splines (trajectories/sampled.py): within its tolerance of
the user's function, as smooth as the law needs, and a function the splines cannot follow is
refused naming the field and the signal."""

import sys
import textwrap

import numpy as np
import pytest

from aerial_drake.simulation.scenarios import ScenarioError, load_scenario, shipped_scenarios
from aerial_drake.trajectories.continuity import find_discontinuity, knot_jumps
from aerial_drake.trajectories.kinds import reference_of
from aerial_drake.trajectories.params import PythonParams, TrajectoryParams
from aerial_drake.trajectories.sampled import (
    COM_SAMPLE_PERIOD,
    TOLERANCE,
    SampledReference,
    _signals,
)

USER_MODULE = '''
import numpy as np
from aerial_drake.trajectories.heading import heading_reference
from aerial_drake.trajectories.reference import ReferenceSample
from aerial_drake.trajectories.so3 import exp_so3, rotation_vector_rates

def _sin(t, w, a, orders):  # a sin(w t) and its derivatives
    return np.array([a * w ** k * np.sin(w * t + k * np.pi / 2) for k in range(orders)])

def reference(t, fast=0.0, wrong_velocity=False):
    """A CoM on a slow loop, the end effector below it turning about a changing axis, one
    joint and the heading moving: every derivative analytic. ``fast``: a 1 mm wiggle of
    that many rad/s on the CoM's x."""
    com = np.zeros((5, 3))
    com[:, 0] = _sin(t, 0.7, 0.2, 5) + (_sin(t, fast, 1e-3, 5) if fast else 0.0)
    com[:, 1] = _sin(t + 1.0, 0.5, 0.15, 5)
    com[:, 2] = _sin(t, 0.3, 0.05, 5)
    com[0] += [0.5, 0.0, 1.9]
    p = com[:3].copy()
    p[0] += [0.3, 0.0, -0.6]
    r = np.stack([_sin(t, 1.1, 0.3, 3)[:, None] * [1.0, 0.0, 0.0]
                  + _sin(t + 0.5, 0.8, 0.4, 3)[:, None] * [0.0, 0.6, 0.8]][0])
    R = exp_so3(r[0])
    omega, domega = rotation_vector_rates(r[0], r[1], r[2])
    q = _sin(t, 0.9, 0.25, 3)
    phi = _sin(t, 0.4, 0.6, 3)
    return ReferenceSample(
        com=com, p_ed=p[0], v_ed=0 * p[1] if wrong_velocity else p[1], a_ed=p[2], R_ed=R,
        w_ed=R @ omega, dw_ed=R @ domega, q_jd=q[:1], q_jd_dot=q[1:2], q_jd_ddot=q[2:],
        b1d=heading_reference(phi))

def too_fast(t):
    return reference(t, fast=400.0)

def wrong_velocity(t):
    return reference(t, wrong_velocity=True)
'''


@pytest.fixture
def user_module(tmp_path):
    (tmp_path / "sampled_paths.py").write_text(textwrap.dedent(USER_MODULE))
    yield tmp_path
    sys.modules.pop("sampled_paths", None)
    if str(tmp_path) in sys.path:
        sys.path.remove(str(tmp_path))


def _source(folder, name):
    return reference_of(TrajectoryParams(kind="python", joint_targets=[0.0], python=PythonParams(
        function=f"sampled_paths:{name}", path=str(folder))), None)


def test_sampled_reference_follows_the_function_within_its_tolerance(user_module):
    function = _source(user_module, "reference")
    sampled = function.for_run(6.0)
    assert isinstance(sampled, SampledReference)
    assert sampled.max_relative_error <= TOLERANCE
    times = np.linspace(0.0, 6.0, 2501)  # between the knots as much as on them
    exact, approx = function.packed(times), sampled.packed(times)
    for name, index in _signals(1):
        scale = max(1.0, np.abs(exact[:, index]).max())
        assert np.abs(approx[:, index] - exact[:, index]).max() <= TOLERANCE * scale, name
    # The same splines for the same function and duration (the load check's and the run's).
    assert function.for_run(6.0) is sampled
    assert _source(user_module, "reference").for_run(6.0) is sampled


def test_sampled_reference_is_as_smooth_as_the_law_needs(user_module):
    sampled = _source(user_module, "reference").for_run(3.0)
    # C^4 x_d, C^2 task and b1d across the knots (the CoM's are every 5th), and each
    # derivative the rate of the one below.
    assert knot_jumps(sampled.sample, sampled.knots[1:-1:3]) == []
    assert find_discontinuity(sampled.sample, np.linspace(0.0, 3.0, 1201)) is None


# The signal named is the chain's worst: the CoM's, or the end effector's (p_ed, v_ed, a_ed).
@pytest.mark.parametrize("name, signal", [("too_fast", "x_d"), ("wrong_velocity", "_ed ")])
def test_a_function_the_splines_cannot_follow_is_refused_naming_the_field(user_module, name,
                                                                          signal):
    with pytest.raises(ValueError) as err:
        _source(user_module, name).for_run(2.0)
    message = str(err.value)
    assert f"'python.function' 'sampled_paths:{name}'" in message
    assert f"{signal}" in message and "t = " in message and "tolerance" in message, message


def test_the_refusal_names_the_field_at_load(user_module):
    base = shipped_scenarios()["nominal"].read_text()
    start, end = base.index("trajectory:"), base.index("\n# The start")
    section = ("trajectory:\n  kind: python\n  joint_targets: [0.0]\n  python:\n"
               "    function: 'sampled_paths:too_fast'\n    path: .\n")
    path = user_module / "fast.yaml"
    path.write_text(base[:start] + section + base[end:].replace("duration: 15.0", ""))
    with pytest.raises(ScenarioError) as err:
        load_scenario(path, overrides={"duration": 1.0})
    assert err.value.field == "trajectory.python.function", str(err.value)
    # Let through by the load-time smoothness check at 10 ms; refused by the splines' bound.
    assert "sampled onto splines" in str(err.value) and "x_d" in str(err.value)


def test_com_knots_are_coarse_enough_for_its_fourth_derivative():
    # The CoM's snap from a segment of length T carries the samples' rounding times ~1/T^4:
    # at 0.1 s that is far below the tolerance (sampled.py).
    assert COM_SAMPLE_PERIOD >= 0.05
