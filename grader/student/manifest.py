"""The hand-in contract: what ``grader submit`` writes and every grader reads.

A submission is the ``exercises`` package, as a folder or a zip, with a ``MANIFEST.json``
of its files' hashes (written by :mod:`grader.student.submit`, verified by
:mod:`grader.batch.submissions`).  Here: the manifest's format, the caps on files and
bytes, the names that are litter, the submission id, and reading a zip safely (no
member outside the destination, no link, no more than the caps).
"""
from __future__ import annotations

import os
import re
import shutil
import stat
import struct
import unicodedata
import zipfile
from pathlib import Path, PurePosixPath

from ..sandbox.process import SOURCE_SUFFIXES

#: Most members one archive may hold.
MAX_FILES = 2_000


#: Most bytes one archive may expand to (all members together), and one folder may hold.
MAX_TOTAL_BYTES = 64 * 1024**2


def byte_size(count: int) -> str:
    """A number of bytes as the grader writes it: ``512 bytes``, ``12 KiB``, ``3.4 MiB``, ``2.0 GiB``."""
    if count < 1024:
        return f"{count} bytes"
    if count < 1024**2:
        return f"{count / 1024:.0f} KiB"
    if count < 1024**3:
        return f"{count / 1024**2:.1f} MiB"
    return f"{count / 1024**3:.1f} GiB"


#: Longest submission id (characters).
MAX_ID_LENGTH = 80


#: Names an id may not take: files the grader writes next to the submission folders.
RESERVED_IDS = frozenset({"gradebook.csv", "index.html", "report.html", "class_report.html", "grading_log.jsonl"})


#: Folders and files that are not part of what was handed in (editor and OS litter).
IGNORED_NAMES = frozenset({"__pycache__", "__MACOSX", ".DS_Store"})


CHUNK = 1 << 16  # bytes read at a time


#: Largest central directory (bytes) of an archive read: 2,000 members with names of
#: 1 KiB fit many times over.
MAX_DIRECTORY_BYTES = 4 * 1024**2


#: Longest name, extra field and comment of one member (bytes).  ``zipfile`` decodes
#: an extra field in time quadratic in its length (one copy per record): a directory
#: of members each with 64 KiB of tiny extra records takes it tens of seconds.
MAX_MEMBER_FIELD_BYTES = 4096


#: The hand-in manifest ``grader submit`` writes at the top of the zip, and its format.
MANIFEST_NAME = "MANIFEST.json"


MANIFEST_FORMAT = "collision-course-submission"


MANIFEST_VERSION = 1


COURSE_NAME = "collision-course"


class SubmissionRefused(Exception):
    """A submission that cannot be graded; the message is written for the student."""


# Source only -----------------------------------------------------------------------------
#: Bytes that mark a file as no source at all: a zip's end record (``zipimport`` imports
#: from any file holding one, whatever its name) and NUL (no text holds one).
NOT_TEXT_MARKS = (b"PK\x05\x06", b"\0")


def source_only_problems(package: str | os.PathLike, limit: int = 8) -> list[str]:
    """What makes the package at ``package`` more than source (at most ``limit``
    problems, as relative paths with the reason): a file whose suffix is not one of
    :data:`SOURCE_SUFFIXES` (``.pyc``, ``.so``, ``.pth``, ``.zip``, ... anything
    Python could import without its source), or a file of those suffixes holding a
    zip's end record or a NUL byte.  ``__pycache__`` and the litter of
    :data:`IGNORED_NAMES` are left out (they are never copied for grading)."""
    package = Path(package)
    problems: list[str] = []
    for root, dirs, files in os.walk(package):
        dirs[:] = sorted(d for d in dirs if d not in IGNORED_NAMES and not os.path.islink(Path(root, d)))
        for name in sorted(files):
            if name in IGNORED_NAMES:
                continue
            path = Path(root, name)
            shown = shown_name(f"{package.name}/{path.relative_to(package).as_posix()}")
            if not name.lower().endswith(SOURCE_SUFFIXES):
                problems.append(f"{shown} (not source)")
            elif path.is_file() and not path.is_symlink():
                with open(path, "rb") as handle:
                    data = handle.read(MAX_TOTAL_BYTES + 1)
                if any(mark in data for mark in NOT_TEXT_MARKS):
                    problems.append(f"{shown} (not text: it holds an archive or binary data)")
            if len(problems) >= limit:
                return problems
    return problems


def check_source_only(package: str | os.PathLike) -> None:
    """SubmissionRefused naming the files that are not source (see
    :func:`source_only_problems`); nothing when the package is source only."""
    problems = source_only_problems(package)
    if problems:
        raise SubmissionRefused(
            "only source is graded: a submission holds .py files (and .md, .txt, .json notes and data), and "
            f"these are not: {', '.join(problems)}. Compiled files (.pyc), extension modules (.so), .pth files "
            "and archives are refused: hand in the .py source of your work (the zip `bash run.sh submit` "
            "writes holds only source)")


