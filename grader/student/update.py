"""``grader update NEW_RELEASE``: take a corrected release of the course, keeping your work.

From the course folder (``bash run.sh update NEW_RELEASE`` runs it)::

    grader update ~/Downloads/course-1.0.1/          # the new release's folder
    grader update ~/Downloads/course-1.0.1.zip       # or a zip of it
    grader update NEW_RELEASE --dry-run              # say what would change, change nothing

The course folder's ``.course-release.json`` (:data:`MARKER`, written by ``grader
release``) holds the SHA-256 of every file as it was handed out; the release also keeps
the original text of its text files in ``.course-release-originals.zip``
(:data:`ORIGINALS`: the base of a 3-way merge, zipped so that no editor, search or
import finds a second copy of the exercises).  For every file of the old or the new
release:

- a file you never changed (its hash is the recorded one) is replaced by the new
  release's, or removed if the release removed it;
- a file you changed that the release also changed is merged, 3-way, with the original
  as base (:mod:`merge3`, the merge of the Breezy version control system): your lines
  and the release's both go in.  Where you and the release changed the same lines, the
  file keeps both, between ``<<<<<<< yours``, ``=======`` and ``>>>>>>> release V``, and
  the update lists it at the end and exits with status 1;
- a notebook you only ran (its cells' sources are the original ones, :func:`notebook_sources`)
  is replaced, outputs included; one whose cells you edited is kept, and the
  release's copy is written beside it (``NAME.release-V.ipynb``), as for any file that
  cannot be merged line by line;
- a file you added is never read or touched.

Before anything changes, ``exercises/``, the notebooks and every file the update will
change or remove are copied to ``backups/update-<date>-<time>/`` (:data:`BACKUPS`), and
the update says where.  Then the folder's marker becomes the new release's, so that a
second run with the same release finds nothing to do and says so.

Nothing changes, and the update says why (exit status 2), when the new release is not a
release (no marker), is the autograder's folder, is older than the course folder or the
same version with other files, or when the course folder is not a student edition.

What changed is printed from the new release's ``CHANGELOG.md`` (:data:`CHANGELOG`): every
section newer than the course folder's version.  :func:`parse_changelog` reads it; the
instructor's ``grader release`` takes the release's version from its newest section.
"""
from __future__ import annotations

import argparse
import hashlib
import io
import json
import os
import re
import shutil
import stat
import sys
import tempfile
import time
import zipfile
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath
from typing import Iterator
from .manifest import SubmissionRefused, safe_extract

#: The marker of a release folder, and its format (see :mod:`grader.release.edition`).
MARKER = ".course-release.json"
MARKER_FORMAT = "collision-course-release"
#: The original text of the release's text files: {relative path: text} as a zip.
ORIGINALS = ".course-release-originals.zip"
#: The course's changelog, at the top of the repository and of the student edition.
CHANGELOG = "CHANGELOG.md"
#: Where the update copies the student's files before changing anything.
BACKUPS = "backups"
#: A release version: numbers separated by dots (1.0, 1.0.1, 2025.2).
VERSION = re.compile(r"\d+(?:\.\d+)*")
#: A changelog section heading: ``## 1.0.1 (2025-03-02)`` or ``## [1.0.1] - 2025-03-02``.
SECTION = re.compile(r"^##\s+\[?v?(?P<version>\d+(?:\.\d+)*)\]?(?P<rest>.*)$")
#: Files kept as originals: text files up to this size (bytes); notebooks never (their
#: cells' sources are compared instead).
MAX_ORIGINAL_BYTES = 512 * 1024
#: Conflict markers (git's), followed by "yours" and "release V".
START, MIDDLE, END = "<<<<<<<", "=======", ">>>>>>>"
YOURS = "yours"
#: Exit statuses: done; done, but files need the student's attention; refused.
DONE, ATTENTION, REFUSED = 0, 1, 2
FIXED_TIME = (2020, 1, 1, 0, 0, 0)  # every member's date in the originals zip: same files, same zip


class UpdateRefused(Exception):
    """The update cannot be done; nothing was changed.  The message says why."""


# Versions and the changelog --------------------------------------------------------------------
def version_key(version: str | None) -> tuple[int, ...] | None:
    """(1, 0, 2) for "1.0.2"; None when ``version`` is not a version."""
    if not isinstance(version, str) or not VERSION.fullmatch(version.strip()):
        return None
    return tuple(int(part) for part in version.strip().split("."))


