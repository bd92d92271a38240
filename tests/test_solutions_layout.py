"""The reference engine's shape: no module of solutions/ imports another's private name,
and none grows past about 500 lines.

A name starting with ``_`` is its module's own; a name two modules share is public
(the compiled twins share the readable modules' constants and each other's stages
that way).  The imports are read from the source (every ``from ... import``, inside
functions too), never by importing.
"""
from __future__ import annotations

import ast
from pathlib import Path

SOLUTIONS = Path(__file__).resolve().parent.parent / "solutions"
#: "About 500 lines": a module may run a tenth over before it must be split.
MAX_LINES = 550


def modules() -> list[Path]:
    return sorted(SOLUTIONS.rglob("*.py"))


def private_imports(path: Path) -> list[str]:
    """``line: module.name`` for each private name ``path`` imports from a module of the package."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and (node.level or (node.module or "").split(".")[0] == "solutions"):
            found += [f"{node.lineno}: {node.module}.{alias.name}" for alias in node.names
                      if alias.name.startswith("_") and not alias.name.startswith("__")]
    return found


def test_no_private_name_crosses_a_module():
    crossing = {path.relative_to(SOLUTIONS).as_posix(): found for path in modules()
                if (found := private_imports(path))}
    assert crossing == {}


def test_the_check_sees_a_private_import(tmp_path):
    module = tmp_path / "module.py"
    module.write_text("from .grid_numba import _grid_pairs, DENSE\nfrom numpy import _core\n")
    assert private_imports(module) == ["1: grid_numba._grid_pairs"]


def test_no_module_is_much_over_500_lines():
    lengths = {path.relative_to(SOLUTIONS).as_posix(): len(path.read_text(encoding="utf-8").splitlines())
               for path in modules()}
    too_long = {name: lines for name, lines in lengths.items() if lines > MAX_LINES}
    assert too_long == {}
