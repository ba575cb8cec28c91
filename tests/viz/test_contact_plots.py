"""contact.png (aerial_drake.viz.contact_plots): written for a run with an environment, and
drawn from the run's own logs (the force panel holds the logged pressing force)."""

import numpy as np

from aerial_drake.simulation.contact import contact_slices
from aerial_drake.simulation.run_folder import load_run
from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import load_scenario
from aerial_drake.viz.contact_plots import CONTACT_FIGURE, figure_contact
from aerial_drake.viz.run_plots import write_run_figures


def test_wall_press_writes_its_contact_figure_from_its_log(tmp_path):
    scenario = load_scenario("wall_press", overrides={"duration": 4.5})  # touch at 3.83 s
    run_scenario(scenario, out_dir=tmp_path / "run", progress=False)
    files = write_run_figures(tmp_path / "run")
    assert (tmp_path / "run" / f"{CONTACT_FIGURE}.png") in files
    run = load_run(tmp_path / "run")
    fig = figure_contact(run)
    force_axes = fig.axes[0]
    lines = {line.get_label(): line for line in force_axes.get_lines()}
    true = lines["true (Drake's contact)"].get_ydata()
    logged = -run.log["contact_wrench"][:, contact_slices()["force"]] @ [1.0, 0.0, 0.0]
    np.testing.assert_array_equal(true, logged)
    assert true.max() > 5.0  # pressing by the end
    assert len(fig.axes) == 5  # four panels and the friction ratio's twin axis
