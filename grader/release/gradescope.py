"""Gradescope: the autograder archive, and the entry point it runs for each submission.

    grader gradescope-zip [--out autograder.zip]
    python -m grader.release.gradescope zip [--out autograder.zip]
    python -m grader.release.gradescope run                 (what run_autograder calls)

``autograder.zip`` holds, at its top (as Gradescope wants):

- ``setup.sh``: run once, as root, when Gradescope builds the image: installs Python
  3.11 or newer with ``venv``, bubblewrap, and the pinned packages of
  ``requirements.txt`` into ``$AUTOGRADER_ROOT/venv``;
- ``run_autograder``: run for every submission: grades ``$AUTOGRADER_ROOT/submission``
  exactly as ``grader grade`` does and writes ``$AUTOGRADER_ROOT/results/results.json``
  (a zip written by ``grader submit``, or its files as Gradescope unpacks an uploaded
  zip, is checked against its ``MANIFEST.json`` first, see :mod:`grader.batch.submissions`;
  an upload without one is graded as it is).  The grader reads the upload as root
  before any sandbox exists, so an upload holding a symbolic link anywhere (say
  ``exercises -> /autograder/source/solutions``), or over the caps on files and bytes,
  is refused with a reason before any of its files is read;
- ``grader/`` (with the whole test spec, hidden tests included), ``solutions/`` (the
  reference engine the checks compare with; the sandbox never mounts it),
  ``pyproject.toml`` and ``requirements.txt`` (pins taken from ``pyproject.toml``).

``AUTOGRADER_ROOT`` defaults to ``/autograder``; set it to try the archive on a fake
layout (``ROOT/source`` holding the unpacked archive, ``ROOT/submission``,
``ROOT/run_autograder``), with ``AUTOGRADER_PYTHON`` naming a Python that has the
requirements when ``setup.sh`` was not run there.

On Gradescope the student code runs under bubblewrap, as an unprivileged user, when
the container lets bubblewrap build a sandbox; otherwise it falls back to the plain
isolation (resource limits only) and says so in the autograder's output, which only
instructors see.  Before grading, ``run`` (as root) makes ``ROOT/source`` -- the grader,
the hidden tests and the reference solutions -- readable by root only, and
``ROOT/results`` writable by root only, so that even the plain fallback, which drops
student code to an unprivileged user when the venv's Python is usable by anyone, can
neither read the solutions nor write a results.json.
"""
from __future__ import annotations

import argparse
import os
import stat
import sys
import tempfile
import time
import zipfile
from pathlib import Path

from ..sandbox.isolation import isolation_words
from .module_graph import files_reached, ignored, third_party_modules
from .pins import locked, pins_for_modules
from ..reports.results import RESULTS_NAME, write_results
from ..harness.results_model import points
from ..harness.spec import SpecError
from ..student.manifest import byte_size
from ..errors import GradingError

GRADER_DIR = Path(__file__).resolve().parents[1]
REPO_ROOT = GRADER_DIR.parent
ZIP_NAME = "autograder.zip"
DEFAULT_ROOT = "/autograder"
ROOT_VARIABLE = "AUTOGRADER_ROOT"
PYTHON_VARIABLE = "AUTOGRADER_PYTHON"
#: Where grading starts (``run_autograder`` runs this module), relative to ``grader/``;
#: the archive holds the grader files it reaches (:mod:`grader.release.module_graph`).
ENTRY_POINTS = ("release/gradescope.py",)
#: Folders of ``grader/`` shipped whole: the graded tests, public and hidden.
GRADER_FOLDERS = ("tests",)
#: Folders of the repository that go into the archive, whole (less caches).  ``exercises``:
#: the library files every submission is graded with (grader.batch.grade.COURSE_LIBRARY).
BUNDLED_FOLDERS = ("solutions", "exercises")
BUNDLED_FILES = ("pyproject.toml",)
#: Modules the bundled code imports only where they are already loaded, never while
#: grading: not installed in the image.
OPTIONAL_MODULES = {"IPython": "grader/student/check.py shows its table as HTML inside a notebook"}
FIXED_TIME = (2020, 1, 1, 0, 0, 0)  # every member's date: the same sources, the same archive

