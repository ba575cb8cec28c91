"""The package's layout by role: every import runs down the layers (or stays in its subpackage),
no module imports back into a cycle, the wheel lists every subpackage, the tests mirror the
package's folders, and modules stay small.

Layers, top to bottom (a module imports from its own subpackage and from layers below only):

    cli (the package: parser, commands, errors), __main__ -> studies -> viz | analysis
    -> simulation -> control -> trajectories -> dynamics -> robots -> drake_compat

``viz`` and ``analysis`` share a layer and must not import each other. ``trajectories`` sits
under ``control``: the controller reads the packed reference vectors whose layout the
trajectories own, and no trajectory needs a controller.
"""

import ast
from pathlib import Path

import pytest

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10: the same parser, as the tomli package
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "aerial_drake"

#: Layer rank of each top-level part of the package: higher may import lower, never higher.
#: The same rank in different parts (viz, analysis) may not import each other either.
RANKS = {
    # Every difference between the supported Drake releases, under everything else.
    "drake_compat": -1,
    "robots": 0,
    "dynamics": 1,
    "trajectories": 2,
    "control": 3,
    "simulation": 4,
    "analysis": 5,
    "viz": 5,
    "studies": 6,
    # The command line, a package: it only parses and prints; everything below it takes typed
    # arguments, never an argparse.Namespace (test_only_the_command_line_parses).
    "cli": 7,
    "__main__": 8,
}

#: Only the compiled law's kernels may pass the size limit (its docstring says why).
MAX_LINES = 400
LONG_MODULES = {"aerial_drake.control.compiled.kernels"}


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def package_modules() -> dict[str, Path]:
    return {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


MODULES = package_modules()


def imports_of(name: str, path: Path):
    """``(line, imported module)`` for every import of the package in the module, including
    imports inside functions; ``from a.b import c`` names ``a.b.c`` when that is a module."""
    is_package = path.name == "__init__.py"
    tree = ast.parse(path.read_text(), str(path))
    # The package root names the public API for the type checker only (``if TYPE_CHECKING:``)
    # and imports it lazily (PEP 562): those imports never run (test_public_api).
    type_only = {id(n) for block in ast.walk(tree) if name == "aerial_drake"
                 and isinstance(block, ast.If) and isinstance(block.test, ast.Name)
                 and block.test.id == "TYPE_CHECKING" for n in ast.walk(block)}
    for node in ast.walk(tree):
        if id(node) in type_only:
            continue
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = name.split(".")
                anchor = anchor if is_package else anchor[:-1]
                anchor = anchor[:len(anchor) - (node.level - 1)]
                base = ".".join(anchor + ([base] if base else []))
            targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in MODULES else base
                       for a in node.names]
        else:
            continue
        for target in targets:
            if target == "aerial_drake" or target.startswith("aerial_drake."):
                yield node.lineno, target


def part(module: str) -> str | None:
    """The top-level part (``control``, ``cli``, ...) of a module, or None for the root."""
    pieces = module.split(".")
    return pieces[1] if len(pieces) > 1 else None


def violations(modules: dict[str, Path]) -> list[str]:
    found = []
    for name, path in modules.items():
        here = part(name)
        for line, target in imports_of(name, path):
            there = part(target)
            if there is None or there == here:
                continue  # the root package (its version) or the module's own subpackage
            if here is None:
                found.append(f"{name} (the package root) imports {target} (line {line}): "
                             "importing aerial_drake must stay light")
            elif there not in RANKS:
                found.append(f"{name} imports {target} (line {line}): {there!r} has no layer "
                             "in tests/test_layers.py")
            elif RANKS[there] > RANKS[here]:
                found.append(f"{name} ({here}) imports {target} ({there}) at line {line}: "
                             "an import up the layers")
            elif RANKS[there] == RANKS[here]:
                found.append(f"{name} ({here}) imports {target} ({there}) at line {line}: "
                             "a sideways import between parts of one layer")
    return found


def test_every_part_has_a_layer():
    parts = {part(name) for name in MODULES} - {None}
    assert parts <= set(RANKS), f"parts without a layer: {sorted(parts - set(RANKS))}"


def test_no_import_runs_up_or_sideways():
    found = violations(MODULES)
    assert not found, "\n".join(found)


def test_the_check_sees_imports_inside_functions(tmp_path):
    # The check itself: an import up the layers inside a function body is reported.
    robots = tmp_path / "aerial_drake" / "robots"
    robots.mkdir(parents=True)
    module = robots / "upward.py"
    module.write_text("def f():\n    from aerial_drake.simulation import runner\n")
    found = violations({"aerial_drake.robots.upward": module})
    assert len(found) == 1 and "aerial_drake.simulation.runner (simulation)" in found[0], found


def test_no_import_cycles():
    graph = {name: {t for _, t in imports_of(name, path) if t in MODULES and t != name}
             for name, path in MODULES.items()}
    # A package's __init__ importing its own modules is not a cycle back.
    state: dict[str, int] = {}

    def visit(name, stack):
        state[name] = 1
        for target in sorted(graph[name]):
            if name.startswith(target + "."):
                continue  # a module imports its package's __init__ (re-exports): fine
            if state.get(target) == 1:
                cycle = stack[stack.index(target):] + [target]
                pytest.fail("import cycle: " + " -> ".join(cycle))
            if target not in state:
                visit(target, stack + [target])
        state[name] = 2

    for name in MODULES:
        if name not in state:
            visit(name, [name])


def test_pyproject_lists_every_subpackage():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    packages = {module_name(p) for p in PACKAGE.rglob("__init__.py")}
    listed = set(config["packages"]) - {"aerial_drake.sdf"}
    assert packages == listed, (f"missing from pyproject: {sorted(packages - listed)}; "
                                f"listed but absent: {sorted(listed - packages)}")
    for data_package in config["package-data"]:
        assert data_package in config["packages"], data_package


def test_tests_mirror_the_package():
    folders = {p.parent.name for p in (ROOT / "tests").glob("*/test_*.py")}
    parts = {part(name) for name in MODULES} - {None}
    assert folders <= parts, f"test folders with no subpackage: {sorted(folders - parts)}"


def test_modules_are_small():
    long = {name: n for name, path in MODULES.items()
            if (n := len(path.read_text().splitlines())) > MAX_LINES}
    assert set(long) <= LONG_MODULES, f"modules over {MAX_LINES} lines: {long}"


#: Modules outside the command-line package that parse arguments: viz.plots keeps its own
#: ``python -m aerial_drake.viz.plots`` (docs/paper.md), parsing in its ``main`` only.
OWN_COMMAND_LINES = {"aerial_drake.viz.plots"}


def test_only_the_command_line_parses():
    """Studies, analysis and the rest take typed arguments: no module below ``cli`` imports
    argparse (so none takes an argparse.Namespace)."""
    found = [name for name, path in MODULES.items()
             if part(name) not in ("cli", "__main__") and name not in OWN_COMMAND_LINES
             and any(isinstance(node, (ast.Import, ast.ImportFrom))
                     and "argparse" in ([a.name for a in node.names]
                                        if isinstance(node, ast.Import) else [node.module])
                     for node in ast.walk(ast.parse(path.read_text(), str(path))))]
    assert not found, f"modules below the command line that import argparse: {found}"
