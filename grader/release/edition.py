"""``grader release --out DIR``: the student edition and the autograder, from one source.

Instructors only (this module never ships to students).  It writes

``DIR/student/``
    a self-contained course folder: the generated ``exercises`` package; the grader's
    student side (a whitelist of ``grader/`` computed by following the imports of
    ``check.py``, ``cli.py``, ``plugin.py``, ``notebook.py``, the student subcommands
    and the public tests, see :func:`student_grader_files`); the chapters as notebooks
    that run on the student's package (:mod:`grader.release.book`) and the ``tools``
    modules they import; ``README.md``, ``run.sh`` and ``pyproject.toml`` (templates in
    ``grader/release/files/``, pins taken from the repository's ``pyproject.toml``).
``DIR/autograder/``
    Gradescope's ``autograder.zip`` (:func:`grader.release.gradescope.build_autograder_zip`) and
    a README on grading locally or on Gradescope.

Each folder is marked with ``.course-release.json`` (date, repository commit, the
SHA-256 of every file written).  The student edition's marker also holds the release's
version and what it changed (the newest section of the repository's ``CHANGELOG.md``,
which the edition copies), and the edition keeps the original text of its text files in
``.course-release-originals.zip``: the base of the 3-way merges of ``grader update``
(:mod:`grader.student.update`), which takes a corrected release into a student's folder.

A folder that exists and is not an unchanged earlier release is never touched: the
release refuses, says why and writes nothing.  An earlier release is replaced only once
the new one is complete and checked.

Before anything is moved into place, :func:`verify_student` proves that the student
folder reveals no solution: no ``solutions`` package, no hidden test, no reference
import anywhere (a Python module or a notebook cell), no compiled file, and none of
the ``### BEGIN SOLUTION`` blocks of ``solutions/`` in any file, notebook output or
zip member (as a stream of Python tokens, whatever the layout and comments).
"""
from __future__ import annotations

import argparse
import ast
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path

from .exercises import SOURCE_PACKAGE, TARGET_PACKAGE, GeneratorError
from .exercises import check as check_generated
from .exercises import generate as generate_exercises
from .chapter_imports import ChapterImportError, StudentModules
from .module_graph import files_reached, ignored, module_file
from .module_graph import imported_modules as third_party_imports
from .pins import installed_closure, normal_name, requirement_name
from .leak_scan import MIN_BLOCK_TOKENS, SolutionBlock, scan_for_solutions, solution_blocks

GRADER_DIR = Path(__file__).resolve().parents[1]
REPO_ROOT = GRADER_DIR.parent
TEMPLATES = Path(__file__).resolve().parent / "files"
from ..student.manifest import byte_size
from ..student.update import CHANGELOG, MARKER, MARKER_FORMAT, parse_changelog, version_key, write_originals
from .gradescope import build_autograder_zip
from ..harness.spec import EXERCISES
STUDENT_PROJECT = "collision-course-student"

#: What of ``grader/`` ships to students: these role folders whole (they import nothing
#: of the instructor folders: checked at every release) and these files.  Paths
#: relative to ``grader/``.
STUDENT_FOLDERS = ("sandbox/", "harness/", "student/", "oracles/", "tests/public/")
STUDENT_FILES = ("__init__.py", "__main__.py", "cli.py", "errors.py",
                 "tests/__init__.py", "tests/conftest.py", "tests/pytest.ini")
#: Subcommands of ``grader/cli.py`` the student edition keeps (their modules ship).
STUDENT_COMMANDS = ("check", "submit", "update")
#: The instructor's folders: never in the student edition.
NEVER_SHIP = ("batch/", "reports/", "release/", "samples/", "tests/hidden/")
#: Leftovers of using a course folder (not someone's work): ignored when replacing a release.
LEFTOVER_NAMES = {".venv", "__pycache__", ".ipynb_checkpoints", ".pytest_cache", ".hypothesis", ".DS_Store",
                  "build", ".virtual_documents"}
