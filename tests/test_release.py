"""``grader release``: the student edition reveals no solution, and works on its own.

One release is built into a temporary folder for the module (about 10 s).  Then:

- no solution block of ``solutions/`` (as a stream of Python tokens: names, literals
  and operators, comments and layout dropped) appears in any file of the student
  edition: text files, notebook sources and outputs, the stored reference outputs,
  compiled files, the insides of zips; the scan is shown to find a planted block;
- ``import solutions`` fails in the student folder;
- the student edition's grader, run from the student folder with PYTHONPATH=<student>
  only, says "not implemented" for every public test on the stubs, gives full marks to
  a package filled with the reference, and agrees test by test with the instructor's
  ``grader check`` on both;
- a chapter notebook runs under nbclient on the student's package: the check cell runs
  the student's public tests, and a cell that needs a stub falls back to the stored
  reference output (marked ``book``: about 25 s);
- a folder that is not an earlier release is never overwritten, an unchanged earlier
  release is replaced.

The repository is installed in this ``.venv`` in editable mode, which makes
``solutions`` (and every ``grader`` module) importable from anywhere.  So the
student-side runs use this ``.venv``'s Python with ``-S``: its site-packages are put on
the path without running their ``.pth`` files, as ``site`` would otherwise do, so the
student folder is all there is of the course.

The README's set-up command, run into a fresh virtualenv and the course used there, is
tests/test_student_fresh_venv.py.
"""
from __future__ import annotations

import io
import json
import os
import re
import shutil
import subprocess
import sys
import sysconfig
import textwrap
import time
import tokenize
import tomllib
import warnings
import zipfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from grader.release.edition import MARKER, ReleaseError, build_release, check_replaceable, student_grader_files

pytestmark = pytest.mark.xdist_group("release")

REPO = Path(__file__).resolve().parent.parent
PYTHON = sys.executable
SITE_PACKAGES = sysconfig.get_path("purelib")
MIN_TOKENS = 8
#: The instructor's folders of grader/: never in the student edition.
NEVER = ("batch", "reports", "release", "samples", "tests/hidden")
#: What of grader/ a student holds: these folders whole, and the package face.
SHIPPED_FOLDERS = ("sandbox", "harness", "student", "oracles", "tests/public")
SHIPPED_FILES = ("__init__.py", "__main__.py", "cli.py", "errors.py", "tests/__init__.py", "tests/conftest.py",
                 "tests/pytest.ini")
#: Python of this .venv without the repository's editable install (see the docstring).
STUDENT_PRELUDE = (f"import sys; sys.prefix = sys.exec_prefix = {sys.prefix!r}; "
                   f"sys.path.append({SITE_PACKAGES!r}); ")
STUDENT_GRADER = STUDENT_PRELUDE + (
    "import grader; print('GRADER_FILE=' + grader.__file__, flush=True); "
    "from grader.cli import main; sys.exit(main(sys.argv[1:]))")


@pytest.fixture(scope="module")
def release(tmp_path_factory):
    start = time.perf_counter()
    made = build_release(tmp_path_factory.mktemp("release") / "out")
    print(f"release built in {time.perf_counter() - start:.1f} s")
    return made


