"""Submissions: find them, name them, open them safely, and fingerprint them.

A submission is a folder or a zip archive holding a copy of the ``exercises`` package
(at its top, one folder down, or as the archive's top itself).  Each gets

- an **id**, its file or folder name made safe for a folder name (``Alice Smith.zip``
  becomes ``Alice_Smith``), the name of its folder in the output;
- a **fingerprint**, the sha256 of what was handed in, so that a rerun can skip what is
  already graded;
- a folder to grade: the folder itself, or a fresh temporary copy of the archive's
  regular files.

Submissions are untrusted, and the grader reads them as root (on Gradescope, and
when it runs bubblewrap), before any sandbox exists.  So nothing is ever read through
a **symbolic link**: a link could name the reference solutions, another student's
folder or zip, or a device.  :func:`scan_folder` walks a folder with ``lstat`` only
and refuses the whole submission (with the link's name) at the first link it finds,
at any depth, and at the first special file (a FIFO, a socket, a device); a path given
on the command line (or Gradescope's ``submission`` folder) that is itself a link is
refused too -- it is not resolved: ``class/alice -> bob`` would grade Bob's work as
Alice's, and ``submission/exercises -> /autograder/source/solutions`` the reference
(only the folders above the last component are resolved: they are the instructor's).
Before anything is read, :func:`scan_folder` also caps the folder's entries
(``MAX_FILES``) and bytes (``MAX_TOTAL_BYTES``), counting each file's apparent size
and its allocated blocks, whichever is larger, so a 2 GiB sparse file is refused
from its ``stat`` alone; an archive file is capped at ``MAX_ARCHIVE_BYTES`` the same
way.  Files are then read with ``O_NOFOLLOW`` and never past the size measured
(:func:`_file_digest`).  :func:`opened` grades a folder where it is once scanned
(nothing writes to it while it is graded; the sandbox copies the package's regular
files only) and an archive from a fresh temporary copy of its regular files.

Archives are untrusted.  :func:`safe_extract` uses the standard library's
:mod:`zipfile` only, checks every member before it writes anything, and refuses the
whole archive (raising :class:`SubmissionRefused` with a message for the student) when
a member has an absolute path, a ``..`` component, a drive letter, is a symbolic link
or another special file, is encrypted, or when the archive holds too many files or
expands to too many bytes (a zip bomb: the bytes are counted as they are written, not
taken from the headers).  Nothing outside the destination folder is ever written.

Hand-in manifests
-----------------
``grader submit`` (:mod:`grader.student.submit`) writes ``MANIFEST.json`` at the top of the zip,
next to ``exercises/``: the sha256 and size of every file it put in.  When a submission
holds one (an archive, or a folder such as Gradescope's unpacked upload), :func:`opened`
checks it with :func:`verify_manifest` before anything is graded: every listed file must
be there with the same size and hash, and no other file may be (``__pycache__`` and the
litter of :data:`IGNORED_NAMES` aside: the grader never reads or copies them).  A
submission that fails is refused, and the message says which file was changed, removed
or added after ``grader submit`` wrote the zip.  The manifest is a check against
accidents (a file edited or added after submitting, a damaged upload), not a signature:
whoever holds the files can write a new one.  Submissions without a manifest are graded
as before.

Only source is graded
---------------------
The package must hold source only (:func:`grader.student.manifest.check_source_only`):
files with the suffixes of :data:`grader.sandbox.process.SOURCE_SUFFIXES` (``.py`` and
``.md``, ``.txt``, ``.json``), none holding a zip's end record or a NUL byte.  A
``.pyc`` (imported without its source), an extension module, a ``.pth``, an archive
to import from, or any other file refuses the submission, naming the files, in
folders, zips and on Gradescope alike; the sandbox copies only those suffixes and
never a ``__pycache__`` (:func:`grader.sandbox.process.copy_package`).

Examples
--------
>>> submission_id("Alice Smith (late).zip")
'Alice_Smith_late'
>>> submission_id("../..")
'submission'
"""
from __future__ import annotations