def submission_id(name: str) -> str:
    """A safe folder name from a file or folder name (stable: the same name, the same id).

    Accents are dropped; ASCII letters, digits, ``.``, ``_`` and ``-`` are kept, every other run of characters
    becomes one ``_``; a ``.zip`` ending is dropped; leading dots and underscores are
    stripped (no hidden folders, no ``..``).  An empty result is ``"submission"``.
    """
    name = unicodedata.normalize("NFKD", name.strip()).encode("ascii", "ignore").decode()
    if name.lower().endswith(".zip"):
        name = name[:-4]
    safe = re.sub(r"[^A-Za-z0-9._-]+", "_", name).strip("._-")[:MAX_ID_LENGTH].strip("._-")
    if not safe:
        return "submission"
    if safe.lower() in RESERVED_IDS:
        safe = "submission_" + safe
    return safe


# Safe extraction -------------------------------------------------------------------------
def shown_name(name: str) -> str:
    """A member name as quoted in a message (control characters escaped, shortened)."""
    text = repr(name)
    return text if len(text) <= 120 else text[:117] + "..."


def member_parts(info: zipfile.ZipInfo) -> tuple[str, ...] | None:
    """The safe relative path of a member as parts; None for folders and ignored litter.

    Raises :class:`SubmissionRefused` for a member the archive may not hold.
    """
    name = info.filename
    if "\0" in name:
        raise SubmissionRefused(f"the archive has a member with a NUL character in its name: {shown_name(name)}")
    if info.flag_bits & 0x1:
        raise SubmissionRefused(f"the archive is password-protected ({shown_name(name)}); hand in a plain zip")
    unified = name.replace("\\", "/")
    if unified.startswith("/") or re.match(r"^[A-Za-z]:", unified):
        raise SubmissionRefused(f"the archive has a member with an absolute path: {shown_name(name)}")
    parts = tuple(p for p in PurePosixPath(unified).parts if p not in ("", "."))
    if ".." in parts:
        raise SubmissionRefused(f"the archive has a member whose path climbs out with '..': {shown_name(name)}")
    mode = info.external_attr >> 16
    kind = stat.S_IFMT(mode)
    if kind == stat.S_IFLNK or (info.create_system == 3 and kind not in (0, stat.S_IFREG, stat.S_IFDIR)):
        what = "a symbolic link" if kind == stat.S_IFLNK else "a special file (not a regular file)"
        raise SubmissionRefused(f"the archive has a member that is {what}: {shown_name(name)}; "
                                "zip your files, not links to them")
    if info.is_dir() or kind == stat.S_IFDIR or not parts:
        return None
    if any(p in IGNORED_NAMES for p in parts):
        return None
    return parts


END_RECORD = b"PK\x05\x06"        # end of central directory record: 22 bytes and a comment
ZIP64_LOCATOR = b"PK\x06\x07"     # zip64 end of central directory locator: 20 bytes
ZIP64_RECORD = b"PK\x06\x06"      # zip64 end of central directory record: 56 bytes at least
DIRECTORY_ENTRY = b"PK\x01\x02"   # central directory file header: 46 bytes and three fields


def check_directory(archive: str | os.PathLike, max_files: int = MAX_FILES,
                    max_directory_bytes: int = MAX_DIRECTORY_BYTES) -> None:
    """Refuse (SubmissionRefused) an archive whose central directory is over the caps,
    reading only its end records and then its directory, each field checked as read.

    Runs before :mod:`zipfile` parses the directory: the end record (and the zip64 one)
    give the entry count and the directory's size, refused over ``max_files`` or
    ``max_directory_bytes``; each entry's name, extra field and comment are then
    capped at :data:`MAX_MEMBER_FIELD_BYTES`.  Reads at most 64 KiB plus the capped
    directory, so any archive is judged in milliseconds.  A file that is not a zip
    is left to :mod:`zipfile`, which says so.
    """
    with open(archive, "rb") as handle:
        size = handle.seek(0, os.SEEK_END)
        tail_start = max(0, size - (22 + 0xFFFF))
        handle.seek(tail_start)
        tail = handle.read()
        at = tail.rfind(END_RECORD)
        if at < 0 or len(tail) - at < 22:
            return
        (_, _, _, _, count, directory_size, directory_offset, _) = struct.unpack("<4sHHHHIIH", tail[at:at + 22])
        zip64 = tail[max(0, at - 20):at]
        if len(zip64) == 20 and zip64.startswith(ZIP64_LOCATOR):
            record_offset = struct.unpack("<Q", zip64[8:16])[0]
            handle.seek(min(record_offset, size))
            record = handle.read(56)
            if len(record) == 56 and record.startswith(ZIP64_RECORD):
                count, directory_size, directory_offset = struct.unpack("<QQQ", record[32:56])
        if count > max_files:
            raise SubmissionRefused(f"the archive holds {count} entries; at most {max_files} are accepted")
        if directory_size > max_directory_bytes:
            raise SubmissionRefused(f"the archive's list of members takes {byte_size(directory_size)}; at "
                                    f"most {byte_size(max_directory_bytes)} are accepted (zip your files "
                                    "again with a standard tool)")
        # The directory is found from the end record (zipfile's way: a prefix before the
        # archive shifts every offset by the same amount).
        start = tail_start + at - directory_size - (56 + 20 if len(zip64) == 20 and zip64.startswith(ZIP64_LOCATOR)
                                                  else 0)
        if start < 0:
            return
        handle.seek(start)
        directory = handle.read(directory_size)
    position = 0
    while position + 46 <= len(directory) and directory[position:position + 4] == DIRECTORY_ENTRY:
        name_length, extra_length, comment_length = struct.unpack("<HHH", directory[position + 28:position + 34])
        longest = max(name_length, extra_length, comment_length)
        if longest > MAX_MEMBER_FIELD_BYTES:
            raise SubmissionRefused(f"a member of the archive has a name, extra field or comment of {longest} bytes; "
                                    f"at most {MAX_MEMBER_FIELD_BYTES} are accepted (zip your files again with a "
                                    "standard tool)")
        position += 46 + name_length + extra_length + comment_length


