"""Which graded tests can see a module of the package: the scope of a mutant's grading
(:mod:`tools.mutation`).

A graded test reaches the student's package only through the sandbox, by module name
(``student.call("broadphase.dynamic_tree", "pairs", ...)``); the sandbox imports that
module, which imports others.  A test file therefore *sees* a module when a string in
it, or in a grader module it imports, names a module whose imports (anywhere in it,
lazily too, with the packages on the way) reach that module.  Read from the source,
never by importing it, and over-inclusive on purpose: a name that only looks like a
module, or a package ``__init__`` importing its siblings, adds tests to the scope,
never removes one, so a mutant killed by any graded test is killed by one in its
scope.
"""
from __future__ import annotations

import ast
import functools
import re
from collections.abc import Iterator
from pathlib import Path

from grader.release.module_graph import references_of

REPO = Path(__file__).resolve().parent.parent
SOLUTIONS = REPO / "solutions"
GRADER = REPO / "grader"
#: The package's own name and the student's: ``"exercises.shapes"`` names ``shapes``.
PACKAGE_NAMES = ("solutions", "exercises")
_DOTTED = re.compile(r"[A-Za-z_]\w*(\.[A-Za-z_]\w*)*")


def module_name(relative: str) -> str:
    """``"broadphase/dynamic_tree.py"`` -> ``"broadphase.dynamic_tree"``; a package's
    ``__init__.py`` is the package (the top one is ``""``)."""
    parts = list(Path(relative).with_suffix("").parts)
    if parts and parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _with_packages(name: str) -> list[str]:
    """``a.b.c`` and the packages importing it runs first: ``""``, ``a``, ``a.b``."""
    parts = name.split(".") if name else []
    return [".".join(parts[:depth]) for depth in range(len(parts) + 1)]


@functools.lru_cache(maxsize=None)
def import_graph(package_dir: Path = SOLUTIONS) -> dict[str, frozenset[str]]:
    """{module: the package's modules it imports}, every import statement counted."""
    files = {module_name(p.relative_to(package_dir).as_posix()): p for p in package_dir.rglob("*.py")
             if "__pycache__" not in p.parts}
    graph = {}
    for name, path in files.items():
        package = name.split(".") if path.name == "__init__.py" and name else name.split(".")[:-1]
        package = [part for part in package if part]
        found: set[str] = set()

        def add(parts: list[str], names: list[str] = ()) -> None:
            for candidate in [".".join(parts)] + [".".join(parts + [n]) for n in names]:
                if candidate in files:
                    found.update(_with_packages(candidate))

        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    top, _, rest = alias.name.partition(".")
                    if top in PACKAGE_NAMES:
                        add(rest.split(".") if rest else [])
            elif isinstance(node, ast.ImportFrom):
                names = [alias.name for alias in node.names if alias.name != "*"]
                module = node.module.split(".") if node.module else []
                if node.level and node.level - 1 <= len(package):
                    add(package[:len(package) - (node.level - 1)] + module, names)
                elif not node.level and module and module[0] in PACKAGE_NAMES:
                    add(module[1:], names)
        graph[name] = frozenset(found - {name})
    return graph


def modules_run_by(names: set[str], graph: dict[str, frozenset[str]]) -> set[str]:
    """The modules importing ``names`` runs: theirs, their packages', and what those import."""
    seen: set[str] = set()
    queue = [n for name in names for n in _with_packages(name)]
    while queue:
        name = queue.pop()
        if name in seen or name not in graph:
            continue
        seen.add(name)
        queue += graph[name]
    return seen


def _docstrings(tree: ast.AST) -> set[int]:
    return {id(node.body[0].value) for node in ast.walk(tree)
            if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body
            and isinstance(node.body[0], ast.Expr) and isinstance(node.body[0].value, ast.Constant)}


@functools.lru_cache(maxsize=None)
def _strings(path: Path) -> frozenset[str]:
    """The dotted names in the string literals (not docstrings) of the Python file ``path``."""
    if path.suffix != ".py":
        return frozenset()
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    docstrings = _docstrings(tree)
    return frozenset(node.value for node in ast.walk(tree) if isinstance(node, ast.Constant)
                     and isinstance(node.value, str) and id(node) not in docstrings and _DOTTED.fullmatch(node.value))


@functools.lru_cache(maxsize=None)
def _grader_files_needed(path: Path) -> tuple[Path, ...]:
    """The grader files ``path`` needs, its packages' ``__init__`` files with them."""
    needed = [file for file, _ in references_of(path, GRADER)] if path.suffix == ".py" else []
    packages = [GRADER / folder / "__init__.py" for folder in path.relative_to(GRADER).parents if str(folder) != "."]
    return tuple(dict.fromkeys(file.resolve() for file in needed + [p for p in packages if p.is_file()]))


@functools.lru_cache(maxsize=None)
def named_modules(test_file: Path, package_dir: Path = SOLUTIONS) -> frozenset[str]:
    """Modules of the package named by a string (not a docstring) in ``test_file`` or in
    the grader files it reaches (what :func:`grader.release.module_graph.files_reached`
    follows, each file read once per process)."""
    graph = import_graph(package_dir)
    reached, queue, names = set(), [Path(test_file).resolve()], set()
    while queue:
        path = queue.pop()
        if path in reached:
            continue
        reached.add(path)
        queue += _grader_files_needed(path)
        for text in _strings(path):
            top, _, rest = text.partition(".")
            name = rest if top in PACKAGE_NAMES else text
            if name and name in graph:
                names.add(name)
    return frozenset(names)


def sees(test_file: Path, module: str, package_dir: Path = SOLUTIONS) -> bool:
    """True when a test of ``test_file`` can run code of ``module`` (a dotted name)."""
    return module in modules_run_by(set(named_modules(Path(test_file).resolve(), package_dir)),
                                    import_graph(package_dir))


def tests_seeing(relative: str, exercise: str, tests: list, every: bool = False) -> Iterator[tuple[str, list]]:
    """The graded tests a mutant of ``solutions/<relative>`` (of ``exercise``) is run by,
    in the order of grading, each group ``("public" | "hidden", [TestSpec, ...])``: its
    exercise's public tests, the other public ones that can see the module, its
    exercise's hidden tests, the other hidden ones that can see it.  The groups are made
    as they are asked for (a mutant the first kills needs no scope).  ``every``: all the
    other tests, seeing or not (the former scope, to compare)."""
    module = module_name(relative)
    own = [t for t in tests if t.exercise == exercise]
    yield "public", [t for t in own if t.public]
    others = [t for t in tests if t.exercise != exercise and (every or sees(Path(t.path), module))]
    yield "public", [t for t in others if t.public]
    yield "hidden", [t for t in own if not t.public]
    yield "hidden", [t for t in others if not t.public]
