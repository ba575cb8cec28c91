"""``robot check`` (aerial_drake.analysis.onboarding.check) on the 4-joint robot of
tests/own_robot.py with a hover scenario beside its description: the report, the static
equilibrium under a push (the CoM moves, the end effector stays), the errors for missing
files, and one push margin against the simulation."""

import json
import warnings

import numpy as np
import pytest

from aerial_drake import cli
from aerial_drake.analysis.onboarding import OnboardingError, check_robot, format_check
from aerial_drake.analysis.onboarding.check import com_compliance
from aerial_drake.analysis.onboarding.check_subject import load_subject
from aerial_drake.analysis.onboarding.loaded_rest import RestLoop
from aerial_drake.analysis.onboarding.push_validation import simulate_push
from aerial_drake.control.gain_design import GainDesignWarning
from tests.own_robot import SCENARIO, write_robot

#: The directions of the force margins checked here.
DIRECTIONS = ("+y", "-y", "-z")
#: The hover point: the CoM at 1.5 m, the end effector at the nominal offset below it.
HOVER = """trajectory:
  kind: hover
  com_offset: [0.186, 0.0, 0.583]
  hover: {ee_position: [0.0, 0.0, 0.917]}
initial:
"""


def hover_scenario_text() -> str:
    """tests/own_robot.py's scenario with its gains and ``trajectory: kind: hover``."""
    text = SCENARIO.format(duration=1.0)
    head, _, rest = text.partition("trajectory:")
    _, _, tail = rest.partition("\ninitial:\n")
    return head + HOVER + tail


@pytest.fixture(scope="module")
def robot(tmp_path_factory):
    """(description, its quad_arm_hover.yaml)."""
    folder = tmp_path_factory.mktemp("own_robot")
    description, _ = write_robot(folder)
    hover = folder / "quad_arm_hover.yaml"
    hover.write_text(hover_scenario_text())
    return description, hover