LEFTOVER_SUFFIXES = (".pyc", ".egg-info")
#: Never copied: caches and editor litter.
IGNORED_NAMES = {"__pycache__", ".ipynb_checkpoints", ".DS_Store", ".pytest_cache", ".hypothesis"}
#: Packages of the notebooks: pinned like the repository's ``book`` extra where it pins
#: them, these versions otherwise.
NOTEBOOK_PACKAGES = {"jupyterlab": "4.6.6", "ipykernel": "7.4.0", "nbclient": "0.11.0", "nbformat": "5.11.1",
                     "ipython": "9.18.1", "jupyter_client": "8.10.0", "matplotlib-inline": "0.2.2"}
#: Solution blocks shorter than this (in tokens) are too generic to look for.
LOCAL_PACKAGES = {"grader", "exercises", "tools"}


class ReleaseError(RuntimeError):
    """The release cannot be written; the message says why (nothing was written)."""


# The student side of the grader -------------------------------------------------------------
def _ignored(relative: Path) -> bool:
    return ignored(relative)


def _never(relative: str) -> bool:
    return any(relative == rule or (rule.endswith("/") and relative.startswith(rule)) for rule in NEVER_SHIP)


def student_grader_files(grader_dir: Path = GRADER_DIR) -> dict[str, str]:
    """The files of ``grader/`` the student edition holds, {path relative to grader/:
    why}: :data:`STUDENT_FOLDERS` whole and :data:`STUDENT_FILES`.  ReleaseError when
    one of them imports or names a file of :data:`NEVER_SHIP` (the student side must
    not depend on the instructor's), a student command's module is not among them, or
    a shipped module imports the reference engine."""
    grader_dir = Path(grader_dir)
    start = [(grader_dir / name, "student file") for name in STUDENT_FILES if (grader_dir / name).is_file()]
    for folder in STUDENT_FOLDERS:
        start += [(file, f"the folder {folder}") for file in sorted((grader_dir / folder).rglob("*"))
                  if file.is_file() and not _ignored(file.relative_to(grader_dir))]
    shipped = {file.relative_to(grader_dir).as_posix() for file, _ in start}

    def refuse_instructor_files(relative: str, reason: str) -> None:
        if _never(relative):
            raise ReleaseError(f"the student edition would need grader/{relative} ({reason}), which never ships "
                               "to students: make the student side stop depending on it")
        if relative not in shipped:
            raise ReleaseError(f"grader/{relative} ({reason}) is in no folder that ships to students: move it "
                               f"into one of {', '.join(STUDENT_FOLDERS)} or the instructor's")

    why = files_reached(grader_dir, start, want=refuse_instructor_files, excluded=_never)
    commands = _subcommand_modules(grader_dir / "cli.py")
    for name in STUDENT_COMMANDS:
        file = module_file(grader_dir, commands[name].split(".")[1:]) if name in commands else None
        if file is None or file.relative_to(grader_dir).as_posix() not in why:
            raise ReleaseError(f"the student command 'grader {name}' has no module among the shipped files")
    for relative in why:
        if relative.endswith(".py"):
            for module in third_party_imports((grader_dir / relative).read_text(encoding="utf-8")):
                if module.split(".")[0] == "solutions":
                    raise ReleaseError(f"grader/{relative} imports the reference engine ({module}) and ships to "
                                       "students: a public test or its oracle must not use solutions")
    return why


