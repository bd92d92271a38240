"""Generate the student package ``exercises/`` from the reference engine ``solutions/``.

A module holding a line that starts with ``### INSTRUCTOR ONLY`` is left out: the
numpy and numba twins that compute what an exercise computes (the SAT of boxes, their
clipping, the solver's impulses) would hand out its answer in another form; the
student package steps the world with the readable code instead.

Every block between a line ``### BEGIN SOLUTION`` and a line ``### END SOLUTION``
(nbgrader style, inside a function body, below the docstring) becomes a
``raise NotImplementedError("write <function>(), then run `grader check <exercise>`")``
at the marker's indentation.  Modules without markers are copied verbatim.  Each file
starts with a header for the student: an exercise file names the ``grader check``
command(s) of its exercise(s) (:data:`EXERCISES`), a library file says it needs no
editing.  The whole output is built in memory first: a marker error writes nothing.

The generator never erases work.  It records what it wrote in ``exercises/.generated.json``
(:data:`MANIFEST`: each file's SHA-256, nothing else), and before writing it compares
the folder with that record: a file edited, added or deleted since (a student's work,
perhaps) makes it refuse, name the files and write nothing.  Without a record (a
first run, a tree older than the record) the folder must equal what it would write.
``--force`` writes anyway, after moving the old folder to ``exercises.backup-<date>-<time>/``
beside it.

Usage::

    python -m grader.release.exercises            # rewrite exercises/ (refused if it holds edits)
    python -m grader.release.exercises --force    # the same, keeping a backup of an edited tree
    python -m grader.release.exercises --check    # exit 1 if exercises/ differs from what it makes

Errors (exit status 2) name the file and line: a nested BEGIN, an END without BEGIN,
a BEGIN never closed, a marker outside a function body, an empty block, an absolute
``solutions`` import (the student package must import its own modules), generated code
that does not parse, or no ``solutions/`` folder at all.  A refusal to overwrite edits
exits with status 3.
"""
from __future__ import annotations

import argparse
import ast
import difflib
import hashlib
import json
import re
import shutil
import sys
import tempfile
import textwrap
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

BEGIN_MARKER = "### BEGIN SOLUTION"
INSTRUCTOR_ONLY_MARKER = "### INSTRUCTOR ONLY"
END_MARKER = "### END SOLUTION"
STUB_LINE = "raise NotImplementedError"
SOURCE_PACKAGE = "solutions"
TARGET_PACKAGE = "exercises"
REPO_ROOT = Path(__file__).resolve().parents[2]
#: What the generator last wrote, in the target folder: {"sha256": {relative path: digest}}.
MANIFEST = ".generated.json"
#: ``--force`` moves an edited target folder to ``<target>.backup-<BACKUP_STAMP>``.
BACKUP_STAMP = "%Y%m%d-%H%M%S"
#: Exit status of a refusal to overwrite edits (2: a marker or source error).
REFUSED = 3
#: Folders and files in the target that are no one's work: Python's caches.
CACHE_PARTS = ("__pycache__",)
CACHE_SUFFIXES = (".pyc", ".pyo")

