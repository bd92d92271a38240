"""Which files of ``grader/`` a set of entry points needs, and which installed packages.

Read from the source, never by importing it: a module needs the grader modules it
imports (anywhere in it, lazily too), the package ``__init__`` files on the way, and the
files it names in string literals (``"worker.py"``, ``"pytest.ini"``).  The student
edition (:mod:`grader.release.edition`) and Gradescope's archive (:mod:`grader.release.gradescope`)
both ship what their entry points reach, and install what that reaches imports.
"""
from __future__ import annotations

import ast
import re
import sys
from pathlib import Path
from typing import Callable, Iterable

#: Top-level names that are this repository's own packages, never a distribution.
LOCAL_PACKAGES = {"grader", "exercises", "solutions", "tools"}
#: Folder and file names that are caches or editor litter, never shipped.
IGNORED_NAMES = {"__pycache__", ".ipynb_checkpoints", ".DS_Store", ".pytest_cache", ".hypothesis"}
_FILE_LITERAL = re.compile(r"^[\w.-]+(?:/[\w.-]+)*\.(?:py|ini|cfg|toml|json|txt|csv|ya?ml)$")


def ignored(relative: Path) -> bool:
    """True for a cache or compiled file (a path relative to the shipped folder)."""
    return any(part in IGNORED_NAMES for part in relative.parts) or relative.suffix in (".pyc", ".pyo")


def _docstring_nodes(tree: ast.AST) -> set[int]:
    ids = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) and isinstance(
                    first.value.value, str):
                ids.add(id(first.value))
    return ids


def module_file(grader_dir: Path, parts: list[str]) -> Path | None:
    """The file of module ``grader.<parts>`` (a module, or a package's ``__init__``)."""
    base = grader_dir.joinpath(*parts) if parts else grader_dir
    if parts and base.with_suffix(".py").is_file():
        return base.with_suffix(".py")
    if (base / "__init__.py").is_file():
        return base / "__init__.py"
    return None


def references_of(path: Path, grader_dir: Path,
                  excluded: Callable[[str], bool] = lambda relative: False) -> list[tuple[Path, str]]:
    """Files of ``grader_dir`` that the module ``path`` needs, each with how (``imports``,
    ``names``).  A bare file name found nowhere near is looked for deeper (``pytest.ini``
    of ``tests/``), except in the places ``excluded`` (path relative to grader_dir) names."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    package = list(path.parent.relative_to(grader_dir).parts)
    found: list[tuple[Path, str]] = []

    def add_module(parts: list[str], names: Iterable[str] = ()) -> None:
        for depth in range(len(parts) + 1):   # the package __init__ files on the way
            file = module_file(grader_dir, parts[:depth])
            if file is not None:
                found.append((file, "imports"))
        for name in names:   # ``from .package import module``
            file = module_file(grader_dir, parts + [name])
            if file is not None:
                found.append((file, "imports"))

    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                parts = alias.name.split(".")
                if parts[0] == "grader":
                    add_module(parts[1:])
        elif isinstance(node, ast.ImportFrom):
            names = [alias.name for alias in node.names if alias.name != "*"]
            if node.level:
                if node.level - 1 > len(package):
                    continue
                base = package[:len(package) - (node.level - 1)]
                add_module(base + (node.module.split(".") if node.module else []), names)
            elif node.module and node.module.split(".")[0] == "grader":
                add_module(node.module.split(".")[1:], names)
    docstrings = _docstring_nodes(tree)
    for node in ast.walk(tree):
        if (isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings
                and _FILE_LITERAL.match(node.value)):
            for candidate in (path.parent / node.value, grader_dir / node.value):
                if candidate.is_file():
                    found.append((candidate, "names"))
                    break
            else:
                if "/" not in node.value:
                    found += [(c, "names") for c in grader_dir.rglob(node.value) if c.is_file()
                              and not ignored(c.relative_to(grader_dir))
                              and not excluded(c.relative_to(grader_dir).as_posix())]
    return found


def files_reached(grader_dir: Path, start: Iterable[tuple[Path, str]],
                  want: Callable[[str, str], None] = lambda relative, reason: None,
                  excluded: Callable[[str], bool] = lambda relative: False) -> dict[str, str]:
    """{path relative to ``grader_dir``: why} of every file the ``start`` files (each with
    a reason) reach; ``want(relative, reason)`` sees each new file first and may raise."""
    grader_dir = Path(grader_dir)
    why: dict[str, str] = {}
    queue: list[Path] = []

    def add(file: Path, reason: str) -> None:
        relative = file.relative_to(grader_dir).as_posix()
        if relative in why:
            return
        want(relative, reason)
        why[relative] = reason
        queue.append(file)

    for file, reason in start:
        add(file, reason)
    while queue:
        file = queue.pop(0)
        relative = file.relative_to(grader_dir).as_posix()
        for folder in file.relative_to(grader_dir).parents:   # packages on the way
            init = grader_dir / folder / "__init__.py"
            if str(folder) != "." and init.is_file():
                add(init, f"package of {relative}")
        if file.suffix != ".py":
            continue
        for needed, how in references_of(file, grader_dir, excluded):
            add(needed, f"{how} by {relative}")
    return dict(sorted(why.items()))


def imported_modules(source: str) -> list[str]:
    """Absolute module names imported by ``source`` (anywhere in it)."""
    tree = ast.parse(source)
    names = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names += [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.append(node.module)
    return names


def third_party_modules(files: Iterable[tuple[str, Path]]) -> dict[str, str]:
    """{top-level module: the first file importing it} of the (name, path) pairs, less
    the standard library, this repository's own packages and the modules beside the
    importing file (a script's own helpers, as ``worker.py`` imports ``codec``)."""
    found: dict[str, str] = {}
    for name, path in files:
        for module in imported_modules(Path(path).read_text(encoding="utf-8")):
            top = module.split(".")[0]
            if (top in sys.stdlib_module_names or top in LOCAL_PACKAGES or top == "__future__"
                    or (Path(path).parent / f"{top}.py").is_file()):
                continue
            found.setdefault(top, name)
    return dict(sorted(found.items()))
