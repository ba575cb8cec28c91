"""Meshcat shows the scenario's environment beside the robot (docs/world.md)."""

from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import load_scenario, shipped_scenarios
from aerial_drake.viz import meshcat_view as dut

WALL = """
environment:
  directives:
  - add_model:
      name: wall
      file: package://aerial_drake/environments/wall.sdf
  - add_weld:
      parent: world
      child: wall::wall
      X_PC:
        translation: [3.6, 0.0, 1.5]
"""


def test_meshcat_draws_the_wall(tmp_path):
    path = tmp_path / "wall.yaml"
    path.write_text(shipped_scenarios()["nominal"].read_text() + WALL)
    scenario = load_scenario(path, overrides={"duration": 0.05})
    view = dut.MeshcatView(scenario, port=0, live=False)
    run_scenario(scenario, progress=False, configure=view.configure)
    assert view.meshcat.HasPath(f"{dut.ROBOT_PREFIX}/wall/wall")
    assert view.meshcat.HasPath(f"{dut.ROBOT_PREFIX}/helicopter/helicopter")