import errno
import hashlib
import json
import os
import re
import shutil
import stat
import tempfile
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import Iterator

from ..harness.package import PackageNotFound, package_folder
from ..student.manifest import (CHUNK, COURSE_NAME, byte_size, check_source_only, IGNORED_NAMES, MANIFEST_FORMAT, MANIFEST_NAME, MANIFEST_VERSION,
                                MAX_FILES, MAX_TOTAL_BYTES, SubmissionRefused, safe_extract, shown_name,
                                submission_id)


#: Largest archive file read (bytes): what it may expand to, plus room for its headers.
MAX_ARCHIVE_BYTES = MAX_TOTAL_BYTES + 8 * 1024**2
#: Largest manifest read (bytes).
MAX_MANIFEST_BYTES = 4 * 1024**2
#: Deepest nesting of a manifest's arrays and objects (a real one nests 3 deep:
#: {"files": [{...}]}); checked before it is parsed, so no nesting reaches the parser's recursion.
MAX_MANIFEST_DEPTH = 8
#: The command that writes the zip, as the student edition's README teaches it: refusals
#: are read by students, who hold the student edition.
SUBMIT_COMMAND = "bash run.sh submit"
#: What to do when a manifest does not match (appended to every such refusal).
RESUBMIT = f"run `{SUBMIT_COMMAND}` again and hand in the zip it writes, unchanged"




class SubmissionPathError(ValueError):
    """Paths given on the command line that are not folders or files at all."""


@dataclass(frozen=True)
class Submission:
    """One submission of the batch.

    Attributes
    ----------
    id : str
        Safe, stable name (see :func:`submission_id`); its folder in the output.
    path : Path
        The folder or archive, absolute.
    kind : str
        ``"folder"`` or ``"zip"`` (every file that is not a folder is taken as an
        archive; one that is not a zip is refused when opened, with a message), or
        ``"link"``: the path is a symbolic link, refused when fingerprinted or opened.
    """

    id: str
    path: Path
    kind: str




def discover(paths: list[str | os.PathLike]) -> list[Submission]:
    """The submissions at ``paths`` (each a folder or an archive), ids made unique.

    Every path is one submission; pass ``class/*`` to grade a folder of them.  Two
    paths with the same name both get a short suffix made from their absolute path,
    so ids stay the same from one run to the next.  Raises
    :class:`SubmissionPathError` naming every path that does not exist (or is not a
    regular file or folder) before anything is graded.

    A path that is itself a symbolic link is not followed: it becomes a submission of
    kind ``"link"``, named after the link, which :func:`fingerprint` and
    :func:`opened` refuse (see the module docstring).  The folders above it are
    resolved (they are the instructor's choice).
    """
    found: list[tuple[str, Path, str]] = []
    missing: list[str] = []
    seen: set[Path] = set()
    for raw in paths:
        path = Path(raw).expanduser()
        if not os.path.lexists(path):
            missing.append(f"{raw}: no such file or folder")
            continue
        try:
            path = _absolute(path)
            info = os.lstat(path)
        except OSError as exc:
            missing.append(f"{raw}: cannot be read ({exc.strerror or exc})")
            continue
        if path in seen:
            continue
        seen.add(path)
        if stat.S_ISLNK(info.st_mode):
            found.append((submission_id(path.name), path, "link"))
        elif stat.S_ISDIR(info.st_mode):
            found.append((submission_id(path.name), path, "folder"))
        elif stat.S_ISREG(info.st_mode):
            found.append((submission_id(path.name), path, "zip"))
        else:
            missing.append(f"{raw}: not a regular file or folder")
    if missing:
        raise SubmissionPathError("cannot grade these paths:\n  " + "\n  ".join(missing))
    counts: dict[str, int] = {}
    for name, _, _ in found:
        counts[name] = counts.get(name, 0) + 1
    submissions = []
    for name, path, kind in found:
        if counts[name] > 1:
            name = f"{name}-{hashlib.sha256(str(path).encode()).hexdigest()[:6]}"
        submissions.append(Submission(name, path, kind))
    return submissions