SETUP_SH = r"""#!/usr/bin/env bash
# Gradescope runs this once, as root, while it builds the autograder image.
# It installs Python >= 3.11 with venv, bubblewrap (the sandbox of student code) and
# the pinned packages of requirements.txt into $AUTOGRADER_ROOT/venv.
set -euo pipefail
export DEBIAN_FRONTEND=noninteractive
ROOT="${AUTOGRADER_ROOT:-/autograder}"
SOURCE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"

apt-get update
apt-get install -y --no-install-recommends ca-certificates python3 python3-venv python3-pip bubblewrap util-linux

# The grader needs Python 3.11 or newer (tomllib; numpy's wheels).  Ubuntu 22.04 ships
# 3.10 as python3, with python3.11 as a separate package.
PYTHON=""
for candidate in python3.13 python3.12 python3.11 python3; do
    if command -v "$candidate" >/dev/null 2>&1 \
            && "$candidate" -c 'import sys; sys.exit(0 if sys.version_info >= (3, 11) else 1)'; then
        PYTHON="$candidate"
        break
    fi
done
if [ -z "$PYTHON" ]; then
    apt-get install -y --no-install-recommends python3.11 python3.11-venv
    PYTHON=python3.11
fi
if ! "$PYTHON" -c 'import ensurepip' >/dev/null 2>&1; then
    apt-get install -y --no-install-recommends "$(basename "$PYTHON")-venv"
fi

"$PYTHON" -m venv "$ROOT/venv"
"$ROOT/venv/bin/python" -m pip install --no-cache-dir --upgrade pip
"$ROOT/venv/bin/python" -m pip install --no-cache-dir -r "$SOURCE/requirements.txt"

# Fail the build now, not at the first submission, if a package the grader imports is
# missing or the grader cannot load its tests.
cd "$SOURCE"
PYTHONPATH="$SOURCE" "$ROOT/venv/bin/python" -m grader.release.gradescope check-setup
"""

RUN_AUTOGRADER = r"""#!/usr/bin/env bash
# Gradescope runs this for every submission (as root, from $AUTOGRADER_ROOT).
# It grades $AUTOGRADER_ROOT/submission and writes $AUTOGRADER_ROOT/results/results.json.
set -uo pipefail
ROOT="${AUTOGRADER_ROOT:-/autograder}"
export AUTOGRADER_ROOT="$ROOT"
SOURCE="$ROOT/source"
PYTHON="${AUTOGRADER_PYTHON:-$ROOT/venv/bin/python}"
if [ ! -x "$PYTHON" ]; then
    echo "run_autograder: no Python at $PYTHON (did setup.sh run?)" >&2
    exit 1
fi
mkdir -p "$ROOT/results"
cd "$SOURCE"
export PYTHONPATH="$SOURCE" PYTHONDONTWRITEBYTECODE=1 MPLBACKEND=Agg
# AUTOGRADER_ISOLATION=plain tries the fallback of a container that refuses bubblewrap.
exec "$PYTHON" -m grader.release.gradescope run --isolation "${AUTOGRADER_ISOLATION:-auto}"
"""


def grader_files(grader_dir: Path = GRADER_DIR) -> list[Path]:
    """The files of ``grader/`` the archive holds: what :data:`ENTRY_POINTS` reach, and
    :data:`GRADER_FOLDERS` whole."""
    grader_dir = Path(grader_dir)
    start = [(grader_dir / name, "entry point") for name in ENTRY_POINTS]
    for folder in GRADER_FOLDERS:
        start += [(path, "graded tests") for path in sorted((grader_dir / folder).rglob("*"))
                  if path.is_file() and not path.is_symlink() and not _hidden(path.relative_to(grader_dir))]
    # release/files/ holds templates of the student edition, not files the grader reads.
    reached = files_reached(grader_dir, start, excluded=lambda relative: relative.startswith("release/files/"))
    return [grader_dir / relative for relative in reached]


def _hidden(relative: Path) -> bool:
    """Caches, compiled files and hidden files (editor swap files, locks)."""
    return ignored(relative) or any(part.startswith(".") for part in relative.parts)


def bundled_files(repo_root: Path = REPO_ROOT) -> list[tuple[str, Path]]:
    """(name in the archive, file) of every grader and reference file, sorted."""
    files = [(path.relative_to(repo_root).as_posix(), path) for path in grader_files(repo_root / "grader")]
    for folder in BUNDLED_FOLDERS:
        for path in sorted((repo_root / folder).rglob("*")):
            if path.is_file() and not path.is_symlink() and not _hidden(path.relative_to(repo_root)):
                files.append((path.relative_to(repo_root).as_posix(), path))
    for name in BUNDLED_FILES:
        files.append((name, repo_root / name))
    return sorted(files)


