"""``paper_plus``: the paper's law (Section III) with integral action (anti-windup) and the
vehicle-force feed-forward, by shaping the references handed to the paper's compiled law
(docs/control.md, "paper_plus"): :mod:`.params` (the scenario's ``controller.plus``),
:mod:`.shaping` (the shifts, pure math) and :mod:`.controller` (the LeafSystem)."""

from typing import Any

from aerial_drake.control.plus.params import PAPER_PLUS, PlusParams

__all__ = ["PAPER_PLUS", "PaperPlusController", "PlusParams"]


def __getattr__(name: str) -> Any:
    # The LeafSystem (and through it the compiled law's numba) on first use only: loading a
    # scenario reads PlusParams and must stay light.
    if name == "PaperPlusController":
        from aerial_drake.control.plus.controller import PaperPlusController
        return PaperPlusController
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
