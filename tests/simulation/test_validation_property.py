"""Property: mutate one field of a valid scenario (type, sign, NaN, inf, huge, tiny, empty,
wrong length); validation either accepts the result or raises a ScenarioError whose message
names that field. Never another exception. Validation only (no simulation), so each example
costs microseconds; derandomized for reproducible CI runs."""

import copy
import dataclasses
import math

from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from aerial_drake.simulation.outputs import strict_json
from aerial_drake.simulation.scenarios import Scenario, ScenarioError, load_scenario
from aerial_drake.simulation.scenarios.checks import estimated_log_mb

BASE = {name: load_scenario(name) for name in ("nominal", "disturbed")}


def _children(obj):
    if dataclasses.is_dataclass(obj):
        return [(f.name, getattr(obj, f.name)) for f in dataclasses.fields(obj)]
    if hasattr(type(obj), "__fields__"):  # Drake's SimulatorConfig
        return [(f.name, getattr(obj, f.name)) for f in type(obj).__fields__]
    return None


def leaf_paths(obj, prefix=()):
    """Every leaf field's path: attribute names and list indices (disturbances[i])."""
    children = _children(obj)
    if children is None:
        return [prefix]
    paths = []
    for name, value in children:
        if isinstance(value, list) and value and _children(value[0]) is not None:
            for i, item in enumerate(value):
                paths += leaf_paths(item, prefix + (name, i))
        else:
            paths += leaf_paths(value, prefix + (name,))
    return paths


def dotted(path) -> str:
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else p)
    return out


def set_path(obj, path, value):
    *head, last = path
    for p in head:
        obj = obj[p] if isinstance(p, int) else getattr(obj, p)
    setattr(obj, last, value)


def get_path(obj, path):
    for p in path:
        obj = obj[p] if isinstance(p, int) else getattr(obj, p)
    return obj


PATHS = sorted({(name, p) for name, s in BASE.items() for p in leaf_paths(s)})


def mutate(value, kind: str, draw_number):
    if kind == "type":
        return "text" if not isinstance(value, str) else 3.0
    if kind == "bool":
        return True
    if kind == "none":
        return None
    if kind == "empty":
        return [] if isinstance(value, list) else ""
    if kind == "wrong_length":
        return (value + [0.0]) if isinstance(value, list) else [value, value]
    scalar = {"sign": None, "nan": math.nan, "inf": math.inf, "-inf": -math.inf,
              "huge": 1e300, "tiny": 1e-300, "number": draw_number}[kind]
    if isinstance(value, list):
        if not value:
            return [scalar if scalar is not None else -1.0]
        out = list(value)
        out[0] = -out[0] if scalar is None else scalar
        return out
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return -value if scalar is None else scalar
    return scalar if scalar is not None else value


KINDS = ["type", "bool", "none", "empty", "wrong_length", "sign", "nan", "inf", "-inf", "huge",
         "tiny", "number"]


@settings(max_examples=400, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(PATHS), st.sampled_from(KINDS),
       st.floats(allow_nan=True, allow_infinity=True))
def test_one_mutated_field_is_accepted_or_named(where, kind, number):
    base, path = where
    scenario: Scenario = copy.deepcopy(BASE[base])
    value = mutate(get_path(scenario, path), kind, number)
    try:
        set_path(scenario, path, value)
    except TypeError:  # Drake's SimulatorConfig holds typed C++ fields: cannot be mistyped
        assume(False)
    field = dotted(path)
    try:
        scenario.validate()
    except ScenarioError as err:
        # The field itself, or (a consistency check) the message names it: e.g. a tiny
        # duration is blamed on log_period "<= duration".
        leaf = field.split(".")[-1].split("[")[0]
        assert field.split("[")[0] in str(err) or leaf in str(err), (field, value, str(err))
        assert "np.float64" not in str(err)
        return
    # Accepted: within every range, so finite where it must be and the log within budget.
    assert estimated_log_mb(scenario.duration, scenario.log_period) <= scenario.max_log_mb
    assert math.isfinite(scenario.duration) and scenario.duration > 0
    strict_json(dataclasses.asdict(scenario.actuation))  # no NaN left where it is required