def parse_changelog(text: str) -> list[tuple[str, str]]:
    """The sections of a changelog, in the file's order (newest first): [(version, text
    below the heading, stripped)].  Headings that name no version (``## Unreleased``)
    end the section above them and are left out.

    >>> parse_changelog("# Log\\n## Unreleased\\n- soon\\n## [1.0.1] - 2025-03-02\\n- Fixed x.\\n## 1.0\\nFirst.")
    [('1.0.1', '- Fixed x.'), ('1.0', 'First.')]
    """
    sections: list[tuple[str, list[str]]] = []
    current: list[str] | None = None
    for line in text.splitlines():
        if line.startswith("## "):
            match = SECTION.match(line)
            current = None
            if match:
                current = []
                sections.append((match["version"], current))
            continue
        if current is not None:
            current.append(line)
    return [(version, "\n".join(lines).strip()) for version, lines in sections]


def newer_sections(text: str, since: str | None) -> list[tuple[str, str]]:
    """The changelog sections newer than version ``since`` (only the newest one when
    ``since`` is unknown)."""
    sections = parse_changelog(text)
    since_key = version_key(since)
    if since_key is None:
        return sections[:1]
    return [(v, t) for v, t in sections if version_key(v) > since_key]


# What a release keeps for the merges -------------------------------------------------------------
def notebook_sources(data: bytes) -> str | None:
    """SHA-256 of a notebook's cells (type and source, in order), outputs and execution
    counts left out: the same for a notebook that was only run.  None if ``data`` is not
    a notebook."""
    try:
        cells = json.loads(data.decode("utf-8"))["cells"]
        text = json.dumps([[c.get("cell_type"), "".join(c["source"]) if isinstance(c.get("source"), list)
                            else c.get("source")] for c in cells])
    except (ValueError, KeyError, TypeError, AttributeError):
        return None
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def keeps_original(relative: str, data: bytes) -> bool:
    """Whether the release keeps the original of a file: UTF-8 text, not a notebook,
    at most MAX_ORIGINAL_BYTES."""
    if relative.endswith(".ipynb") or relative in (MARKER, ORIGINALS) or len(data) > MAX_ORIGINAL_BYTES:
        return False
    if b"\0" in data:
        return False
    try:
        data.decode("utf-8")
    except UnicodeDecodeError:
        return False
    return True


def write_originals(folder: Path) -> dict:
    """Write ``folder/ORIGINALS`` (the text files of the release folder ``folder``) and
    return what the marker records of it: ``{"originals": ORIGINALS, "notebook_sources":
    {path: digest}}``."""
    folder = Path(folder)
    notebooks = {}
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
        for path in sorted(p for p in folder.rglob("*") if p.is_file() and not p.is_symlink()):
            relative = path.relative_to(folder).as_posix()
            data = path.read_bytes()
            if relative.endswith(".ipynb"):
                digest = notebook_sources(data)
                if digest is not None:
                    notebooks[relative] = digest
            elif keeps_original(relative, data):
                info = zipfile.ZipInfo(relative, FIXED_TIME)
                info.compress_type = zipfile.ZIP_DEFLATED
                info.external_attr = 0o644 << 16
                archive.writestr(info, data)
    (folder / ORIGINALS).write_bytes(buffer.getvalue())
    return {"originals": ORIGINALS, "notebook_sources": notebooks}


def read_originals(folder: Path) -> dict[str, bytes]:
    """The originals kept in ``folder`` ({} for a release older than them)."""
    path = Path(folder) / ORIGINALS
    if not path.is_file() or path.is_symlink():
        return {}
    try:
        with zipfile.ZipFile(path) as archive:
            return {info.filename: archive.read(info) for info in archive.infolist() if not info.is_dir()}
    except (zipfile.BadZipFile, OSError, ValueError):
        return {}


# Finding and checking the two folders ----------------------------------------------------------
def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def read_marker(folder: Path) -> dict | None:
    """The release marker of ``folder``, or None if it has none that ``grader release`` wrote."""
    path = Path(folder) / MARKER
    try:
        if path.is_symlink() or not path.is_file():
            return None
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or data.get("format") != MARKER_FORMAT or not isinstance(data.get("files"), dict):
        return None
    return data