def _absolute(path: Path) -> Path:
    """``path`` made absolute with its folders resolved but not its last component (a
    link stays a link); ``.``, ``..`` and the root are resolved whole."""
    if path.name in ("", ".", ".."):
        return path.resolve()
    return Path(os.path.realpath(path.parent)) / path.name


# Checking before reading -----------------------------------------------------------------
def _stored_size(info: os.stat_result) -> int:
    """Bytes a file counts for: its apparent size or its allocated blocks, the larger
    (a sparse file is as large as it says, a file with preallocated blocks as large as
    its blocks)."""
    return max(info.st_size, getattr(info, "st_blocks", 0) * 512)


def _link_refusal(path: Path, where: str) -> SubmissionRefused:
    try:
        target = f" (to {shown_name(os.readlink(path))})"
    except OSError:
        target = ""
    return SubmissionRefused(f"{where} is a symbolic link{target}; the grader never follows links: hand in "
                             f"your files themselves (the zip `{SUBMIT_COMMAND}` writes never holds a link)")


def checked_path(path: str | os.PathLike) -> os.stat_result:
    """``lstat`` of a submission's own path: SubmissionRefused if it is a symbolic link or
    neither a folder nor a regular file (OSError if it cannot be read)."""
    path = Path(path)
    info = os.lstat(path)
    if stat.S_ISLNK(info.st_mode):
        raise _link_refusal(path, f"the submission {shown_name(path.name)}")
    if not (stat.S_ISDIR(info.st_mode) or stat.S_ISREG(info.st_mode)):
        raise SubmissionRefused(f"the submission {shown_name(path.name)} is not a regular file or folder")
    return info


def check_archive_size(info: os.stat_result, name: str, limit: int = MAX_ARCHIVE_BYTES) -> int:
    """The size of an archive file, SubmissionRefused when over ``limit`` (from ``stat``
    alone: nothing is read)."""
    size = _stored_size(info)
    if size > limit:
        raise SubmissionRefused(f"the archive {shown_name(name)} is {byte_size(size)}; at most {byte_size(limit)} are accepted")
    return size


def scan_folder(folder: str | os.PathLike, max_files: int = MAX_FILES, max_total_bytes: int = MAX_TOTAL_BYTES,
                links: str = "refuse") -> list[tuple[tuple[str, ...], int]]:
    """Every regular file of a submission folder, as (relative path parts, size): each
    folder's files in sorted order, then its sub-folders in sorted order.

    Reads nothing but ``lstat``, and stops at the first problem, raising
    SubmissionRefused saying what it is: a symbolic link (at any depth; links are
    never followed), a special file, more than ``max_files`` entries (files, folders
    and links, counted as they are listed), or more than ``max_total_bytes`` bytes (each file counted at its
    apparent size or its allocated blocks, the larger).  Litter such as
    ``__pycache__`` is counted too: it is on the disk, though the grader never reads it.
    With ``links="skip"``, a symbolic link is left out (neither followed nor listed)
    instead of refused.
    """
    if links not in ("refuse", "skip"):
        raise ValueError(f"links must be 'refuse' or 'skip', got {links!r}")
    folder = Path(folder)
    files: list[tuple[tuple[str, ...], int]] = []
    entries = 0
    total = 0
    stack: list[tuple[str, ...]] = [()]
    while stack:
        parts = stack.pop()
        children = []
        try:
            with os.scandir(folder.joinpath(*parts)) as listing:
                for entry in listing:  # counted as listed: a folder of millions stops at the cap
                    entries += 1
                    if entries > max_files:
                        raise SubmissionRefused(f"the submission holds more than {max_files} files and folders; "
                                                f"at most {max_files} are accepted")
                    children.append((entry.name, entry.stat(follow_symlinks=False)))
        except OSError as exc:
            raise SubmissionRefused(f"the folder {shown_name('/'.join(parts) or '.')} could not be read "
                                    f"({exc.strerror or exc})") from None
        folders = []
        for name, info in sorted(children, key=lambda child: child[0]):
            child = parts + (name,)
            shown = shown_name("/".join(child))
            if stat.S_ISLNK(info.st_mode) and links == "skip":
                continue
            if stat.S_ISLNK(info.st_mode):
                raise _link_refusal(folder.joinpath(*child), shown)
            if stat.S_ISDIR(info.st_mode):
                folders.append(child)
            elif stat.S_ISREG(info.st_mode):
                # A hard link is graded by its content, as any file (see hard_links).
                size = _stored_size(info)
                total += size
                if total > max_total_bytes:
                    raise SubmissionRefused(
                        f"the submission's files add up to more than {byte_size(max_total_bytes)} ({shown} alone is "
                        f"{byte_size(size)}); at most {byte_size(max_total_bytes)} are accepted")
                files.append((child, info.st_size))
            else:
                raise SubmissionRefused(f"{shown} is not a regular file (a device, a pipe or a socket); hand in "
                                        "your files only")
        stack.extend(reversed(folders))  # each folder's files, then its folders in turn (as os.walk)
    return files


