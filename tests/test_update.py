"""``grader update``: a corrected release taken into a student's folder without losing work.

One release (1.0.0) is built from the repository for the module (about 6 s); each
"corrected" release is derived from a copy of its student edition the way a second
``grader release`` would differ: files edited, added or removed, a new section on top
of ``CHANGELOG.md``, the originals kept again and the marker written again with the new
version and hashes (:func:`grader.student.update.write_originals`, the release's own ``_marker``).
Each test works on a fresh copy of the student edition, edited as a student would.
"""
from __future__ import annotations

import hashlib
import json
import os
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

from grader.release.edition import MARKER, _marker, build_release
from grader.student.update import (ATTENTION, BACKUPS, CHANGELOG, DONE, ORIGINALS, REFUSED, UpdateRefused, merge_text,
                           notebook_sources, update, write_originals)

pytestmark = pytest.mark.xdist_group("release")

MOMENTUM = "exercises/response/momentum_1d.py"
LIBRARY = "exercises/vector.py"
DOCSTRING_LINE = '"""Head-on collisions of two bodies moving along one line (point masses).\n'
LIBRARY_LINE = "    return np.stack([edge[..., 1], -edge[..., 0]], axis=-1)\n"


@pytest.fixture(scope="module")
def release(tmp_path_factory) -> Path:
    """The student edition of a release built from the repository (version 1.0.0 or
    whatever CHANGELOG.md's newest section says)."""
    return build_release(tmp_path_factory.mktemp("release") / "out").student


def derive(source: Path, target: Path, version: str, changes: str, edits: dict | None = None,
           written: dict | None = None, removed: tuple = ()) -> Path:
    """A newer release made from the student edition ``source``: ``edits`` {path: (old
    text, new text)} replaced once each, ``written`` {path: text} written whole, ``removed``
    deleted, CHANGELOG.md given a new top section, originals and marker written again."""
    shutil.copytree(source, target)
    for relative, (old, new) in (edits or {}).items():
        text = (target / relative).read_text(encoding="utf-8")
        assert text.count(old) == 1, f"{relative}: the edit's old text is not there once"
        (target / relative).write_text(text.replace(old, new), encoding="utf-8")
    for relative, text in (written or {}).items():
        (target / relative).parent.mkdir(parents=True, exist_ok=True)
        (target / relative).write_text(text, encoding="utf-8")
    for relative in removed:
        (target / relative).unlink()
    log = (target / CHANGELOG).read_text(encoding="utf-8")
    head, _, rest = log.partition("\n## ")
    (target / CHANGELOG).write_text(f"{head}\n## {version} (2030-01-01)\n\n{changes}\n\n## {rest}", encoding="utf-8")
    old = json.loads((target / MARKER).read_text(encoding="utf-8"))
    (target / MARKER).unlink()
    (target / ORIGINALS).unlink()
    kept = write_originals(target)
    _marker(target, "student", "2030-01-01T00:00:00+00:00", old.get("commit"), False,
            {"version": version, "changes": changes, "grader_files": old["grader_files"], **kept})
    return target


def student_copy(release: Path, folder: Path) -> Path:
    course = folder / "course"
    shutil.copytree(release, course)
    return course


def edit(path: Path, old: str, new: str) -> None:
    text = path.read_text(encoding="utf-8")
    assert text.count(old) >= 1, f"{path}: {old!r} not found"
    path.write_text(text.replace(old, new, 1), encoding="utf-8")


def implement_first_stub(path: Path) -> str:
    """Replace the first ``raise NotImplementedError(...)`` line with a line of "student
    code"; that line."""
    lines = path.read_text(encoding="utf-8").splitlines(keepends=True)
    index = next(i for i, line in enumerate(lines) if line.strip().startswith("raise NotImplementedError"))
    indent = lines[index][:len(lines[index]) - len(lines[index].lstrip())]
    mine = f"{indent}return 0.5 * (v1 + v2)  # my own code\n"
    lines[index] = mine
    path.write_text("".join(lines), encoding="utf-8")
    return mine


