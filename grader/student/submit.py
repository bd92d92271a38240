"""``grader submit``: the zip a student hands in, with a manifest of what is in it.

In a shell, from the course folder (the one holding ``exercises/``)::

    grader submit                          # submission-<user>-<YYYYmmdd-HHMMSS>.zip here
    grader submit --name "Ada Lovelace" --check --out handin/

In a notebook cell::

    from grader import submit
    submit(name="Ada Lovelace", check=True)

The package is found as ``grader check`` finds it (:func:`grader.student.check.find_package`:
``--package``, ``$GRADER_CHECK_PACKAGE``, ``exercises/`` here or in a parent folder).
The zip holds ``exercises/`` (whatever the package folder is called) and, at its top,
``MANIFEST.json``::

    {"format": "collision-course-submission", "format_version": 1,
     "course": "collision-course", "created": "2025-03-01T14:05:09+01:00",
     "student": "Ada Lovelace", "package": "exercises", "file_count": 33, "total_bytes": 371204,
     "files": [{"path": "exercises/__init__.py", "size": 120, "sha256": "9f86d0..."}, ...]}

``grader grade`` and the Gradescope autograder check every file against it
(:func:`grader.batch.submissions.verify_manifest`) and refuse a zip changed after it was
written, saying which file.

Only regular files with the suffixes of :data:`ALLOWED_SUFFIXES` go in; ``__pycache__``,
``.pyc`` files and hidden files and folders (names starting with ``.``, such as the
generator's ``.generated.json`` record or ``.ipynb_checkpoints``) are left out quietly;
files with other suffixes are left out too, and the summary names them.  A symbolic link anywhere in the
package is refused, naming it: copy the file in its place.  The number of files and
their bytes are capped by the limits the grader applies to archives
(:data:`grader.batch.submissions.MAX_FILES`, :data:`grader.batch.submissions.MAX_TOTAL_BYTES`).
Each file is read once, and the bytes hashed are the bytes zipped.
"""
from __future__ import annotations

import argparse
import getpass
import hashlib
import json
import os
import stat
import sys
import tempfile
import time
import zipfile
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path

from ..harness.package import PackageNotFound, find_package
from .check import CheckError, command_name, run_check
from .manifest import (COURSE_NAME, byte_size, IGNORED_NAMES, MANIFEST_FORMAT, MANIFEST_NAME, MANIFEST_VERSION, MAX_FILES,
                          MAX_TOTAL_BYTES, submission_id)

#: Suffixes of the files that go into the zip.
ALLOWED_SUFFIXES = (".py", ".md", ".txt", ".json")
#: Folder name of the package inside the zip.
PACKAGE_NAME = "exercises"
#: Files named in a "left out" note, at most.
SHOWN_LEFT_OUT = 8


class SubmitError(ValueError):
    """The zip cannot be written; the message says why and what to do."""


@dataclass
class SubmitResult:
    """What ``submit`` wrote: the zip, its manifest, and the public checks' score if run."""

    path: Path
    manifest: dict
    left_out: list[str] = field(default_factory=list)
    check_score: float | None = None
    check_max_score: float | None = None

    @property
    def file_count(self) -> int:
        return len(self.manifest["files"])

    @property
    def total_bytes(self) -> int:
        return int(self.manifest["total_bytes"])

    def summary(self) -> str:
        """One line: what went in, and what to do with it."""
        count = len(self.left_out)
        left = f"; {count} other file{'s' if count != 1 else ''} left out" if count else ""
        who = f" for {self.manifest['student']}" if self.manifest.get("student") else ""
        return (f"{self.file_count} files of exercises/ ({byte_size(self.total_bytes)}) with their sha256 in "
                f"{MANIFEST_NAME}{who}{left}: hand in this zip as it is")

    def __repr__(self) -> str:
        return f"<SubmitResult {self.path}: {self.file_count} files, {byte_size(self.total_bytes)}>"


def _listed(names: list[str]) -> str:
    shown = ", ".join(names[:SHOWN_LEFT_OUT])
    return shown + (f" and {len(names) - SHOWN_LEFT_OUT} more" if len(names) > SHOWN_LEFT_OUT else "")