def imported_packages(files: list[tuple[str, Path]]) -> dict[str, str]:
    """{third-party top-level module: the first bundled file importing it}, less
    :data:`OPTIONAL_MODULES`."""
    found = third_party_modules((name, path) for name, path in files if name.endswith(".py"))
    return {module: where for module, where in found.items() if module not in OPTIONAL_MODULES}


def requirements(repo_root: Path = REPO_ROOT) -> list[str]:
    """The pins of ``pyproject.toml`` that provide what the bundled code imports (pytest,
    numpy, numba ...), in its order."""
    return pins_for_modules(imported_packages(bundled_files(repo_root)), repo_root / "pyproject.toml")


def requirements_text(repo_root: Path = REPO_ROOT) -> str:
    """``requirements.txt``: those pins, then what they pulled in here (a lock: the image
    gets the versions the grader was tested with)."""
    direct = requirements(repo_root)
    return "\n".join([
        "# Written by `grader gradescope-zip`: the pins of the course's pyproject.toml that",
        "# provide what the grader and the reference engine import,",
        *direct,
        "# and what those pulled in, at the versions the grader was tested with.",
        *locked(direct), ""])


def _add(archive: zipfile.ZipFile, name: str, data: bytes, executable: bool = False) -> None:
    info = zipfile.ZipInfo(name, date_time=FIXED_TIME)
    info.external_attr = ((0o100755 if executable else 0o100644) & 0xFFFF) << 16
    info.create_system = 3
    info.compress_type = zipfile.ZIP_DEFLATED
    archive.writestr(info, data)


def build_autograder_zip(out: str | os.PathLike = ZIP_NAME, repo_root: Path = REPO_ROOT) -> Path:
    """Write Gradescope's ``autograder.zip`` to ``out`` (atomically) and return its path."""
    out = Path(out)
    if out.is_dir():
        out = out / ZIP_NAME
    out.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(prefix=f".{out.name}.", suffix=".tmp", dir=out.parent)
    os.close(handle)
    try:
        with zipfile.ZipFile(temporary, "w") as archive:
            _add(archive, "setup.sh", SETUP_SH.encode(), executable=True)
            _add(archive, "run_autograder", RUN_AUTOGRADER.encode(), executable=True)
            _add(archive, "requirements.txt", requirements_text(repo_root).encode())
            for name, path in bundled_files(repo_root):
                _add(archive, name, path.read_bytes())
        os.chmod(temporary, 0o644)
        os.replace(temporary, out)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise
    return out


def autograder_root() -> Path:
    """``$AUTOGRADER_ROOT``, or Gradescope's ``/autograder``."""
    return Path(os.environ.get(ROOT_VARIABLE) or DEFAULT_ROOT)


def protect_source(root: Path) -> bool:
    """Make ``root/source`` readable by root only and ``root/results`` writable by root
    only; True when done (the grader runs as root), False otherwise (nothing changed).

    ``source`` itself becomes 0700 (nobody else can even look inside) and every file
    and folder under it loses its group and other permissions, in case one is reached
    another way (a hard link, a bind mount).  Symbolic links are left alone.
    """
    if os.geteuid() != 0:
        return False
    source = root / "source"
    if source.is_dir() and not source.is_symlink():
        for folder, dirs, files in os.walk(source):
            for name in dirs + files:
                path = os.path.join(folder, name)
                info = os.lstat(path)
                if not stat.S_ISLNK(info.st_mode):
                    os.chmod(path, stat.S_IMODE(info.st_mode) & ~0o077)
        os.chown(source, 0, 0)
        os.chmod(source, 0o700)
    results = root / "results"
    results.mkdir(exist_ok=True)
    if not results.is_symlink():
        os.chown(results, 0, 0)
        os.chmod(results, 0o755)
    return True


