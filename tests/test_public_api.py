"""The public API (aerial_drake/__init__.py): every name resolves, importing the package loads
neither Drake nor numba, and the API reference documents the public names apart from the
internals."""

import subprocess
import sys
from pathlib import Path

import aerial_drake as dut

DOCS = Path(__file__).resolve().parents[1] / "docs" / "api"


def test_every_public_name_resolves_to_its_defining_module():
    assert set(dut.__all__) == {"__version__", *dut._PUBLIC}
    for name, module in dut._PUBLIC.items():
        value = getattr(dut, name)
        assert value.__module__.startswith(module), (name, value.__module__, module)
    assert sorted(dir(dut)) == sorted(dut.__all__)


def test_an_unknown_name_lists_the_public_ones():
    try:
        dut.run_scenrio  # noqa: B018 (a misspelling)
    except AttributeError as err:
        assert "run_scenario" in str(err)
    else:
        raise AssertionError("a misspelt public name resolved")


def test_importing_the_package_loads_neither_drake_nor_numba():
    code = ("import sys, aerial_drake\n"
            "heavy = [m for m in ('pydrake', 'numba', 'matplotlib') if m in sys.modules]\n"
            "print(heavy); sys.exit(1 if heavy else 0)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr


def test_the_reference_has_a_public_page_with_every_public_name():
    public = (DOCS / "public.rst").read_text()
    for name in dut._PUBLIC:
        assert f"aerial_drake.{name}" in public, name
