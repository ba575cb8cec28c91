"""The force loop's and friction's checks before a contact run
(aerial_drake.simulation.contact_rates): each refusal from a concrete scenario, its bound
from the measured runs, and the shipped scenarios passing."""

import pytest
from pydrake.multibody.plant import CoulombFriction

from aerial_drake.simulation import contact_rates as dut
from aerial_drake.simulation.contact_checks import check_contact
from aerial_drake.simulation.diagram import build_closed_loop
from aerial_drake.simulation.scenarios import ScenarioError, load_scenario


def _check(name, **overrides):
    scenario = load_scenario(name, overrides=overrides or None)
    check_contact(scenario, build_closed_loop(scenario))


@pytest.mark.parametrize("name", ["wall_press", "surface_slide", "quadrotor_ur3e_wall_press",
                                  "quadrotor_ur3e_surface_slide"])
def test_shipped_contact_scenarios_pass(name):
    _check(name)


def test_drakes_default_stiction_tolerance_is_refused_naming_the_fix():
    """At Drake's 1e-4 m/s the helicopter's wall press flipped its tangential force every few
    steps (measured): c h / m = 0.24 * 10 / 1e-4 * 1e-3 / 3.29 = 7.3."""
    with pytest.raises(ScenarioError, match=r"c h / m = 7\.3") as err:
        _check("wall_press", **{"plant.stiction_tolerance": 1e-4})
    assert err.value.field == "plant.stiction_tolerance"
    assert "plant.stiction_tolerance >= 0.00073 m/s" in str(err.value)
    # The fix it names passes.
    _check("wall_press", **{"plant.stiction_tolerance": 0.00074})


def test_the_ur3e_light_wrist_needs_a_larger_tolerance():
    """Across the push the UR3e's pad has 0.089 kg apparent: 1e-3 m/s (it flipped, measured)
    is refused, the scenario's 0.03 passes (above)."""
    with pytest.raises(ScenarioError, match="apparent mass is 0.089"):
        _check("quadrotor_ur3e_wall_press", **{"plant.stiction_tolerance": 1e-3})


def test_the_discrete_plant_is_not_held_to_the_friction_bound():
    _check("wall_press", **{"plant.stiction_tolerance": 1e-4, "plant.time_step": 0.001,
                            "plant.discrete_contact_approximation": "sap"})


def test_a_force_loop_gain_past_one_is_refused():
    """k T / D = 3e4 N/m (the pad; the wall far stiffer, in series) x 1 ms / 20 = 1.5."""
    with pytest.raises(ScenarioError, match=r"k T / D = 1\.5") as err:
        _check("wall_press", **{"controller.force.admittance_damping": 20.0})
    assert err.value.field == "controller.force.admittance_damping"
    _check("wall_press", **{"controller.force.admittance_damping": 30.0})  # 1.0


class _Props:
    def __init__(self, friction):
        self._friction = friction

    def HasProperty(self, group, name):  # noqa: N802 (Drake's name)
        assert (group, name) == ("material", "coulomb_friction")
        return self._friction is not None

    def GetProperty(self, group, name):  # noqa: N802 (Drake's name)
        assert (group, name) == ("material", "coulomb_friction") and self._friction is not None
        return self._friction


class _Inspector:
    def __init__(self, table):
        self._table = table

    def GetProximityProperties(self, geometry):  # noqa: N802 (Drake's name)
        return _Props(self._table[geometry])


def test_pair_friction_combines_as_drake_and_defaults_to_one():
    inspector = _Inspector({1: CoulombFriction(0.2, 0.15), 2: CoulombFriction(0.6, 0.6),
                            3: None})
    assert dut.pair_friction(inspector, 1, 2) == pytest.approx(2 * 0.15 * 0.6 / 0.75)
    assert dut.pair_friction(inspector, 1, 3) == pytest.approx(2 * 0.15 * 1.0 / 1.15)
