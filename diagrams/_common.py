"""Shared by the diagram scripts: their command line, and a Diagram's block diagram as
Graphviz (and SVG)."""

from __future__ import annotations

import argparse
import shutil
import subprocess
from pathlib import Path

from pydrake.systems.framework import Diagram


def write_graphviz(diagram: Diagram, out: Path, max_depth: int = 1) -> list[Path]:
    """``out.dot`` always; ``out.svg`` too where Graphviz's ``dot`` is installed."""
    out.parent.mkdir(parents=True, exist_ok=True)
    dot_path = out.with_suffix(".dot")
    dot_path.write_text(diagram.GetGraphvizString(max_depth=max_depth))
    written = [dot_path]
    if shutil.which("dot"):
        svg = out.with_suffix(".svg")
        subprocess.run(["dot", "-Tsvg", str(dot_path), "-o", str(svg)], check=True)
        written.append(svg)
    return written


def parse_command_line(doc: str) -> argparse.Namespace:
    """``[SCENARIO] [--duration S] [--out DIR]``, described by ``doc``'s first line."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("scenario", nargs="?", default="nominal")
    parser.add_argument("--duration", type=float, default=2.0)
    parser.add_argument("--out", default="out/diagrams")
    return parser.parse_args()


def draw_closed_loop(scenario, out: Path) -> None:
    """The scenario's closed loop (its blocks: plant, reference, controller, lag, saturation,
    actuators, as a Diagram of their own, depth 1) written as ``out/<name>_closed_loop``."""
    from aerial_drake.simulation.diagram import build_closed_loop

    for path in write_graphviz(build_closed_loop(scenario).diagram,
                               out / f"{scenario.name}_closed_loop"):
        print(f"wrote {path}")