@pytest.fixture(scope="module")
def report(robot):
    """The check of the description (gains and hover from quad_arm_hover.yaml beside it);
    the force margins along +y, -y and -z only, no end-effector torques (each search costs
    about a second)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GainDesignWarning)  # the report says it
        return check_robot(robot[0], torques=False, directions=DIRECTIONS)


def test_the_report_holds_every_margin(report, robot):
    subject = report.subject
    assert subject.scenario_source == str(robot[1])
    assert subject.model.n == 4 and subject.mass == pytest.approx(5.2)
    # sigma_min(J_3) at the nominal posture, well above the default limit.
    assert report.rest.ok and report.rest.sigma_min > 10 * report.sigma_limit
    assert [r.direction for r in report.reach] == ["+x", "-x", "+y", "-y", "+z", "-z"]
    for r in report.reach:
        assert 0.0 < r.distance < 1.0 and r.binding and not r.capped
    # The symmetric arm (roll, pitch, pitch, wrist yaw, in the x-z plane): +y and -y alike.
    assert report.reach[2].distance == pytest.approx(report.reach[3].distance, abs=2e-3)
    for margins in (report.push, report.ee_force):
        assert [m.direction for m in margins] == list(DIRECTIONS)
        for m in margins:
            assert m.largest > 0 and m.binding and m.state is not None and m.state.ok
    assert report.push[0].largest == pytest.approx(report.push[1].largest, rel=0.02)
    assert report.ee_torque == []
    assert len(report.roots) == 2 * (6 + 4)
    # Table-II-like gains on this robot: the attitude root is slower than the CoM's.
    assert report.loop_roots.separation < 1.0
    assert any("attitude loop" in w for w in report.warnings)
    json.dumps(report.to_json(), allow_nan=False)  # strict JSON
    text = format_check(report)
    for phrase in ("sigma_min(J_3)", "reach of the end effector", "largest static push",
                   "largest force held at the end effector", " N, CoM moved", "past it:",
                   "closed-loop roots", "warnings:"):
        assert phrase in text


def test_a_push_moves_the_com_and_the_arm_holds_the_end_effector(report):
    """The static equilibrium under a push on the vehicle, far from every limit: along z the
    CoM settles F / K_x away (f_d's K_x x~ balances it: no tilt); along x, the one-axis
    model of docs/control.md, (1 + (Lbar2 K_x + k_w D_x) / (k_R m)) F / K_x (the law's
    feed-forwards miss F / m), 7.2x F / K_x here; the end effector stays (decoupling)."""
    subject = report.subject
    loop = RestLoop(subject)
    com0, ee0 = loop.com_and_ee(subject.q0)
    K_x = subject.scenario.gains.K_x[0]
    compliance = com_compliance(subject)
    assert compliance[0] * K_x == pytest.approx(7.24, abs=0.01)
    for force in (np.array([0.0, 0.0, -2.0]), np.array([0.3, 0.0, 0.0])):
        q, why = loop.equilibrium(loop.vehicle_push(np.zeros(3), force), subject.q0)
        assert q is not None, why
        com, ee = loop.com_and_ee(q)
        axis = int(np.argmax(np.abs(force)))
        assert (com - com0)[axis] == pytest.approx(compliance[axis] * force[axis], rel=0.02)
        assert np.linalg.norm(ee - ee0) < 2e-4  # m: the arm absorbs the CoM's move
        assert np.linalg.norm(com - com0) > 0.02
        assert loop.limits_at(q).ok


def test_the_push_margin_against_the_simulation(report):
    """Down (-z), where a limit a run stops on is reached with the binding one: the check's
    largest push, ramped slowly, survives with the CoM where the check puts it; 1.3 times it
    stops on joint j2's position limit, which the check finds at 98 % or more there (the
    binding limit, the task loop's speed, is within the search's 1 % of it)."""
    push = {m.direction: m for m in report.push}["-z"]
    assert push.state is not None
    assert push.state.usage["joint 'j2' position"] > 0.98
    down = np.array([0.0, 0.0, -1.0])
    held = simulate_push(report.subject, push.largest * down)
    assert held.survived, held.failure
    assert held.com_deflection_end == pytest.approx(np.linalg.norm(push.com_deflection),
                                                    rel=0.01)
    over = simulate_push(report.subject, 1.3 * push.largest * down)
    assert not over.survived and over.cause == "joint limit" and "j2" in over.failure


def test_a_description_without_its_hover_file_is_refused(tmp_path):
    description, scenario = write_robot(tmp_path)
    with pytest.raises(OnboardingError) as err:
        check_robot(description)
    message = str(err.value)
    assert str(tmp_path / "quad_arm_hover.yaml") in message
    assert "robot init" in message and "--scenario" in message
    with pytest.raises(OnboardingError, match="--scenario .*no such file"):
        check_robot(description, scenario=str(tmp_path / "missing.yaml"))
    with pytest.raises(OnboardingError, match="only for a robot description"):
        check_robot(scenario, scenario=str(scenario))
    with pytest.raises(OnboardingError, match="no such file"):
        check_robot(tmp_path / "nothing.yaml")


def test_the_command_line_says_which_file_is_missing(tmp_path, capsys):
    """``aerial-drake robot check`` on a description without its hover file: exit status 2
    and the message on stderr, no traceback."""
    description, _ = write_robot(tmp_path)
    assert cli.main(["robot", "check", str(description), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "quad_arm_hover.yaml" in err and "Traceback" not in err


def test_a_scenario_file_is_its_own_hover(robot):
    """FILE a scenario: its robot, gains and reference at t = 0."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GainDesignWarning)
        subject = load_subject(robot[1])
    assert subject.scenario_source == str(robot[1])
    np.testing.assert_allclose(subject.hover.com[0], [0.186, 0.0, 1.5], atol=1e-12)
    np.testing.assert_allclose(subject.hover.com[1:], 0.0)
    subject.model.plant.SetPositions(ctx := subject.model.plant.CreateDefaultContext(),
                                     subject.q0)
    np.testing.assert_allclose(
        subject.model.plant.CalcCenterOfMassPositionInWorld(ctx), [0.186, 0.0, 1.5],
        atol=1e-9)
