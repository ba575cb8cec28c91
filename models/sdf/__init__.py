"""Data-only package: the SDF models, model directives and package.xml of aerial_drake.

Installed as ``aerial_drake.sdf`` (see pyproject.toml). This file makes it a regular package,
so ``importlib.resources.files("aerial_drake.sdf")`` is a plain path rather than a namespace
package's MultiplexedPath.
"""
