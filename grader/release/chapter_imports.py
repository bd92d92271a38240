"""Which modules a chapter cell can import in the student edition (instructors only;
used by :mod:`grader.release.book`).

A student's notebook runs with what the student edition holds: the standard library,
the packages its ``pyproject.toml`` installs, and the ``exercises``, ``grader`` and
``tools`` modules it ships.  A chapter cell that imports anything else (the
instructor's ``bench/`` scripts, a compiled twin of ``solutions`` that ``exercises``
does not mirror), or that changes ``sys.path`` to reach files of the instructor's
repository, would raise ``ModuleNotFoundError`` there once the student's code no
longer falls back.  Such a cell carries the tag :data:`REFERENCE_OUTPUT_TAG`: the
student notebook keeps its code, does not run it and shows the reference's stored
output.  Without the tag, the release stops and names the chapter, the cell and
the module; it stops as well at a later cell that reads a name only such a cell binds.
"""
from __future__ import annotations

import ast
import sys
from importlib import metadata
from pathlib import Path

from .module_graph import imported_modules

#: The cell tag (``:tags: [reference-output-only]`` in a chapter's ``.md``) of a cell
#: that uses what only the instructor has: the student notebook shows its stored output.
REFERENCE_OUTPUT_TAG = "reference-output-only"
#: What :func:`instructor_only` says of a cell that changes ``sys.path``.
SYS_PATH = "sys.path"


def changes_sys_path(python: str) -> bool:
    """True when the Python ``python`` changes ``sys.path`` (a call of a method of it,
    such as ``insert`` or ``append``, an assignment to it or to an item of it, or
    ``site.addsitedir``)."""
    def is_sys_path(node: ast.AST) -> bool:
        return (isinstance(node, ast.Attribute) and node.attr == "path" and isinstance(node.value, ast.Name)
                and node.value.id == "sys")

    for node in ast.walk(ast.parse(python)):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
            if is_sys_path(node.func.value):
                return True
            if node.func.attr == "addsitedir" and isinstance(node.func.value, ast.Name) and node.func.value.id == "site":
                return True
        targets = (node.targets if isinstance(node, ast.Assign)
                   else [node.target] if isinstance(node, (ast.AugAssign, ast.AnnAssign)) else [])
        for target in targets:
            if is_sys_path(target) or (isinstance(target, ast.Subscript) and is_sys_path(target.value)):
                return True
    return False


class StudentModules:
    """``available(module)``: whether a student's kernel can import ``module``: the
    standard library; a module of a local package (``roots``: top-level name -> the
    folder the student edition ships it as) that has a file there; any other module
    that an installed distribution provides (the release pins it for the student, or
    stops when nothing of ``pyproject.toml`` pins it)."""

    def __init__(self, roots: dict[str, Path]):
        self.roots = {name: Path(folder) for name, folder in roots.items()}
        self.distributed = set(metadata.packages_distributions())

    def available(self, module: str) -> bool:
        parts = module.split(".")
        if parts[0] in sys.stdlib_module_names or parts[0] == "__future__":
            return True
        if parts[0] in self.roots:
            base = self.roots[parts[0]].joinpath(*parts[1:])
            return (base / "__init__.py").is_file() or (len(parts) > 1 and base.with_suffix(".py").is_file())
        return parts[0] in self.distributed


def instructor_only(python: str, modules: StudentModules) -> list[str]:
    """What the Python of a cell uses that the student edition does not hold: the
    modules it imports that are not ``available``, and :data:`SYS_PATH` when it
    changes ``sys.path``, in that order."""
    found = [m for m in dict.fromkeys(imported_modules(python)) if not modules.available(m)]
    return found + ([SYS_PATH] if changes_sys_path(python) else [])


def bound_names(python: str) -> set[str]:
    """Names the Python of a cell binds at its top level (assigned, imported, defined)."""
    names = set()
    for node in ast.parse(python).body:
        for inner in ast.walk(node):
            if isinstance(inner, ast.Name) and isinstance(inner.ctx, ast.Store):
                names.add(inner.id)
            elif isinstance(inner, (ast.Import, ast.ImportFrom)):
                names.update((a.asname or a.name.split(".")[0]) for a in inner.names if a.name != "*")
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
    return names


def loaded_names(python: str) -> set[str]:
    """Names the Python of a cell reads."""
    return {n.id for n in ast.walk(ast.parse(python)) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)}


def unshipped_message(where: str, needs: list[str]) -> str:
    """The release's refusal of the cell ``where`` that uses ``needs`` untagged."""
    what = "; ".join(f"it changes {n}, which reaches files of the instructor's repository" if n == SYS_PATH
                     else f"it imports {n}, which is neither the standard library, a package the student edition "
                          "installs, nor a module it ships" for n in needs)
    return (f"{where}: {what}.  In a student's notebook the cell would fail; if it must use what only the "
            f"instructor has, tag it `{REFERENCE_OUTPUT_TAG}` (the student notebook then shows its stored output)")


class ChapterImportError(ValueError):
    """A chapter cell would fail in the student edition; the message says which and why."""


class ChapterGuard:
    """The code cells of one chapter, seen in order (:meth:`cell`)."""

    def __init__(self, modules: StudentModules):
        self.modules = modules
        self.never_bound: dict[str, str] = {}   # name -> the tagged cell that alone binds it

    def cell(self, where: str, python: str, shown_only: bool) -> list[str]:
        """What the cell ``where`` (its Python; tagged or not) uses that only the
        instructor has (:func:`instructor_only`); ChapterImportError for an untagged cell
        that uses any, or one that reads a name only a tagged cell binds."""
        needs = instructor_only(python, self.modules)
        if needs and not shown_only:
            raise ChapterImportError(unshipped_message(where, needs))
        bound = bound_names(python)
        unbound = sorted((loaded_names(python) - bound) & set(self.never_bound))
        if unbound:
            raise ChapterImportError(f"{where}: the cell reads {', '.join(unbound)}, which only "
                                     f"{self.never_bound[unbound[0]]} binds; that cell is {REFERENCE_OUTPUT_TAG} and "
                                     "never runs in the student notebook: bind it in a cell that runs")
        for name in bound:
            if shown_only:
                self.never_bound[name] = where
            else:
                self.never_bound.pop(name, None)
        return needs
