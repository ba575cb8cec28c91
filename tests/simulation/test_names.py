"""Public names say ``vehicle`` (any vehicle, not only the paper's helicopter): the earlier
``helicopter`` names still answer, each with a FutureWarning naming today's. A run's log
stores one label per task row."""

import warnings

import pytest

from aerial_drake.simulation.diagram import build_closed_loop
from aerial_drake.simulation.scenarios import load_scenario


def test_the_closed_loop_port_is_vehicle_wrench_and_the_old_name_warns():
    loop = build_closed_loop(load_scenario("nominal", overrides={"duration": 0.1}))
    assert "vehicle_wrench" in loop.inputs and "helicopter_wrench" not in loop.inputs
    assert loop.diagram.HasInputPort("vehicle_wrench")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        port = loop.input_port("vehicle_wrench")  # today's name: no warning
    with pytest.warns(FutureWarning, match="'helicopter_wrench' is now 'vehicle_wrench'"):
        old = loop.input_port("helicopter_wrench")
    assert old.get_index() == port.get_index()
    with pytest.raises(KeyError, match="vehicle_wrench"):
        loop.input_port("rotor_wrench")


def test_a_run_stores_its_task_labels_with_the_log(tmp_path):
    import json

    import numpy as np

    from aerial_drake.simulation.runner import run_scenario
    result = run_scenario(load_scenario("nominal", overrides={"duration": 0.01}),
                          out_dir=tmp_path, progress=False)
    expected = ("p_x", "p_y", "p_z", "o_x", "o_y", "o_z")
    assert result.task_labels[:6] == expected and len(result.task_labels) == 7
    layout = json.loads(str(np.load(tmp_path / "log.npz")["layout"]))
    assert tuple(layout["task"]) == result.task_labels
