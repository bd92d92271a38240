"""The student edition's ``run.sh`` (``grader/release/files/run.sh``), run for real by bash.

Python, pip and Jupyter are stand-ins so that no package is downloaded: a fake
``python3`` makes a stub virtual environment whose ``bin/python`` runs this
interpreter except for ``-m pip`` and ``-m ipykernel`` (which print what pip prints and
exit with ``FAKE_PIP_STATUS``; ``-m grader.student.*``, the kernel spec's rewrite and the
venv's trim, does nothing), and whose ``bin/jupyter`` prints its arguments.  A fake
``id`` answers ``id -u`` with ``FAKE_UID``, so the root and non-root cases both run
whoever runs the tests.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
TEMPLATE = REPO / "grader" / "release" / "files" / "run.sh"
#: What setuptools prints on an editable install (the box students saw on every set-up).
PIP_CHATTER = "!!\n  ****  SetuptoolsDeprecationWarning: editable install  ****\n!!"

STUB_PYTHON = """#!/bin/sh
# A stub venv's python: pip and ipykernel faked, anything else run by the real interpreter.
echo "$*" >> "$(dirname "$0")/../calls.log"
if [ "$1" = -m ] && [ "$2" = pip ]; then printf '%s\\n' "$PIP_CHATTER"; exit "${FAKE_PIP_STATUS:-0}"; fi
if [ "$1" = -m ] && [ "$2" = ipykernel ]; then echo "Installed kernelspec"; exit 0; fi
case "$1 $2" in "-m grader.student."*) exit 0 ;; esac
exec REAL "$@"
"""
STUB_JUPYTER = """#!/bin/sh
printf 'JUPYTER'; for a in "$@"; do printf ' [%s]' "$a"; done; echo
"""
FAKE_SYSTEM_PYTHON = """#!/bin/sh
# python3 of the system: `-m venv DIR` makes a stub venv, anything else runs the real one.
if [ "$1" = -m ] && [ "$2" = venv ]; then
    mkdir -p "$3/bin"
    echo "home = /usr/bin" > "$3/pyvenv.cfg"
    cp "$STUBS/python" "$3/bin/python"
    cp "$STUBS/jupyter" "$3/bin/jupyter"
    chmod +x "$3/bin/python" "$3/bin/jupyter"
    exit 0
fi
exec REAL "$@"
"""
FAKE_ID = """#!/bin/sh
if [ "$1" = -u ]; then echo "$FAKE_UID"; else exec /usr/bin/id "$@"; fi
"""


def _script(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text.replace("REAL", sys.executable), encoding="utf-8")
    path.chmod(0o755)
    return path


@pytest.fixture
def course(tmp_path) -> Path:
    """A course folder holding the template run.sh, a pyproject.toml and a file of the student's."""
    folder = tmp_path / "course"
    folder.mkdir()
    shutil.copy2(TEMPLATE, folder / "run.sh")
    (folder / "pyproject.toml").write_text('[project]\nname = "course"\nversion = "1"\n', encoding="utf-8")
    (folder / "exercises").mkdir()
    (folder / "exercises" / "mine.py").write_text("ANSWER = 42\n", encoding="utf-8")
    stubs = tmp_path / "stubs"
    _script(stubs / "python", STUB_PYTHON)
    _script(stubs / "jupyter", STUB_JUPYTER)
    _script(tmp_path / "bin" / "python3", FAKE_SYSTEM_PYTHON)
    _script(tmp_path / "bin" / "id", FAKE_ID)
    return folder


def run(course: Path, *args: str, uid: int = 1000, pip_status: int = 0) -> subprocess.CompletedProcess:
    fakes = course.parent / "bin"
    env = {k: v for k, v in os.environ.items() if k not in ("VIRTUAL_ENV", "PYTHONPATH", "PYTHON")}
    env.update(PATH=f"{fakes}{os.pathsep}{env.get('PATH', '')}", FAKE_UID=str(uid), FAKE_PIP_STATUS=str(pip_status),
               PIP_CHATTER=PIP_CHATTER, STUBS=str(course.parent / "stubs"), PYTHON=str(fakes / "python3"))
    return subprocess.run(["bash", "run.sh", *args], cwd=course, env=env, capture_output=True, text=True, timeout=120)


def jupyter_arguments(result: subprocess.CompletedProcess) -> list[str]:
    line = next(line for line in result.stdout.splitlines() if line.startswith("JUPYTER"))
    return [part.strip("[]") for part in line.split(" ")[1:]]


def test_lab_as_root_starts_jupyter_with_allow_root_and_says_so(course):
    result = run(course, "lab", "--no-browser", uid=0)
    assert result.returncode == 0, result.stdout + result.stderr
    arguments = jupyter_arguments(result)
    assert arguments[0] == "lab" and "--allow-root" in arguments and "--no-browser" in arguments, arguments
    assert arguments[-1] == "book/intro.md"
    said = [line for line in result.stdout.splitlines() if "--allow-root" in line and not line.startswith("JUPYTER")]
    assert len(said) == 1 and "root" in said[0], result.stdout


def test_lab_as_another_user_does_not_allow_root(course):
    result = run(course, "lab", uid=1000)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "--allow-root" not in result.stdout + result.stderr
    assert jupyter_arguments(result)[0] == "lab"


def test_setup_keeps_pip_chatter_in_a_log_shown_only_on_failure(course):
    result = run(course, "setup")
    assert result.returncode == 0, result.stdout + result.stderr
    assert "Setuptools" not in result.stdout + result.stderr and "kernelspec" not in result.stdout
    assert "ready:" in result.stdout
    assert "SetuptoolsDeprecationWarning" in (course / ".venv" / "pip.log").read_text()
    again = run(course, "setup")
    assert again.returncode == 0 and again.stdout == again.stderr == "", again.stdout + again.stderr

    shutil.rmtree(course / ".venv")
    failed = run(course, "setup", pip_status=1)
    assert failed.returncode == 1
    assert "SetuptoolsDeprecationWarning" in failed.stderr and "failed" in failed.stderr, failed.stderr
    assert not list((course / ".venv").glob(".installed-*")), "a failed install must not be recorded as done"


def test_a_venv_whose_python_vanished_is_made_again_and_nothing_else_is_touched(course):
    assert run(course, "setup").returncode == 0
    python = course / ".venv" / "bin" / "python"
    python.unlink()
    python.symlink_to("/nonexistent/python3.9")  # the system Python the venv was made from, upgraded away
    (course / ".venv" / "lib-of-the-old-python").mkdir()
    result = run(course, "check")  # any command sets up first
    assert "no longer runs" in result.stdout and "python3.9" in result.stdout, result.stdout + result.stderr
    assert "apt" not in result.stdout + result.stderr
    assert python.is_file() and not python.is_symlink(), "the venv was not made again"
    assert not (course / ".venv" / "lib-of-the-old-python").exists()
    assert (course / "exercises" / "mine.py").read_text() == "ANSWER = 42\n"
    assert (course / "run.sh").is_file() and (course / "pyproject.toml").is_file()


def test_a_dot_venv_that_is_not_a_venv_is_left_alone(course):
    (course / ".venv" / "bin").mkdir(parents=True)
    (course / ".venv" / "notes.txt").write_text("mine\n", encoding="utf-8")
    result = run(course, "setup")
    assert result.returncode == 2 and "not a virtual environment" in result.stderr, result.stdout + result.stderr
    assert (course / ".venv" / "notes.txt").read_text() == "mine\n"
