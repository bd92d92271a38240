"""Gradescope's autograder.zip, run against a fake /autograder layout in a temporary folder.

Gradescope unpacks the archive into ``/autograder/source``, copies ``run_autograder`` to
``/autograder/run_autograder``, puts the submission in ``/autograder/submission`` and
reads ``/autograder/results/results.json``.  Here the root is a temporary folder
(``AUTOGRADER_ROOT``).  The grading tests run in a fresh venv built from the archive's
own ``requirements.txt`` and nothing else (``AUTOGRADER_PYTHON``): the instructor's
packages prove nothing about the image.  setup.sh's system part (apt, as root, in a
fresh image) is tried by ``bash run.sh release-check`` (tools/release_check.py).
"""
from __future__ import annotations

import json
import os
import shutil
import stat
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest

from grader.release.gradescope import build_autograder_zip, requirements
from grader.harness.run import load_spec

REPO = Path(__file__).resolve().parent.parent
IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc")


@pytest.fixture(scope="module")
def archive(tmp_path_factory) -> Path:
    return build_autograder_zip(tmp_path_factory.mktemp("zip") / "autograder.zip")


def fake_root(tmp_path: Path, archive: Path) -> Path:
    """The layout Gradescope builds: source/ (the archive), run_autograder, results/."""
    root = tmp_path / "autograder"
    (root / "source").mkdir(parents=True)
    with zipfile.ZipFile(archive) as handle:
        handle.extractall(root / "source")
    shutil.copy(root / "source" / "run_autograder", root / "run_autograder")
    (root / "run_autograder").chmod(0o755)
    (root / "submission").mkdir()
    return root


def run_autograder(root: Path) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env.update(AUTOGRADER_ROOT=str(root), AUTOGRADER_PYTHON=sys.executable)
    return subprocess.run(["bash", str(root / "run_autograder")], cwd=root, env=env, capture_output=True,
                          text=True, timeout=120)


def test_archive_holds_what_gradescope_needs_at_its_top(archive):
    with zipfile.ZipFile(archive) as handle:
        infos = {info.filename: info for info in handle.infolist()}
    for name in ("setup.sh", "run_autograder", "requirements.txt", "pyproject.toml", "grader/__init__.py",
                 "grader/batch/grade.py", "grader/batch/scheduler.py", "grader/batch/gradebook.py", "grader/sandbox/isolation.py", "grader/sandbox/worker.py", "grader/harness/plugin.py", "grader/tests/pytest.ini",
                 "grader/tests/conftest.py", "grader/tests/public/test_momentum.py", "grader/tests/hidden/test_grid.py",
                 "solutions/__init__.py"):
        assert name in infos, name
    for script in ("setup.sh", "run_autograder"):
        assert stat.S_IMODE(infos[script].external_attr >> 16) == 0o755
    assert not [n for n in infos if "__pycache__" in n or n.endswith(".pyc")]
    assert not [n for n in infos if n.startswith(("tests/", ".venv/", "book/", "tools/"))]
    assert not [n for n in infos if n.startswith("/") or ".." in n.split("/")]


def test_archive_is_the_same_from_the_same_sources(archive, tmp_path):
    assert build_autograder_zip(tmp_path / "again.zip").read_bytes() == archive.read_bytes()


def test_requirements_are_pins_of_pyproject_for_what_the_archive_imports(archive):
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    every_pin = [*project["dependencies"], *(r for extra in project["optional-dependencies"].values() for r in extra)]
    with zipfile.ZipFile(archive) as handle:
        lines = handle.read("requirements.txt").decode().splitlines()
    pinned = [line for line in lines if line and not line.startswith("#")]
    assert all("==" in p for p in pinned)
    direct = requirements()
    assert pinned[:len(direct)] == direct and set(direct) <= set(every_pin)
    names = {p.split("==")[0] for p in pinned}
    # The graded tests run under pytest and shrink with hypothesis; the reference is compiled.
    assert {"pytest", "hypothesis", "numpy", "numba"} <= names
    # What only the instructor or the book uses is not installed on Gradescope.
    assert not names & {"jupyter-book", "sphinx", "myst-nb", "box2d", "cosmic-ray", "scipy", "ipython"}


def test_archive_holds_only_what_grading_reaches(archive):
    with zipfile.ZipFile(archive) as handle:
        names = set(handle.namelist())
    for instructor_only in ("grader/release/edition.py", "grader/release/book.py", "grader/batch/similarity.py",
                            "grader/samples/example_class.py", "grader/release/files/run.sh"):
        assert instructor_only not in names


def test_scripts_are_valid_bash(archive, tmp_path):
    with zipfile.ZipFile(archive) as handle:
        handle.extractall(tmp_path)
    for script in ("setup.sh", "run_autograder"):
        assert subprocess.run(["bash", "-n", str(tmp_path / script)], capture_output=True).returncode == 0
    setup = (tmp_path / "setup.sh").read_text()
    assert "bubblewrap" in setup and "-venv" in setup and "requirements.txt" in setup


def test_run_autograder_explains_an_empty_submission(archive, tmp_path):
    root = fake_root(tmp_path, archive)
    (root / "submission" / "notes.md").write_text("sorry\n")
    completed = run_autograder(root)
    assert completed.returncode == 0, completed.stdout + completed.stderr
    data = json.loads((root / "results" / "results.json").read_text())
    assert data["score"] == 0
    assert "no exercises package" in data["output"] and "notes.md" in data["output"]


def test_run_autograder_without_python_says_so(archive, tmp_path):
    root = fake_root(tmp_path, archive)
    env = dict(os.environ, AUTOGRADER_ROOT=str(root), AUTOGRADER_PYTHON=str(tmp_path / "no-python"))
    completed = subprocess.run(["bash", str(root / "run_autograder")], env=env, capture_output=True, text=True)
    assert completed.returncode != 0 and "did setup.sh run?" in completed.stderr
    assert not (root / "results" / "results.json").exists()
