"""Sphinx configuration of the API reference (``python -m sphinx -W -b html docs/api out/api``).

The reference is built from the docstrings by autodoc, which imports every module: importing
the package compiles nothing (numba compiles on first call) and starts nothing.
"""

project = "aerial_drake"
author = "aerial_drake contributors"
# napoleon: the docstrings' "Args:" sections (Google style).
extensions = ["sphinx.ext.autodoc", "sphinx.ext.napoleon", "sphinx.ext.viewcode"]
# Members in source order, as the modules are written to be read.
autodoc_member_order = "bysource"
# A package's __all__ re-exports its modules' functions: each is documented once, where it is
# defined (ignore-module-all), so a function named like its module is no duplicate.
autodoc_default_options = {"members": True, "show-inheritance": True, "ignore-module-all": True}
# Type hints in the description, so long pydrake signatures stay readable.
autodoc_typehints = "description"
html_theme = "alabaster"
html_title = "aerial_drake API reference"
exclude_patterns = ["_build"]


def _norm_bars(app, what, name, obj, options, lines):
    """The docstrings write norms as in the paper, ``|f_d|``; reStructuredText would read
    ``|...|`` as a substitution, so the bars are escaped (no docstring holds an RST table)."""
    lines[:] = [line.replace("|", "\\|") for line in lines]


def setup(app):
    app.connect("autodoc-process-docstring", _norm_bars)
