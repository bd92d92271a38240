"""Every command and repository path that README.md and docs/*.md show exists.

Read from the pages' code (inline code spans and ``bash``/``sh``/``text`` blocks; Python
blocks are examples of code, not commands):

- ``bash run.sh X``: a case ``X)`` of the repository's ``run.sh``, or, under a heading
  that names students (or any heading above it does: "Students", "The student
  edition's notebooks"), of the student edition's ``grader/release/files/run.sh``;
- ``grader X``, ``.venv/bin/grader X``, ``python -m grader X``: a subcommand of the
  ``grader`` console script's parser (the module named in ``pyproject.toml``), and under
  a student heading one the student edition keeps (``STUDENT_COMMANDS``, and ``list``);
- ``python -m MODULE [SUBCOMMAND]``: MODULE importable; when its source declares
  argparse subcommands (``add_parser("...")``), SUBCOMMAND among them;
- a word that looks like a repository path (contains ``/`` and ends with ``/`` or a file
  extension, or is an argument of ``python``/``pytest``): it exists in the checkout.
  Placeholders are written so they can be told apart: an upper-case first segment
  (``DIR/results.json``, ``PATH/TO/exercises``) is skipped, ``<...>`` and ``*`` are
  globs that must match something; absolute paths and :data:`OUTPUTS` (what commands
  write) are not looked for;
- a dotted name of the project's packages (``grader.harness.credit.check_cases``, ``from X import
  Y``): a module, or an attribute of one;
- a Markdown link to a local file: the file exists, and its ``#anchor`` is a heading of it;
- README.md is at most :data:`README_MAX_LINES` lines.
"""
from __future__ import annotations

import ast
import importlib
import importlib.util
import re
import sys
import tomllib
from dataclasses import dataclass
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
README_MAX_LINES = 150
#: Paths the commands write (or a student's folder holds): not in a checkout.
OUTPUTS = ("out/", "dist/", "student/", "autograder/", "backups/", "book/_build/", "book/_vendor/", ".venv/",
           "exercises.backup-")
#: Fenced blocks whose lines are commands.
COMMAND_BLOCKS = {"bash", "sh", "shell", "console", "text", ""}
STUDENT_HEADING = re.compile(r"\bstudents?\b|\bstudent's\b", re.IGNORECASE)


def doc_files() -> list[Path]:
    return [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]


@dataclass(frozen=True)
class Snippet:
    """A piece of code shown on a page: an inline span or one line of a command block."""
    file: Path
    line: int
    text: str
    student: bool   # under a heading that names students

    def where(self) -> str:
        return f"{self.file.relative_to(REPO)}:{self.line}: {self.text!r}"


def headings_and_snippets(path: Path) -> tuple[list[str], list[Snippet], list[tuple[int, str]]]:
    """The page's headings, its code snippets, and its prose lines (outside code)."""
    headings, snippets, prose = [], [], []
    stack: list[tuple[int, str]] = []   # (level, heading) of the enclosing headings
    fence = None   # the open block's language, or None outside a block
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        stripped = line.strip()
        opening = re.match(r"^(```+|~~~+)\s*([\w-]*)", stripped)
        if opening:
            fence = opening[2].lower() if fence is None else None
            continue
        student = any(STUDENT_HEADING.search(text) for _, text in stack)
        if fence is not None:
            if fence in COMMAND_BLOCKS and stripped:
                snippets.append(Snippet(path, number, stripped.split(" #")[0].strip(), student))
            continue
        heading = re.match(r"^(#{1,6})\s+(.*)", line)
        if heading:
            level = len(heading[1])
            stack = [(lv, text) for lv, text in stack if lv < level] + [(level, heading[2].strip())]
            headings.append(heading[2].strip())
            continue
        prose.append((number, line))
        for match in re.finditer(r"(`+)(.+?)\1", line):
            snippets.append(Snippet(path, number, match[2].strip(), student))
    return headings, snippets, prose


def all_snippets() -> list[Snippet]:
    return [s for path in doc_files() for s in headings_and_snippets(path)[1]]


def slug(heading: str) -> str:
    """GitHub's anchor of a heading."""
    text = re.sub(r"[`*_]", "", heading).strip().lower()
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