@pytest.fixture(scope="module")
def filled(tmp_path_factory) -> Path:
    """A folder holding ``exercises``: a copy of the reference engine."""
    folder = tmp_path_factory.mktemp("filled")
    shutil.copytree(REPO / "solutions", folder / "exercises", ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    return folder


def student_env(student: Path, **extra) -> dict:
    env = {k: v for k, v in os.environ.items() if k not in ("GRADER_CHECK_PACKAGE", "PYTHONPATH")}
    env.update(PYTHONPATH=str(student), NO_COLOR="1", **extra)
    return env


def test_the_student_edition_has_no_twins_and_steps_with_the_students_code(release, tmp_path, monkeypatch):
    """The numpy and numba twins compute what exercises compute: they stay on the
    instructor's side, and the student's world runs the readable stages, the student's
    own clipping included."""
    from grader.release.exercises import is_instructor_only

    twins = sorted(p.relative_to(REPO / "solutions").as_posix() for p in (REPO / "solutions").rglob("*.py")
                   if is_instructor_only(p.read_text()))
    assert {"solver/kernel_numba.py", "narrowphase/box_pairs_numba.py", "narrowphase/speculative_batch.py",
            "narrowphase/batch_sat.py", "response/soft_step_numba.py"} <= set(twins)
    student = release.student
    assert not [t for t in twins if (student / "exercises" / t).exists()]
    assert not [p for p in student.rglob("*.py") if is_instructor_only(p.read_text(errors="replace"))]
    script = STUDENT_PRELUDE + textwrap.dedent("""
        import json
        from exercises.scenes import get_scene
        from exercises.world import WorldSettings
        try:
            WorldSettings(backend="numba")
        except ValueError as error:
            print("REFUSED", error)
        scene = get_scene("stack_10")
        world = scene.build_world(scene.recommended_settings())
        try:
            for _ in range(30):
                world.step(scene.dt)
        except NotImplementedError as error:
            print("STUB", error)
        else:
            print("STATE", json.dumps(world.state.position.tolist()))
    """)
    result = subprocess.run([PYTHON, "-S", "-c", script], cwd=student, env=student_env(student),
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert "REFUSED backend='numba' runs the compiled twins of the instructor's edition" in result.stdout
    # The first exercise a box stack reaches: the reference-face choice of the contacts exercise.
    assert "STUB write reference_face_candidates()" in result.stdout, result.stdout
    # A student who wrote the contacts and sequential exercises (here: the reference's
    # files) steps the stack exactly as the instructor's readable loop does.
    solved = tmp_path / "solved"
    shutil.copytree(student / "exercises", solved / "exercises")
    for done in ("narrowphase/polygon_polygon.py", "solver/contact_point.py", "solver/contact_sweeps.py"):
        shutil.copy(REPO / "solutions" / done, solved / "exercises" / done)
    result = subprocess.run([PYTHON, "-S", "-c", script], cwd=solved, env=student_env(solved),
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert "STATE " in result.stdout, result.stdout
    got = json.loads(result.stdout.split("STATE ", 1)[1])
    import solutions.world as world_module
    from solutions.scenes import get_scene

    monkeypatch.setattr(world_module, "HAS_TWINS", False)   # the loop, as the student edition runs
    scene = get_scene("stack_10")
    world = scene.build_world(scene.recommended_settings())
    for _ in range(30):
        world.step(scene.dt)
    assert got == world.state.position.tolist()



# Layout -------------------------------------------------------------------------------------
def test_student_folder_layout(release):
    student = release.student
    for name in ("README.md", "run.sh", "pyproject.toml", ".gitignore", MARKER, "exercises/__init__.py",
                 "grader/__init__.py", "grader/cli.py", "grader/student/check.py", "grader/student/notebook.py",
                 "grader/tests/pytest.ini", "grader/tests/conftest.py", "book/intro.md", "book/conventions.md",
                 "book/glossary.md"):
        assert (student / name).is_file(), name
    assert os.access(student / "run.sh", os.X_OK)
    if (REPO / "exercises" / ".generated.json").is_file():
        record = json.loads((student / "exercises" / ".generated.json").read_text())
        assert record.keys() == json.loads((REPO / "exercises" / ".generated.json").read_text()).keys()
    # Every repository module of exercises/ is there, byte for byte but for the commands
    # the exercise files name (`bash run.sh check sat` for `grader check sat`).
    for path in (REPO / "exercises").rglob("*.py"):
        if "__pycache__" not in path.parts:
            copy = student / "exercises" / path.relative_to(REPO / "exercises")
            assert copy.read_text().replace("`bash run.sh ", "`grader ") == path.read_text(), copy
    # The grader: the student's role folders whole and the package face, nothing else.
    shipped = sorted(p.relative_to(student / "grader").as_posix() for p in (student / "grader").rglob("*")
                     if p.is_file())
    source = REPO / "grader"
    expected = sorted([*SHIPPED_FILES, *(p.relative_to(source).as_posix() for folder in SHIPPED_FOLDERS
                                         for p in (source / folder).rglob("*")
                                         if p.is_file() and "__pycache__" not in p.parts)])
    assert shipped == expected == sorted(student_grader_files(REPO / "grader"))
    assert sorted(p.name for p in (student / "grader/tests/public").glob("test_*.py")) == sorted(
        p.name for p in (REPO / "grader/tests/public").glob("test_*.py"))
    for name in NEVER:
        assert not (student / "grader" / name).exists(), name
    for folder in ("grader/tests/hidden", "grader/spec", "grader/checks", "solutions"):
        assert not (student / folder).exists(), folder
    # One notebook per chapter, which holds the reference outputs (stored once: no other copy).
    chapters = sorted(p.stem for p in (REPO / "book/chapters").glob("*.ipynb"))
    assert sorted(p.stem for p in (student / "book").glob("*.ipynb")) == chapters
    assert sorted(p.relative_to(student / "book").as_posix() for p in (student / "book").rglob("*")) == sorted(
        [f"{c}.ipynb" for c in chapters] + ["intro.md", "conventions.md", "glossary.md"])
    # README: the two commands, the notebooks, submitting; not a word of solutions.
    readme = (student / "README.md").read_text()
    for text in ("bash run.sh setup", "bash run.sh check", "bash run.sh lab", "bash run.sh submit",
                 "%%reference_fallback", "08_momentum.ipynb"):
        assert text in readme, text
    assert "solution" not in readme.lower()
    run_sh = (student / "run.sh").read_text()
    for command in ("setup)", "check)", "lab)", "submit)", "ipykernel install", "pip install"):
        assert command in run_sh, command
    # pyproject: the repository's pins but those only the instructor's side imports (the
    # compiled twins' numba and llvmlite, the batch grader's tqdm), pytest's, JupyterLab 4
    # and the kernel packages.
    ours = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    theirs = tomllib.loads((student / "pyproject.toml").read_text())
    dependencies = theirs["project"]["dependencies"]
    left_out = {r for r in ours["dependencies"] if r.split("==")[0] in ("numba", "llvmlite", "tqdm")}
    assert set(ours["dependencies"]) - set(dependencies) == left_out and len(left_out) == 3
    pytest_pin = next(r for r in ours["optional-dependencies"]["dev"] if r.startswith("pytest=="))
    assert pytest_pin in dependencies
    assert any(re.fullmatch(r"jupyterlab==4\.\d+\.\d+", r) for r in dependencies)
    for name in ("ipykernel==", "nbclient==", "nbformat=="):
        assert any(r.startswith(name) for r in dependencies), name
    assert theirs["project"]["scripts"] == {"grader": "grader.cli:main"}
    assert theirs["project"]["name"] == "collision-course-student"
    marker = json.loads((student / MARKER).read_text())
    assert marker["edition"] == "student" and marker["created"] and "commit" in marker
    # The autograder side.
    assert (release.autograder / "autograder.zip").is_file() and (release.autograder / "README.md").is_file()
    with zipfile.ZipFile(release.autograder / "autograder.zip") as archive:
        assert "run_autograder" in archive.namelist()
    print(f"student edition: {sum(p.stat().st_size for p in student.rglob('*') if p.is_file()) / 1e6:.1f} MB, "
          f"{len(shipped)} grader files")


# No solution anywhere ---------------------------------------------------------------------------
_SKIP = {tokenize.COMMENT, tokenize.NL, tokenize.NEWLINE, tokenize.INDENT, tokenize.DEDENT, tokenize.ENDMARKER}
_ATOM = re.compile(r"\w+|[^\w\s]")


def block_texts() -> list[tuple[str, str]]:
    """(where, dedented text) of every ``### BEGIN/END SOLUTION`` block of solutions/."""
    blocks = []
    for path in sorted((REPO / "solutions").rglob("*.py")):
        lines = path.read_text().splitlines(keepends=True)
        start = None
        for number, line in enumerate(lines):
            if line.strip() == "### BEGIN SOLUTION":
                start = number
            elif line.strip() == "### END SOLUTION":
                text = textwrap.dedent("".join(lines[start + 1:number]))
                blocks.append((f"{path.relative_to(REPO)}:{start + 1}", text))
    return blocks


def block_tokens() -> list[tuple[str, list[str]]]:
    """(where, tokens) of every solution block: Python tokens, comments and layout dropped."""
    return [(where, [t.string for t in tokenize.generate_tokens(io.StringIO(text).readline) if t.type not in _SKIP])
            for where, text in block_texts()]


def _key(tokens) -> str:
    # Each token split into words and single marks, so that a block is found in any
    # text: tokenized Python, prose, HTML or a string of a notebook's JSON.
    return "\x1f" + "\x1f".join(a for t in tokens for a in _ATOM.findall(t)) + "\x1f"


def haystacks(name: str, data: bytes) -> list[str]:
    """The token streams a file holds (a zip's members, a notebook's cells and outputs)."""
    if data[:4] == b"PK\x03\x04":
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            return [h for m in archive.infolist() if not m.is_dir() for h in haystacks(m.filename, archive.read(m))]
    text = data.decode("utf-8", errors="replace")
    texts = [text]
    if name.endswith((".ipynb", ".json")):
        def strings(value):   # every string of the JSON (images left out), lists of lines joined
            if isinstance(value, str):
                yield value
            elif isinstance(value, list) and value and all(isinstance(v, str) for v in value):
                yield "".join(value)
            elif isinstance(value, dict):
                for key, item in value.items():
                    if not key.startswith("image/"):
                        yield from strings(item)
            elif isinstance(value, list):
                for item in value:
                    yield from strings(item)
        try:
            texts = list(strings(json.loads(text)))   # the parsed strings hold all of the text
        except ValueError:
            pass
    out = []
    for text in texts:
        out.append(_key(_ATOM.findall(text)))
        python = "\n".join(line for line in text.splitlines() if not line.lstrip().startswith("%"))
        try:
            out.append(_key(t.string for t in tokenize.generate_tokens(io.StringIO(python).readline)
                            if t.type not in _SKIP))
        except (tokenize.TokenError, IndentationError, SyntaxError):
            pass
    return out


def find_leaks(folder: Path, blocks) -> list[str]:
    keys = [(where, _key(tokens)) for where, tokens in blocks]
    found = []
    for path in sorted(p for p in folder.rglob("*") if p.is_file()):
        streams = haystacks(path.name, path.read_bytes())
        found += [f"{path.relative_to(folder)}: {where}" for where, key in keys if any(key in s for s in streams)]
    return found


def test_no_solution_block_in_the_student_edition(release, tmp_path):
    blocks = block_tokens()
    assert len(blocks) >= 20, "the solution blocks of solutions/ were not found"
    short = [f"{where} ({len(tokens)} tokens)" for where, tokens in blocks if len(tokens) < MIN_TOKENS]
    if short:
        warnings.warn(f"solution blocks too short to look for (not checked): {', '.join(short)}")
    checked = [(where, tokens) for where, tokens in blocks if len(tokens) >= MIN_TOKENS]
    student = release.student
    compiled = [p for p in student.rglob("*") if p.suffix in (".pyc", ".pyo") or p.name == "__pycache__"]
    assert not compiled, compiled
    assert not find_leaks(student, checked)
    # No notebook cell imports the reference engine.
    for notebook in (student / "book").glob("*.ipynb"):
        for cell in json.loads(notebook.read_text())["cells"]:
            if cell["cell_type"] == "code":
                source = "".join(cell["source"])
                assert not re.search(r"^\s*(from|import)\s+solutions\b|\bsolutions\.", source, re.M), source[:200]
    # The scan finds a block that is there: re-indented, commented, in a notebook output and a zip.
    texts = {where: text for where, text in block_texts()}
    where, tokens = max(((w, t) for w, t in checked if '"""' not in texts[w] and "'''" not in texts[w]),
                        key=lambda b: len(b[1]))
    planted = "\n".join(f"  {line}  # note" if line.strip() else line for line in texts[where].splitlines())
    (tmp_path / "plant").mkdir()
    notebook = {"cells": [{"cell_type": "code", "source": "", "outputs": [
        {"output_type": "stream", "name": "stdout", "text": planted.splitlines(True)}]}]}
    (tmp_path / "plant" / "n.ipynb").write_text(json.dumps(notebook))
    with zipfile.ZipFile(tmp_path / "plant" / "a.zip", "w") as archive:
        archive.writestr("inner/x.py", "# header\n" + planted)
    found = find_leaks(tmp_path / "plant", [(where, tokens)])
    assert sorted(found) == [f"a.zip: {where}", f"n.ipynb: {where}"], found


def test_import_solutions_fails_in_the_student_folder(release):
    student = release.student
    result = subprocess.run([PYTHON, "-S", "-c", STUDENT_PRELUDE + "import solutions"], cwd=student,
                            env=student_env(student), capture_output=True, text=True, timeout=60)
    assert result.returncode != 0 and "No module named 'solutions'" in result.stderr, result.stderr
    # The same interpreter does find the student's own packages there.
    probe = STUDENT_PRELUDE + "import grader, exercises; print(grader.__file__); print(exercises.__file__)"
    result = subprocess.run([PYTHON, "-S", "-c", probe], cwd=student, env=student_env(student), capture_output=True,
                            text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    assert [Path(p).resolve() for p in result.stdout.split()] == [
        student / "grader/__init__.py", student / "exercises/__init__.py"]
    # The student command line holds the student commands only.
    result = subprocess.run([PYTHON, "-S", "-c", STUDENT_GRADER, "--help"], cwd=student, env=student_env(student),
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    commands = re.search(r"\{([\w,-]+)\}", result.stdout).group(1).split(",")
    assert set(commands) <= {"check", "submit", "update", "list"} and {"check", "update"} <= set(commands), \
        result.stdout


def test_the_student_edition_names_the_commands_its_readme_teaches(release):
    """The README teaches `bash run.sh check` and `bash run.sh submit`: the stubs, the
    exercise headers and the grader's usage lines in the student edition say so too."""
    student = release.student
    exercises = student / "exercises"
    texts = {p.relative_to(exercises).as_posix(): p.read_text(encoding="utf-8") for p in exercises.rglob("*.py")}
    assert not [name for name, text in texts.items() if "`grader check" in text or "`grader submit" in text]
    assert "then run `bash run.sh check momentum`" in texts["response/momentum_1d.py"]
    record = json.loads((exercises / ".generated.json").read_text(encoding="utf-8"))["sha256"]
    from grader.release.edition import _sha256
    assert {name: _sha256(exercises / name) for name in record} == record, "the generator's record went stale"
    for command in ("check", "submit"):
        result = subprocess.run([PYTHON, "-S", "-c", STUDENT_GRADER, command, "--help"], cwd=student,
                                env=student_env(student), capture_output=True, text=True, timeout=60)
        assert result.returncode == 0 and f"usage: bash run.sh {command}" in result.stdout, result.stdout


# The student's grader ------------------------------------------------------------------------------
#: A test's line in ``grader check``'s table: label, score/points, title, [name].
ROW = re.compile(r"^(?P<label>[A-Z][A-Z_ ]*[A-Z])\s+(?P<score>[\d.]+)/(?P<points>[\d.]+)\s+.*"
                 r"\[(?P<name>[^\]\s]+)\]\s*$")


def statuses(output: str) -> dict[str, str]:
    return {m["name"]: m["label"] for m in map(ROW.match, output.splitlines()) if m}


def test_student_grader_agrees_with_the_instructors(release, filled):
    student = release.student
    runs = {
        "student, stubs": ([PYTHON, "-S", "-c", STUDENT_GRADER, "check"], student, student_env(student)),
        "student, filled": ([PYTHON, "-S", "-c", STUDENT_GRADER, "check", "--package", str(filled)], student,
                            student_env(student)),
        "instructor, stubs": ([PYTHON, "-m", "grader", "check", "--package", str(student / "exercises")], REPO,
                              student_env(REPO)),
        "instructor, filled": ([PYTHON, "-m", "grader", "check", "--package", str(filled / "exercises")], REPO,
                               student_env(REPO)),
    }
    start = time.perf_counter()

    def run(item):
        name, (command, cwd, env) = item
        return name, subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True, timeout=900)

    with ThreadPoolExecutor(max_workers=4) as pool:
        results = dict(pool.map(run, runs.items()))
    print(f"four grader check runs: {time.perf_counter() - start:.1f} s")
    for name, result in results.items():
        assert result.returncode in (0, 1), f"{name}: exit {result.returncode}\n{result.stdout[-3000:]}{result.stderr}"
    for name in ("student, stubs", "student, filled"):
        first = results[name].stdout.splitlines()[0]
        assert Path(first.removeprefix("GRADER_FILE=")).resolve() == student / "grader/__init__.py", first
    stub, full = statuses(results["student, stubs"].stdout), statuses(results["student, filled"].stdout)
    assert stub, results["student, stubs"].stdout[-3000:]
    assert set(stub.values()) == {"TO DO"}, {k: v for k, v in stub.items() if v != "TO DO"}
    assert "not implemented yet" in results["student, stubs"].stdout
    assert results["student, stubs"].returncode == 1
    assert set(full) == set(stub) and set(full.values()) == {"PASS"}, {k: v for k, v in full.items() if v != "PASS"}
    score = re.search(r"Score ([\d.]+)/([\d.]+) points", results["student, filled"].stdout)
    assert score and score[1] == score[2] and results["student, filled"].returncode == 0
    assert statuses(results["instructor, stubs"].stdout) == stub
    assert statuses(results["instructor, filled"].stdout) == full


CLASSIC_BUGS = ("restitution-sign", "grid-own-cell", "quadtree-drops-straddling", "flt-min", "one-point-manifold",
                "separate-impulses")


def test_student_grader_loses_exactly_the_expected_tests_on_classic_bugs(release, tmp_path):
    """Classic bugs of the example class, one or more per exercise: the student edition's
    check fails exactly the public tests each bug must fail, as the instructor's does."""
    from grader.samples.example_class import BUGGY_SAMPLES, build_buggy_sample
    from grader.harness.run import load_spec

    public = {t.name for t in load_spec() if t.public}
    samples = [s for s in BUGGY_SAMPLES if s.name in CLASSIC_BUGS]
    assert len(samples) == len(CLASSIC_BUGS)
    student = release.student
    runs = {}
    exercise_of = {}
    for sample in samples:
        # Each classic bug fails the tests of one exercise: check that exercise alone (the
        # whole course's public tests, twice per bug, cost more than a minute).
        exercises = {name.split(".", 1)[0] for name in sample.expected_failures}
        assert len(exercises) == 1, (sample.name, exercises)
        exercise_of[sample.name] = exercise = exercises.pop()
        folder = build_buggy_sample(sample, tmp_path)
        runs[(sample.name, "student")] = ([PYTHON, "-S", "-c", STUDENT_GRADER, "check", exercise, "--package",
                                           str(folder)], student, student_env(student))
        runs[(sample.name, "instructor")] = ([PYTHON, "-m", "grader", "check", exercise, "--package", str(folder)],
                                             REPO, student_env(REPO))

    def run(item):
        key, (command, cwd, env) = item
        return key, subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True, timeout=900)

    with ThreadPoolExecutor(max_workers=4) as pool:
        results = dict(pool.map(run, runs.items()))
    for sample in samples:
        mine, theirs = (statuses(results[(sample.name, side)].stdout) for side in ("student", "instructor"))
        assert mine and mine == theirs, sample.name
        failed = {name for name, label in mine.items() if label != "PASS"}
        assert failed == sample.expected_failures & public, sample.name
        assert {name.split(".", 1)[0] for name in mine} == {exercise_of[sample.name]}, sample.name


# A chapter notebook --------------------------------------------------------------------------------------
def _text(output) -> str:
    if output.get("output_type") == "stream":
        return "".join(output.get("text", ""))
    value = output.get("data", {}).get("text/plain", "")
    return "".join(value) if isinstance(value, list) else value


def _same(outputs, stored) -> bool:
    """The same outputs, as a person sees them (text, and which kinds of data)."""
    def shape(items):
        return [(o.get("output_type") if o.get("output_type") == "stream" else "data", _text(o),
                 sorted(o.get("data", {}))) for o in items]
    return shape(outputs) == shape(stored)


@pytest.mark.book
def test_chapter_notebook_runs_on_the_students_package(release, filled, monkeypatch):
    import nbformat
    from nbclient import NotebookClient

    student = release.student
    public = {p.stem.removeprefix("test_") for p in (student / "grader/tests/public").glob("test_*.py")}
    candidates = []
    for path in sorted((student / "book").glob("*.ipynb")):
        nb = nbformat.read(path, as_version=4)
        for cell in nb.cells:
            match = re.search(r"\bcheck\(\"(\w+)\"\)", cell.source) if cell.cell_type == "code" else None
            if match and match[1] in public:
                candidates.append((path, match[1]))
    assert candidates, f"no chapter has a check cell of a public exercise ({public})"
    # The momentum chapter runs quickest; any chapter with a public check otherwise.
    path, exercise = min(candidates, key=lambda c: (c[1] != "momentum", c[0].stat().st_size))
    shipped = nbformat.read(path, as_version=4)
    stored = {c.source.split("\n", 1)[0].partition(":")[2]: c.outputs for c in shipped.cells
              if c.cell_type == "code" and c.source.startswith("%%reference_fallback")}
    probe = ("import json, sys\n"
             "print('MODULES=' + json.dumps({m: getattr(sys.modules[m], '__file__', None) for m in list(sys.modules)"
             " if m.split('.')[0] in ('grader', 'exercises', 'tools', 'solutions')}))")

    def execute(extra: Path | None):
        nb = nbformat.read(path, as_version=4)
        nb.cells.append(nbformat.v4.new_code_cell(probe))
        monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(extra)] if extra else []) + (
            os.pathsep if extra else "") + str(student))
        if extra:
            monkeypatch.setenv("GRADER_CHECK_PACKAGE", str(extra / "exercises"))
        else:
            monkeypatch.delenv("GRADER_CHECK_PACKAGE", raising=False)
        start = time.perf_counter()
        NotebookClient(nb, kernel_name="collision-course", timeout=600, allow_errors=False,
                       resources={"metadata": {"path": str(path.parent)}}).execute()
        print(f"{path.name} ({'filled' if extra else 'stubs'}): {time.perf_counter() - start:.1f} s")
        modules = json.loads(next(_text(o) for o in nb.cells[-1].outputs if "MODULES=" in _text(o)).split(
            "MODULES=", 1)[1])
        assert not [m for m in modules if m.split(".")[0] == "solutions"], modules
        for module, file in modules.items():
            if file and module.split(".")[0] in ("grader", "tools"):
                assert Path(file).resolve().is_relative_to(student), (module, file)
        return nb, modules

    def cells(nb):
        return [c for c in nb.cells if c.cell_type == "code"]

    # On the stubs: fallbacks, each followed by exactly the stored output; the check runs the student's tests.
    nb, modules = execute(None)
    assert Path(modules["exercises"]).resolve() == student / "exercises/__init__.py"
    fell_back, ran = 0, 0
    for cell in cells(nb):
        if not cell.source.startswith("%%reference_fallback"):
            continue
        key = cell.source.split("\n", 1)[0].partition(":")[2]
        texts = [_text(o) for o in cell.outputs]
        if texts and texts[0].startswith("[reference output] this cell needs"):
            fell_back += 1
            assert "which you have not written yet" in texts[0]
            assert _same(cell.outputs[1:], stored[key]), key
        else:
            ran += 1
            assert not any("[reference output]" in t for t in texts), key
    assert fell_back >= 1 and ran >= 1, (fell_back, ran)
    check_cell = next(c for c in cells(nb) if f'check("{exercise}")' in c.source)
    html = "".join(o.get("data", {}).get("text/html", "") for o in check_cell.outputs)
    assert "not implemented yet" in html and "TO DO" in html, html[:2000]
    assert "package exercises" in html or str(student / "exercises") in html, html[:500]
    # On a package filled with the reference: every cell runs the package, the check passes.
    nb, modules = execute(filled)
    assert Path(modules["exercises"]).resolve() == filled / "exercises/__init__.py"
    for cell in cells(nb):
        assert not any("[reference output]" in _text(o) for o in cell.outputs), cell.source[:200]
    check_cell = next(c for c in cells(nb) if f'check("{exercise}")' in c.source)
    report = " ".join(_text(o) for o in check_cell.outputs)
    match = re.search(r"(\d+)/(\d+) points, (\d+)/(\d+) tests passed", report)
    assert match and match[1] == match[2] and match[3] == match[4], report


