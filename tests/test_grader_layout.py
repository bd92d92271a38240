"""The grader's shape shows who runs what: role folders, imports that run one way, no circle.

Roles, from the bottom up (a module imports only its own role or those below it):

- ``sandbox``: runs student code (ships to students);
- ``harness``: the graded-test format (ships);
- ``oracles``: what public tests compare with (ships);
- ``student``: check, submit, update, the notebooks' fallback (ships);
- ``reports``: results.json and the pages (instructor);
- ``batch``: grading a class (instructor);
- ``release``: the student edition and Gradescope's archive (instructor);
- ``samples``: the example class and the hostile submissions (instructor).

The package face (``__init__``, ``__main__``, ``cli``) may name any role; ``errors``
imports nothing.  The imports are read from the source (every ``import`` statement,
inside functions too), never by importing.
"""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

GRADER = Path(__file__).resolve().parent.parent / "grader"
ROLES = ("sandbox", "harness", "oracles", "student", "reports", "batch", "release", "samples")
#: Roles that do not import each other although neither is below the other.
SIDE_BY_SIDE = {frozenset({"student", "reports"})}
FACE = ("__init__", "__main__", "cli")
SHIPPED_ROLES = ("sandbox", "oracles", "harness", "student")


def modules() -> dict[str, Path]:
    """{dotted name under grader: file} of every module of grader/ but the graded tests."""
    found = {}
    for path in sorted(GRADER.rglob("*.py")):
        relative = path.relative_to(GRADER)
        if relative.parts[0] == "tests":
            continue
        parts = list(relative.with_suffix("").parts)
        if parts[-1] == "__init__" and len(parts) > 1:
            parts = parts[:-1]
        found[".".join(parts)] = path
    return found


def imports_of(name: str, path: Path, known: dict[str, Path]) -> list[tuple[str, int, bool]]:
    """(grader module imported, line, inside a function) for each import statement."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    if name == "__init__":
        package = []
    inside = {id(n) for f in ast.walk(tree) if isinstance(f, (ast.FunctionDef, ast.AsyncFunctionDef))
              for n in ast.walk(f)}
    found = []

    def add(target: list[str], node: ast.AST) -> None:
        while target and ".".join(target) not in known:
            target = target[:-1]   # a name imported from a module, not a module
        if target:
            found.append((".".join(target), node.lineno, id(node) in inside))

    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("grader."):
                    add(alias.name.split(".")[1:], node)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[:len(package) - (node.level - 1)]
            elif node.module and node.module.split(".")[0] == "grader":
                base = []
                node_module = node.module.split(".")[1:]
                for alias in node.names:
                    add(node_module + [alias.name], node)
                continue
            else:
                continue
            module = base + (node.module.split(".") if node.module else [])
            for alias in node.names:
                add(module + [alias.name], node)
    return found


def role_of(module: str) -> str:
    return module.split(".")[0]


@pytest.fixture(scope="module")
def graph() -> dict[str, list[tuple[str, int, bool]]]:
    known = modules()
    return {name: imports_of(name, path, known) for name, path in known.items()}


def test_every_module_is_in_a_role_folder_or_the_face():
    loose = [name for name in modules() if "." not in name and name not in (*FACE, "errors", *ROLES)]
    assert loose == []
    assert set(ROLES) <= set(modules())   # each role folder is a package with its __init__


def test_imports_run_one_way(graph):
    wrong = []
    for name, targets in graph.items():
        role = role_of(name)
        if role in FACE:
            continue
        for target, line, _ in targets:
            other = role_of(target)
            if other == role or other == "errors":
                continue
            if role == "errors" or other in FACE or frozenset({role, other}) in SIDE_BY_SIDE \
                    or ROLES.index(other) > ROLES.index(role):
                wrong.append(f"grader.{name}:{line} imports grader.{target} ({role} -> {other})")
    assert wrong == []


def test_no_import_circle(graph):
    # Tarjan's strongly connected components over the import statements.
    index, low, stack, on_stack, circles = {}, {}, [], set(), []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for target, _, _ in graph.get(node, []):
            if target == node:
                continue
            if target not in index:
                visit(target)
                low[node] = min(low[node], low[target])
            elif target in on_stack:
                low[node] = min(low[node], index[target])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                circles.append(sorted(component))

    for node in graph:
        if node not in index:
            visit(node)
    assert circles == []


def test_a_deferred_import_says_why(graph):
    """An import inside a function defers a heavy import (pytest, matplotlib, numba ...):
    its line, or the one above, says so; it never dodges a circle."""
    silent = []
    for name, targets in graph.items():
        lines = modules()[name].read_text(encoding="utf-8").splitlines()
        for target, line, inside in targets:
            if inside and "deferred" not in lines[line - 1] + lines[line - 2]:
                silent.append(f"grader.{name}:{line} imports grader.{target} inside a function")
    assert silent == []


def test_the_shipped_roles_import_nothing_of_the_instructor(graph):
    for name, targets in graph.items():
        if role_of(name) in SHIPPED_ROLES:
            assert not [t for t, _, _ in targets if role_of(t) not in (*SHIPPED_ROLES, "errors")], name


def test_the_graded_tests_import_only_what_ships():
    for path in sorted((GRADER / "tests").rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("grader."):
                role = node.module.split(".")[1]
                allowed = (*SHIPPED_ROLES, "tests") if "hidden" in path.parts else SHIPPED_ROLES
                assert role in allowed, f"{path.relative_to(GRADER)} imports {node.module}"


def test_no_private_name_crosses_a_module():
    crossing = []
    for name, path in modules().items():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and (node.level or (node.module or "").startswith("grader")):
                crossing += [f"grader.{name}:{node.lineno} imports {a.name}" for a in node.names
                             if a.name.startswith("_") and a.name != "__version__"]
    assert crossing == []