# Hard links ----------------------------------------------------------------------------
def hard_links(submissions: list[Submission]) -> dict[str, list[str]]:
    """``{submission id: [what its hard links share]}`` for the submissions holding a file
    with more than one name on this disk (the submission's own archive, or a file of its
    folder).

    A hard link is graded by its content and refused for no one.  Its two names are
    the same file: nothing on the disk says which student made the link, so refusing the
    files that have two names (as the grader once did) refused the classmate whose file
    was linked to as surely as the student who linked it, and refusing one side by age
    or by link count would guess.  What a hard link can carry is the content of a file
    elsewhere: the grader reads each submission's files by content (the fingerprint,
    the manifest and the sandbox's copy all read bytes, never the link), so a student
    who links a classmate's file hands in a copy of it, which is what
    ``grader similarity`` and this flag are for.  Each submission sharing a file is
    flagged for the instructor (results.json's ``extra_data["source_flags"]
    ["hard_links"]`` and the class report), naming the other submission, or saying
    the other name lies outside the batch.
    """
    owners: dict[tuple[int, int], list[tuple[str, str]]] = {}
    counts: dict[tuple[int, int], int] = {}
    for submission in submissions:
        path = Path(submission.path)
        try:
            info = os.lstat(path)
            if stat.S_ISREG(info.st_mode):
                entries = [((), info)]
            elif stat.S_ISDIR(info.st_mode):
                entries = []
                for parts, _ in scan_folder(path, links="skip"):
                    entries.append((parts, os.lstat(path.joinpath(*parts))))
            else:
                continue
        except (OSError, SubmissionRefused):
            continue  # refused or unreadable: said when it is graded
        for parts, entry in entries:
            if entry.st_nlink > 1:
                key = (entry.st_dev, entry.st_ino)
                owners.setdefault(key, []).append((submission.id, "/".join(parts) or path.name))
                counts[key] = entry.st_nlink
    flags: dict[str, list[str]] = {}
    for key, names in owners.items():
        for sid, name in names:
            others = [f"{other}'s {shown_name(other_name)}" for other, other_name in names
                      if (other, other_name) != (sid, name)]
            outside = counts[key] - len(names)
            where = ", ".join(others + ([f"{outside} name(s) outside this batch"] if outside > 0 else []))
            flags.setdefault(sid, []).append(f"{shown_name(name)} is a hard link: the same file as {where}")
    return flags