# Refusing and replacing --------------------------------------------------------------------------------------
def _tree(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def test_release_never_overwrites_what_is_not_an_earlier_release(release, tmp_path):
    # A student's folder (no marker): refused, nothing written.
    out = tmp_path / "out"
    (out / "student" / "exercises").mkdir(parents=True)
    (out / "student" / "exercises" / "mine.py").write_text("my work\n")
    before = _tree(out)
    with pytest.raises(ReleaseError, match="not an earlier release"):
        build_release(out)
    assert _tree(out) == before and sorted(p.name for p in out.iterdir()) == ["student"]
    # An autograder folder that is not a release: refused too.
    out = tmp_path / "out2"
    (out / "autograder").mkdir(parents=True)
    with pytest.raises(ReleaseError, match="not an earlier release"):
        build_release(out)
    assert sorted(p.name for p in out.iterdir()) == ["autograder"]
    # An earlier release someone changed (a student's copy of it): refused, untouched.
    out = tmp_path / "out3"
    shutil.copytree(release.out, out, symlinks=True)
    (out / "student/exercises/response/momentum_1d.py").write_text("# my answers\n", encoding="utf-8")
    before = _tree(out)
    with pytest.raises(ReleaseError, match="changed since"):
        build_release(out)
    assert _tree(out) == before
    # The leftovers of using it (a venv, caches, egg-info) do not count as changes.
    out = tmp_path / "out4"
    shutil.copytree(release.out, out, symlinks=True)
    (out / "student/.venv/bin").mkdir(parents=True)
    (out / "student/.venv/bin/python").write_text("")
    (out / "student/exercises/__pycache__").mkdir()
    (out / "student/exercises/__pycache__/x.cpython-311.pyc").write_bytes(b"\0")
    (out / "student/collision_course_student.egg-info").mkdir()
    assert check_replaceable(out / "student", "student") is True


def test_release_refuses_an_edition_that_would_reveal_a_solution(tmp_path):
    """The release's own guard (run before anything is moved into place) names each leak."""
    from grader.release.edition import verify_student
    from grader.release.leak_scan import solution_blocks

    folder = tmp_path / "student"
    (folder / "exercises/response").mkdir(parents=True)
    solved = (REPO / "solutions/response/momentum_1d.py").read_text()
    (folder / "exercises/response/momentum_1d.py").write_text(solved.replace("    ", "  "))
    (folder / "solutions").mkdir()
    (folder / "solutions/__init__.py").write_text("")
    (folder / "grader/tests/hidden").mkdir(parents=True)
    (folder / "grader/tests/hidden/test_grid.py").write_text("")
    (folder / "book").mkdir()
    with zipfile.ZipFile(folder / "book/old.zip", "w") as archive:
        archive.writestr("impulse.py", (REPO / "solutions/response/impulse.py").read_text())
    with pytest.raises(ReleaseError) as refused:
        verify_student(folder, solution_blocks(REPO / "solutions"))
    message = str(refused.value)
    for expected in ("exercises/response/momentum_1d.py holds the solution block of solutions/response/momentum_1d.py",
                     "book/old.zip holds the solution block of solutions/response/impulse.py",
                     "solutions/__init__.py is part of a solutions package",
                     "grader/tests/hidden/test_grid.py never ships to students"):
        assert expected in message, message


def test_release_command_replaces_an_earlier_release(release, tmp_path):
    out = tmp_path / "out"
    shutil.copytree(release.out, out, symlinks=True)
    (out / "student" / ".venv").mkdir()
    old = json.loads((out / "student" / MARKER).read_text())
    result = subprocess.run([PYTHON, "-m", "grader", "release", "--out", str(out)], cwd=REPO, capture_output=True,
                            text=True, timeout=600)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "student edition:" in result.stdout and "none found" in result.stdout
    new = json.loads((out / "student" / MARKER).read_text())
    # A release from a tree with uncommitted changes is written, with a warning.
    warned = re.search(r"warning: \d+ files? of the repository ha(ve|s) uncommitted changes", result.stderr)
    assert bool(warned) == new["uncommitted_changes"], result.stderr
    assert new["files"].keys() == old["files"].keys()
    assert not (out / "student" / ".venv").exists()
    assert sorted(p.name for p in out.iterdir()) == ["autograder", "student"]   # no staging folder left


def test_changed_files_are_what_git_status_lists(tmp_path):
    from grader.release.edition import changed_files, repository_commit

    def git(*args):
        subprocess.run(["git", "-C", str(tmp_path), "-c", "user.name=t", "-c", "user.email=t@example.org", *args],
                       check=True, capture_output=True)

    git("init", "-q")
    (tmp_path / "a.txt").write_text("one\n")
    git("add", "a.txt")
    git("commit", "-q", "-m", "one")
    assert changed_files(tmp_path) == [] and repository_commit(tmp_path)[1] is False
    (tmp_path / "a.txt").write_text("two\n")
    (tmp_path / "b.txt").write_text("new\n")
    assert changed_files(tmp_path) == ["a.txt", "b.txt"] and repository_commit(tmp_path)[1] is True
    assert changed_files(tmp_path / "not-a-repository") == []


def test_the_student_edition_does_not_install_the_instructors_compiled_twins(release):
    """The compiled twins stay on the instructor's side, and so does numba: the student's
    pyproject pins only what the edition imports (and what those packages need)."""
    dependencies = tomllib.loads((release.student / "pyproject.toml").read_text())["project"]["dependencies"]
    names = {re.split(r"[=<>!~ \[]", d, maxsplit=1)[0].lower() for d in dependencies}
    assert {"numpy", "pymunk", "pytest"} <= names
    assert not names & {"numba", "llvmlite"}, dependencies
    assert not list(release.student.rglob("*numba*.py"))


def test_a_runtime_pin_is_kept_for_an_imported_module_and_for_what_it_needs():
    from grader.release.edition import used_requirements

    pins = ["numpy==2.4.6", "numba==0.68.1", "llvmlite==0.50.0", "sympy==1.14.0"]
    assert used_requirements(pins, {"numpy", "os"}) == ["numpy==2.4.6"]
    assert used_requirements(pins, {"numba"}) == ["numpy==2.4.6", "numba==0.68.1", "llvmlite==0.50.0"]
    assert used_requirements(pins, set()) == []