def collect_files(package: str | os.PathLike) -> tuple[list[tuple[str, Path]], list[str]]:
    """The files of ``package`` that go into the zip, as (path inside the package, file),
    sorted; and the relative paths left out.  Raises SubmitError for a symbolic link or a
    special file, or when there are too many files or bytes."""
    package = Path(package)
    chosen: list[tuple[str, Path]] = []
    left_out: list[str] = []
    links: list[str] = []
    total = 0
    for root, dirs, files in os.walk(package):
        here = Path(root)
        keep = []
        for name in sorted(dirs + files):
            full = here / name
            relative = full.relative_to(package).as_posix()
            mode = os.lstat(full).st_mode
            if stat.S_ISLNK(mode):
                links.append(f"{package.name}/{relative}")
            elif stat.S_ISDIR(mode):
                if name in IGNORED_NAMES:
                    continue
                if not name.startswith("."):
                    keep.append(name)
            elif name in IGNORED_NAMES or name.endswith(".pyc") or name.startswith("."):
                continue
            elif Path(name).suffix.lower() not in ALLOWED_SUFFIXES:
                left_out.append(relative)
            elif not stat.S_ISREG(mode):
                raise SubmitError(f"{package.name}/{relative} is not a regular file (a pipe or a device?): "
                                  "remove it, then submit again")
            else:
                chosen.append((relative, full))
                total += os.lstat(full).st_size
        dirs[:] = keep
    if links:
        raise SubmitError(f"{package.name}/ holds symbolic links, which a submission may not: "
                          f"{_listed(links)}. Replace each by a copy of the "
                          "file it points to (or delete it), then submit again")
    if len(chosen) + 1 > MAX_FILES:
        raise SubmitError(f"{package.name}/ holds {len(chosen)} files to hand in; at most {MAX_FILES - 1} are accepted. "
                          "Remove files you did not write for the course, then submit again")
    if total > MAX_TOTAL_BYTES:
        raise SubmitError(f"the files to hand in add up to {byte_size(total)}; at most {byte_size(MAX_TOTAL_BYTES)} are "
                          "accepted. Remove large data files, then submit again")
    if not chosen:
        raise SubmitError(f"{package} holds no file to hand in (.py, .md, .txt or .json)")
    return sorted(chosen), sorted(left_out)


def zip_name(name: str | None = None, when: time.struct_time | None = None) -> str:
    """``submission-<name or user>-<YYYYmmdd-HHMMSS>.zip``, the name made safe for a file."""
    who = name
    if not who:
        try:
            who = getpass.getuser()
        except Exception:  # no user name in this environment
            who = "student"
    stamp = time.strftime("%Y%m%d-%H%M%S", when or time.localtime())
    return f"submission-{submission_id(who)}-{stamp}.zip"


def _target(out: str | os.PathLike | None, name: str | None, when: time.struct_time) -> Path:
    if out is not None and str(out).lower().endswith(".zip"):
        return Path(out).expanduser()
    folder = Path(out).expanduser() if out is not None else Path.cwd()
    if folder.exists() and not folder.is_dir():
        raise SubmitError(f"--out {folder} is a file, not a folder (give a folder, or a path ending in .zip)")
    return folder / zip_name(name, when)


def _member(name: str, when: time.struct_time) -> zipfile.ZipInfo:
    info = zipfile.ZipInfo(name, date_time=tuple(max(v, d) for v, d in zip(when[:6], (1980, 1, 1, 0, 0, 0))))
    info.create_system = 3
    info.external_attr = (stat.S_IFREG | 0o644) << 16
    info.compress_type = zipfile.ZIP_DEFLATED
    return info


def write_submission(package: str | os.PathLike, out: str | os.PathLike | None = None,
                     name: str | None = None) -> SubmitResult:
    """Write the hand-in zip of ``package`` (the package folder itself) and return what was written.

    Parameters
    ----------
    package : path
        The student's package folder (the one holding ``__init__.py``).
    out : path, optional
        A folder for the zip (default: the current folder), or the zip's own path
        (ending in ``.zip``).
    name : str, optional
        The student's name or id: written into the manifest and the zip's name.
    """
    package = Path(package)
    now = datetime.now().astimezone()
    when = now.timetuple()
    files, left_out = collect_files(package)
    target = _target(out, name, when)
    target.parent.mkdir(parents=True, exist_ok=True)
    entries = []
    handle, temporary = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    os.close(handle)
    try:
        with zipfile.ZipFile(temporary, "w") as archive:
            for relative, path in files:
                data = path.read_bytes()  # read once: the bytes hashed are the bytes zipped
                member = f"{PACKAGE_NAME}/{relative}"
                entries.append({"path": member, "size": len(data), "sha256": hashlib.sha256(data).hexdigest()})
                archive.writestr(_member(member, when), data)
            total = sum(e["size"] for e in entries)
            if total > MAX_TOTAL_BYTES:  # a file grew while it was being zipped
                raise SubmitError(f"the files to hand in add up to {byte_size(total)}; at most "
                                  f"{byte_size(MAX_TOTAL_BYTES)} are accepted")
            manifest = {
                "format": MANIFEST_FORMAT,
                "format_version": MANIFEST_VERSION,
                "course": COURSE_NAME,
                "created": now.isoformat(timespec="seconds"),
                "student": name or None,
                "package": PACKAGE_NAME,
                "file_count": len(entries),
                "total_bytes": total,
                "files": entries,
            }
            archive.writestr(_member(MANIFEST_NAME, when), json.dumps(manifest, indent=1) + "\n")
        os.chmod(temporary, 0o644)
        os.replace(temporary, target)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise
    return SubmitResult(target, manifest, left_out)