# Fingerprints --------------------------------------------------------------------------
def _file_digest(path: Path, limit: int | None = None) -> str:
    """sha256 (hex) of a regular file, read without following a link and never past
    ``limit`` bytes: SubmissionRefused if it is longer (it grew since it was measured)."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_CLOEXEC | getattr(os, "O_NONBLOCK", 0))
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise _link_refusal(Path(path), shown_name(Path(path).name)) from None
        raise
    digest = hashlib.sha256()
    with open(fd, "rb", closefd=True) as handle:
        info = os.fstat(handle.fileno())
        if not stat.S_ISREG(info.st_mode):
            raise SubmissionRefused(f"{shown_name(Path(path).name)} is not a regular file")
        limit = _stored_size(info) if limit is None else limit
        read = 0
        while chunk := handle.read(min(CHUNK, limit + 1 - read)):
            read += len(chunk)
            if read > limit:
                raise SubmissionRefused(f"{shown_name(Path(path).name)} grew while it was read; hand it in again")
            digest.update(chunk)
    return digest.hexdigest()


def fingerprint(path: str | os.PathLike) -> str:
    """sha256 (hex) of a submission: the archive's bytes, or a folder's regular files.

    A folder's fingerprint covers every regular file's relative path and contents,
    in sorted order; ``__pycache__`` folders (which running the code locally writes)
    are left out, since the grader never reads them.  The
    submission is checked first (:func:`checked_path`, :func:`scan_folder`,
    :func:`check_archive_size`): a link, a special file or a submission over the caps
    raises SubmissionRefused before any file is read, and no file is read past the
    size measured.
    """
    path = Path(path)
    info = checked_path(path)
    if not stat.S_ISDIR(info.st_mode):
        return _file_digest(path, check_archive_size(info, path.name))
    digest = hashlib.sha256()
    for parts, size in scan_folder(path):
        if _ignored(parts):
            continue
        relative = "/".join(parts)
        digest.update(relative.encode("utf-8", "surrogateescape") + b"\0")
        digest.update(_file_digest(path.joinpath(*parts), size).encode() + b"\n")
    return digest.hexdigest()










def submitted_package(folder: Path) -> Path:
    """The ``exercises`` package in a submission folder, or SubmissionRefused saying what is there."""
    try:
        return package_folder(folder)
    except PackageNotFound:
        pass
    entries = sorted(p.name + ("/" if p.is_dir() else "") for p in folder.iterdir()
                     if p.name not in IGNORED_NAMES)
    seen = ", ".join(entries[:12]) + (", ..." if len(entries) > 12 else "") if entries else "nothing"
    raise SubmissionRefused("no exercises package found: hand in the folder 'exercises' (with its "
                            f"__init__.py), or a zip of it. Your submission holds: {seen}") from None


# Manifests --------------------------------------------------------------------------------
def _ignored(parts: tuple[str, ...]) -> bool:
    """Files no part of the grader reads: ``__pycache__`` folders, editor and OS litter.
    A ``.pyc`` anywhere else is not ignored: Python imports it without its source, so it
    counts in the fingerprint and the manifest, and is refused (:func:`check_source_only`)."""
    return any(p in IGNORED_NAMES for p in parts)


#: A JSON string (its brackets are not nesting).
JSON_STRING = re.compile(r'"(?:[^"\\]|\\.)*"', re.DOTALL)


def json_depth(text: str, limit: int | None = None) -> int:
    """The deepest nesting of arrays and objects in JSON ``text`` (brackets inside
    strings not counted), in one pass without recursion; malformed text is left to
    the parser.  With ``limit``, counting stops once past it.

    >>> json_depth('{"files": [{"path": "a[b"}]}')
    3
    """
    depth = deepest = 0
    for bracket in re.finditer(r"[][{}]", JSON_STRING.sub("", text)):
        depth += 1 if bracket[0] in "[{" else -1
        deepest = max(deepest, depth)
        if limit is not None and deepest > limit:
            break
    return deepest


def read_manifest(path: Path) -> dict:
    """The manifest at ``path``, checked for shape; SubmissionRefused if it is damaged."""
    def damaged(why: str) -> SubmissionRefused:
        return SubmissionRefused(f"{MANIFEST_NAME} is damaged ({why}); {RESUBMIT}")

    try:
        info = os.lstat(path)
        if not stat.S_ISREG(info.st_mode):
            raise damaged("it is not a regular file")
        if info.st_size > MAX_MANIFEST_BYTES:
            raise damaged(f"{info.st_size} bytes, at most {MAX_MANIFEST_BYTES} are read")
        text = Path(path).read_text(encoding="utf-8")
        depth = json_depth(text, MAX_MANIFEST_DEPTH)
        if depth > MAX_MANIFEST_DEPTH:
            raise damaged(f"its JSON nests {depth} levels deep; a manifest nests at most {MAX_MANIFEST_DEPTH}")
        data = json.loads(text)
    except (OSError, ValueError, RecursionError) as exc:
        raise damaged(f"not readable JSON: {exc}") from None
    if not isinstance(data, dict) or data.get("format") != MANIFEST_FORMAT:
        raise damaged(f"not a manifest written by `{SUBMIT_COMMAND}`: no \"format\": \"{MANIFEST_FORMAT}\"")
    if data.get("format_version") != MANIFEST_VERSION:
        raise SubmissionRefused(f"{MANIFEST_NAME} has format version {data.get('format_version')!r}; this grader "
                                f"reads version {MANIFEST_VERSION}: update your course files, then {RESUBMIT}")
    if data.get("course") != COURSE_NAME:
        raise SubmissionRefused(f"{MANIFEST_NAME} was written for the course {data.get('course')!r}, not "
                                f"{COURSE_NAME!r}: hand in the zip of this course's exercises")
    files = data.get("files")
    if not isinstance(files, list) or len(files) > MAX_FILES:
        raise damaged("its \"files\" is not a list of at most "
                      f"{MAX_FILES} entries")
    seen = set()
    for entry in files:
        if not (isinstance(entry, dict) and isinstance(entry.get("path"), str)
                and isinstance(entry.get("sha256"), str) and isinstance(entry.get("size"), int)
                and not isinstance(entry.get("size"), bool)):
            raise damaged(f"an entry of \"files\" is not {{path, sha256, size}}: {shown_name(str(entry))}")
        parts = PurePosixPath(entry["path"]).parts
        if (not parts or entry["path"].startswith("/") or "\\" in entry["path"] or ".." in parts or "." in parts
                or parts == (MANIFEST_NAME,)):
            raise damaged(f"it lists an impossible path {shown_name(entry['path'])}")
        if parts in seen:
            raise damaged(f"it lists {shown_name(entry['path'])} twice")
        seen.add(parts)
    return data


def manifest_folder(folder: Path) -> Path | None:
    """The folder whose ``MANIFEST.json`` describes the submission in ``folder``: the
    folder itself, or the one holding its ``exercises`` package; None if there is none."""
    folder = Path(folder)
    if os.path.lexists(folder / MANIFEST_NAME):
        return folder
    try:
        package = submitted_package(folder)
    except SubmissionRefused:
        return None
    base = package.parent
    if base != folder and folder in base.parents and os.path.lexists(base / MANIFEST_NAME):
        return base
    return None


def verify_manifest(folder: str | os.PathLike) -> dict | None:
    """Check the submission in ``folder`` against its ``MANIFEST.json`` (see the module
    docstring); the manifest, or None when there is none.  Raises SubmissionRefused
    naming the first difference (and how many more there are)."""
    base = manifest_folder(Path(folder))
    if base is None:
        return None
    manifest = read_manifest(base / MANIFEST_NAME)
    listed = {tuple(PurePosixPath(e["path"]).parts): e for e in manifest["files"]}
    present: dict[tuple[str, ...], Path] = {}
    problems: list[str] = []
    for root, dirs, files in os.walk(base):
        here = Path(root)
        for name in sorted(dirs + files):
            full = here / name
            parts = full.relative_to(base).parts
            shown = shown_name("/".join(parts))
            mode = os.lstat(full).st_mode
            if stat.S_ISLNK(mode):
                problems.append(f"{shown} is a symbolic link; `{SUBMIT_COMMAND}` never puts links in the zip")
            elif stat.S_ISDIR(mode) or parts == (MANIFEST_NAME,) or _ignored(parts):
                continue
            elif not stat.S_ISREG(mode):
                problems.append(f"{shown} is not a regular file")
            else:
                present[parts] = full
        dirs[:] = sorted(d for d in dirs if d not in IGNORED_NAMES and not os.path.islink(here / d))
    for parts, entry in listed.items():
        shown = shown_name("/".join(parts))
        path = present.get(parts)
        if path is None:
            problems.append(f"file {shown} is listed in {MANIFEST_NAME} but missing: it was removed after "
                            f"`{SUBMIT_COMMAND}` wrote the zip")
        elif path.stat().st_size != entry["size"] or _file_digest(path) != entry["sha256"].lower():
            problems.append(f"file {shown} was changed after `{SUBMIT_COMMAND}` wrote the zip (its size or sha256 "
                            f"differs from {MANIFEST_NAME})")
    for parts in sorted(set(present) - set(listed)):
        problems.append(f"file {shown_name('/'.join(parts))} is not in {MANIFEST_NAME}: it was added after "
                        f"`{SUBMIT_COMMAND}` wrote the zip")
    if problems:
        more = f" (and {len(problems) - 1} more difference{'s' if len(problems) > 2 else ''})" \
            if len(problems) > 1 else ""
        raise SubmissionRefused(f"{problems[0]}{more}; {RESUBMIT}")
    return manifest


# Opening ----------------------------------------------------------------------------------
def _no_link_on_the_way(folder: Path, inner: Path) -> None:
    """SubmissionRefused if ``inner`` (a folder under ``folder``) or a folder between
    them is a symbolic link."""
    for step in [inner, *inner.parents]:
        if step == folder or folder not in step.parents:
            break
        if step.is_symlink():
            raise _link_refusal(step, shown_name(step.relative_to(folder).as_posix()))


@contextmanager
def opened(submission: Submission, workdir: str | os.PathLike | None = None,
           verify: bool = True, links: str | None = None) -> Iterator[Path]:
    """The submission as a folder to grade (a temporary copy for an archive), removed after.

    The submission is checked before anything of it is read (see the module
    docstring): its own path must not be a symbolic link; an archive file must be
    within ``MAX_ARCHIVE_BYTES`` (:func:`check_archive_size`) and is extracted by
    :func:`safe_extract`; a folder is walked by :func:`scan_folder` (within the caps,
    no special file) and then graded where it is.  ``links`` says what a symbolic link
    inside a folder does: ``"refuse"`` (the default when ``verify``: the grader)
    refuses the submission naming it; ``"skip"`` (the default without ``verify``:
    :mod:`grader.batch.similarity`, which compares code tampered or not) leaves it out of
    the scan -- it is never followed, and a link on the way to the package is still
    refused.

    A folder holding no package but exactly one zip archive is taken as that archive
    (a student who uploads the archive itself to Gradescope, say).  With ``verify``,
    a submission holding a ``MANIFEST.json`` is checked against it first
    (:func:`verify_manifest`; SubmissionRefused if it does not match).
    """
    links = links or ("refuse" if verify else "skip")
    path = Path(submission.path)
    try:
        info = checked_path(path)
    except OSError as exc:
        raise SubmissionRefused(f"the submission could not be read ({exc.strerror or exc})") from None
    if stat.S_ISDIR(info.st_mode):
        scan_folder(path, links=links)
        try:
            package = submitted_package(path)
            archives = []
        except SubmissionRefused:
            package = None
            archives = [p for p in path.iterdir() if p.suffix.lower() == ".zip" and not p.is_symlink() and p.is_file()]
        if package is None and len(archives) == 1:
            with opened(Submission(submission.id, archives[0], "zip"), workdir, verify, links) as folder:
                yield folder
            return
        if package is not None:
            _no_link_on_the_way(path, package)
        if verify:
            verify_manifest(path)
            if package is not None:
                check_source_only(package)
        yield path
        return
    check_archive_size(info, path.name)
    folder = Path(tempfile.mkdtemp(prefix="submission-", dir=workdir))
    try:
        safe_extract(path, folder)
        if verify:
            verify_manifest(folder)
            try:
                package = submitted_package(folder)
            except SubmissionRefused:
                package = None  # no package: said when the grader looks for it
            if package is not None:
                check_source_only(package)
        yield folder
    finally:
        shutil.rmtree(folder, ignore_errors=True)


# The course's library files -------------------------------------------------------------------
#: The first words of a library file of the ``exercises`` package (the header
#: grader/release/exercises.py writes: ``LIBRARY_HEADER``); an exercise file starts with
#: "# Exercise file".  A file is classed by the course's copy, never the submission's.
LIBRARY_HEADER = "# Library file of the collision course"


def files_with_header(reference: str | os.PathLike, header: str) -> dict[str, Path]:
    """The ``.py`` files of the course's ``exercises`` package at ``reference`` whose first
    line starts with ``header``: {path relative to the package: file}."""
    reference = Path(reference)
    found = {}
    for path in sorted(reference.rglob("*.py")):
        relative = path.relative_to(reference)
        if "__pycache__" in relative.parts or path.is_symlink():
            continue
        with open(path, encoding="utf-8", errors="replace") as handle:
            if handle.readline().startswith(header):
                found[relative.as_posix()] = path
    return found


def library_files(reference: str | os.PathLike) -> dict[str, Path]:
    """The library files of the course's ``exercises`` package at ``reference`` (what
    students were given): {path relative to the package: file}."""
    return files_with_header(reference, LIBRARY_HEADER)


def library_hash(reference: str | os.PathLike | None) -> str | None:
    """sha256 of the course's library files (paths and bytes), None without them: a
    submission graded with other library files is graded again."""
    if reference is None or not Path(reference).is_dir():
        return None
    digest = hashlib.sha256()
    for relative, path in library_files(reference).items():
        digest.update(relative.encode() + b"\0" + hashlib.sha256(path.read_bytes()).digest())
    return digest.hexdigest()


@contextmanager
def with_course_library(package: Path, reference: str | os.PathLike | None,
                        workdir: str | os.PathLike | None = None) -> Iterator[tuple[Path, list[str]]]:
    """The submission's package as graded: a temporary copy whose library files are the
    course's (from ``reference``, the course's ``exercises`` package), with the library
    files of the submission that differed or were missing ([relative paths]).  The
    exercise files and any file the student added come from the submission.  Without a
    ``reference`` folder, the package itself and [].

    The copy holds regular files only (the submission was scanned: it has no link), and
    nothing of the reference but its library files, which students have too."""
    if reference is None or not Path(reference).is_dir():
        yield package, []
        return
    library = library_files(reference)
    scratch = Path(tempfile.mkdtemp(prefix="graded-", dir=workdir))
    try:
        graded = scratch / "exercises"
        shutil.copytree(package, graded, symlinks=True, ignore=shutil.ignore_patterns(*IGNORED_NAMES, "*.pyc"))
        replaced = []
        for relative, source in library.items():
            target = graded / relative
            data = source.read_bytes()
            if target.is_symlink() or not target.is_file() or _file_digest(target) != hashlib.sha256(data).hexdigest():
                replaced.append(relative)
                if target.is_symlink() or target.is_dir():
                    raise SubmissionRefused(f"exercises/{shown_name(relative)} is not a regular file; it must be the "
                                            "course's library file")
                target.parent.mkdir(parents=True, exist_ok=True)
                target.write_bytes(data)
        yield graded, replaced
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def library_note(replaced: list[str]) -> str:
    """The line of the results a student sees when library files were replaced."""
    shown = ", ".join(f"exercises/{name}" for name in replaced[:12]) + (", ..." if len(replaced) > 12 else "")
    return (f"Library files of your submission that differ from the course's (or are missing) were graded as "
            f"the course released them: {shown}. Library files are the course's: put your code in the exercise "
            "files (the first line of each file says which it is); `bash run.sh update` takes a corrected "
            "release of the course into your folder.")
