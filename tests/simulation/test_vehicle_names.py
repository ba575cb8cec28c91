"""Public names say ``vehicle`` (any vehicle, not only the paper's helicopter); the earlier
``helicopter`` names still answer, each with a FutureWarning naming today's."""

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