def _shown(path: Path) -> str:
    try:
        return str(path.resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(path)


def submit(name: str | None = None, package: str | os.PathLike | None = None, out: str | os.PathLike | None = None,
           check: bool = False, show: bool = True) -> SubmitResult:
    """Write the zip to hand in: your ``exercises`` package and a manifest of its files.

    Parameters
    ----------
    name : str, optional
        Your name or student id: written into the manifest and the zip's name
        (default: the zip is named after your user name, and the manifest names nobody).
    package : str or Path, optional
        The package to hand in (default: your ``exercises`` folder, found as
        ``check`` finds it).
    out : str or Path, optional
        Folder for the zip (default: the current folder), or the zip's own path.
    check : bool
        Run the public tests first and say the score (the zip is written either way).
    show : bool
        Print where the zip is and a one-line summary.

    Returns
    -------
    SubmitResult
        ``.path`` (the zip), ``.manifest``, ``.left_out`` and, with ``check``,
        ``.check_score`` and ``.check_max_score``.

    Raises
    ------
    grader.student.check.CheckError
        When no package is found.
    SubmitError
        For a symbolic link or a special file in the package, or too many files or bytes.
    """
    folder = find_package(package)
    score = maximum = None
    if check:
        score, maximum = _run_checks(folder, show)
    result = write_submission(folder, out, name)
    result.check_score, result.check_max_score = score, maximum
    if show:
        print(f"wrote {_shown(result.path)}")
        print(result.summary())
        if result.left_out:
            print(f"left out (only .py, .md, .txt and .json files go in): "
                  f"{_listed(result.left_out)}")
    return result


def _run_checks(folder: Path, show: bool) -> tuple[float | None, float | None]:
    """Run every public test on ``folder``; (score, max score), or (None, None) if they could not run."""
    if show:
        print("running the public tests first ...", flush=True)
    try:
        report = run_check(None, folder)
    except Exception as exc:
        if os.environ.get("GRADER_DEBUG"):
            raise
        if show:
            print(f"the public tests could not run ({type(exc).__name__}: {exc}); the zip is written anyway",
                  flush=True)
        return None, None
    if show:
        print(f"public tests: {report.summary()}", flush=True)
    return report.score, report.max_score


# Shell command ----------------------------------------------------------------------------
def add_submit_arguments(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """Options of ``grader submit``."""
    parser.add_argument("--name", default=None, metavar="NAME",
                        help="your name or student id, written into the manifest and the zip's name")
    parser.add_argument("--out", default=None, metavar="PATH",
                        help="folder for the zip (default: the current folder), or the zip's path (*.zip)")
    parser.add_argument("--package", default=None, metavar="PATH",
                        help="the package to hand in (default: ./exercises, as `grader check` finds it)")
    parser.add_argument("--check", action="store_true", help="run the public tests first and say the score")
    return parser


def main_submit(args: argparse.Namespace) -> int:
    """Run ``grader submit``: 0 when the zip is written, 2 when it cannot be."""
    try:
        submit(name=args.name, package=args.package, out=args.out, check=args.check)
    except (CheckError, PackageNotFound, SubmitError) as exc:
        print(f"grader submit: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"grader submit: could not write the zip: {exc}", file=sys.stderr)
        return 2
    return 0


def main(argv: list[str] | None = None) -> int:
    """``python -m grader.student.submit [--name NAME] [--out PATH] [--package PATH] [--check]``."""
    parser = add_submit_arguments(argparse.ArgumentParser(
        prog=command_name("submit"), description="Write the zip to hand in: your exercises and a manifest of their hashes."))
    return main_submit(parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
