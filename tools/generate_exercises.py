"""Generate the student package ``exercises/`` from the reference engine ``solutions/``.

Every block between a line ``### BEGIN SOLUTION`` and a line ``### END SOLUTION``
(nbgrader style, inside a function body, below the docstring) becomes
``raise NotImplementedError`` at the marker's indentation.  Modules without markers
are copied verbatim (apart from a header naming their source).  The whole output is
built in memory first: a marker error writes nothing.

Usage::

    python -m tools.generate_exercises            # rewrite exercises/
    python -m tools.generate_exercises --check    # exit 1 if exercises/ is stale

Errors (``MarkerError``, exit status 2) name the file and line: a nested BEGIN, an END
without BEGIN, a BEGIN never closed, a marker outside a function body, an empty block,
an absolute ``solutions`` import (the student package must import its own modules),
or generated code that does not parse.
"""
from __future__ import annotations

import argparse
import ast
import difflib
import re
import shutil
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

BEGIN_MARKER = "### BEGIN SOLUTION"
END_MARKER = "### END SOLUTION"
STUB_LINE = "raise NotImplementedError"
SOURCE_PACKAGE = "solutions"
TARGET_PACKAGE = "exercises"
REPO_ROOT = Path(__file__).resolve().parent.parent
HEADER = ("# Generated from {source} by tools/generate_exercises.py: edit solutions/, "
          "then run `python -m tools.generate_exercises`.\n")
ABSOLUTE_IMPORT = re.compile(rf"^\s*(from|import)\s+{SOURCE_PACKAGE}\b")
# Doctest lines import from the package by name; the student copy imports its own.
DOCTEST_IMPORT = re.compile(rf"^(\s*(?:>>>|\.\.\.)\s+(?:from|import)\s+){SOURCE_PACKAGE}\b")


class MarkerError(ValueError):
    """A solution marker is misplaced; the message names the file and line."""


@dataclass(frozen=True)
class StubbedFunction:
    """A function whose solution block was replaced: ``module`` and ``qualname``."""

    module: str
    qualname: str


def _function_spans(tree: ast.AST, lines: list[str]) -> list[tuple[int, int, int, str]]:
    """(def line, last line, def column, qualname) of every function, innermost last.

    The last line is extended over trailing comment lines indented deeper than the
    ``def``, so that a block whose END marker closes the function still belongs to it.
    """
    spans: list[tuple[int, int, int, str]] = []

    def extended_end(node) -> int:
        end = node.end_lineno
        while end < len(lines):
            text = lines[end]
            indent = len(text) - len(text.lstrip())
            if text.strip() and not (text.lstrip().startswith("#") and indent > node.col_offset):
                break
            end += 1
        return end

    def visit(node, prefix):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                name = f"{prefix}{child.name}"
                spans.append((child.lineno, extended_end(child), child.col_offset, name))
                visit(child, f"{name}.<locals>.")
            elif isinstance(child, ast.ClassDef):
                visit(child, f"{prefix}{child.name}.")
            else:
                visit(child, prefix)

    visit(tree, "")
    return spans


def strip_solutions(source: str, filename: str = "<string>") -> tuple[str, list[str]]:
    """Return ``(student_source, stubbed_qualnames)`` for one module's text.

    >>> text = 'def f(x):\\n    \"\"\"Double x.\"\"\"\\n    ### BEGIN SOLUTION\\n    return 2 * x\\n    ### END SOLUTION\\n'
    >>> print(strip_solutions(text)[0], end="")
    def f(x):
        \"\"\"Double x.\"\"\"
        raise NotImplementedError
    """
    lines = source.splitlines(keepends=True)
    try:
        tree = ast.parse(source, filename=filename)
    except SyntaxError as exc:
        raise MarkerError(f"{filename}:{exc.lineno}: the solution file does not parse: {exc.msg}") from exc
    spans = _function_spans(tree, lines)
    out: list[str] = []
    stubbed: list[str] = []
    begin_line = None
    block_has_code = False
    for number, line in enumerate(lines, start=1):
        stripped = line.strip()
        if ABSOLUTE_IMPORT.match(line):
            raise MarkerError(f"{filename}:{number}: absolute import of '{SOURCE_PACKAGE}'; "
                              "use a relative import so the student package imports its own modules")
        if stripped == BEGIN_MARKER:
            if begin_line is not None:
                raise MarkerError(f"{filename}:{number}: nested '{BEGIN_MARKER}' "
                                  f"(the block opened at line {begin_line} is not closed)")
            indent_width = len(line) - len(line.lstrip())
            owners = [name for first, last, column, name in spans
                      if first < number <= last and indent_width > column]
            if not owners:
                raise MarkerError(f"{filename}:{number}: '{BEGIN_MARKER}' outside a function body")
            begin_line = number
            block_has_code = False
            indent = line[: len(line) - len(line.lstrip())]
            out.append(f"{indent}{STUB_LINE}\n")
            stubbed.append(owners[-1])
            continue
        if stripped == END_MARKER:
            if begin_line is None:
                raise MarkerError(f"{filename}:{number}: '{END_MARKER}' without a matching '{BEGIN_MARKER}'")
            if not block_has_code:
                raise MarkerError(f"{filename}:{begin_line}: empty solution block")
            begin_line = None
            continue
        if BEGIN_MARKER in line or END_MARKER in line:
            raise MarkerError(f"{filename}:{number}: a solution marker must stand alone on its line")
        if begin_line is not None:
            block_has_code = block_has_code or bool(stripped and not stripped.startswith("#"))
            continue
        out.append(DOCTEST_IMPORT.sub(rf"\g<1>{TARGET_PACKAGE}", line))
    if begin_line is not None:
        raise MarkerError(f"{filename}:{begin_line}: '{BEGIN_MARKER}' is never closed by '{END_MARKER}'")
    student = "".join(out)
    try:
        ast.parse(student, filename=filename)
    except SyntaxError as exc:
        raise MarkerError(f"{filename}:{exc.lineno}: the generated student code does not parse: {exc.msg}") from exc
    return student, stubbed


