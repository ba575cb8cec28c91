"""The API reference (docs/api, built by ``.ci/run``): it lists every module, and importing the
modules, as Sphinx autodoc does, compiles no numba kernel."""

import subprocess
import sys
from pathlib import Path

from test_layers import MODULES

INDEX = Path(__file__).resolve().parents[1] / "docs" / "api" / "internals.rst"


def test_every_module_is_in_the_reference():
    listed = {line.split("::", 1)[1].strip() for line in INDEX.read_text().splitlines()
              if line.startswith(".. automodule::")}
    expected = {name for name in MODULES if not name.endswith("__main__")} - {"aerial_drake"}
    assert listed == expected


def test_importing_every_module_compiles_nothing():
    """autodoc imports each module: numba's dispatchers must still have no compiled
    signature afterwards (a kernel compiles, or loads from the cache, on its first call)."""
    names = sorted(n for n in MODULES if not n.endswith("__main__"))
    code = (
        "import importlib, sys\n"
        "from numba.core.registry import CPUDispatcher\n"
        f"mods = [importlib.import_module(n) for n in {names!r}]\n"
        "compiled = sorted(f'{m.__name__}.{k}' for m in mods for k, v in vars(m).items()\n"
        "                  if isinstance(v, CPUDispatcher) and v.signatures)\n"
        "dispatchers = sum(isinstance(v, CPUDispatcher) for m in mods for v in vars(m).values())\n"
        "print(dispatchers, compiled)\n"
        "sys.exit(1 if compiled or not dispatchers else 0)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
