"""The gains' one rule set (aerial_drake.control.gains) and the packed gains' one order
(aerial_drake.control.compiled.kernels.GAIN_LAYOUT)."""

import numpy as np
import pytest

from aerial_drake.control.compiled import pack_gains
from aerial_drake.control.compiled.kernels import GAIN_LAYOUT, _packed_gains_size
from aerial_drake.control.gains import GainError, GainMatrices, Gains


def paper_gains(**changes):
    values = dict(K_x=[800.0] * 3, D_x=[420.0] * 3, k_R=250.0, k_w=200.0,
                  Lambda2_bar=[1.46, 0.36, 1.46], K_y=[30.0] * 3 + [10.0] * 3 + [7.0],
                  K_z=[30.0] * 7)
    values.update(changes)
    return Gains(**values)


@pytest.mark.parametrize("changes,field,match", [
    ({"k_R": 2e6}, "gains.k_R", r"gains\.k_R must be finite, > 0 and <= 1e\+06; got 2000000\.0"),
    ({"k_w": "x"}, "gains.k_w", r"gains\.k_w must be a number > 0 and <= 1e\+06; got 'x'"),
    ({"K_x": [800.0, 0.0, 800.0]}, "gains.K_x", r"gains\.K_x = \[800\.0, 0\.0, 800\.0\] is not "
     r"positive definite with bounded entries: entry 1"),
    ({"K_z": [30.0] * 6}, "gains.K_z", r"gains\.K_z must be a list of 7 diagonal entries"),
])
def test_the_controller_and_the_scenario_share_one_rule_set(changes, field, match):
    """A controller built without a scenario (GainMatrices.from_gains) refuses what the
    scenario's check refuses, with the same message: the rules are written once."""
    for check in (lambda g: g.validate(7), lambda g: GainMatrices.from_gains(g, 7)):
        with pytest.raises(GainError, match=match) as err:
            check(paper_gains(**changes))
        assert err.value.field == field


def test_unequal_orientation_gains_need_the_task_rows():
    unequal = paper_gains(K_y=[30.0] * 3 + [10.0, 10.0, 20.0] + [7.0])
    unequal.validate(7)  # without the task's rows: no orientation check
    with pytest.raises(GainError, match=r"orientation entries \(task rows 4, 5, 6"):
        unequal.validate(7, task_rows=(0, 1, 2, 3, 4, 5, 6))


def test_the_packed_order_is_the_layout():
    K = GainMatrices.from_gains(paper_gains(), 7)
    packed = pack_gains(K, 9.81)
    assert packed.size == _packed_gains_size(7) == 17 + 2 * 7
    at = 0
    for name, size in GAIN_LAYOUT:
        size = 7 if size < 0 else size
        expected = 9.81 if name == "gravity" else getattr(K, name)
        np.testing.assert_array_equal(packed[at:at + size], np.ravel(expected))
        at += size
    assert at == packed.size
    with pytest.raises(ValueError, match="gain K_z has 6 entries for a task of 7 rows"):
        pack_gains(GainMatrices(**{**K.__dict__, "K_z": K.K_z[:6]}), 9.81)
