"""The shipped contact scenarios (issue 30; docs/contact.md), flown whole: the force held, no
contact lost, the motion across the push tracked. Each bound is within 3x of the figure
measured when the scenarios were written (docs/contact.md, "The figures"), and inside the
issue's goal (force within 5 % on the wall, 10 % on the table; path within 5 mm)."""

import numpy as np
import pytest

from aerial_drake.simulation.contact import contact_slices
from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import load_scenario

# name: (force_error_max_rel, tangential_error_max_m, slip_m bound (press) or None (slide)),
# each 3x the figure measured 2026-12-05 (drake 1.51.1): wall_press 0.00114, 0.16 mm,
# 0.12 mm; surface_slide 0.0027, 0.24 mm; quadrotor_ur3e_wall_press 0.0037, 0.38 mm, 0.65 mm;
# quadrotor_ur3e_surface_slide 0.0044, 1.47 mm.
BOUNDS = {
    "wall_press": (0.0034, 0.5e-3, 0.36e-3),
    "surface_slide": (0.008, 0.72e-3, None),
    "quadrotor_ur3e_wall_press": (0.011, 1.15e-3, 1.8e-3),
    "quadrotor_ur3e_surface_slide": (0.013, 4.4e-3, None),
}


@pytest.fixture(scope="module", params=sorted(BOUNDS))
def flown(request):
    scenario = load_scenario(request.param)
    return request.param, scenario, run_scenario(scenario, progress=False)


def test_force_task_goals(flown):
    name, scenario, result = flown
    assert result.completed, result.failure
    c = result.metrics["contact"]
    force_bound, path_bound, slip_bound = BOUNDS[name]
    assert c["force_error_max_rel"] <= force_bound
    assert c["contact_lost_s"] == 0.0 and c["contact_transitions"] == 0
    assert c["tangential_error_max_m"] <= path_bound
    if slip_bound is not None:  # a press: the pad stays put
        assert c["slip_m"] <= slip_bound
    else:  # a slide: 0.5 m along y
        assert c["slip_m"] == pytest.approx(0.5, abs=5e-3)
    assert not result.metrics["joint_limits_exceeded"]
    # The touch is gentle (the force never far past the desired one) and released at the end.
    assert c["peak_pressing_force_N"] <= 1.1 * c["force_desired_N"]
    assert c["contact_transitions_run"] == 2


def test_contact_wrench_agrees_with_the_sensor_and_the_task(flown):
    """The logged true wrench, the sensor's measurement and the controller's reading of it
    tell the same story over the hold."""
    name, scenario, result = flown
    log, t = result.log, result.log["t"]
    task = scenario.controller.force
    d = np.asarray(task.unit_direction())
    h0, h1 = task.hold()
    hold = (t >= h0 + 1.0) & (t <= h1)
    true = -log["contact_wrench"][:, contact_slices()["force"]] @ d
    measured = -log["measured_contact_force"] @ d
    # The sensor: the true force filtered (200 Hz) with 0.05 N noise per axis.
    assert np.abs(measured[hold] - true[hold]).max() < 0.3
    assert abs(np.mean(measured[hold] - true[hold])) < 0.01
    # The contact point is on the surface: the wall's face x = 1.0, the table's top z = 0.75.
    point = log["contact_wrench"][:, contact_slices()["point"]][hold]
    axis, face = (0, 1.0) if "wall" in name else (2, 0.75)
    assert np.abs(point[:, axis] - face).max() < 1e-3
