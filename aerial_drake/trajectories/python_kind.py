"""``kind: python``: a reference of the user's own (docs/trajectories.md).

``trajectory.python.function: "module:name"`` names one of:

- a function ``f(t) -> ReferenceSample`` giving the reference and every derivative the law
  reads at time t (x_d, the system's CoM, to the 4th, p_ed, R_ed as w_ed, dw_ed, and q_jd
  to the 2nd, b1d to the 2nd: :class:`~aerial_drake.trajectories.reference.ReferenceSample`);
- a dict of Drake ``Trajectory`` objects (their derivatives from ``EvalDerivative``):
  ``com`` (3 rows, required: the system's CoM x_d), ``ee_position`` (3 rows, required),
  ``ee_rotation_vector`` (3 rows: R_ed = exp(hat(r(t))), :mod:`.so3`; default identity),
  ``heading`` (1 row, phi4; default 0), ``joints`` (one row per joint component of the task;
  default the joint targets);
- a function of no arguments returning either (called once, at load).

The reference is evaluated once at load (shapes and finiteness, with errors naming the
field); the scenario's checks then test its derivatives numerically over the whole run
(:mod:`aerial_drake.trajectories.continuity`) before anything is simulated. Whatever the
user's code raises at load (importing the module, the call of no arguments, f(0)) is a
ValueError naming ``python.function`` and the error; code that runs past
:data:`LOAD_TIME_LIMIT` there is stopped (:mod:`.time_limit`) with the same.

A run does not call the user's code at each controller sample: ``for_run`` samples it once
onto compiled splines of the order the law needs, their error bound checked against it
(:mod:`.sampled`).
"""

from __future__ import annotations

import importlib
import inspect
import sys
from pathlib import Path
from typing import Any, Callable

import numpy as np

from aerial_drake.trajectories.base import ReferenceSource
from aerial_drake.trajectories.heading import heading_reference
from aerial_drake.trajectories.params import PythonParams
from aerial_drake.trajectories.reference import ReferenceSample
from aerial_drake.trajectories.sampled import sample_onto_splines
from aerial_drake.trajectories.so3 import exp_so3, rotation_vector_rates
from aerial_drake.trajectories.time_limit import TimeLimitExceeded, time_limit

__all__ = ["PythonReference", "DrakeTrajectoriesReference", "resolve_python_reference",
           "TRAJECTORY_KEYS", "LOAD_TIME_LIMIT"]

#: The time the user's code may take at load: importing its module, the call of no
#: arguments and the evaluation at t = 0, together (s).
LOAD_TIME_LIMIT = 10.0

#: The keys of a dict of Drake trajectories, and the rows each must have (None: n_j).
TRAJECTORY_KEYS: dict[str, int | None] = {
    "com": 3, "ee_position": 3, "ee_rotation_vector": 3, "heading": 1, "joints": None}
_REQUIRED = ("com", "ee_position")
_SHAPES = {"com": (5, 3), "p_ed": (3,), "v_ed": (3,), "a_ed": (3,), "R_ed": (3, 3),
           "w_ed": (3,), "dw_ed": (3,), "b1d": (3, 3)}


def resolve_python_reference(params: PythonParams) -> Any:
    """The object ``params.function`` names (``module:name``), after putting ``params.path``
    first on the import path; a function of no arguments is called. ValueError naming the
    field if it cannot be found. ``params`` already checked
    (:func:`aerial_drake.trajectories.kinds.reference_of` does)."""
    module_name, name = (part.strip() for part in params.function.split(":"))
    if params.path:
        folder = str(Path(params.path).expanduser().resolve())
        if not Path(folder).is_dir():
            raise ValueError(f"Invalid python: 'python.path' {params.path!r} is not a folder")
        if folder not in sys.path:
            sys.path.insert(0, folder)
    try:
        module = importlib.import_module(module_name)
    except Exception as err:  # the user's module: any error while importing it
        raise ValueError(f"Invalid python: 'python.function' {params.function!r}: module "
                         f"{module_name!r} cannot be imported ({type(err).__name__}: {err}); "
                         "set python.path to its folder") from None
    if not hasattr(module, name):
        raise ValueError(f"Invalid python: 'python.function' {params.function!r}: module "
                         f"{module_name!r} has no {name!r}")
    target = getattr(module, name)
    if callable(target) and not isinstance(target, dict) and _parameters(target) == 0:
        try:
            target = target()
        except Exception as err:  # the user's function: any error, named
            raise ValueError(f"Invalid python: 'python.function' {params.function!r} (a "
                             f"function of no arguments) raised {type(err).__name__}: {err}"
                             ) from None
    return target


