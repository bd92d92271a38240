"""autograder.zip as Gradescope builds it: a fresh venv made from the archive's own
``requirements.txt`` (nothing of the instructor's environment), setup.sh's closing check,
then ``run_autograder`` on the reference, the stubs and a student's zip, compared test by
test with local grading (``grader grade`` in the instructor's venv).

The venv lives where any user can run it, as ``/autograder/venv`` does on Gradescope,
so that the plain fallback (a container that refuses bubblewrap) drops the student's
code to a user of its own, as it does there; ``run_autograder`` makes its grading folder
as root, 0700, as on Gradescope.  The first run downloads the pinned packages (then
pip's cache serves them: about 15 s).
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

import pytest

from grader.release.gradescope import build_autograder_zip
from grader.batch.grade import grade_submissions
from grader.sandbox.isolation import resolve_isolation
from grader.harness.run import load_spec
from tools import release_check

REPO = Path(__file__).resolve().parent.parent

pytestmark = pytest.mark.xdist_group("fresh-autograder")


def system_python() -> str:
    """A Python >= 3.11 of the system (not this venv's), as a fresh image has one."""
    for candidate in ("/usr/bin/python3", shutil.which("python3"), getattr(sys, "_base_executable", None)):
        if candidate and os.path.exists(candidate) and subprocess.run(
                [candidate, "-c", "import sys, venv, ensurepip; sys.exit(sys.version_info < (3, 11))"],
                capture_output=True).returncode == 0:
            return candidate
    pytest.skip("no system Python 3.11 or newer with venv and ensurepip")


@pytest.fixture(scope="module")
def image(tmp_path_factory):
    """The fake /autograder: source/ (the archive unpacked), run_autograder, and venv/
    made from source/requirements.txt alone."""
    root = Path(tempfile.mkdtemp(prefix="autograder-image-"))
    os.chmod(root, 0o755)   # /autograder: the venv's Python usable by anyone
    try:
        archive = build_autograder_zip(tmp_path_factory.mktemp("zip") / "autograder.zip")
        with zipfile.ZipFile(archive) as handle:
            handle.extractall(root / "source")
        shutil.copy(root / "source" / "run_autograder", root / "run_autograder")
        (root / "run_autograder").chmod(0o755)
        started = time.perf_counter()
        subprocess.run([system_python(), "-m", "venv", str(root / "venv")], check=True)
        python = root / "venv" / "bin" / "python"
        env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "VIRTUAL_ENV"))}
        installed = subprocess.run([str(python), "-m", "pip", "install", "--quiet", "--disable-pip-version-check",
                                    "-r", str(root / "source" / "requirements.txt")],
                                   env=env, capture_output=True, text=True, timeout=1200)
        assert installed.returncode == 0, installed.stdout + installed.stderr
        print(f"fresh venv from requirements.txt: {time.perf_counter() - started:.0f} s")
        yield root
    finally:
        shutil.rmtree(root, ignore_errors=True)


def run_autograder(root: Path, submission: Path, isolation: str = "auto") -> tuple[subprocess.CompletedProcess, dict]:
    """Put ``submission`` (a folder's contents, or a zip as Gradescope unpacks it) in place
    and run ``run_autograder`` with the image's Python; its result and results.json."""
    release_check.place(submission, root / "submission")
    shutil.rmtree(root / "results", ignore_errors=True)
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "VIRTUAL_ENV"))}
    env.update(AUTOGRADER_ROOT=str(root), AUTOGRADER_PYTHON=str(root / "venv" / "bin" / "python"),
               AUTOGRADER_ISOLATION=isolation)
    completed = subprocess.run(["bash", str(root / "run_autograder")], cwd=root, env=env, capture_output=True,
                               text=True, timeout=600)
    results = root / "results" / "results.json"
    data = json.loads(results.read_text()) if results.exists() else None
    return completed, data


@pytest.fixture(scope="module")
def submissions(tmp_path_factory) -> dict[str, Path]:
    """The reference, the stubs, and a student's zip written by `grader submit` (two
    exercise files solved, the rest stubs): the release-check's three."""
    return release_check.submissions(tmp_path_factory.mktemp("submissions"))


@pytest.fixture(scope="module")
def local_grades(submissions, tmp_path_factory) -> dict[str, dict]:
    """Each submission graded locally, as an instructor does with `grader grade`."""
    rows = grade_submissions(list(submissions.values()), tmp_path_factory.mktemp("local"), jobs=1,
                             progress=False, html=False)
    return {name: row["results"] for name, row in zip(submissions, rows)}


def test_setup_check_passes_in_the_fresh_venv(image):
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "VIRTUAL_ENV"))}
    env["PYTHONPATH"] = str(root_source := image / "source")
    completed = subprocess.run([str(image / "venv" / "bin" / "python"), "-m", "grader.release.gradescope", "check-setup"],
                               cwd=root_source, env=env, capture_output=True, text=True, timeout=300)
    assert completed.returncode == 0, completed.stdout + completed.stderr
    tests = load_spec()
    assert f"{len(tests)} tests, {sum(t.points for t in tests):g} points" in completed.stdout


@pytest.mark.parametrize("name", ["reference", "stubs", "student"])
def test_the_image_grades_like_local_grading(image, submissions, local_grades, name):
    completed, data = run_autograder(image, submissions[name])
    assert completed.returncode == 0 and data is not None, completed.stdout + completed.stderr
    local = local_grades[name]
    assert release_check.by_test(data) == release_check.by_test(local)
    assert data["score"] == local["score"] and data["max_score"] == local["max_score"]
    expected = {"reference": local["max_score"], "stubs": 0}.get(name)
    if expected is not None:
        assert data["score"] == expected
    else:
        assert 0 < data["score"] < data["max_score"]
    assert data["extra_data"]["isolation"] == resolve_isolation("auto")


def test_the_plain_fallback_gives_the_reference_full_marks(image, submissions):
    """The fallback of a container that refuses bubblewrap: the student's code runs as a
    user of its own (when the grader runs as root), its folder reachable by that user
    though the grading folder is root's and 0700."""
    completed, data = run_autograder(image, submissions["reference"], isolation="plain")
    assert completed.returncode == 0 and data is not None, completed.stdout + completed.stderr
    assert data["score"] == data["max_score"] > 0, [t for t in data["tests"] if t["status"] != "passed"][:3]
    assert data["extra_data"]["isolation"] == "plain"
    assert "isolation: plain" in completed.stdout