def _describe(marker: dict) -> str:
    version = marker.get("version")
    created = str(marker.get("created") or "an unknown date")[:10]
    return f"version {version} ({created})" if version else f"the release of {created} (no version)"


def course_marker(course: Path) -> dict:
    """The marker of the student's course folder; UpdateRefused unless it is a student edition."""
    marker = read_marker(course)
    if marker is None:
        raise UpdateRefused(f"{course} is not a course folder written by `grader release` (it has no readable "
                            f"{MARKER}): run the update from your course folder, the one holding run.sh and "
                            "exercises/")
    if marker.get("edition") != "student":
        raise UpdateRefused(f"{course} is the {marker.get('edition')!r} edition of a release, not a student's "
                            "course folder: nothing to update")
    return marker


def release_folder(path: Path) -> Path:
    """The student edition inside ``path``: ``path`` itself, ``path/student`` (the
    ``--out`` folder of ``grader release``) or the one folder of an unpacked zip."""
    for candidate in (path, path / "student"):
        if (candidate / MARKER).is_file():
            return candidate
    inner = [p.parent for p in path.glob(f"*/{MARKER}")] + [p.parent for p in path.glob(f"*/student/{MARKER}")]
    if len(inner) == 1:
        return inner[0]
    raise UpdateRefused(f"{path} is not a release of the course: no {MARKER} in it (give the folder your "
                        "instructor handed out, the one holding run.sh, exercises/ and a .course-release.json; "
                        "or a zip of it)")


@contextmanager
def opened_release(path: str | os.PathLike) -> Iterator[Path]:
    """The new release as a folder (a zip is unpacked, safely, into a temporary folder)."""
    path = Path(path).expanduser()
    if not path.exists():
        raise UpdateRefused(f"{path}: no such file or folder")
    if path.is_dir():
        yield release_folder(path)
        return

    with tempfile.TemporaryDirectory(prefix="course-release-") as scratch:
        try:
            safe_extract(path, scratch)
        except SubmissionRefused as exc:
            message = str(exc).replace("hand in a .zip holding your exercises folder", "give the release's folder "
                                                                                      "or its zip")
            raise UpdateRefused(f"{path} cannot be read as a release: {message}") from None
        yield release_folder(Path(scratch))


def check_versions(old: dict, new: dict) -> bool:
    """True when the new release is newer than the course folder; False when it is the
    same release (nothing to do); UpdateRefused otherwise."""
    if new.get("edition") != "student":
        raise UpdateRefused(f"that is the {new.get('edition')!r} edition of the release, not the student edition: "
                            "give the student/ folder")
    if new.get("files") == old.get("files"):
        return False
    old_key, new_key = version_key(old.get("version")), version_key(new.get("version"))
    if new_key is not None and old_key is not None:
        if new_key == old_key:
            raise UpdateRefused(f"the release is {_describe(new)}, the version your folder already has, but its "
                                "files differ from the ones you were given: ask your instructor which one is right")
        if new_key < old_key:
            raise UpdateRefused(f"the release is {_describe(new)}, older than your folder's "
                                f"{_describe(old)}: nothing to take from it")
        return True
    if new_key is None and old_key is not None:
        raise UpdateRefused(f"the release has no version and your folder is {_describe(old)}: it cannot be told "
                            "apart from an older release; ask your instructor for the newest one")
    if new_key is None and str(new.get("created") or "") <= str(old.get("created") or ""):
        raise UpdateRefused(f"the release ({_describe(new)}) is not newer than your folder ({_describe(old)})")
    return True


# Merging --------------------------------------------------------------------------------------
def _lines(text: str) -> list[str]:
    if text and not text.endswith("\n"):
        text += "\n"   # a last line without newline would carry a conflict marker on its end
    return text.splitlines(keepends=True)


def merge_text(base: str, yours: str, theirs: str, label: str) -> tuple[str, int]:
    """3-way merge of ``yours`` and ``theirs`` against ``base``: (text, conflicts).
    Conflicting lines are kept both, between ``<<<<<<< yours`` and ``>>>>>>> label``."""
    try:
        import merge3
    except ImportError:
        raise UpdateRefused("the package merge3 is missing from this Python: run `bash run.sh setup`, then the "
                            "update again") from None
    merger = merge3.Merge3(_lines(base), _lines(yours), _lines(theirs))
    regions = list(merger.reprocess_merge_regions(merger.merge_regions()))
    conflicts = sum(1 for region in regions if region[0] == "conflict")
    text = "".join(merger.merge_lines(name_a=YOURS, name_b=label, start_marker=START, mid_marker=MIDDLE,
                                      end_marker=END, reprocess=True))
    return text, conflicts