def _parameters(function: Callable) -> int | None:
    try:
        return len(inspect.signature(function).parameters)
    except (TypeError, ValueError):
        return None


def python_reference(params: PythonParams, joint_targets: np.ndarray) -> ReferenceSource:
    """The reference source ``params`` names (module docstring), evaluated once at t = 0,
    within :data:`LOAD_TIME_LIMIT`."""
    try:
        with time_limit(LOAD_TIME_LIMIT, f"python.function {params.function!r}"):
            return _load(params, joint_targets)
    except TimeLimitExceeded:
        raise ValueError(f"Invalid python: 'python.function' {params.function!r} did not "
                         f"return within {LOAD_TIME_LIMIT:g} s at load (importing its module "
                         "and evaluating it at t = 0): a loop that never ends? Make f(t) "
                         "return promptly (it is called thousands of times per run)") from None


def _load(params: PythonParams, joint_targets: np.ndarray) -> ReferenceSource:
    target = resolve_python_reference(params)
    joint_targets = np.asarray(joint_targets, dtype=float)
    source: _UserReference
    if isinstance(target, dict):
        source = DrakeTrajectoriesReference(target, joint_targets)
    elif callable(target):
        source = PythonReference(target, joint_targets.size)
    else:
        raise ValueError(f"Invalid python: 'python.function' {params.function!r} is a "
                         f"{type(target).__name__}: give a function f(t) -> ReferenceSample "
                         "or a dict of Drake trajectories (docs/trajectories.md)")
    source.label = params.function
    try:
        source.evaluate(0.0)
    except ValueError as err:  # a wrong shape (named by fill), or the user's own ValueError
        raise ValueError(f"Invalid python: 'python.function' {params.function!r} at t = 0: "
                         f"{err}") from None
    except Exception as err:  # the user's function: whatever it raises, named
        raise ValueError(f"Invalid python: 'python.function' {params.function!r} raised "
                         f"{type(err).__name__} at t = 0: {err}") from None
    return source


class _UserReference(ReferenceSource):
    """The user's reference, called per evaluation; a run evaluates it sampled onto splines
    (:meth:`for_run`)."""

    kind = "python"
    #: ``python.function``, for the messages.
    label = "?"
    #: The joint targets the reference falls back on (part of the sampled splines' key).
    _targets: np.ndarray

    def _target(self) -> Any:
        """The user's object this reference calls (what the sampled splines are cached by)."""
        raise NotImplementedError

    def packed(self, times: np.ndarray) -> np.ndarray:
        """As :meth:`ReferenceSource.packed`, each time's row kept: the load-time check's
        samples (10 ms apart) hold the splines' knots (20 ms apart), which are not asked of
        the function again."""
        times = np.asarray(times, dtype=float)
        if times.ndim != 1:
            raise ValueError(f"times must be a 1-D array, got shape {times.shape}")
        memo = self.__dict__.setdefault("_rows", {})
        out = np.empty((times.size, self.size))
        for i, t in enumerate(times.tolist()):
            row = memo.get(t)
            if row is None:
                self.fill(t, out[i])
                memo[t] = out[i].copy()
            else:
                out[i] = row
        return out

    def for_run(self, duration: float) -> ReferenceSource:
        """Sampled once over [0, ``duration``] onto compiled splines of the order the law
        needs, checked against this reference (:func:`.sampled.sample_onto_splines`). Kept
        for the same function object, duration and joint targets within the process (the
        load-time check and the run, a study's runs), so the function is sampled once."""
        target = self._target()
        key = (id(target), float(duration), self._targets.tobytes())
        hit = _SAMPLED.get(key)
        if hit is not None and hit[0] is target:
            return hit[1]
        sampled = sample_onto_splines(self, duration, self.label)
        self.__dict__.pop("_rows", None)  # the samples kept for it (packed) are in it now
        if len(_SAMPLED) >= _SAMPLED_KEPT:
            _SAMPLED.clear()
        _SAMPLED[key] = (target, sampled)
        return sampled