def snapshot(folder: Path) -> dict[str, str]:
    """{relative path: sha256} of every file under ``folder``."""
    return {p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def run_update(course: Path, release: Path) -> tuple[int, str]:
    printed = []
    status = update(course, release, out=printed.append)
    return status, "\n".join(printed)


def test_the_release_records_its_version_and_keeps_the_originals(release):
    marker = json.loads((release / MARKER).read_text(encoding="utf-8"))
    repo_log = (Path(__file__).resolve().parent.parent / CHANGELOG).read_text(encoding="utf-8")
    assert marker["version"] and f"## {marker['version']}" in repo_log
    assert (release / CHANGELOG).read_text(encoding="utf-8") == repo_log
    with zipfile.ZipFile(release / ORIGINALS) as archive:
        originals = {name: archive.read(name) for name in archive.namelist()}
    assert originals[MOMENTUM] == (release / MOMENTUM).read_bytes()
    assert originals["run.sh"] == (release / "run.sh").read_bytes()
    assert not [name for name in originals if name.endswith(".ipynb")]
    notebooks = sorted(p.relative_to(release).as_posix() for p in (release / "book").glob("*.ipynb"))
    assert sorted(marker["notebook_sources"]) == notebooks


def test_update_merges_an_edited_exercise_and_replaces_untouched_files(release, tmp_path):
    course = student_copy(release, tmp_path)
    mine = implement_first_stub(course / MOMENTUM)
    (course / "exercises" / "my_helpers.py").write_text("HELP = 1\n", encoding="utf-8")
    before = (course / MOMENTUM).read_text(encoding="utf-8")
    library_before = (course / LIBRARY).read_bytes()
    new = derive(release, tmp_path / "new", "9.0.1", "- Fixed: perp's docstring and its result's dtype.",
                 edits={MOMENTUM: (DOCSTRING_LINE, DOCSTRING_LINE.replace("(point masses)", "(point masses, "
                                                                          "corrected)")),
                        LIBRARY: (LIBRARY_LINE, LIBRARY_LINE.replace("axis=-1)", "axis=-1).astype(float)"))},
                 written={"book/errata.md": "# Errata\n"}, removed=("book/glossary.md",))

    status, said = run_update(course, new)

    assert status == DONE, said
    merged = (course / MOMENTUM).read_text(encoding="utf-8")
    assert mine in merged and "(point masses, corrected)" in merged and "<<<<<<<" not in merged
    assert (course / LIBRARY).read_bytes() == (new / LIBRARY).read_bytes() != library_before
    assert (course / "book/errata.md").is_file() and not (course / "book/glossary.md").exists()
    assert (course / "exercises" / "my_helpers.py").read_text(encoding="utf-8") == "HELP = 1\n"
    assert json.loads((course / MARKER).read_text(encoding="utf-8"))["version"] == "9.0.1"
    backups = list((course / BACKUPS).iterdir())
    assert len(backups) == 1 and str(backups[0].relative_to(course)) in said
    assert (backups[0] / MOMENTUM).read_text(encoding="utf-8") == before
    assert (backups[0] / LIBRARY).read_bytes() == library_before
    assert (backups[0] / "book/glossary.md").is_file()
    assert "perp's docstring" in said
    assert f"merged (your changes kept, the release's added): 1\n  {MOMENTUM}" in said

    again = snapshot(course)
    status, said = run_update(course, new)
    assert status == DONE and "already" in said and "nothing to do" in said
    assert snapshot(course) == again


def test_a_conflict_keeps_both_versions_and_is_listed_last(release, tmp_path):
    course = student_copy(release, tmp_path)
    edit(course / MOMENTUM, DOCSTRING_LINE, '"""My own summary of head-on collisions.\n')
    new = derive(release, tmp_path / "new", "9.0.2", "- Clearer summary.",
                 edits={MOMENTUM: (DOCSTRING_LINE, '"""Head-on collisions of two point masses on one line.\n')})

    status, said = run_update(course, new)

    assert status == ATTENTION
    text = (course / MOMENTUM).read_text(encoding="utf-8")
    assert ('<<<<<<< yours\n"""My own summary of head-on collisions.\n=======\n'
            '"""Head-on collisions of two point masses on one line.\n>>>>>>> release 9.0.2\n') in text
    tail = said[said.index("CONFLICTS"):]
    assert f"{MOMENTUM}: 1 place" in tail and "Clearer summary" not in tail   # the list comes last
    backup = next((course / BACKUPS).iterdir())
    assert "My own summary" in (backup / MOMENTUM).read_text(encoding="utf-8")


def test_the_students_edition_runs_the_update_itself(release, tmp_path):
    """``python -m grader update`` in the student folder, with the student edition's own
    grader on the path (no release.py there), from a zip of the new release: the exit
    status says there are conflicts; a dry run changes nothing."""
    course = student_copy(release, tmp_path)
    edit(course / LIBRARY, LIBRARY_LINE, LIBRARY_LINE.replace("-edge", "-1.0 * edge"))
    new = derive(release, tmp_path / "new", "9.0.3", "- perp rewritten.",
                 edits={LIBRARY: (LIBRARY_LINE, LIBRARY_LINE.replace("-edge", "(-edge)"))})
    archive = tmp_path / "course-9.0.3.zip"
    with zipfile.ZipFile(archive, "w") as out:
        for path in sorted(new.rglob("*")):
            if path.is_file():
                out.write(path, f"student/{path.relative_to(new).as_posix()}")
    prelude = (f"import sys; sys.path.append({sysconfig.get_path('purelib')!r}); "
               "from grader.cli import main; sys.exit(main(sys.argv[1:]))")
    env = {**{k: v for k, v in os.environ.items() if k != "PYTHONPATH"}, "PYTHONPATH": str(course)}

    def grader(*args):
        return subprocess.run([sys.executable, "-S", "-c", prelude, *args], cwd=course, env=env,
                              capture_output=True, text=True, timeout=120)

    before = snapshot(course)
    dry = grader("update", str(archive), "--dry-run")
    assert dry.returncode == ATTENTION, dry.stderr
    assert "nothing was changed" in dry.stdout and snapshot(course) == before
    done = grader("update", str(archive))
    assert done.returncode == ATTENTION, done.stdout + done.stderr
    assert "-1.0 * edge" in (course / LIBRARY).read_text() and "(-edge)" in (course / LIBRARY).read_text()
    assert "CONFLICTS" in done.stdout
    assert not (course / "grader" / "release.py").exists()


def test_refusals_change_nothing(release, tmp_path):
    course = student_copy(release, tmp_path)
    implement_first_stub(course / MOMENTUM)
    newer = derive(release, tmp_path / "newer", "9.1.0", "- Newer.")
    assert run_update(course, newer)[0] == DONE
    before = snapshot(course)
    older = derive(release, tmp_path / "older", "9.0.9", "- Older.")
    same_version = derive(release, tmp_path / "same", "9.1.0", "- Same number, other files.",
                          written={"book/other.md": "x\n"})
    not_a_release = tmp_path / "random"
    (not_a_release / "exercises").mkdir(parents=True)
    cases = {older: "older than your folder", same_version: "files differ", not_a_release: "not a release",
             release.parent / "autograder": "not the student edition"}
    for path, reason in cases.items():
        with pytest.raises(UpdateRefused, match=reason):
            update(course, path, out=lambda _: None)
        assert snapshot(course) == before
    with pytest.raises(UpdateRefused, match="not a course folder"):
        update(tmp_path / "random", newer, out=lambda _: None)
    autograder = json.loads((release.parent / "autograder" / MARKER).read_text())
    assert autograder["edition"] == "autograder"
    with pytest.raises(UpdateRefused, match="not a student's course folder"):
        update(release.parent / "autograder", newer, out=lambda _: None)
    assert REFUSED == 2


def test_notebooks_only_run_are_replaced_and_edited_ones_kept(release, tmp_path):
    course = student_copy(release, tmp_path)
    ran, wrote = sorted((course / "book").glob("*.ipynb"))[:2]
    for path, change_source in ((ran, False), (wrote, True)):
        data = json.loads(path.read_text(encoding="utf-8"))
        code = next(c for c in data["cells"] if c["cell_type"] == "code")
        code["execution_count"] = 99   # what running a cell changes
        if change_source:
            code["source"] = "# my note\n" + "".join(code["source"])
        path.write_text(json.dumps(data), encoding="utf-8")
    corrected = {}
    for path in (ran, wrote):
        relative = path.relative_to(course).as_posix()
        data = json.loads((release / relative).read_text(encoding="utf-8"))
        markdown = next(c for c in data["cells"] if c["cell_type"] == "markdown")
        markdown["source"] = "Corrected. " + "".join(markdown["source"])
        corrected[relative] = json.dumps(data)
    new = derive(release, tmp_path / "new", "9.0.4", "- Chapter text corrected.", written=corrected)
    old = json.loads((release / MARKER).read_text())
    assert notebook_sources(ran.read_bytes()) == old["notebook_sources"][ran.relative_to(course).as_posix()]
    assert notebook_sources(wrote.read_bytes()) != old["notebook_sources"][wrote.relative_to(course).as_posix()]

    status, said = run_update(course, new)

    assert status == ATTENTION
    assert ran.read_bytes() == (new / ran.relative_to(course)).read_bytes()
    assert "# my note" in wrote.read_text(encoding="utf-8")
    beside = wrote.with_name(f"{wrote.stem}.release-9.0.4.ipynb")
    assert beside.read_bytes() == (new / wrote.relative_to(course)).read_bytes()
    assert beside.relative_to(course).as_posix() in said


def test_a_folder_from_before_versions_and_originals_is_updated_without_a_merge(release, tmp_path):
    """A marker with no version and no originals (releases made before them): the
    update goes ahead; a file both sides changed is kept, the release's copy beside it."""
    course = student_copy(release, tmp_path)
    marker = json.loads((course / MARKER).read_text())
    for key in ("version", "changes", "originals", "notebook_sources"):
        marker.pop(key)
    (course / ORIGINALS).unlink()
    (course / MARKER).write_text(json.dumps(marker))
    implement_first_stub(course / MOMENTUM)
    new = derive(release, tmp_path / "new", "9.0.5", "- Fixed.",
                 edits={MOMENTUM: (DOCSTRING_LINE, DOCSTRING_LINE.replace("line", "straight line"))})

    status, said = run_update(course, new)

    assert status == ATTENTION
    assert "# my own code" in (course / MOMENTUM).read_text()
    assert "straight line" in (course / "exercises/response/momentum_1d.release-9.0.5.py").read_text()
    assert (course / ORIGINALS).is_file() and "Fixed." in said


def test_merge_text_puts_both_sides_of_a_conflict_between_markers():
    base = "a\nb\nc\nd\n"
    clean, conflicts = merge_text(base, "A\nb\nc\nd\n", "a\nb\nc\nD\n", "release 2")
    assert (clean, conflicts) == ("A\nb\nc\nD\n", 0)
    text, conflicts = merge_text(base, "a\nmine\nc\nd", "a\ntheirs\nc\nd\n", "release 2")
    assert conflicts == 1
    assert text == "a\n<<<<<<< yours\nmine\n=======\ntheirs\n>>>>>>> release 2\nc\nd\n"


# Grading with the course's library files -----------------------------------------------------------
def test_grading_uses_the_courses_library_files_and_says_which_differed(tmp_path):
    """A submission whose library file is broken is graded with the course's (and told
    so); its exercise file and its own files are its own; without the course's library
    the same submission fails, so the course's files are what made it pass."""
    from grader.batch.grade import grade_submissions
    from grader.harness.run import load_spec

    repo = Path(__file__).resolve().parent.parent
    tests = [t for t in load_spec() if t.exercise == "momentum"]

    def submission(name: str, tamper: bool) -> Path:
        package = tmp_path / "class" / name / "exercises"
        shutil.copytree(repo / "exercises", package, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
        shutil.copy(repo / "solutions" / "response" / "momentum_1d.py", package / "response" / "momentum_1d.py")
        (package / "my_notes.py").write_text("NOTE = 'mine'\n", encoding="utf-8")
        if tamper:
            (package / "response" / "__init__.py").write_text('raise RuntimeError("my own library")\n')
        return package.parent

    honest, tampered = submission("honest", False), submission("tampered", True)
    rows = {r["id"]: r for r in grade_submissions([honest, tampered], tmp_path / "out", jobs=1, progress=False,
                                                  tests=tests, html=False, calibrate=False)}
    full = sum(t.points for t in tests)
    assert rows["honest"]["score"] == rows["tampered"]["score"] == full, rows
    said = rows["tampered"]["results"]["output"]
    assert "exercises/response/__init__.py" in said and "graded as the course released" in said
    assert rows["tampered"]["results"]["extra_data"]["library_replaced"] == ["response/__init__.py"]
    assert "library" not in rows["honest"]["results"]["output"].lower()
    assert "library_replaced" not in rows["honest"]["results"]["extra_data"]
    assert (tampered / "exercises" / "response" / "__init__.py").read_text().startswith("raise")  # not touched

    as_handed_in = grade_submissions([tampered], tmp_path / "plain", jobs=1, progress=False, tests=tests,
                                     html=False, calibrate=False, library=None)
    assert as_handed_in[0]["score"] == 0


def test_the_graded_copy_holds_the_submissions_exercises_and_the_courses_library_only(tmp_path):
    from grader.release.leak_scan import scan_for_solutions, solution_blocks
    from grader.batch.submissions import library_files, with_course_library

    repo = Path(__file__).resolve().parent.parent
    package = tmp_path / "exercises"
    shutil.copytree(repo / "exercises", package, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    (package / "vector.py").write_text("# Exercise file, says the student\n")
    (package / "body.py").unlink()
    library = library_files(repo / "exercises")
    assert "vector.py" in library and "response/momentum_1d.py" not in library and len(library) > 20
    with with_course_library(package, repo / "exercises", tmp_path) as (graded, replaced):
        assert replaced == ["body.py", "vector.py"]
        for relative, source in library.items():
            assert (graded / relative).read_bytes() == source.read_bytes()
        stub = "response/momentum_1d.py"
        assert (graded / stub).read_bytes() == (package / stub).read_bytes()
        assert scan_for_solutions(graded, solution_blocks(repo / "solutions")) == []
    assert not graded.exists()


def test_the_autograder_bundles_the_courses_exercises_package(tmp_path):
    from grader.release.gradescope import build_autograder_zip

    with zipfile.ZipFile(build_autograder_zip(out=tmp_path / "autograder.zip")) as archive:
        names = set(archive.namelist())
    repo = Path(__file__).resolve().parent.parent
    for path in (repo / "exercises").rglob("*.py"):
        if "__pycache__" not in path.parts:
            assert f"exercises/{path.relative_to(repo / 'exercises').as_posix()}" in names


def test_the_student_editions_library_files_are_the_courses(release):
    """What students get is what grading compares with: no student is told that an
    untouched library file differs."""
    from grader.batch.submissions import library_files

    repo = Path(__file__).resolve().parent.parent
    for relative, path in library_files(repo / "exercises").items():
        assert (release / "exercises" / relative).read_bytes() == path.read_bytes(), relative


def test_run_sh_update_takes_a_path_relative_to_where_it_was_called(release, tmp_path):
    """``bash course/run.sh update new`` run by bash from the folder above: run.sh finds
    the release there and hands over to the course's own ``grader update`` (the .venv is
    a stand-in: its python is this one, already set up, its ``grader`` the course's)."""
    course = student_copy(release, tmp_path)
    new = derive(release, tmp_path / "new", "9.0.6", "- Relative paths.",
                 edits={LIBRARY: (LIBRARY_LINE, LIBRARY_LINE.replace("-edge", "(-edge)"))})
    bin_folder = course / ".venv" / "bin"
    bin_folder.mkdir(parents=True)
    (course / ".venv" / "pyvenv.cfg").write_text("home = /usr/bin\n")
    (bin_folder / "python").symlink_to(sys.executable)
    stamp = hashlib.sha1((course / "pyproject.toml").read_bytes()).hexdigest()[:12]
    (course / ".venv" / f".installed-{stamp}").touch()
    entry = f"import sys; sys.path.insert(0, {str(course)!r}); from grader.cli import main; sys.exit(main())"
    (bin_folder / "grader").write_text(f'#!/bin/sh\nexec {sys.executable} -c "{entry}" "$@"\n')
    (bin_folder / "grader").chmod(0o755)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}

    usage = subprocess.run(["bash", "course/run.sh", "update"], cwd=tmp_path, env=env, capture_output=True, text=True)
    assert usage.returncode == 2 and "NEW_RELEASE" in usage.stderr
    done = subprocess.run(["bash", "course/run.sh", "update", "new"], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == DONE, done.stdout + done.stderr
    assert "to version 9.0.6" in done.stdout and "Relative paths." in done.stdout
    assert (course / LIBRARY).read_bytes() == (new / LIBRARY).read_bytes()


def test_the_grader_knows_a_library_file_by_the_header_the_generator_writes():
    from grader.batch.submissions import LIBRARY_HEADER as KNOWN
    from grader.release.exercises import EXERCISE_HEADER, LIBRARY_HEADER, header

    assert header("solutions/vector.py").startswith(KNOWN)
    assert not header("solutions/x.py", [("f", "sat")]).startswith(KNOWN)
    assert ("# " + LIBRARY_HEADER).startswith(KNOWN) and not ("# " + EXERCISE_HEADER).startswith(KNOWN)
