"""Gain design help (aerial_drake.control.gain_design and the load-time check of
aerial_drake.simulation.scenarios.gain_check): the loops' roots, the warning Table II's gains
get on the paper's robot, and none for gains whose attitude loop is 3x faster; each robot
with its own mass."""

import warnings

import numpy as np
import pytest

from aerial_drake.control import gain_design as dut
from aerial_drake.simulation.diagram import build_closed_loop
from aerial_drake.simulation.scenarios import load_scenario

TABLE_II = dict(K_x=[800.0] * 3, D_x=[420.0] * 3, k_R=250.0, k_w=200.0,
                attitude_inertia=[1.46, 0.36, 1.46])


def test_table_ii_roots_are_docs_control_md_s():
    """m = 54.8 kg: CoM -3.538, -4.126; attitude -1.2616, -135.7 (b1, b3) and -1.2528,
    -554.3 (b2) 1/s (docs/control.md; docs/analysis.md's linearisation finds the same)."""
    roots = dut.loop_roots(54.8, **TABLE_II)
    np.testing.assert_allclose(roots.com[0], [-3.5379, -4.1263], atol=1e-4)
    np.testing.assert_allclose(roots.attitude[0], [-1.2616, -135.7247], atol=1e-4)
    np.testing.assert_allclose(roots.attitude[1], [-1.2528, -554.303], atol=1e-3)
    assert roots.slowest_com == pytest.approx(-3.5379, abs=1e-4)
    assert roots.slowest_attitude == pytest.approx(-1.2528, abs=1e-4)
    assert roots.separation == pytest.approx(1.2528 / 3.5379, rel=1e-4)


def test_the_suggested_gains_separate_the_loops():
    """Either suggestion of the message (a faster attitude loop, or a slower CoM loop)
    passes the check, and the other loop's roots are unchanged."""
    roots = dut.loop_roots(54.8, **TABLE_II)
    k_R, k_w = dut.suggested_attitude_gains(roots)
    faster = dut.loop_roots(54.8, **{**TABLE_II, "k_R": k_R, "k_w": k_w})
    assert faster.fast_enough() and dut.gain_design_message(faster, "") is None
    assert 3.0 <= faster.separation < 3.3
    K_x, D_x = dut.suggested_com_gains(roots)
    slower = dut.loop_roots(54.8, **{**TABLE_II, "K_x": [K_x] * 3, "D_x": [D_x] * 3})
    assert slower.fast_enough() and 3.0 <= slower.separation < 3.3


def test_table_ii_on_the_paper_robot_warns_at_load_naming_the_roots():
    with pytest.warns(dut.GainDesignWarning) as caught:
        load_scenario("nominal")
    message = str(caught[0].message)
    for needle in ("-1.253 1/s", "-3.538 1/s", "m = 54.8 kg", "-1.262, -135.7",
                   "-1.253, -554.3", "-3.538, -4.126", "gains.Lambda2_bar", "k_R = ",
                   "k_w = ", "K_x = ", "D_x = "):
        assert needle in message, (needle, message)


def test_gains_with_an_attitude_loop_3x_faster_do_not_warn():
    roots = dut.loop_roots(54.8, **TABLE_II)
    k_R, k_w = dut.suggested_attitude_gains(roots)
    with warnings.catch_warnings():
        warnings.simplefilter("error", dut.GainDesignWarning)
        load_scenario("nominal", overrides={"gains.k_R": k_R, "gains.k_w": k_w})


def test_each_robot_is_checked_with_its_own_mass():
    """The quadrotor with a UR3e (30.16 kg, its own Lambda2_bar) keeps Table II's poles by
    scaled gains: it warns with its own mass and inertia, not the helicopter's."""
    with pytest.warns(dut.GainDesignWarning) as caught:
        load_scenario("quadrotor_ur3e")
    message = str(caught[0].message)
    assert "m = 30.16 kg" in message and "[1.74, 1.65, 2.35]" in message, message
    assert "54.8" not in message


def test_the_baselines_are_checked_with_the_inertia_their_vehicle_law_assumes():
    """Their attitude loop is J s^2 + k_w s + k_R with the robot locked at its start (about
    its CoM), not Lambda2_bar."""
    scenario = load_scenario("nominal", overrides={"controller.type": "uncoupled"})
    # Checked where the registry builds the baseline: the locked inertia needs the run's
    # reference (a check at load built a second reference and model for it).
    with pytest.warns(dut.GainDesignWarning) as caught:
        build_closed_loop(scenario)
    message = str(caught[0].message)
    assert "locked at its start" in message and "Lambda2_bar" not in message, message