#: The sampled references kept (:meth:`_UserReference.for_run`), at most _SAMPLED_KEPT.
_SAMPLED: dict[tuple, tuple[Any, ReferenceSource]] = {}
_SAMPLED_KEPT = 8


class PythonReference(_UserReference):
    """A function f(t) -> ReferenceSample, each result's shapes checked."""

    def __init__(self, function: Callable[[float], ReferenceSample], n_joints: int) -> None:
        super().__init__(n_joints)
        self._function = function
        self._targets = np.zeros(0)  # the function gives its own q_jd

    def _target(self) -> Any:
        return self._function

    def fill(self, t: float, out: np.ndarray) -> None:
        sample = self._function(t)
        if not isinstance(sample, ReferenceSample):
            raise ValueError(f"the function returned a {type(sample).__name__}, not a "
                             "ReferenceSample")
        shapes = dict(_SHAPES, q_jd=(self.n_joints,), q_jd_dot=(self.n_joints,),
                      q_jd_ddot=(self.n_joints,))
        for field, shape in shapes.items():
            value = np.shape(getattr(sample, field))
            if value != shape:
                raise ValueError(f"ReferenceSample.{field} has shape {value}, expected {shape}"
                                 + (" (one entry per joint component of the task)"
                                    if field.startswith("q_jd") else ""))
        out[:] = np.concatenate(sample.to_vectors())


class DrakeTrajectoriesReference(_UserReference):
    """A dict of Drake trajectories (module docstring)."""

    def __init__(self, trajectories: dict[str, Any], joint_targets: np.ndarray) -> None:
        super().__init__(joint_targets.size)
        unknown = set(trajectories) - set(TRAJECTORY_KEYS)
        missing = [k for k in _REQUIRED if k not in trajectories]
        if unknown or missing:
            raise ValueError(f"the dict of trajectories has keys {sorted(trajectories)}: "
                             f"{'unknown ' + str(sorted(unknown)) if unknown else ''}"
                             f"{' missing ' + str(missing) if missing else ''} (keys: "
                             f"{', '.join(TRAJECTORY_KEYS)}; com and ee_position required)")
        for key, trajectory in trajectories.items():
            rows = TRAJECTORY_KEYS[key] or self.n_joints
            if not hasattr(trajectory, "EvalDerivative"):
                raise ValueError(f"'{key}' is a {type(trajectory).__name__}, not a Drake "
                                 "Trajectory")
            if trajectory.rows() != rows or trajectory.cols() != 1:
                raise ValueError(f"'{key}' is {trajectory.rows()} x {trajectory.cols()}, "
                                 f"expected {rows} x 1")
        self._trajectories = trajectories
        self._joint_targets = self._targets = np.asarray(joint_targets, dtype=float)

    def _target(self) -> Any:
        return self._trajectories

    def _derivatives(self, key: str, t: float, orders: int) -> np.ndarray | None:
        trajectory = self._trajectories.get(key)
        if trajectory is None:
            return None
        return np.array([np.asarray(trajectory.value(t)).reshape(-1)] + [
            np.asarray(trajectory.EvalDerivative(t, k)).reshape(-1) for k in range(1, orders)])

    def fill(self, t: float, out: np.ndarray) -> None:
        com = self._derivatives("com", t, 5)
        p = self._derivatives("ee_position", t, 3)
        assert com is not None and p is not None  # required keys, checked in __init__
        r = self._derivatives("ee_rotation_vector", t, 3)
        phi = self._derivatives("heading", t, 3)
        q = self._derivatives("joints", t, 3)
        zero = np.zeros(3)
        if r is None:
            R, w, dw = np.eye(3), zero, zero
        else:
            R = exp_so3(r[0])
            omega, domega = rotation_vector_rates(r[0], r[1], r[2])
            w, dw = R @ omega, R @ domega
        if q is None:
            q = np.array([self._joint_targets, 0 * self._joint_targets,
                          0 * self._joint_targets])
        sample = ReferenceSample(
            com=com, p_ed=p[0], v_ed=p[1], a_ed=p[2], R_ed=R, w_ed=w, dw_ed=dw,
            q_jd=q[0], q_jd_dot=q[1], q_jd_ddot=q[2],
            b1d=heading_reference(np.zeros(3) if phi is None else phi[:, 0]))
        out[:] = np.concatenate(sample.to_vectors())