#: The exercise (the name ``grader check`` takes, see grader/harness/spec.py) of every stubbed
#: function, by module under solutions/: one name for all the module's stubs, or
#: {qualname: exercise} where the module serves two exercises.  A stub not listed
#: (tests/test_generate_exercises.py fails for the repository's own) names plain
#: ``grader check``, which runs every exercise.
EXERCISES: dict[str, str | dict[str, str]] = {
    "response/momentum_1d.py": "momentum",
    "broadphase/uniform_grid.py": "grid",
    "broadphase/quadtree.py": "quadtree",
    "broadphase/dynamic_tree.py": "dynamic_tree",
    "narrowphase/projection.py": "sat",
    "narrowphase/aabb_aabb.py": {"aabbs_overlap": "sat", "collide_aabb_aabb": "contacts"},
    "narrowphase/circle_circle.py": {"circles_overlap": "sat", "collide_circle_circle": "contacts"},
    "narrowphase/circle_polygon.py": {"circle_polygon_overlap": "sat", "collide_circle_polygon": "contacts"},
    "narrowphase/polygon_polygon.py": {"polygons_overlap": "sat", "obbs_overlap": "sat",
                                       "max_face_separation": "contacts",
                                       "reference_face_candidates": "contacts",
                                       "clip_segment_to_half_plane": "contacts",
                                       "reference_face_manifold": "contacts",
                                       "collide_polygon_polygon": "contacts"},
    "response/impulse.py": "impulse",
    "solver/contact_point.py": "sequential",
    "solver/contact_sweeps.py": "sequential",
    "response/positional_correction.py": "impulse",
}
#: The comment lines above each student file (:func:`header`): what it is, how to check
#: it, where it came from; never how to regenerate it, which would replace a student's work.
EXERCISE_HEADER = ("Exercise file of the collision course: write the functions that raise NotImplementedError, "
                   "then check them with {commands}.")
LIBRARY_HEADER = "Library file of the collision course (you do not need to edit it)."
PROVENANCE = "Handed out with the course; generated from {source} on the instructor's side."
HEADER_WIDTH = 100
ABSOLUTE_IMPORT = re.compile(rf"^\s*(from|import)\s+{SOURCE_PACKAGE}\b")
# Doctest lines import from the package by name; the student copy imports its own.
DOCTEST_IMPORT = re.compile(rf"^(\s*(?:>>>|\.\.\.)\s+(?:from|import)\s+){SOURCE_PACKAGE}\b")
# Cross-references in docstrings (``:mod:`solutions.shapes```, ``solutions.world.World``)
# name a dotted path in the package, or the package itself as a role's target.
CROSS_REFERENCE = re.compile(rf"(?<![\w/.]){SOURCE_PACKAGE}((?:\.[A-Za-z_]\w*)+)|(?<=:`){SOURCE_PACKAGE}(?=`)")
# The same, whole: a role (``:mod:`~solutions.x```) or a literal (````solutions.x````).
WRAPPED_REFERENCE = re.compile(rf":[\w:-]+:`~?({SOURCE_PACKAGE}(?:\.[A-Za-z_]\w*)+)`"
                               rf"|``({SOURCE_PACKAGE}(?:\.[A-Za-z_]\w*)+)``")


class GeneratorError(ValueError):
    """The student package cannot be generated; the message says why (exit status 2)."""


class MarkerError(GeneratorError):
    """A solution marker is misplaced; the message names the file and line."""


@dataclass(frozen=True)
class StubbedFunction:
    """A function whose solution block was replaced: ``module`` and ``qualname``, and
    the ``exercise`` whose ``grader check`` tests it (None if :data:`EXERCISES` has none)."""

    module: str
    qualname: str
    exercise: str | None = None


def exercise_of(relative: str, qualname: str, table: dict | None = None) -> str | None:
    """The exercise of the stub ``qualname`` in ``solutions/<relative>`` (see :data:`EXERCISES`)."""
    entry = (EXERCISES if table is None else table).get(relative)
    if isinstance(entry, dict):
        return entry.get(qualname)
    return entry


def check_commands(exercises: list[str | None]) -> str:
    """The ``grader check`` command(s) that test functions of these exercises."""
    named = list(dict.fromkeys(e for e in exercises if e))
    commands = [f"`grader check {e}`" for e in named]
    if not named or None in exercises:
        commands.append("`grader check`")  # every exercise
    return " and ".join(commands)


def stub_line(qualname: str, exercise: str | None) -> str:
    """The statement that replaces a solution block: it names what to write and how to check it."""
    message = f"write {qualname}(), then run {check_commands([exercise])}"
    return f"{STUB_LINE}({json.dumps(message)})"


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