def _subcommand_modules(cli: Path) -> dict[str, str]:
    """``SUBCOMMANDS`` of cli.py, read without importing it: {command: module}."""
    tree = ast.parse(cli.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        targets = node.targets if isinstance(node, ast.Assign) else [node.target] if isinstance(
            node, ast.AnnAssign) else []
        if any(isinstance(t, ast.Name) and t.id == "SUBCOMMANDS" for t in targets) and isinstance(
                node.value, ast.Dict):
            out = {}
            for key, value in zip(node.value.keys, node.value.values):
                if isinstance(key, ast.Constant) and isinstance(value, ast.Tuple) and value.elts and isinstance(
                        value.elts[0], ast.Constant):
                    out[key.value] = value.elts[0].value
            return out
    return {}


def public_tests_using_reference(grader_dir: Path = GRADER_DIR) -> list[str]:
    """Public graded tests that ask for the ``reference`` fixture (it cannot run on the
    student's side, where the reference is absent)."""
    found = []
    for file in sorted((grader_dir / "tests" / "public").rglob("test_*.py")):
        for node in ast.walk(ast.parse(file.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name.startswith("test_") and any(
                    a.arg == "reference" for a in node.args.args + node.args.kwonlyargs):
                found.append(f"{file.relative_to(grader_dir).as_posix()}::{node.name}")
    return found


# Dependencies ----------------------------------------------------------------------------------
def student_requirements(modules: set[str], pyproject: Path = REPO_ROOT / "pyproject.toml") -> list[str]:
    """The runtime pins of the repository that the student edition needs, pytest as its
    dev extra pins it, and the notebook packages (pinned like the ``book`` extra where
    it pins them).  ``modules``: the top-level modules the edition imports; a runtime
    pin is kept if it provides one of them or a kept pin depends on it (llvmlite for
    numba), so the instructor's compiled twins do not make students install numba."""
    data = tomllib.loads(Path(pyproject).read_text(encoding="utf-8"))
    project = data["project"]
    extras = project.get("optional-dependencies", {})
    pins = {requirement_name(r): r for extra in extras.values() for r in extra}
    requirements = used_requirements(list(project.get("dependencies", [])), modules)
    if "pytest" not in pins:
        raise ReleaseError("the repository's pyproject.toml pins no pytest in its extras")
    requirements.append(pins["pytest"])
    for name, version in NOTEBOOK_PACKAGES.items():
        requirements.append(pins.get(normal_name(name), f"{name}=={version}"))
    return requirements


def used_requirements(requirements: list[str], modules: set[str]) -> list[str]:
    """The ``requirements`` whose distribution provides one of ``modules`` (top-level
    names), and those that the kept ones depend on, as installed here; in their order."""
    from importlib import metadata

    provided = metadata.packages_distributions()
    wanted = {normal_name(d) for module in modules for d in provided.get(module, [])}
    kept = [r for r in requirements if requirement_name(r) in wanted]
    needed = installed_closure(kept)
    return [r for r in requirements if requirement_name(r) in needed]


def check_dependencies(modules: dict[str, str], requirements: list[str],
                       pyproject: Path = REPO_ROOT / "pyproject.toml") -> tuple[list[str], list[str]]:
    """Make sure every module the student edition imports is installed by its
    requirements.  ``modules``: {top-level module: where it is imported}.  Returns
    (requirements added from the repository's extras, warnings); ReleaseError for a
    module that no pin of the repository provides."""
    from importlib import metadata

    provided = metadata.packages_distributions()
    installed = installed_closure(requirements)
    extras = tomllib.loads(Path(pyproject).read_text(encoding="utf-8"))["project"].get("optional-dependencies", {})
    pins = {requirement_name(r): r for extra in extras.values() for r in extra}
    added, warnings = [], []
    for module, where in sorted(modules.items()):
        if module in sys.stdlib_module_names or module in LOCAL_PACKAGES or module == "__future__":
            continue
        distributions = [normal_name(d) for d in provided.get(module, [])]
        if not distributions:
            warnings.append(f"{where} imports {module}, which is not installed here: is it optional?")
            continue
        if any(d in installed for d in distributions):
            continue
        pinned = next((pins[d] for d in distributions if d in pins), None)
        if pinned is None:
            raise ReleaseError(f"{where} imports {module} ({', '.join(distributions)}), which no pin of "
                               "pyproject.toml provides: pin it there")
        added.append(pinned)
        requirements.append(pinned)
        installed |= installed_closure([pinned])
    return added, warnings


# Writing -----------------------------------------------------------------------------------------
def _sha256(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def _files(folder: Path) -> list[Path]:
    return sorted(p for p in Path(folder).rglob("*") if p.is_file() or p.is_symlink())


def _leftover(relative: Path) -> bool:
    return any(part in LEFTOVER_NAMES or part.endswith(LEFTOVER_SUFFIXES) for part in relative.parts)


def check_replaceable(folder: Path, edition: str) -> bool:
    """True when ``folder`` holds an unchanged earlier release of ``edition`` (it may be
    replaced), False when it does not exist; ReleaseError otherwise."""
    folder = Path(folder)
    if not folder.exists() and not folder.is_symlink():
        return False
    def refuse(why: str) -> ReleaseError:
        return ReleaseError(f"{folder} exists and is not an earlier release written by `grader release` ({why}); "
                            "it may be someone's work, so nothing was written. Choose another --out, or move that "
                            "folder away yourself.")

    if folder.is_symlink() or not folder.is_dir():
        raise refuse("it is not a folder")
    try:
        marker = json.loads((folder / MARKER).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        raise refuse(f"it has no readable {MARKER}") from None
    if not isinstance(marker, dict) or marker.get("format") != MARKER_FORMAT:
        raise refuse(f"its {MARKER} is not one the release writes")
    if marker.get("edition") != edition:
        raise refuse(f"its {MARKER} marks the {marker.get('edition')!r} edition, not the {edition!r} one")
    recorded = marker.get("files", {})
    changed = [name for name, digest in recorded.items()
               if not (folder / name).is_file() or (folder / name).is_symlink() or _sha256(folder / name) != digest]
    added = [p.relative_to(folder).as_posix() for p in _files(folder)
             if p.relative_to(folder).as_posix() not in recorded and p.name != MARKER
             and not _leftover(p.relative_to(folder))]
    if changed or added:
        what = []
        if changed:
            what.append(f"{len(changed)} of its files changed or removed (e.g. {', '.join(changed[:3])})")
        if added:
            what.append(f"{len(added)} files added (e.g. {', '.join(added[:3])})")
        raise ReleaseError(f"{folder} is an earlier release that was changed since ({'; '.join(what)}): it may "
                           "be someone's work, so nothing was written. Choose another --out, or move it away yourself.")
    return True


def _copy_tree(source: Path, target: Path) -> list[Path]:
    written = []
    for path in sorted(Path(source).rglob("*")):
        relative = path.relative_to(source)
        if _ignored(relative) or path.is_dir():
            continue
        if path.is_symlink():
            raise ReleaseError(f"{path} is a symbolic link: the release copies regular files only")
        destination = target / relative
        destination.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(path, destination)
        written.append(destination)
    return written


#: The grader's commands as the student edition's README teaches them (its run.sh's).
STUDENT_COMMANDS_NAMED = {"`grader check": "`bash run.sh check", "`grader submit": "`bash run.sh submit"}
#: The generator's record of the files it wrote (grader/release/exercises.py), kept true.
GENERATED_RECORD = ".generated.json"


def name_student_commands(exercises: Path) -> list[str]:
    """Say `bash run.sh check ...` where the ``exercises`` files (their headers and the
    stubs' NotImplementedError) say `grader check ...`; the generator's record of their
    hashes follows.  Returns the files rewritten, relative to ``exercises``."""
    rewritten = []
    for path in sorted(exercises.rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        named = text
        for old, new in STUDENT_COMMANDS_NAMED.items():
            named = named.replace(old, new)
        if named != text:
            path.write_text(named, encoding="utf-8")
            rewritten.append(path.relative_to(exercises).as_posix())
    record = exercises / GENERATED_RECORD
    if rewritten and record.is_file():
        data = json.loads(record.read_text(encoding="utf-8"))
        for name in rewritten:
            if name in data.get("sha256", {}):
                data["sha256"][name] = _sha256(exercises / name)
        record.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
    return rewritten


def _fill(template: str, values: dict[str, str]) -> str:
    for key, value in values.items():
        template = template.replace("{{" + key + "}}", value)
    left = re.findall(r"\{\{\w+\}\}", template)
    if left:
        raise ReleaseError(f"template placeholders left unfilled: {', '.join(left)}")
    return template


def repository_commit(repo_root: Path = REPO_ROOT) -> tuple[str | None, bool]:
    """(commit, has uncommitted changes) of the repository, (None, False) without git."""
    try:
        commit = subprocess.run(["git", "-C", str(repo_root), "rev-parse", "HEAD"], capture_output=True, text=True,
                                timeout=30, check=True).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None, False
    return commit, bool(changed_files(repo_root))


def changed_files(repo_root: Path = REPO_ROOT) -> list[str]:
    """The files ``git status`` lists as changed, added or untracked (none without git)."""
    try:
        status = subprocess.run(["git", "-C", str(repo_root), "status", "--porcelain"], capture_output=True,
                                text=True, timeout=30, check=True).stdout
    except (OSError, subprocess.SubprocessError):
        return []
    return [line[3:] for line in status.splitlines() if line.strip()]


def tools_files(modules: list[str], tools_dir: Path) -> dict[str, str]:
    """The ``tools`` modules the chapters import, and the ``tools`` modules they import:
    {file relative to tools/: source rewritten to import ``exercises``}."""
    from .book import check_code, rewrite_code  # deferred: nbformat, only when the student edition is written

    out: dict[str, str] = {}
    queue = [m.split(".")[1:] for m in modules if m.split(".")[1:]]
    while queue:
        parts = queue.pop(0)
        file = tools_dir.joinpath(*parts).with_suffix(".py")
        if not file.is_file():
            file = tools_dir.joinpath(*parts) / "__init__.py"
        if not file.is_file():
            raise ReleaseError(f"a chapter imports tools.{'.'.join(parts)}, which does not exist")
        relative = file.relative_to(tools_dir).as_posix()
        if relative in out:
            continue
        source = rewrite_code(file.read_text(encoding="utf-8"))
        check_code(source, f"tools/{relative}")
        out[relative] = source
        for module in third_party_imports(source):
            if module.split(".")[0] == "tools" and module.split(".")[1:]:
                queue.append(module.split(".")[1:])
        tree = ast.parse(source)
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.level:
                base = list(Path(relative).parent.parts)[:len(Path(relative).parent.parts) - (node.level - 1)]
                queue.append(base + (node.module.split(".") if node.module else []))
    return out


@dataclass
class Release:
    """What ``build_release`` wrote."""

    out: Path
    student: Path
    autograder: Path
    grader_files: dict[str, str]
    notebooks: list[tuple[str, str]]
    pages: list[str]
    tools: list[str]
    requirements: list[str]
    added_requirements: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    short_blocks: list[str] = field(default_factory=list)
    checked_blocks: int = 0
    seconds: float = 0.0
    version: str | None = None   # from CHANGELOG.md's newest section (None without one)

    def sizes(self) -> dict[str, int]:
        def size(folder: Path) -> int:
            return sum(p.stat().st_size for p in _files(folder) if p.is_file())

        return {"student": size(self.student), "autograder": size(self.autograder),
                "student/book": size(self.student / "book"), "student/grader": size(self.student / "grader"),
                "student/exercises": size(self.student / "exercises")}


def exercises_out_of_date(repo_root: Path = REPO_ROOT) -> str | None:
    """A warning when ``exercises/`` is not what the generator makes from ``solutions/``
    (``python -m grader.release.exercises --check``), else None."""
    repo_root = Path(repo_root)
    try:
        files, _ = generate_exercises(repo_root / SOURCE_PACKAGE)
    except GeneratorError as exc:
        return f"could not check that exercises/ is up to date ({exc})"
    problems = check_generated(files, repo_root / TARGET_PACKAGE)
    if not problems:
        return None
    return ("exercises/ is not what `python -m grader.release.exercises` makes from solutions/ (the release "
            f"copies it as it is): {problems[0][:300]}")


def write_student(target: Path, repo_root: Path = REPO_ROOT) -> dict:
    """Write the student edition into the empty folder ``target``; return what it holds."""
    # deferred: nbformat, only when the student edition is written
    from .book import BookConversionError, imported_modules, is_shown_only, write_book

    repo_root = Path(repo_root)
    grader_dir = repo_root / "grader"
    target.mkdir(parents=True)
    if not (repo_root / "exercises" / "__init__.py").is_file():
        raise ReleaseError(f"{repo_root / 'exercises'} is not a package: run `python -m grader.release.exercises`")
    _copy_tree(repo_root / "exercises", target / "exercises")
    name_student_commands(target / "exercises")
    grader_files = student_grader_files(grader_dir)
    for relative in grader_files:
        destination = target / "grader" / relative
        destination.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(grader_dir / relative, destination)
    kernel_modules = StudentModules({"exercises": target / "exercises", "grader": target / "grader",
                                     "tools": repo_root / "tools"})   # tools: it ships what the chapters import
    try:
        book = write_book(repo_root / "book" / "chapters", repo_root / "book", target / "book", kernel_modules)
    except (BookConversionError, ChapterImportError) as exc:
        raise ReleaseError(f"a chapter cannot be made into a student notebook; nothing was written:\n  {exc}") from None
    tools = tools_files(book["tools_modules"], repo_root / "tools")
    if tools:
        (target / "tools").mkdir()
        (target / "tools" / "__init__.py").write_text('"""Helpers the chapters use."""\n', encoding="utf-8")
        for relative, source in tools.items():
            destination = target / "tools" / relative
            destination.parent.mkdir(parents=True, exist_ok=True)
            destination.write_text(source, encoding="utf-8")
    # Every module the edition imports must be installed by its pyproject.
    modules: dict[str, str] = {}
    for path in sorted(target.rglob("*.py")):
        for module in third_party_imports(path.read_text(encoding="utf-8")):
            top = module.split(".")[0]
            if not (path.parent / f"{top}.py").is_file():   # a sibling file (the worker's codec)
                modules.setdefault(top, path.relative_to(target).as_posix())
    for notebook, _ in book["notebooks"]:
        import nbformat

        for cell in nbformat.read(target / "book" / notebook, as_version=4).cells:
            if cell.cell_type == "code" and not is_shown_only(cell.source):   # a shown-only cell never runs
                for module in imported_modules(cell.source):
                    modules.setdefault(module.split(".")[0], f"book/{notebook}")
    requirements = student_requirements(set(modules), repo_root / "pyproject.toml")
    added, warnings = check_dependencies(modules, requirements, repo_root / "pyproject.toml")
    for test in public_tests_using_reference(grader_dir):
        warnings.append(f"grader/{test} asks for the reference fixture: on the student's side it cannot run")
    stale = exercises_out_of_date(repo_root)
    if stale:
        warnings.append(stale)
    project = tomllib.loads((repo_root / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    version, changes = release_version(repo_root)
    if version is None:
        warnings.append(f"no {CHANGELOG} at the top of the repository: this release has no version, and "
                        "`grader update` cannot tell students what changed")
    else:
        shutil.copy2(repo_root / CHANGELOG, target / CHANGELOG)
    packages = ["exercises*", "grader*"] + (["tools*"] if tools else [])
    values = {
        "version": version or project.get("version", "0.0.0"),
        "requires_python": project.get("requires-python", ">=3.11"),
        "dependencies": "\n".join(f'    "{r}",' for r in requirements),
        "packages": ", ".join(f'"{p}"' for p in packages),
        "exercises": ", ".join(EXERCISES),
        "chapters": "\n".join(f"- `book/{file}`: {title}" for file, title in book["notebooks"]),
        "tools_row": "| `tools/` | helpers the chapters use (the same scene built in pymunk) |\n" if tools else "",
    }
    (target / "pyproject.toml").write_text(_fill((TEMPLATES / "pyproject.toml").read_text(encoding="utf-8"),
                                                 values), encoding="utf-8")
    (target / "README.md").write_text(_fill((TEMPLATES / "README.md").read_text(encoding="utf-8"), values),
                                      encoding="utf-8")
    shutil.copy2(TEMPLATES / "run.sh", target / "run.sh")
    os.chmod(target / "run.sh", 0o755)
    shutil.copy2(TEMPLATES / "gitignore", target / ".gitignore")
    return {"grader_files": grader_files, "notebooks": book["notebooks"], "pages": book["pages"],
            "tools": sorted(tools), "requirements": requirements, "added": added, "warnings": warnings,
            "version": version, "changes": changes}


def release_version(repo_root: Path = REPO_ROOT) -> tuple[str | None, str | None]:
    """(version, what changed) of the release: the newest section of the repository's
    ``CHANGELOG.md`` (``## 1.0.1 (2025-03-02)``, newest first); (None, None) without
    one.  ReleaseError for a changelog with no section or a newest section whose heading
    is not a version (numbers and dots), or versions out of order."""
    path = Path(repo_root) / CHANGELOG
    if not path.is_file():
        return None, None
    sections = parse_changelog(path.read_text(encoding="utf-8"))
    if not sections:
        raise ReleaseError(f"{path} has no section '## VERSION' (numbers and dots, e.g. '## 1.0.1 (2025-03-02)'): "
                           "write what this release changes under one, newest first")
    keys = [version_key(v) for v, _ in sections]
    if any(newer <= older for newer, older in zip(keys, keys[1:])):
        raise ReleaseError(f"{path}: the versions of its sections ({', '.join(v for v, _ in sections)}) must go "
                           "down from the top, the newest first")
    version, changes = sections[0]
    if not changes:
        raise ReleaseError(f"{path}: the newest section, {version}, says nothing: write what changed")
    return version, changes


def verify_student(folder: Path, blocks: list[SolutionBlock]) -> None:
    """ReleaseError unless ``folder`` reveals no solution (see the module docstring)."""
    from .book import SOURCE_PACKAGE, check_code  # deferred: nbformat, only when the student edition is written

    problems = []
    for path in _files(folder):
        relative = path.relative_to(folder)
        name = relative.as_posix()
        if path.is_symlink():
            problems.append(f"{name} is a symbolic link")
        if SOURCE_PACKAGE in relative.parts[:-1] or relative.parts[0] == SOURCE_PACKAGE:
            problems.append(f"{name} is part of a {SOURCE_PACKAGE} package")
        if "__pycache__" in relative.parts or path.suffix in (".pyc", ".pyo"):
            problems.append(f"{name} is compiled code")
        if relative.parts[0] == "grader" and _never("/".join(relative.parts[1:])):
            problems.append(f"{name} never ships to students")
        if path.suffix == ".py":
            for module in third_party_imports(path.read_text(encoding="utf-8")):
                if module.split(".")[0] == SOURCE_PACKAGE:
                    problems.append(f"{name} imports {module}")
        if path.suffix == ".ipynb":
            import nbformat

            for index, cell in enumerate(nbformat.read(path, as_version=4).cells):
                if cell.cell_type == "code":
                    try:
                        check_code(cell.source, f"{name}, cell {index}")
                    except ValueError as exc:
                        problems.append(str(exc))
    problems += scan_for_solutions(folder, blocks)
    if problems:
        raise ReleaseError("the student edition would reveal solutions; nothing was written:\n  "
                           + "\n  ".join(problems[:40]))


def _marker(folder: Path, edition: str, created: str, commit: str | None, dirty: bool, extra: dict) -> None:
    files = {p.relative_to(folder).as_posix(): _sha256(p) for p in _files(folder)}
    data = {"format": MARKER_FORMAT, "format_version": 1, "edition": edition, "created": created,
            "commit": commit, "uncommitted_changes": dirty, **extra, "files": files}
    (folder / MARKER).write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")


def build_release(out: str | os.PathLike, repo_root: Path = REPO_ROOT) -> Release:
    """Write ``out/student`` and ``out/autograder`` (see the module docstring)."""

    start = time.perf_counter()
    repo_root = Path(repo_root).resolve()
    out = Path(out).expanduser().resolve()
    for source in ("grader", "exercises", "solutions", "book", "tools"):
        inside = repo_root / source
        if out == inside or inside in out.parents:
            raise ReleaseError(f"--out {out} is inside the course's own {source}/ folder: choose a folder outside it")
    student, autograder = out / "student", out / "autograder"
    replace = {"student": check_replaceable(student, "student"),
               "autograder": check_replaceable(autograder, "autograder")}
    commit, dirty = repository_commit(repo_root)
    created = datetime.now(timezone.utc).astimezone().isoformat(timespec="seconds")
    blocks = solution_blocks(repo_root / "solutions")
    made_out = not out.exists()
    out.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=".release-", dir=out))
    try:
        new_student, new_autograder = staging / "student", staging / "autograder"
        content = write_student(new_student, repo_root)
        kept = write_originals(new_student)   # the base of `grader update`'s merges
        verify_student(new_student, blocks)
        _marker(new_student, "student", created, commit, dirty,
                {"version": content["version"], "changes": content["changes"],
                 "grader_files": list(content["grader_files"]), **kept})
        new_autograder.mkdir()
        zip_path = build_autograder_zip(out=new_autograder / "autograder.zip", repo_root=repo_root)
        zip_line = (f"`autograder.zip`: {byte_size(zip_path.stat().st_size)}, sha256 "
                    f"{_sha256(zip_path)[:16]}...")
        (new_autograder / "README.md").write_text(_fill(
            (TEMPLATES / "autograder_README.md").read_text(encoding="utf-8"),
            {"created": created, "zip_line": zip_line,
             "commit": (commit or "unknown")[:12] + (" (with uncommitted changes)" if dirty else "")}),
            encoding="utf-8")
        _marker(new_autograder, "autograder", created, commit, dirty, {})
        # Swap in: an earlier release is replaced only now, and only if still unchanged.
        for name, new in (("student", new_student), ("autograder", new_autograder)):
            final = out / name
            if check_replaceable(final, name) != replace[name]:
                raise ReleaseError(f"{final} appeared or vanished while the release was written; nothing was replaced")
            if replace[name]:
                final.rename(staging / f"earlier-{name}")
            new.rename(final)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        if made_out:
            try:
                out.rmdir()
            except OSError:
                pass
        raise
    shutil.rmtree(staging, ignore_errors=True)
    return Release(out=out, student=student, autograder=autograder, grader_files=content["grader_files"],
                   notebooks=content["notebooks"], pages=content["pages"], tools=content["tools"],
                   requirements=content["requirements"], added_requirements=content["added"],
                   warnings=content["warnings"],
                   short_blocks=[f"{b.where} ({len(b.tokens)} tokens)" for b in blocks
                                 if len(b.tokens) < MIN_BLOCK_TOKENS],
                   checked_blocks=sum(len(b.tokens) >= MIN_BLOCK_TOKENS for b in blocks),
                   seconds=time.perf_counter() - start, version=content["version"])


# Command line ------------------------------------------------------------------------------------------
def describe(release: Release) -> str:
    """What was written, for the shell."""
    sizes = release.sizes()
    student_files = len([p for p in _files(release.student)])
    lines = [f"version: {release.version}" if release.version else "version: none (no CHANGELOG.md)",
             f"student edition: {release.student} ({student_files} files, {byte_size(sizes['student'])}: "
             f"book {byte_size(sizes['student/book'])}, grader {byte_size(sizes['student/grader'])}, "
             f"exercises {byte_size(sizes['student/exercises'])})",
             f"  {len(release.notebooks)} chapter notebooks, reading pages {', '.join(release.pages)}"
             + (f", tools: {', '.join(release.tools)}" if release.tools else ""),
             f"  grader files ({len(release.grader_files)}): " + ", ".join(release.grader_files),
             f"  {release.checked_blocks} solution blocks looked for in every file: none found"
             + (f"; too short to look for: {', '.join(release.short_blocks)}" if release.short_blocks else ""),
             f"autograder: {release.autograder} (autograder.zip "
             f"{byte_size((release.autograder / 'autograder.zip').stat().st_size)}, README.md)"]
    for requirement in release.added_requirements:
        lines.append(f"note: added {requirement} to the student requirements (imported by the student edition)")
    for warning in release.warnings:
        lines.append(f"warning: {warning}")
    lines.append(f"done in {release.seconds:.1f} s")
    return "\n".join(lines)


def add_release_arguments(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    parser.add_argument("--out", required=True, metavar="DIR",
                        help="write DIR/student (the course folder students get) and DIR/autograder "
                             "(autograder.zip for Gradescope); an earlier release there is replaced, anything "
                             "else is never touched")
    parser.add_argument("--verbose", action="store_true", help="say why each grader file ships")
    return parser


def main_release(args: argparse.Namespace) -> int:
    changed = changed_files(REPO_ROOT)
    if changed:
        print(f"grader release: warning: {len(changed)} file{'s' if len(changed) != 1 else ''} of the repository "
              f"{'have' if len(changed) != 1 else 'has'} uncommitted changes (e.g. {changed[0]}): the release is made "
              f"from the working tree, and its {MARKER} records it", file=sys.stderr)
    try:
        release = build_release(args.out)
    except ReleaseError as exc:
        print(f"grader release: {exc}", file=sys.stderr)
        return 2
    print(describe(release))
    if getattr(args, "verbose", False):
        for name, why in release.grader_files.items():
            print(f"  grader/{name}: {why}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = add_release_arguments(argparse.ArgumentParser(prog="grader release", description=__doc__.split("\n")[0]))
    return main_release(parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