def beside(relative: str, version: str) -> str:
    """Where the release's copy of a file that cannot be merged goes: ``book/02.ipynb``
    -> ``book/02.release-1.0.1.ipynb``."""
    path = PurePosixPath(relative)
    return str(path.with_name(f"{path.stem}.release-{version}{path.suffix}"))


# The plan ---------------------------------------------------------------------------------------
@dataclass
class Step:
    """What the update does to one file of the course folder."""

    path: str
    action: str        # see ACTIONS
    note: str = ""
    data: bytes | None = None    # what to write at path (replace, add, merge, conflict)
    beside: str | None = None    # the release's copy written there (keep-beside)
    conflicts: int = 0


#: Action -> (heading of the summary, does it change the file at ``path``?).
ACTIONS = {
    "replace": ("replaced (you had not changed them)", True),
    "add": ("added by the release", True),
    "restore": ("restored (you had deleted them; the release changed them)", True),
    "notebook": ("replaced (notebooks you had only run: their outputs were yours, the cells the release's)", True),
    "merge": ("merged (your changes kept, the release's added)", True),
    "remove": ("removed by the release (you had not changed them)", True),
    "keep-removed": ("kept as you left them (the release removed them, you had changed them)", False),
    "keep-beside": ("kept as you left them; the release's copy written beside", False),
    "conflict": ("CONFLICTS", True),
}


@dataclass
class Plan:
    course: Path
    release: Path
    old: dict
    new: dict
    steps: list[Step] = field(default_factory=list)

    @property
    def label(self) -> str:
        return f"release {self.new.get('version') or str(self.new.get('created') or '')[:10]}"

    def changing(self) -> list[Step]:
        return [s for s in self.steps if ACTIONS[s.action][1] or s.beside]

    def attention(self) -> list[Step]:
        return [s for s in self.steps if s.action in ("conflict", "keep-beside", "keep-removed")]


def plan_update(course: Path, release: Path, old: dict, new: dict) -> Plan:
    """Decide what happens to each file of the old and the new release (see the module
    docstring); reads the course folder, changes nothing."""
    plan = Plan(course, release, old, new)
    old_files: dict = old.get("files") or {}
    new_files: dict = new.get("files") or {}
    originals = read_originals(course)
    old_notebooks = old.get("notebook_sources") or {}
    version = str(new.get("version") or str(new.get("created") or "new")[:10])
    for relative in sorted(set(old_files) | set(new_files)):
        if relative in (MARKER, ORIGINALS) or PurePosixPath(relative).is_absolute() or ".." in relative.split("/"):
            continue
        was, now = old_files.get(relative), new_files.get(relative)
        if was == now:
            continue   # the release did not change it: whatever you did to it stays
        here = course / relative
        if here.is_symlink() or (here.exists() and not here.is_file()):
            plan.steps.append(Step(relative, "keep-beside" if now else "keep-removed",
                                   "it is not a regular file here", beside=beside(relative, version) if now else None))
            continue
        current = _sha256(here) if here.is_file() else None
        if current is not None and current == now:
            continue   # it already is the release's
        if now is None:
            if current is None:
                continue
            if current == was:
                plan.steps.append(Step(relative, "remove"))
            else:
                plan.steps.append(Step(relative, "keep-removed"))
            continue
        theirs = (release / relative).read_bytes()
        if current is None:
            plan.steps.append(Step(relative, "add" if was is None else "restore", data=theirs))
        elif current == was:
            plan.steps.append(Step(relative, "replace", data=theirs))
        elif was is None:
            plan.steps.append(Step(relative, "keep-beside", "you have a file of your own with this name",
                                   beside=beside(relative, version)))
        else:
            plan.steps.append(_merge_step(relative, here.read_bytes(), theirs, originals.get(relative),
                                          old_notebooks.get(relative), plan.label, version))
    return plan


