"""A run's id changes with every field that changes the run: each leaf of its resolved
scenario (changed by an awkward amount, or by one unit in the last place), and each field of
the study that reaches its runs (the duration, the settings, the seed, a parameter's values)."""

import copy
import dataclasses
import math
import typing
from pathlib import Path

import numpy as np

from aerial_drake.studies import spec as dut

SMALL = Path(__file__).resolve().parent / "small_study.yaml"


def _names(obj):
    if dataclasses.is_dataclass(obj):
        return [f.name for f in dataclasses.fields(obj)]
    return [f.name for f in getattr(type(obj), "__fields__", ())]  # Drake's config structs


def _names_of_type(kind):
    return dataclasses.is_dataclass(kind) or hasattr(kind, "__fields__")


def _leaves(obj, path=()):
    names = _names(obj)
    if names:
        for name in names:
            yield from _leaves(getattr(obj, name), (*path, name))
    elif isinstance(obj, list) and obj and _names(obj[0]):
        for i, item in enumerate(obj):
            yield from _leaves(item, (*path, i))
    else:
        yield path, obj


def _changed(value, parent, name, tiny):
    if isinstance(value, bool):
        return not value
    if isinstance(value, int):
        return value + 1
    if isinstance(value, float):
        if math.isnan(value):
            return 0.37
        return float(np.nextafter(value, math.inf)) if tiny else value * 1.37 + 0.013
    if isinstance(value, str):
        return value + "_x"
    if isinstance(value, list) and value:
        return [*value[:-1], _changed(value[-1], None, None, tiny)]
    # An empty list: one item of its type (a default-built section, or a number / text).
    (item,) = typing.get_args(typing.get_type_hints(type(parent))[name])
    return [item() if _names_of_type(item) else item(1)]


def _with(scenario, path, value):
    copied = copy.deepcopy(scenario)
    obj = copied
    for part in path[:-1]:
        obj = obj[part] if isinstance(part, int) else getattr(obj, part)
    setattr(obj, path[-1], value)
    return copied


def test_every_field_of_a_run_changes_its_id():
    base = dut.load_study(SMALL).base
    before = dut.run_id(dut.scenario_text(base))
    leaves = list(_leaves(base))
    assert len(leaves) > 90  # every section walked, Drake's config structs included
    same = []
    for tiny in (False, True):
        for path, value in leaves:
            parent = base
            for part in path[:-1]:
                parent = parent[part] if isinstance(part, int) else getattr(parent, part)
            if tiny and not isinstance(value, float):
                continue
            changed = _with(base, path, _changed(value, parent, path[-1], tiny))
            if dut.run_id(dut.scenario_text(changed)) == before:
                same.append((".".join(map(str, path)), tiny))
    assert same == []


def _ids(**changes):
    loaded = dut.load_study(SMALL, **{k: v for k, v in changes.items()
                                      if k in ("duration", "draws")})
    study = dataclasses.replace(loaded.study, **{k: v for k, v in changes.items()
                                                 if k not in ("duration", "draws")})
    return [r.run_id for r in dut.plan_runs(dataclasses.replace(loaded, study=study))]


def test_the_studys_fields_that_reach_a_run_change_its_id():
    ids = _ids()
    assert len(set(ids)) == len(ids) == 6
    # The duration (the issue's case: an id that ignored it mixed two studies' rows).
    assert not set(_ids(duration=0.3000000000000001)) & set(ids)
    assert not set(_ids(duration=0.2)) & set(ids)
    assert not set(_ids(seed=8)) & set(ids)
    grid = dataclasses.replace(dut.load_study(SMALL).study.parameters[0], values=[250.0, 501.0])
    params = [grid, *dut.load_study(SMALL).study.parameters[1:]]
    changed = _ids(parameters=params)
    assert changed[:3] == ids[:3] and not set(changed[3:]) & set(ids)  # k_R 500 -> 501 only
    # More draws extend the study: the first draws keep their ids.
    more = _ids(draws=4)
    assert set(ids) < set(more)