def strip_solutions(source: str, filename: str = "<string>",
                    exercise: Callable[[str], str | None] = lambda qualname: None) -> tuple[str, list[str]]:
    """Return ``(student_source, stubbed_qualnames)`` for one module's text.

    ``exercise(qualname)`` names the exercise of a stub, for its message (None: all).

    >>> text = 'def f(x):\\n    \"\"\"Double x.\"\"\"\\n    ### BEGIN SOLUTION\\n    return 2 * x\\n    ### END SOLUTION\\n'
    >>> print(strip_solutions(text, exercise=lambda qualname: "momentum")[0], end="")
    def f(x):
        \"\"\"Double x.\"\"\"
        raise NotImplementedError("write f(), then run `grader check momentum`")
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
            out.append(f"{indent}{stub_line(owners[-1], exercise(owners[-1]))}\n")
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


def header(source: str, stubs: list[tuple[str, str | None]] = ()) -> str:
    """The comment lines above a student file: what it is, how to check it, where it came from.

    ``stubs`` lists the file's (qualname, exercise); a file serving two exercises says
    which functions each one checks.
    """
    if not stubs:
        first = LIBRARY_HEADER
    else:
        exercises = list(dict.fromkeys(exercise for _, exercise in stubs))
        commands = check_commands(exercises) if len(exercises) == 1 else " and ".join(
            f"{check_commands([exercise])} ({', '.join(q for q, e in stubs if e == exercise)})"
            for exercise in exercises)
        first = EXERCISE_HEADER.format(commands=commands)
    lines = []
    for sentence in (first, PROVENANCE.format(source=source)):
        lines += textwrap.wrap(sentence, width=HEADER_WIDTH, initial_indent="# ", subsequent_indent="# ",
                               break_long_words=False, break_on_hyphens=False)
    return "\n".join(lines) + "\n"


def is_instructor_only(source: str) -> bool:
    """Whether a module is kept out of the student package (a line starting with
    :data:`INSTRUCTOR_ONLY_MARKER`).

    >>> is_instructor_only("'Doc.'\\n### INSTRUCTOR ONLY: a twin.\\nx = 1\\n"), is_instructor_only("x = 1\\n")
    (True, False)
    """
    return any(line.startswith(INSTRUCTOR_ONLY_MARKER) for line in source.splitlines())


def module_name(relative: str) -> str:
    """The dotted name of the reference module at ``relative`` (a path under solutions/).

    >>> module_name("response/soft_step.py"), module_name("narrowphase/__init__.py")
    ('solutions.response.soft_step', 'solutions.narrowphase')
    """
    return ".".join([SOURCE_PACKAGE, *Path(relative).with_suffix("").parts]).removesuffix(".__init__")


def point_references_at_the_student_package(text: str, modules: dict[str, bool]) -> str:
    """``text`` with every cross-reference into a module the student edition holds
    renamed into the student package.  ``modules`` maps each reference module's dotted
    name to whether it is handed out; a reference names the longest module that is a
    prefix of it.  A reference to one of the instructor's own modules (the compiled
    twins), which the student does not have, becomes its file, said to be the
    instructor's; prose is left alone.

    >>> point_references_at_the_student_package(
    ...     "see :func:`~solutions.shapes.polygon_vertices`, :mod:`solutions` and "
    ...     ":mod:`solutions.response.twin`; the solutions of the LCP; solutions/shapes.py",
    ...     {"solutions": True, "solutions.shapes": True, "solutions.response": True,
    ...      "solutions.response.twin": False})
    "see :func:`~exercises.shapes.polygon_vertices`, :mod:`exercises` and ``response/twin.py`` of the \
instructor's edition; the solutions of the LCP; solutions/shapes.py"
    """
    def module_of(dotted: str) -> str:
        parts = dotted.split(".")
        return next(".".join(parts[:k]) for k in range(len(parts), 0, -1) if ".".join(parts[:k]) in modules
                    or k == 1)

    def instructors(dotted: str, wrapped: bool) -> str:
        module = module_of(dotted)
        path = "/".join(module.split(".")[1:]) + ".py"
        inside = dotted[len(module) + 1:]
        quote = "``" if wrapped else ""
        return (f"{quote}{path}{quote}" + (f" (``{inside}``)" if inside else "")
                + " of the instructor's edition")

    def unwrapped(match: re.Match) -> str:
        dotted = match.group(1) or match.group(2)
        return match.group(0) if modules.get(module_of(dotted), True) else instructors(dotted, True)

    def renamed(match: re.Match) -> str:
        dotted = SOURCE_PACKAGE + (match.group(1) or "")
        if modules.get(module_of(dotted), True):
            return TARGET_PACKAGE + match.group(0)[len(SOURCE_PACKAGE):]
        return instructors(dotted, False)

    return CROSS_REFERENCE.sub(renamed, WRAPPED_REFERENCE.sub(unwrapped, text))


def generate(source_dir: Path, exercises: dict | None = None) -> tuple[dict[str, str], list[StubbedFunction]]:
    """Every file of the student package, as {relative path: text}, and the stubs made.

    ``exercises`` maps modules and stubs to exercise names (default :data:`EXERCISES`).
    """
    source_dir = Path(source_dir)
    sources = [p for p in sorted(source_dir.rglob("*.py")) if "__pycache__" not in p.parts] \
        if source_dir.is_dir() else []
    if not sources:
        raise GeneratorError(f"{source_dir}: no reference package here (no .py files), so nothing to generate "
                             f"from: the generator runs on the instructor's side, beside {SOURCE_PACKAGE}/. "
                             "To test your own exercises, run `grader check <exercise>`.")
    files: dict[str, str] = {}
    stubs: list[StubbedFunction] = []
    texts = {path.relative_to(source_dir).as_posix(): path.read_text(encoding="utf-8") for path in sources}
    modules = {module_name(relative): not is_instructor_only(text) for relative, text in texts.items()}
    for relative, text in texts.items():
        if is_instructor_only(text):
            continue
        student, stubbed = strip_solutions(text, f"{SOURCE_PACKAGE}/{relative}",
                                           lambda qualname: exercise_of(relative, qualname, exercises))
        student = point_references_at_the_student_package(student, modules)
        made = [exercise_of(relative, name, exercises) for name in stubbed]
        files[relative] = header(f"{SOURCE_PACKAGE}/{relative}", list(zip(stubbed, made))) + student
        module = TARGET_PACKAGE + module_name(relative).removeprefix(SOURCE_PACKAGE)
        stubs += [StubbedFunction(module, name, ex) for name, ex in zip(stubbed, made)]
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


# The record of what was written, and the refusal to overwrite anything else -----------
def digest(data: bytes | str) -> str:
    """SHA-256 of a file's bytes, line endings read as ``\n`` (a CRLF checkout is no edit)."""
    if isinstance(data, str):
        data = data.encode("utf-8")
    return hashlib.sha256(data.replace(b"\r\n", b"\n")).hexdigest()