def _merge_step(relative: str, yours: bytes, theirs: bytes, base: bytes | None, notebook: str | None,
                label: str, version: str) -> Step:
    """A file both the student and the release changed."""
    if relative.endswith(".ipynb"):
        if notebook is not None and notebook_sources(yours) == notebook:
            return Step(relative, "notebook", data=theirs)
        return Step(relative, "keep-beside", "you edited its cells", beside=beside(relative, version))
    if base is None:
        return Step(relative, "keep-beside", "your course folder keeps no original of it to merge with",
                    beside=beside(relative, version))
    try:
        texts = [data.decode("utf-8") for data in (base, yours, theirs)]
    except UnicodeDecodeError:
        return Step(relative, "keep-beside", "it is not text", beside=beside(relative, version))
    merged, conflicts = merge_text(*texts, label=label)
    note = "it held conflict markers before this update" if f"\n{START} {YOURS}" in "\n" + texts[1] else ""
    return Step(relative, "conflict" if conflicts else "merge", note, data=merged.encode("utf-8"),
                conflicts=conflicts)


# Doing it ----------------------------------------------------------------------------------------
def _write(path: Path, data: bytes, mode: int | None) -> None:
    """Write ``path`` whole or not at all (a new file renamed into place: a script being
    read keeps its old content)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".update", dir=path.parent)
    try:
        with os.fdopen(handle, "wb") as sink:
            sink.write(data)
        if mode is not None:
            os.chmod(temporary, stat.S_IMODE(mode))
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def backup(plan: Plan, stamp: str) -> Path:
    """Copy ``exercises/``, the notebooks of ``book/``, the marker and every file the plan
    changes or removes into a new folder ``backups/update-<stamp>``; its path."""
    base = plan.course / BACKUPS
    if base.exists() and not base.is_dir():
        raise UpdateRefused(f"{base} is a file: the update keeps its backups in a folder of that name; move it away")
    target = base / f"update-{stamp}"
    number = 1
    while target.exists():
        number += 1
        target = base / f"update-{stamp}-{number}"
    wanted = {s.path for s in plan.changing()} | {s.beside for s in plan.steps if s.beside}
    for folder, pattern in (("exercises", "**/*"), ("book", "*.ipynb")):
        for path in (plan.course / folder).glob(pattern):
            relative = path.relative_to(plan.course)
            if path.is_file() and not path.is_symlink() and "__pycache__" not in relative.parts \
                    and path.suffix != ".pyc":
                wanted.add(relative.as_posix())
    wanted |= {MARKER, ORIGINALS}
    for relative in sorted(wanted):
        source = plan.course / relative
        if source.is_file() and not source.is_symlink():
            destination = target / relative
            destination.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, destination)
    target.mkdir(parents=True, exist_ok=True)
    return target


def apply(plan: Plan) -> None:
    """Change the course folder as planned, then make its marker the new release's."""
    for step in plan.steps:
        here = plan.course / step.path
        if step.action == "remove":
            here.unlink(missing_ok=True)
        elif step.data is not None:
            mode = here.stat().st_mode if here.is_file() else (plan.release / step.path).stat().st_mode
            _write(here, step.data, mode)
        if step.beside:
            source = plan.release / step.path
            _write(plan.course / step.beside, source.read_bytes(), source.stat().st_mode)
    for name in (ORIGINALS, MARKER):   # the marker last: an interrupted update is redone by a rerun
        source = plan.release / name
        if source.is_file():
            _write(plan.course / name, source.read_bytes(), None)
        elif name == ORIGINALS:
            (plan.course / name).unlink(missing_ok=True)


def changelog_text(plan: Plan) -> str:
    """What the release says changed since the course folder's version."""
    path = plan.release / CHANGELOG
    sections = []
    if path.is_file():
        sections = newer_sections(path.read_text(encoding="utf-8", errors="replace"), plan.old.get("version"))
    if not sections and plan.new.get("changes"):
        sections = [(str(plan.new.get("version")), str(plan.new["changes"]))]
    return "\n".join(f"## {version}\n{text}\n" for version, text in sections)