def safe_extract(archive: str | os.PathLike, destination: str | os.PathLike, max_files: int = MAX_FILES,
                 max_total_bytes: int = MAX_TOTAL_BYTES) -> list[Path]:
    """Extract the regular files of a zip archive into ``destination`` (which must be empty).

    Every member is checked before anything is written (see the module docstring);
    bytes are counted while they are written, so a header that understates a
    member's size does not get past the cap.  On refusal, whatever was written is
    removed again and :class:`SubmissionRefused` says why.

    Returns
    -------
    list of Path
        The files written.
    """
    destination = Path(destination)
    try:
        check_directory(archive, max_files)
        archive_file = zipfile.ZipFile(archive)
    except zipfile.BadZipFile:
        raise SubmissionRefused("the file handed in is not a zip archive (or it is damaged); "
                                "hand in a .zip holding your exercises folder") from None
    except UnicodeDecodeError:  # a member name flagged as UTF-8 that is not
        raise SubmissionRefused("the archive has a member whose name is marked as UTF-8 but is not valid "
                                "UTF-8; zip your files again with a standard tool") from None
    except (ValueError, EOFError, NotImplementedError, RecursionError) as exc:
        raise SubmissionRefused(f"the archive is damaged or uses an unsupported format: {exc}") from None
    except OSError as exc:
        raise SubmissionRefused(f"the archive could not be read ({exc.strerror or exc})") from None
    with archive_file:
        members = archive_file.infolist()
        if len(members) > max_files:
            raise SubmissionRefused(f"the archive holds {len(members)} entries; at most {max_files} are accepted")
        declared = sum(info.file_size for info in members)
        if declared > max_total_bytes:
            raise SubmissionRefused(f"the archive expands to {byte_size(declared)}; at most "
                                    f"{byte_size(max_total_bytes)} are accepted (is it a zip bomb?)")
        plan: list[tuple[zipfile.ZipInfo, tuple[str, ...]]] = []
        taken: dict[tuple[str, ...], str] = {}
        for info in members:
            parts = member_parts(info)
            if parts is None:
                continue
            if parts in taken:
                raise SubmissionRefused(f"the archive holds {shown_name(info.filename)} twice")
            taken[parts] = info.filename
            plan.append((info, parts))
        folders = {key[:i] for key in taken for i in range(1, len(key))}
        clash = next((name for key, name in taken.items() if key in folders), None)
        if clash is not None:
            raise SubmissionRefused(f"the archive holds {shown_name(clash)} both as a file and as a folder")
        written: list[Path] = []
        total = 0
        try:
            for info, parts in plan:
                target = destination.joinpath(*parts)
                target.parent.mkdir(parents=True, exist_ok=True)
                with archive_file.open(info) as source, open(target, "xb") as sink:
                    written.append(target)
                    for chunk in iter(lambda: source.read(CHUNK), b""):
                        total += len(chunk)
                        if total > max_total_bytes:
                            raise SubmissionRefused(
                                f"the archive expands to more than {byte_size(max_total_bytes)} "
                                "(is it a zip bomb?)")
                        sink.write(chunk)
        except SubmissionRefused:
            empty_folder(destination)
            raise
        except (zipfile.BadZipFile, EOFError, ValueError, NotImplementedError) as exc:
            empty_folder(destination)
            raise SubmissionRefused(f"the archive is damaged or uses an unsupported format: {exc}") from None
        except OSError as exc:
            empty_folder(destination)
            raise SubmissionRefused(f"a member of the archive could not be written: "
                                    f"{exc.strerror or exc} ({shown_name(getattr(exc, 'filename', '') or '')})") from None
    return written


def empty_folder(folder: Path) -> None:
    for entry in list(folder.iterdir()) if folder.is_dir() else []:
        if entry.is_dir() and not entry.is_symlink():
            shutil.rmtree(entry, ignore_errors=True)
        else:
            entry.unlink(missing_ok=True)
