"""The student edition as a student receives it: a release's student folder, its README's
``bash run.sh setup`` into a fresh venv (pinned packages from the index or pip's cache), then
the course used: ``check``, ``bash run.sh lab`` with a chapter run through the server's
kernel (completion and the debugger asked for too), ``submit``.

The venv stays under :data:`VENV_LIMIT` after setup and after that use (Python caches what
it imports: PYTHONDONTWRITEBYTECODE is unset, as on a student's machine); both sizes are
printed.  Runs when ``COURSE_RELEASE_VENV=1``, which ``bash run.sh test`` sets.
"""
from __future__ import annotations

import json
import os
import re
import shutil
import socket
import subprocess
import time
import uuid
from pathlib import Path

import pytest

from grader.release.edition import build_release
from grader.student.venv_trim import CYTHON_HEADER

REPO = Path(__file__).resolve().parent.parent
#: The student venv's size target (decimal megabytes, as ``du -sB1`` counts the disk it takes).
VENV_LIMIT = 350_000_000
CHAPTER = "book/08_momentum.ipynb"

pytestmark = pytest.mark.skipif(os.environ.get("COURSE_RELEASE_VENV") != "1",
                                reason="downloads the pinned packages into a fresh venv: set COURSE_RELEASE_VENV=1")


def disk_bytes(folder: Path) -> int:
    return int(subprocess.run(["du", "-sB1", str(folder)], capture_output=True, text=True,
                              check=True).stdout.split()[0])


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def lab_session(student: Path, env: dict) -> dict:
    """``bash run.sh lab`` headless, driven by tests/student_lab_session.py in the student's venv."""
    port, token = free_port(), uuid.uuid4().hex
    log = (student.parent / "lab.log").open("w")
    lab = subprocess.Popen(["bash", "run.sh", "lab", "--no-browser", f"--port={port}", "--ServerApp.ip=127.0.0.1",
                            f"--IdentityProvider.token={token}"], cwd=student, env=env, stdout=log,
                           stderr=subprocess.STDOUT)
    try:
        session = subprocess.run([str(student / ".venv/bin/python"), str(REPO / "tests/student_lab_session.py"),
                                  str(port), token, CHAPTER], cwd=student, env=env, capture_output=True, text=True,
                                 timeout=900)
    finally:
        lab.terminate()
        lab.wait(60)
        log.close()
    assert session.returncode == 0, session.stdout + session.stderr + (student.parent / "lab.log").read_text()
    return json.loads(session.stdout)