# What exists -----------------------------------------------------------------------------------------------
def run_sh_cases(path: Path) -> set[str]:
    """The commands of a run.sh: the patterns of its `case "$command" in`."""
    text = path.read_text(encoding="utf-8")
    body = text.split('case "$command" in', 1)[1]
    cases = set()
    for pattern in re.findall(r"^ {4}([\w|-]+)\)", body, re.MULTILINE):
        cases.update(pattern.split("|"))
    assert cases, f"no commands found in {path}"
    return cases


def student_run_sh() -> Path:
    """The student edition's run.sh: the one run.sh among the grader's release files."""
    found = sorted(REPO.glob("grader/**/run.sh"))
    assert len(found) == 1, f"expected one student edition run.sh under grader/, found {found}"
    return found[0]


def grader_subcommands() -> set[str]:
    """The subcommands of the parser behind the `grader` console script."""
    scripts = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["project"]["scripts"]
    module = importlib.import_module(scripts["grader"].split(":")[0])
    parser = module.build_parser()
    for action in parser._actions:
        if action.choices and hasattr(action, "add_parser"):
            return set(action.choices)
    raise AssertionError("the grader's parser has no subcommands")


def student_edition_commands() -> set[str]:
    """``STUDENT_COMMANDS`` (found wherever the release module lives), and ``list``."""
    for path in sorted((REPO / "grader").rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        if "STUDENT_COMMANDS" not in text:
            continue
        for node in ast.walk(ast.parse(text)):
            if (isinstance(node, (ast.Assign, ast.AnnAssign))
                    and any(isinstance(t, ast.Name) and t.id == "STUDENT_COMMANDS"
                            for t in (node.targets if isinstance(node, ast.Assign) else [node.target]))):
                return set(ast.literal_eval(node.value)) | {"list"}
    raise AssertionError("STUDENT_COMMANDS not found under grader/")


def module_subcommands(module: str) -> set[str] | None:
    """The argparse subcommands a module's source declares, or None when it has none."""
    spec = importlib.util.find_spec(module)
    origin = spec.origin if spec else None
    if spec and spec.submodule_search_locations:   # a package run with -m: its __main__
        main = Path(next(iter(spec.submodule_search_locations))) / "__main__.py"
        origin = str(main) if main.is_file() else origin
    if not origin or not origin.endswith(".py"):
        return None
    found = set(re.findall(r"add_parser\(\s*[\"']([\w-]+)[\"']", Path(origin).read_text(encoding="utf-8")))
    return found or None


# What the pages show ---------------------------------------------------------------------------------------
RUN_SH = re.compile(r"\bbash\s+(?:\S*/)?run\.sh\s+([\w-]+)")
GRADER = re.compile(r"^(?:[A-Z_]+=\S+\s+)*(?:\S*/)?grader\s+([a-z][\w-]*)")
PYTHON_M = re.compile(r"(?:^|\s)(?:\S*/)?python3?\s+-m\s+([\w.]+)(?:\s+([a-z][\w-]*))?")
EXTENSION = re.compile(r"\.[A-Za-z][\w]*$")


def shown_run_sh(snippets):
    return [(s, m[1]) for s in snippets for m in RUN_SH.finditer(s.text)]


def shown_grader(snippets):
    found = [(s, m[1]) for s in snippets if (m := GRADER.match(s.text))]
    found += [(s, m[2]) for s in snippets for m in PYTHON_M.finditer(s.text) if m[1] == "grader" and m[2]]
    return found


def shown_modules(snippets):
    return [(s, m[1], m[2]) for s in snippets for m in PYTHON_M.finditer(s.text) if m[1] != "grader"]


def path_words(snippet: Snippet) -> list[str]:
    """Words of a snippet that name repository paths (see the module's docstring)."""
    words = re.sub(r"<[^<>]*>", lambda m: m[0].replace(" ", "_"), snippet.text).split()   # <a b>: one word
    out = []
    for i, word in enumerate(words):
        word = re.sub(r"^--[\w-]+=", "", word).strip("\"'(),;:[]")
        if "/" not in word or "://" in word or word.startswith(("/", "~", "$", "../", "-")):
            continue
        after_runner = i > 0 and re.search(r"(?:^|/)(python3?|pytest)$", words[i - 1]) is not None
        if not (word.endswith("/") or EXTENSION.search(word.rstrip("*")) or after_runner):
            continue
        first = word.split("/")[0]
        if re.fullmatch(r"[A-Z][A-Z0-9_]*", first) or word.startswith(OUTPUTS):
            continue
        out.append(word)
    return out


def exists(word: str) -> bool:
    pattern = re.sub(r"<[^>/]*>", "*", word)
    if "*" in pattern:
        return any(REPO.glob(pattern.rstrip("/")))
    return (REPO / word).exists()


# Checks ----------------------------------------------------------------------------------------------------
def stale_commands(snippets) -> list[str]:
    """Every shown command that does not exist, as 'file:line: snippet: why'."""
    problems = []
    student_sh = student_run_sh()
    repository_run, student_run = run_sh_cases(REPO / "run.sh"), run_sh_cases(student_sh)
    for snippet, command in shown_run_sh(snippets):
        cases, which = (student_run, student_sh.relative_to(REPO).as_posix()) if snippet.student else (
            repository_run, "run.sh")
        if command not in cases:
            problems.append(f"{snippet.where()}: no command '{command}' in {which} ({', '.join(sorted(cases))})")
    everything, student = grader_subcommands(), student_edition_commands()
    for snippet, command in shown_grader(snippets):
        allowed, which = (everything & student, "the student edition's grader") if snippet.student else (
            everything, "grader")
        if command not in allowed:
            problems.append(f"{snippet.where()}: no subcommand '{command}' in {which} ({', '.join(sorted(allowed))})")
    for snippet, module, command in shown_modules(snippets):
        if importlib.util.find_spec(module) is None:
            problems.append(f"{snippet.where()}: module {module} is not importable")
            continue
        declared = module_subcommands(module)
        if declared and command and command not in declared:
            problems.append(f"{snippet.where()}: python -m {module} has no subcommand '{command}' "
                            f"({', '.join(sorted(declared))})")
    return problems


DOTTED = re.compile(r"(?<![\w/.-])((?:grader|solutions|exercises|tools)(?:\.\w+)+)(?![\w/-])")
FROM_IMPORT = re.compile(r"\bfrom\s+([\w.]+)\s+import\s+(\w+(?:\s*,\s*\w+)*)")


def resolves(name: str) -> bool:
    """A dotted name is a module, or an attribute of the longest module it starts with."""
    parts = name.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            spec = importlib.util.find_spec(".".join(parts[:cut]))
        except (ImportError, ValueError):   # a parent that is a module, not a package
            spec = None
        if spec is None:
            continue
        thing = importlib.import_module(".".join(parts[:cut]))
        for attribute in parts[cut:]:
            if not hasattr(thing, attribute):
                return False
            thing = getattr(thing, attribute)
        return True
    return False


def shown_names(snippets):
    """Dotted names of the project's packages, and what ``from X import Y`` imports."""
    found = [(s, m[1]) for s in snippets for m in DOTTED.finditer(s.text)]
    found += [(s, f"{m[1]}.{name.strip()}") for s in snippets for m in FROM_IMPORT.finditer(s.text)
              for name in m[2].split(",")]
    return found


def stale_names(snippets) -> list[str]:
    return [f"{s.where()}: {name} is neither a module nor in one" for s, name in shown_names(snippets)
            if not resolves(name)]


def stale_paths(snippets) -> list[str]:
    return [f"{s.where()}: {word} does not exist" for s in snippets for word in path_words(s) if not exists(word)]


def stale_links(path: Path) -> list[str]:
    problems = []
    for number, line in headings_and_snippets(path)[2]:
        for target in re.findall(r"\]\(([^)\s]+)\)", re.sub(r"(`+).+?\1", "", line)):
            if "://" in target or target.startswith("mailto:"):
                continue
            file, _, anchor = target.partition("#")
            linked = (path.parent / file).resolve() if file else path
            where = f"{path.relative_to(REPO)}:{number}: link {target}"
            if not linked.exists():
                problems.append(f"{where}: {file} does not exist")
            elif anchor and linked.suffix == ".md" and anchor not in {
                    slug(h) for h in headings_and_snippets(linked)[0]}:
                problems.append(f"{where}: no heading #{anchor} in {linked.relative_to(REPO)}")
    return problems


def test_readme_is_a_front_door():
    lines = len((REPO / "README.md").read_text(encoding="utf-8").splitlines())
    assert lines <= README_MAX_LINES, f"README.md has {lines} lines (at most {README_MAX_LINES}): move detail to docs/"


def test_the_pages_show_commands_and_paths():
    """The pages are read at all: a change to the parsing that finds nothing fails here."""
    snippets = all_snippets()
    assert {"main", "test", "bench"} <= {c for s, c in shown_run_sh(snippets) if not s.student}
    assert {"setup", "check", "lab", "submit", "update"} <= {c for s, c in shown_run_sh(snippets) if s.student}
    assert {"release", "grade"} <= {c for _, c in shown_grader(snippets)}
    assert {"tools.book", "grader.release.exercises", "tools.mutation"} <= {m for _, m, _ in shown_modules(snippets)}
    assert len([w for s in snippets for w in path_words(s)]) > 50


def test_every_command_shown_exists():
    problems = stale_commands(all_snippets())
    assert not problems, "\n".join(problems)


def test_every_path_shown_exists():
    problems = stale_paths(all_snippets())
    assert not problems, "\n".join(problems)


def test_every_module_and_function_named_exists():
    problems = stale_names(all_snippets())
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("path", doc_files(), ids=lambda p: p.name)
def test_every_link_leads_somewhere(path):
    problems = stale_links(path)
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("text, student, stale", [
    ("bash run.sh benchmark", False, "no command 'benchmark' in run.sh"),
    ("bash run.sh lab", False, "no command 'lab' in run.sh"),               # a student command, instructor's page
    ("bash run.sh release-check", True, "in grader/release/files/run.sh"),  # and the other way round
    (".venv/bin/grader grade-all --out out/x", False, "no subcommand 'grade-all'"),
    (".venv/bin/grader grade CLASS/*.zip --out out/grades", True, "the student edition's grader"),
    (".venv/bin/python -m tools.boook build", False, "tools.boook is not importable"),
    (".venv/bin/python -m tools.book compile", False, "no subcommand 'compile'"),
])
def test_a_stale_command_is_caught(text, student, stale):
    problems = stale_commands([Snippet(REPO / "README.md", 1, text, student)])
    assert len(problems) == 1 and stale in problems[0], problems


@pytest.mark.parametrize("text, stale", [
    ("grader/sandboxes.py", "grader/sandboxes.py"),
    (".venv/bin/python bench/bench_everything.py --quick", "bench/bench_everything.py"),
    (".venv/bin/pytest grader/tests/secret --student PATH/TO/exercises", "grader/tests/secret"),
    ("grader/tests/public/<test_exercise>.toml", "<test_exercise>.toml"),
    ("docs/nowhere/", "docs/nowhere/"),
])
def test_a_stale_path_is_caught(text, stale):
    problems = stale_paths([Snippet(REPO / "README.md", 1, text, False)])
    assert len(problems) == 1 and stale in problems[0], problems


@pytest.mark.parametrize("text, stale", [
    ("grader.harness.credit.check_everything(...)", "grader.harness.credit.check_everything"),
    ("grader.sandboxing.run", "grader.sandboxing.run"),
    ("from solutions.narrowphase.circle_circle import collide_circles", "circle_circle.collide_circles"),
    ("from grader import check, submit_all", "grader.submit_all"),
])
def test_a_stale_name_is_caught(text, stale):
    problems = stale_names([Snippet(REPO / "README.md", 1, text, False)])
    assert len(problems) == 1 and stale in problems[0], problems


def test_a_stale_link_is_caught(tmp_path, monkeypatch):
    page = REPO / "docs" / "engine.md"
    fake = tmp_path / "docs" / "page.md"
    fake.parent.mkdir()
    (tmp_path / "docs" / "engine.md").write_text(page.read_text(encoding="utf-8"), encoding="utf-8")
    fake.write_text("# A page\n\nSee [the engine](engine.md#conventions), [gone](grading.md) and\n"
                    "[no such part](engine.md#the-solver-of-old).\n", encoding="utf-8")
    monkeypatch.setattr(sys.modules[__name__], "REPO", tmp_path)
    problems = stale_links(fake)
    assert [p.split(": ", 1)[1] for p in problems] == [
        "link grading.md: grading.md does not exist",
        "link engine.md#the-solver-of-old: no heading #the-solver-of-old in docs/engine.md"], problems