def run_autograder(root: str | os.PathLike | None = None, isolation: str = "auto",
                   per_submission_seconds: float | None = None) -> int:
    """Grade ``ROOT/submission`` and write ``ROOT/results/results.json``; the exit status.

    What it prints goes to Gradescope's autograder output, which only instructors see.
    When the grader itself fails, no results.json is written (Gradescope then tells the
    student the autograder failed) and the reason is printed.
    """
    from ..batch.grade import DEFAULT_PER_SUBMISSION_SECONDS, grade_submissions  # deferred: the grading machinery, not needed to build the archive

    root = Path(root) if root is not None else autograder_root()
    submission = root / "submission"
    results_path = root / "results" / RESULTS_NAME
    if not submission.is_dir():
        print(f"run_autograder: no submission folder at {submission}", flush=True)
        return 1
    if not protect_source(root):
        print("run_autograder: not running as root: the solutions and hidden tests in "
              f"{root / 'source'} keep their permissions", flush=True)
    started = time.perf_counter()
    try:
        with tempfile.TemporaryDirectory(prefix="grading-") as out:
            rows = grade_submissions([submission], out, jobs=1, regrade=True, isolation=isolation,
                                     per_submission_seconds=per_submission_seconds or DEFAULT_PER_SUBMISSION_SECONDS,
                                     progress=False, html=False)
    except (GradingError, SpecError) as exc:
        print(f"run_autograder: the grader could not run: {exc}", flush=True)
        return 1
    row = rows[0]
    if row["results"] is None:
        print(f"run_autograder: the grader failed: {row['message']}", flush=True)
        return 1
    data = row["results"]
    write_results(data, results_path)
    print(f"{row['state']}: {points(data['score'])} / {points(data['max_score'])} points in "
          f"{time.perf_counter() - started:.1f} s")
    isolation = (data.get("extra_data") or {}).get("isolation")
    if isolation:
        print(isolation_words(isolation))
    if row["state"] == "refused":
        print(data["output"])
    for test in data["tests"]:
        extra = test.get("extra_data") or {}
        print(f"  {test['score']:>5g} / {test['max_score']:<4g} {extra.get('status', test['status']):16s} "
              f"{extra.get('test', test['name'])} ({test['visibility']})")
    print(f"results: {results_path}", flush=True)
    return 0


def check_setup(source: Path = REPO_ROOT) -> int:
    """What ``setup.sh`` ends with: import every package the bundled code imports and
    load the graded tests; 0 when all is there, else 1 with what is missing."""
    import importlib

    from ..harness.run import load_spec  # deferred: pytest, heavy to import

    files = [(path.relative_to(source).as_posix(), path) for path in sorted(source.rglob("*.py"))
             if path.is_file() and not _hidden(path.relative_to(source))
             and path.relative_to(source).parts[0] in ("grader", *BUNDLED_FOLDERS)]
    missing = []
    for module, where in imported_packages(files).items():
        try:
            importlib.import_module(module)
        except ImportError as exc:
            missing.append(f"{module} (imported by {where}): {exc}")
    if missing:
        print("check-setup: these packages cannot be imported; is requirements.txt complete?\n  "
              + "\n  ".join(missing), flush=True)
        return 1
    try:
        tests = load_spec()
    except SpecError as exc:
        print(f"check-setup: the graded tests cannot be loaded: {exc}", flush=True)
        return 1
    print(f"check-setup: {len(files)} modules' imports found; {len(tests)} tests, "
          f"{points(sum(t.points for t in tests))} points", flush=True)
    return 0


# Command line -------------------------------------------------------------------------------
def add_gradescope_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``grader gradescope-zip``."""
    parser.add_argument("--out", default=ZIP_NAME, metavar="FILE",
                        help="where to write the archive (default: %(default)s; a folder gets autograder.zip)")


def main_gradescope_zip(args: argparse.Namespace) -> int:
    """Run ``grader gradescope-zip``."""
    path = build_autograder_zip(args.out)
    with zipfile.ZipFile(path) as archive:
        count = len(archive.infolist())
    print(f"wrote {path} ({count} files, {byte_size(path.stat().st_size)}): upload it as the "
          "autograder of a Gradescope programming assignment")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m grader.release.gradescope", description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    run = commands.add_parser("run", help="grade $AUTOGRADER_ROOT/submission (what run_autograder calls)")
    run.add_argument("--root", default=None, help=f"autograder root (default: ${ROOT_VARIABLE} or {DEFAULT_ROOT})")
    run.add_argument("--isolation", choices=("auto", "bwrap", "plain"), default="auto")
    run.add_argument("--timeout-submission", type=float, default=None, metavar="SECONDS")
    add_gradescope_arguments(commands.add_parser("zip", help="build autograder.zip"))
    commands.add_parser("check-setup", help="import what the grader needs and load its tests (setup.sh's last step)")
    args = parser.parse_args(argv)
    if args.command == "zip":
        return main_gradescope_zip(args)
    if args.command == "check-setup":
        return check_setup()
    return run_autograder(args.root, args.isolation, args.timeout_submission)


if __name__ == "__main__":
    sys.exit(main())