def test_student_setup_in_fresh_venv(tmp_path):
    release = build_release(tmp_path / "out")
    student = tmp_path / "course"
    shutil.copytree(release.student, student)
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "VIRTUAL_ENV", "GRADER_CHECK_PACKAGE", "PYTHONDONTWRITEBYTECODE")}
    env["PATH"] = os.pathsep.join(p for p in env.get("PATH", "").split(os.pathsep)
                                  if not Path(p).resolve().is_relative_to(REPO))
    env.setdefault("PYTHON", shutil.which("python3", path=env["PATH"]) or "python3")
    venv = student / ".venv"

    start = time.perf_counter()
    result = subprocess.run(["bash", "run.sh", "setup"], cwd=student, env=env, capture_output=True, text=True,
                            timeout=3600)
    setup_seconds = time.perf_counter() - start
    assert result.returncode == 0, result.stdout + result.stderr
    start = time.perf_counter()
    again = subprocess.run(["bash", "run.sh", "setup"], cwd=student, env=env, capture_output=True, text=True,
                           timeout=600)
    print(f"bash run.sh setup: {setup_seconds:.0f} s in a fresh venv, {time.perf_counter() - start:.1f} s again")
    assert again.returncode == 0 and again.stdout == "", again.stdout + again.stderr
    after_setup = disk_bytes(venv)
    folder = int(subprocess.run(["du", "-sB1", "--exclude=.venv", "--exclude=__pycache__", "."], cwd=student,
                                capture_output=True, text=True, check=True).stdout.split()[0])
    python = venv / "bin/python"
    # Nothing compiled ahead (sympy is imported by no step of setup), no setuptools, and what
    # grader/student/venv_trim.py lists is gone: no library's test suite, no locale but English ...
    site = Path(subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
                               env=env, capture_output=True, text=True, check=True).stdout.strip())
    assert (site / "sympy").is_dir() and not list((site / "sympy").rglob("*.pyc"))
    assert not list(site.glob("setuptools*")), list(site.glob("setuptools*"))
    assert (site / "numpy/_core").is_dir() and not [p for p in site.rglob("tests") if p.is_dir()]
    locales = {p.stem for p in (site / "babel/locale-data").glob("*.dat")}
    assert {"root", "en"} <= locales and not [name for name in locales if name != "root" and name[:2] != "en"]
    assert not (site / "jupyterlab/galata").exists()
    assert not [p for p in site.rglob("*.c") if p.read_bytes().startswith(CYTHON_HEADER)]
    assert os.path.samefile(site / "jupyterlab/static/index.html", venv / "share/jupyter/lab/static/index.html")
    assert after_setup < VENV_LIMIT, f"the venv takes {after_setup / 1e6:.0f} MB after setup"

    result = subprocess.run([str(python), "-c", "import solutions"], cwd=student, env=env, capture_output=True,
                            text=True)
    assert result.returncode != 0 and "No module named 'solutions'" in result.stderr
    result = subprocess.run(["bash", "run.sh", "check", "momentum"], cwd=student, env=env, capture_output=True,
                            text=True, timeout=900)
    assert result.returncode == 1 and "not implemented yet" in result.stdout, result.stdout + result.stderr
    kernels = subprocess.run([str(venv / "bin/jupyter"), "kernelspec", "list", "--json"], env=env,
                             capture_output=True, text=True, check=True)
    spec = json.loads(kernels.stdout)["kernelspecs"]["collision-course"]
    assert Path(spec["resource_dir"]).resolve().is_relative_to(venv)
    assert "--log-level=ERROR" in spec["spec"]["argv"], spec   # no TCP warning on every kernel start
    # The chapters open trusted in JupyterLab: setup signed them for this user.
    trusted = subprocess.run([str(python), "-c", "import glob, nbformat\nfrom nbformat.sign import NotebookNotary\n"
                              "print(sorted(p for p in glob.glob('book/*.ipynb')\n"
                              "             if not NotebookNotary().check_signature(nbformat.read(p, 4))))"],
                             cwd=student, env=env, capture_output=True, text=True, check=True)
    assert trusted.stdout.strip() == "[]", trusted.stdout

    # JupyterLab as the student opens it: the page and its scripts, English, a chapter run in
    # the student's own kernel (its check cell runs the student's tests), completion, debugger.
    start = time.perf_counter()
    seen = lab_session(student, env)
    lab_seconds = time.perf_counter() - start
    assert seen["lab"]["status"] == 200 and seen["lab"]["scripts"], seen["lab"]
    assert set(seen["lab"]["scripts"].values()) == {200}, seen["lab"]
    assert list(seen["languages"]) == ["en"], seen["languages"]
    failed = [cell for cell in seen["cells"] if cell["status"] != "ok"]
    assert not failed, failed
    assert any(re.search(r"momentum: 0/\d+ points", cell["printed"]) for cell in seen["cells"]), seen["cells"]
    assert "linalg" in seen["completions"]["np.linal"], seen["completions"]
    assert "OrderedDict" in seen["completions"]["import collections\ncollections.Ordered"], seen["completions"]
    assert seen["debugger"] == {"initialize": True, "attach": True, "debugInfo": True}, seen["debugger"]

    result = subprocess.run(["bash", "run.sh", "submit"], cwd=student, env=env, capture_output=True, text=True,
                            timeout=600)
    assert result.returncode == 0, result.stdout + result.stderr
    assert list(student.glob("submission*.zip")), result.stdout
    after_use = disk_bytes(venv)
    print(f"JupyterLab session (chapter {CHAPTER}, completion, debugger): {lab_seconds:.0f} s, first cell "
          f"{seen['cells'][0]['seconds']} s; student venv {after_setup / 1e6:.0f} MB ({after_setup / 2**20:.0f} MiB) "
          f"after setup, {after_use / 1e6:.0f} MB ({after_use / 2**20:.0f} MiB) after a check, the chapter in "
          f"JupyterLab and a submit; student folder as released {folder / 1e6:.1f} MB")
    assert after_use < VENV_LIMIT, f"the venv takes {after_use / 1e6:.0f} MB once used"