def manifest_text(files: dict[str, str]) -> str:
    """The record of ``files`` as the generator writes it: hashes only, no file's text."""
    record = {
        "about": "SHA-256 of each file grader/release/exercises.py wrote in this folder. Before it writes "
                 "again it compares the folder with these and refuses to overwrite a file that differs "
                 "(someone's work); --force keeps a backup first.",
        "sha256": {name: digest(text) for name, text in sorted(files.items())},
    }
    return json.dumps(record, indent=1) + "\n"


def read_manifest(target_dir: Path) -> dict[str, str] | None:
    """{relative path: SHA-256} recorded in ``target_dir``; None if absent or unreadable."""
    try:
        record = json.loads((target_dir / MANIFEST).read_text(encoding="utf-8"))
        hashes = record["sha256"]
    except (OSError, ValueError, TypeError, KeyError):
        return None
    if not isinstance(hashes, dict) or not all(isinstance(k, str) and isinstance(v, str) for k, v in hashes.items()):
        return None
    return hashes


def _is_cache(relative: Path) -> bool:
    return any(part in CACHE_PARTS for part in relative.parts) or relative.suffix in CACHE_SUFFIXES


def tree_hashes(target_dir: Path) -> dict[str, str]:
    """{relative path: SHA-256} of every file in ``target_dir`` but the record and caches."""
    if not target_dir.is_dir():
        return {}
    hashes = {}
    for path in sorted(target_dir.rglob("*")):
        relative = path.relative_to(target_dir)
        if path.is_dir() or _is_cache(relative) or relative.as_posix() == MANIFEST:
            continue
        hashes[relative.as_posix()] = digest(path.read_bytes())
    return hashes


