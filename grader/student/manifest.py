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
import unicodedata
import zipfile
from pathlib import Path, PurePosixPath

#: Most members one archive may hold.
MAX_FILES = 2_000


#: Most bytes one archive may expand to (all members together), and one folder may hold.
MAX_TOTAL_BYTES = 64 * 1024**2


#: Longest submission id (characters).
MAX_ID_LENGTH = 80


#: Names an id may not take: files the grader writes next to the submission folders.
RESERVED_IDS = frozenset({"gradebook.csv", "index.html", "report.html", "class_report.html", "grading_log.jsonl"})


#: Folders and files that are not part of what was handed in (editor and OS litter).
IGNORED_NAMES = frozenset({"__pycache__", "__MACOSX", ".DS_Store"})


CHUNK = 1 << 16  # bytes read at a time


#: The hand-in manifest ``grader submit`` writes at the top of the zip, and its format.
MANIFEST_NAME = "MANIFEST.json"


MANIFEST_FORMAT = "collision-course-submission"


MANIFEST_VERSION = 1


COURSE_NAME = "collision-course"


class SubmissionRefused(Exception):
    """A submission that cannot be graded; the message is written for the student."""


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
            raise SubmissionRefused(f"the archive expands to {declared / 1024**2:.1f} MiB; at most "
                                    f"{max_total_bytes / 1024**2:.0f} MiB are accepted (is it a zip bomb?)")
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
                                f"the archive expands to more than {max_total_bytes / 1024**2:.0f} MiB "
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
