"""Shared by the diagram scripts: write a Diagram's block diagram as Graphviz (and SVG)."""

from __future__ import annotations

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