@dataclass(frozen=True)
class Change:
    """A file of the target folder that differs from the generator's: ``kind`` is
    "edited", "added" or "deleted" (against the record), or "differs", "not generated" or
    "missing" (against what the generator makes, when there is no record); ``path`` is
    relative to the target folder."""

    kind: str
    path: str


def changes_since_written(files: dict[str, str], target_dir: Path) -> tuple[list[Change], bool]:
    """What overwriting ``target_dir`` with ``files`` would lose, and whether a record exists.

    With a record (:data:`MANIFEST`), every file that differs from it; without one, every
    file that differs from ``files``.  A folder holding no files (caches aside) loses nothing.
    """
    present = tree_hashes(target_dir)
    recorded = read_manifest(target_dir)
    has_record = recorded is not None
    if not present:
        return [], has_record
    if recorded is None:
        recorded = {name: digest(text) for name, text in files.items()}
    added, deleted, edited = ("added", "deleted", "edited") if has_record else ("not generated", "missing", "differs")
    changes = []
    for name in sorted(set(present) | set(recorded)):
        if name not in recorded:
            changes.append(Change(added, name))
        elif name not in present:
            changes.append(Change(deleted, name))
        elif present[name] != recorded[name]:
            changes.append(Change(edited, name))
    return changes, has_record


class TreeHasEdits(RuntimeError):
    """The target folder holds edits; the message names them and says how to keep or drop them."""

    def __init__(self, target_dir: Path, changes: list[Change], has_record: bool):
        self.target_dir, self.changes = Path(target_dir), changes
        name = self.target_dir.name
        compared = (f"what grader/release/exercises.py last wrote there (recorded in {name}/{MANIFEST})"
                    if has_record else
                    f"what grader/release/exercises.py would write (there is no record, {name}/{MANIFEST}, "
                    "of what it last wrote)")
        listed = "\n".join(f"  {c.kind}: {name}/{c.path}" for c in changes)
        super().__init__(
            f"{self.target_dir} holds edits, maybe a student's work: {len(changes)} file(s) differ from "
            f"{compared}:\n{listed}\nNothing was written. To keep this work, leave {name}/ as it is (students "
            f"check their code with `grader check <exercise>`). To replace it with fresh stubs anyway, run "
            f"again with --force: the current {name}/ is first moved to a backup folder "
            f"{name}.backup-<date>-<time>/ beside it.")


def backup_path(target_dir: Path) -> Path:
    """A new ``<target>.backup-YYYYmmdd-HHMMSS`` folder name beside ``target_dir``."""
    stem = f"{target_dir.name}.backup-{time.strftime(BACKUP_STAMP)}"
    candidate, number = target_dir.with_name(stem), 1
    while candidate.exists():
        number += 1
        candidate = target_dir.with_name(f"{stem}-{number}")
    return candidate