def report(plan: Plan, backup_folder: Path | None, dry_run: bool) -> str:
    """The summary printed at the end: what was done, the changelog, and last the files
    that need the student's attention."""
    lines = [f"{'would update' if dry_run else 'updated'} your course folder from {_describe(plan.old)} to "
             f"{_describe(plan.new)}"]
    if backup_folder is not None:
        lines.append(f"backup of your files before the update: {backup_folder} (exercises/, the notebooks and "
                     "every file changed or removed)")
    for action, (heading, _) in ACTIONS.items():
        steps = [s for s in plan.steps if s.action == action]
        if action == "conflict" or not steps:
            continue
        lines.append(f"{heading}: {len(steps)}")
        for step in steps:
            extra = f" (release's copy: {step.beside})" if step.beside else ""
            lines.append(f"  {step.path}{extra}" + (f"; {step.note}" if step.note else ""))
    if any(s.path == "pyproject.toml" and s.data is not None for s in plan.steps):
        lines.append("the course's packages changed (pyproject.toml): the next `bash run.sh` command installs them")
    changes = changelog_text(plan)
    if changes:
        lines += ["", "What changed in the release:", changes.rstrip()]
    conflicts = [s for s in plan.steps if s.action == "conflict"]
    if conflicts:
        lines += ["", f"CONFLICTS in {len(conflicts)} file{'s' * (len(conflicts) > 1)}: you and the release changed "
                      "the same lines. Each file keeps both versions, yours between "
                      f"'{START} {YOURS}' and '{MIDDLE}', the release's between '{MIDDLE}' and "
                      f"'{END} {plan.label}'. Edit each place to what it should be and delete the three marker "
                      "lines; until then the file does not run:"]
        for step in conflicts:
            lines.append(f"  {step.path}: {step.conflicts} place{'s' * (step.conflicts > 1)}"
                         + (f" ({step.note})" if step.note else ""))
    others = [s for s in plan.attention() if s.action != "conflict"]
    if others:
        lines += ["", "Look at these files too (kept as you left them):"]
        lines += [f"  {s.path}" + (f": the release's copy is {s.beside}" if s.beside else
                                   ": the release removed it") for s in others]
    return "\n".join(lines)


def update(course: str | os.PathLike, release: str | os.PathLike, dry_run: bool = False,
           out=print) -> int:
    """Update the course folder ``course`` to the release at ``release`` (a folder or a
    zip); print what happened with ``out``; the exit status (:data:`DONE`,
    :data:`ATTENTION`).  UpdateRefused, with nothing changed, when it cannot be done."""
    course = Path(course).expanduser().resolve()
    old = course_marker(course)
    with opened_release(release) as folder:
        folder = folder.resolve()
        if folder == course:
            raise UpdateRefused(f"{folder} is your course folder itself: give the folder of the new release")
        new = read_marker(folder)
        if new is None:
            raise UpdateRefused(f"{folder} is not a release of the course: its {MARKER} is not one "
                                "`grader release` writes")
        if not check_versions(old, new):
            out(f"your course folder is already at {_describe(new)}: nothing to do")
            return DONE
        plan = plan_update(course, folder, old, new)
        if dry_run:
            out(report(plan, None, True))
            out("(--dry-run: nothing was changed)")
            return ATTENTION if plan.attention() else DONE
        saved = backup(plan, time.strftime("%Y%m%d-%H%M%S"))
        try:
            apply(plan)
        except OSError as exc:
            raise UpdateRefused(f"the update stopped half way ({exc}); your files as they were are in {saved}; "
                                "run the same update again to finish it") from None
        shown = saved.relative_to(course) if course in saved.parents else saved
        out(report(plan, shown, False))
        return ATTENTION if plan.attention() else DONE


# Command line -----------------------------------------------------------------------------------
def add_update_arguments(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    parser.add_argument("release", metavar="NEW_RELEASE",
                        help="the new release your instructor handed out: its folder (or the folder holding "
                             "student/), or a zip of it")
    parser.add_argument("--course", default=".", metavar="DIR",
                        help="your course folder (default: this folder)")
    parser.add_argument("--dry-run", action="store_true", help="say what the update would do; change nothing")
    return parser


def main_update(args: argparse.Namespace) -> int:
    try:
        return update(args.course, args.release, dry_run=args.dry_run)
    except UpdateRefused as exc:
        print(f"grader update: nothing was changed: {exc}", file=sys.stderr)
        return REFUSED


def main(argv: list[str] | None = None) -> int:
    parser = add_update_arguments(argparse.ArgumentParser(prog="grader update", description=__doc__.split("\n")[0]))
    return main_update(parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