def generate(source_dir: Path) -> tuple[dict[str, str], list[StubbedFunction]]:
    """Every file of the student package, as {relative path: text}, and the stubs made."""
    files: dict[str, str] = {}
    stubs: list[StubbedFunction] = []
    for path in sorted(source_dir.rglob("*.py")):
        if "__pycache__" in path.parts:
            continue
        relative = path.relative_to(source_dir).as_posix()
        text = path.read_text(encoding="utf-8")
        student, stubbed = strip_solutions(text, f"{SOURCE_PACKAGE}/{relative}")
        files[relative] = HEADER.format(source=f"{SOURCE_PACKAGE}/{relative}") + student
        module = ".".join([TARGET_PACKAGE, *Path(relative).with_suffix("").parts])
        module = module.removesuffix(".__init__")
        stubs += [StubbedFunction(module, name) for name in stubbed]
    return files, stubs


def existing_files(target_dir: Path) -> dict[str, str]:
    """The student package as committed: {relative path: text} of its .py files."""
    if not target_dir.exists():
        return {}
    return {p.relative_to(target_dir).as_posix(): p.read_text(encoding="utf-8")
            for p in sorted(target_dir.rglob("*.py")) if "__pycache__" not in p.parts}


def differences(wanted: dict[str, str], present: dict[str, str]) -> list[str]:
    """Human-readable list of what differs between generated and committed files."""
    problems = []
    for name in sorted(set(wanted) | set(present)):
        if name not in present:
            problems.append(f"missing: {TARGET_PACKAGE}/{name}")
        elif name not in wanted:
            problems.append(f"stale (no source in {SOURCE_PACKAGE}/): {TARGET_PACKAGE}/{name}")
        elif wanted[name] != present[name]:
            diff = difflib.unified_diff(present[name].splitlines(), wanted[name].splitlines(),
                                        f"{TARGET_PACKAGE}/{name} (committed)", "(generated)", lineterm="", n=1)
            problems.append("differs: " + "\n".join(list(diff)[:12]))
    return problems


def write(files: dict[str, str], target_dir: Path) -> None:
    """Replace ``target_dir`` by ``files``, built in a temporary folder first."""
    target_dir.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=".exercises-", dir=target_dir.parent))
    try:
        for name, text in files.items():
            out = staging / name
            out.parent.mkdir(parents=True, exist_ok=True)
            out.write_text(text, encoding="utf-8")
        backup = target_dir.with_name(target_dir.name + ".old")
        if target_dir.exists():
            target_dir.rename(backup)
        staging.rename(target_dir)
        shutil.rmtree(backup, ignore_errors=True)
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="compare with exercises/ and exit 1 if stale")
    parser.add_argument("--source", type=Path, default=REPO_ROOT / SOURCE_PACKAGE)
    parser.add_argument("--target", type=Path, default=REPO_ROOT / TARGET_PACKAGE)
    args = parser.parse_args(argv)
    try:
        files, stubs = generate(args.source)
    except MarkerError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if args.check:
        problems = differences(files, existing_files(args.target))
        for problem in problems:
            print(problem, file=sys.stderr)
        if problems:
            print("exercises/ is out of date: run `python -m tools.generate_exercises`", file=sys.stderr)
            return 1
        print(f"exercises/ is in sync: {len(files)} modules, {len(stubs)} stubs")
        return 0
    write(files, args.target)
    print(f"wrote {args.target}: {len(files)} modules, {len(stubs)} stubs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