def write(files: dict[str, str], target_dir: Path, force: bool = False) -> Path | None:
    """Replace ``target_dir`` by ``files`` and their record (:data:`MANIFEST`).

    The new folder is built beside it first.  If ``target_dir`` holds edits
    (:func:`changes_since_written`), raise :class:`TreeHasEdits` and write nothing,
    unless ``force``: then the old folder is moved to :func:`backup_path`, which is
    returned (None when nothing needed keeping).
    """
    target_dir = Path(target_dir)
    if target_dir.exists() and not target_dir.is_dir():
        raise GeneratorError(f"{target_dir} is not a folder")
    changes, has_record = changes_since_written(files, target_dir)
    if changes and not force:
        raise TreeHasEdits(target_dir, changes, has_record)
    target_dir.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{target_dir.name}-new-", dir=target_dir.parent))
    backup = old = None
    try:
        for name, text in {**files, MANIFEST: manifest_text(files)}.items():
            out = staging / name
            out.parent.mkdir(parents=True, exist_ok=True)
            out.write_bytes(text.encode("utf-8"))
        if target_dir.exists() and changes:
            backup = backup_path(target_dir)
            target_dir.rename(backup)
        elif target_dir.exists():  # only what the generator wrote (and caches): no one's work
            old = Path(tempfile.mkdtemp(prefix=f".{target_dir.name}-old-", dir=target_dir.parent))
            target_dir.rename(old / target_dir.name)
        staging.rename(target_dir)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
    return backup


def check(files: dict[str, str], target_dir: Path) -> list[str]:
    """What differs between ``target_dir`` and what the generator makes (its record included)."""
    target_dir = Path(target_dir)
    problems = differences(files, existing_files(target_dir))
    name = target_dir.name
    others = [p for p in tree_hashes(target_dir) if not p.endswith(".py")]
    problems += [f"not generated: {name}/{p}" for p in others]
    record = target_dir / MANIFEST
    if not record.is_file():
        problems.append(f"missing: {name}/{MANIFEST} (the record of what the generator wrote)")
    elif record.read_bytes().replace(b"\r\n", b"\n") != manifest_text(files).encode("utf-8"):
        problems.append(f"differs: {name}/{MANIFEST} (the record of what the generator wrote)")
    changes, has_record = changes_since_written(files, target_dir)
    if changes and has_record:
        problems.append(f"edited since the generator last wrote {name}/ (perhaps a student's work): "
                        + ", ".join(f"{c.path} ({c.kind})" for c in changes))
    return problems


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true",
                        help="compare with exercises/ and exit 1 if it differs; writes nothing")
    parser.add_argument("--force", action="store_true",
                        help="overwrite an exercises/ holding edits, after moving it to "
                             "exercises.backup-<date>-<time>/ beside it")
    parser.add_argument("--source", type=Path, default=REPO_ROOT / SOURCE_PACKAGE)
    parser.add_argument("--target", type=Path, default=REPO_ROOT / TARGET_PACKAGE)
    args = parser.parse_args(argv)
    name = args.target.name
    try:
        files, stubs = generate(args.source)
    except GeneratorError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if args.check:
        problems = check(files, args.target)
        for problem in problems:
            print(problem, file=sys.stderr)
        if problems:
            print(f"{name}/ differs from what grader/release/exercises.py makes from {args.source.name}/.\n"
                  f"If {args.source.name}/ changed, run `python -m grader.release.exercises`: it refuses, naming "
                  f"the files and writing nothing, when {name}/ holds edits made since it last wrote it "
                  f"(perhaps a student's work). Add --force only if those edits are not wanted: it moves "
                  f"{name}/ to a backup folder first.", file=sys.stderr)
            return 1
        print(f"{name}/ is in sync: {len(files)} modules, {len(stubs)} stubs")
        return 0
    try:
        backup = write(files, args.target, force=args.force)
    except TreeHasEdits as exc:
        print(f"error: {exc}", file=sys.stderr)
        return REFUSED
    except GeneratorError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if backup is not None:
        print(f"kept the edited {name}/ as {backup}")
    print(f"wrote {args.target}: {len(files)} modules, {len(stubs)} stubs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
