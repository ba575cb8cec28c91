"""Every difference between the Drake releases we support, in one place.

Supported: drake 1.51.1 (the newest wheel for Python 3.10 and 3.11) up to the newest release
(Python 3.12 and 3.13; 1.58.0 when this was written). Everything else in the package is written
against the API the releases share; what differs is translated here, with the release that
changed it, so that a scenario file means the same run on every supported release.

- ``SimulatorConfig.publish_every_time_step``: a field in 1.51.1, gone in 1.58.0 (deprecated by
  Drake PR #23940 in favour of per-step events that systems declare themselves). Its default,
  ``false``, is what both releases do without it, and the only value aerial_drake accepts:
  ``true`` would make every logger record at each integrator step as well as at its period.
  Shipped files leave the field out; a user's file may keep ``false`` (removed here before
  Drake sees it) but not ``true`` (an error saying to remove the field).
- ``MultibodyPlantConfig.discrete_contact_approximation: tamsi``: 1.51.1 has the TAMSI solver,
  1.58.0 does not (``DiscreteContactApproximation`` lost ``kTamsi``). The choices a scenario's
  ``plant`` section accepts are the installed release's (:data:`DISCRETE_CONTACT_APPROXIMATIONS`),
  so ``tamsi`` is refused at load, naming the field and the choices, where Drake lacks it.
- **Diagrams with a Python system outlive their use** in drake 1.51.1 (Drake issue #23161:
  any Python ``LeafSystem`` in a diagram keeps the whole diagram alive, out of reach of
  Python's collector); fixed by 1.58.0. A run builds such a diagram, so one process running
  run after run (a study's worker) grows by about 5 MB per run on 1.51.1 and not on 1.58.0
  (measured 2026-12-05). :func:`python_systems_outlive_diagrams` finds out which release is
  installed by trying it; the study's local cluster then restarts its workers periodically
  (aerial_drake.studies.executor).
"""

import functools
import gc
import weakref
from typing import Any

from pydrake.multibody.plant import DiscreteContactApproximation

#: The ``plant.discrete_contact_approximation`` names the installed Drake accepts (its enum's
#: members, lower case): ``tamsi`` only where the release still has that solver.
DISCRETE_CONTACT_APPROXIMATIONS: tuple[str, ...] = tuple(
    name for name in ("tamsi", "sap", "similar", "lagged")
    if hasattr(DiscreteContactApproximation, "k" + name.capitalize()))

# SimulatorConfig fields that some supported release lacks: name -> (the only accepted
# value, why, which releases have it).
_REMOVED_SIMULATOR_FIELDS: dict[str, tuple[Any, str, str]] = {
    "publish_every_time_step": (
        False,
        "aerial_drake's loggers and viewer publish at their own periods; per-step publishing "
        "would add a log entry at every integrator step",
        "1.51.1 has it but 1.58.0 does not (deprecated by Drake PR #23940)"),
}


class SimulatorFieldError(ValueError):
    """A ``simulator:`` field of a scenario that no supported Drake release can honour."""


def translate_simulator_section(section: Any, where: str) -> bool:
    """Remove, in place, the ``simulator:`` fields of a scenario's raw YAML data (a mapping as
    ``yaml_load_data`` returns it) that only some Drake releases know, after checking that
    their value is the one every release honours. ``where`` names the section in messages.

    Returns whether anything was removed. Raises :class:`SimulatorFieldError` naming the field,
    its value and the fix.
    """
    if not isinstance(section, dict):
        return False
    changed = False
    for name, (accepted, why, release) in _REMOVED_SIMULATOR_FIELDS.items():
        if name not in section:
            continue
        value = section[name]
        if value != accepted or not isinstance(value, type(accepted)):
            shown = str(value).lower() if isinstance(value, bool) else repr(value)
            raise SimulatorFieldError(
                f"{where}.{name}: {shown} is not supported ({why}). Remove the field: Drake "
                f"{release}, and its default, {str(accepted).lower()}, is what every release "
                "does without it.")
        del section[name]
        changed = True
    return changed



@functools.cache
def python_systems_outlive_diagrams() -> bool:
    """Whether the installed Drake keeps a diagram holding a Python ``LeafSystem`` alive after
    its last reference is dropped (module docstring): tried once, on an empty system."""
    from pydrake.systems.framework import DiagramBuilder, LeafSystem

    class _Probe(LeafSystem):  # a Python subclass: what the leak needs
        pass

    builder = DiagramBuilder()
    builder.AddSystem(_Probe())
    diagram = builder.Build()
    alive = weakref.ref(diagram)
    del builder, diagram
    gc.collect()
    return alive() is not None
