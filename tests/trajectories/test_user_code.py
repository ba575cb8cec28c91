"""The user's trajectory code at load (``kind: python``): whatever it raises at t = 0, or a
function that never returns, is refused naming ``python.function`` and the cause, exit 2 on
the command line (issue 27), and the time limit leaves no timer or handler behind."""

import signal
import sys
import textwrap

import pytest

from aerial_drake import cli
from aerial_drake.simulation.scenarios import ScenarioError, load_scenario, shipped_scenarios
from aerial_drake.simulation.scenarios import trajectory as scenario_trajectory
from aerial_drake.trajectories import python_kind
from aerial_drake.trajectories.time_limit import TimeLimitExceeded, time_limit

USER_MODULE = '''
import numpy as np
from aerial_drake.trajectories.reference import ReferenceSample

def hold(t):
    com = np.zeros((5, 3))
    com[0] = [0.6, 0.0, 1.8]
    return ReferenceSample(com=com, p_ed=np.array([0.6, 0.0, 1.3]), v_ed=np.zeros(3),
                           a_ed=np.zeros(3), R_ed=np.eye(3), w_ed=np.zeros(3),
                           dw_ed=np.zeros(3), q_jd=np.zeros(1), q_jd_dot=np.zeros(1),
                           q_jd_ddot=np.zeros(1), b1d=np.array([[1.0, 0, 0], [0, 0, 0],
                                                                [0, 0, 0]]))

def raises_at_start(t):
    return {}["no such key"]

def maker_raises():
    raise RuntimeError("no config file")

def never_returns(t):
    while True:
        try:
            pass
        except Exception:  # a user's catch-all must not swallow the time limit
            pass

def hangs_later(t):
    while t > 0.5:
        pass
    return hold(t)
'''


@pytest.fixture
def user_module(tmp_path):
    (tmp_path / "slow_paths.py").write_text(textwrap.dedent(USER_MODULE))
    yield tmp_path
    sys.modules.pop("slow_paths", None)
    if str(tmp_path) in sys.path:
        sys.path.remove(str(tmp_path))


def _scenario(folder, function: str):
    """The nominal scenario with a python kind's trajectory section, 1 s long."""
    base = shipped_scenarios()["nominal"].read_text()
    start, end = base.index("trajectory:"), base.index("\n# The start")
    section = ("trajectory:\n  kind: python\n  joint_targets: [0.0]\n  python:\n"
               f"    function: '{function}'\n    path: .\n")
    path = folder / "user_scenario.yaml"
    path.write_text(base[:start] + section + base[end:])
    return path


@pytest.mark.parametrize("function, words", [
    ("slow_paths:raises_at_start", "raised KeyError at t = 0: 'no such key'"),
    ("slow_paths:maker_raises", "raised RuntimeError: no config file"),
])
def test_a_function_raising_at_load_is_named(user_module, function, words):
    with pytest.raises(ScenarioError) as err:
        load_scenario(_scenario(user_module, function))
    assert err.value.field == "trajectory.python.function"
    assert function in str(err.value) and words in str(err.value), str(err.value)


def test_the_command_line_exits_2_naming_the_function_and_its_error(user_module, capsys):
    path = _scenario(user_module, "slow_paths:raises_at_start")
    status = cli.main(["run", str(path), "--out", str(user_module / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert status == 2, err
    assert "slow_paths:raises_at_start" in err and "KeyError" in err
    assert "unexpected" not in err and "Traceback" not in err


def test_a_function_that_never_returns_at_t0_is_stopped(user_module, monkeypatch):
    monkeypatch.setattr(python_kind, "LOAD_TIME_LIMIT", 0.3)
    with pytest.raises(ScenarioError) as err:  # (it returns at all only through the limit)
        load_scenario(_scenario(user_module, "slow_paths:never_returns"))
    message = str(err.value)
    assert err.value.field == "trajectory.python.function"
    assert "slow_paths:never_returns" in message and "did not return within 0.3 s" in message
    assert signal.getsignal(signal.SIGALRM) is signal.SIG_DFL
    assert signal.getitimer(signal.ITIMER_REAL) == (0.0, 0.0)


def test_a_function_that_hangs_later_is_stopped_by_the_sampling_limit(user_module, capsys,
                                                                     monkeypatch):
    monkeypatch.setattr(scenario_trajectory, "SAMPLING_TIME_LIMIT", 0.5)
    path = _scenario(user_module, "slow_paths:hangs_later")
    status = cli.main(["run", str(path), "--out", str(user_module / "out"), "--quiet",
                       "--duration", "1"])
    err = capsys.readouterr().err
    assert status == 2, err
    assert "slow_paths:hangs_later" in err and "within 0.5 s" in err, err


def test_time_limit_restores_the_outer_timer_and_handler():
    fired = []
    previous = signal.signal(signal.SIGALRM, lambda *a: fired.append(1))
    try:
        signal.setitimer(signal.ITIMER_REAL, 5.0)
        with pytest.raises(TimeLimitExceeded, match="inner did not return within 0.05 s"):
            with time_limit(0.05, "inner"):
                while True:
                    pass
        left, _ = signal.getitimer(signal.ITIMER_REAL)
        assert 4.0 < left <= 5.0  # the outer timer, less the time spent inside
        assert not fired
        with time_limit(1.0, "quick"):
            pass
        assert signal.getitimer(signal.ITIMER_REAL)[0] > 3.0
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)
