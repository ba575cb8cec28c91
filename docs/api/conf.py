"""Sphinx configuration of the API reference (``python -m sphinx -W -b html docs/api out/api``).

The reference is built from the docstrings by autodoc, which imports every module: importing
the package compiles nothing (numba compiles on first call) and starts nothing.
"""

project = "aerial_drake"
author = "aerial_drake contributors"
extensions = ["sphinx.ext.autodoc", "sphinx.ext.viewcode"]
# Members in source order, as the modules are written to be read.
autodoc_member_order = "bysource"
autodoc_default_options = {"members": True, "show-inheritance": True}
# Type hints in the description, so long pydrake signatures stay readable.
autodoc_typehints = "description"
html_theme = "alabaster"
html_title = "aerial_drake API reference"
exclude_patterns = ["_build"]
