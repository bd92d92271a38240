"""``grader submit``: the hand-in zip and its manifest, and the grader's check of it.

Most tests open the zip as the grader does (:func:`grader.batch.submissions.opened`) without
running any graded test; one batch grades a submitted zip, a tampered one and the same
two unpacked (as Gradescope unpacks an uploaded zip) on the momentum tests.
"""
from __future__ import annotations

import hashlib
import importlib
import io
import json
import os
import re
import shutil
import struct
import zipfile
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path
from types import SimpleNamespace

import pytest

import grader
from grader.cli import main as cli_main
from grader.batch.grade import grade_submissions
from grader.harness.run import load_spec
from grader.batch.submissions import (MANIFEST_NAME, Submission, SubmissionRefused, opened, safe_extract,
                                verify_manifest)
from grader.student.submit import SubmitError, collect_files, submit, write_submission, zip_name

# `grader.submit` and `grader.check` are the notebook functions; these are their modules.
submit_module = importlib.import_module("grader.student.submit")
check_module = importlib.import_module("grader.student.check")
REPO = Path(__file__).resolve().parent.parent
REFERENCE = REPO / "solutions"
IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc")


def course(tmp_path: Path, package: Path = REFERENCE, name: str = "course") -> Path:
    """A student's course folder holding a copy of ``package`` as ``exercises/``."""
    folder = tmp_path / name
    shutil.copytree(package, folder / "exercises", ignore=IGNORE)
    return folder


def members(path: Path) -> dict[str, bytes]:
    with zipfile.ZipFile(path) as archive:
        return {info.filename: archive.read(info) for info in archive.infolist()}


def rewrite(source: Path, target: Path, change) -> Path:
    """A copy of the zip ``source`` whose members pass through ``change(name, data)``
    (None drops a member); ``change`` may return extra (name, data) pairs under key None."""
    with zipfile.ZipFile(source) as old, zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as new:
        for info in old.infolist():
            data = change(info.filename, old.read(info))
            if data is not None:
                new.writestr(info, data)
        for name, data in change(None, None) or []:
            new.writestr(name, data)
    return target


def refusal(path: Path, tmp_path: Path) -> str:
    with pytest.raises(SubmissionRefused) as caught:
        with opened(Submission("s", path, "zip"), tmp_path):
            pass
    return str(caught.value)


@pytest.fixture()
def handed_in(tmp_path):
    folder = course(tmp_path)
    result = write_submission(folder / "exercises", tmp_path / "out", name="Ada Lovelace")
    return SimpleNamespace(folder=folder, result=result, zip=result.path)


# The zip ---------------------------------------------------------------------------------------
def test_the_zip_holds_the_package_and_a_manifest_of_every_file(handed_in):
    assert re.fullmatch(r"submission-Ada_Lovelace-\d{8}-\d{6}\.zip", handed_in.zip.name)
    assert handed_in.zip.parent.name == "out"
    content = members(handed_in.zip)
    manifest = json.loads(content.pop(MANIFEST_NAME))
    assert manifest["format"] == "collision-course-submission" and manifest["format_version"] == 1
    assert manifest["course"] == "collision-course" and manifest["student"] == "Ada Lovelace"
    assert re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d[+-]\d\d:\d\d", manifest["created"])
    listed = {e["path"]: e for e in manifest["files"]}
    assert set(listed) == set(content) and all(name.startswith("exercises/") for name in content)
    for name, data in content.items():
        assert listed[name]["size"] == len(data)
        assert listed[name]["sha256"] == hashlib.sha256(data).hexdigest()
    on_disk = {f"exercises/{p.relative_to(handed_in.folder / 'exercises').as_posix()}"
               for p in (handed_in.folder / "exercises").rglob("*")
               if p.is_file() and p.suffix in (".py", ".md", ".txt", ".json") and not p.name.startswith(".")}
    assert set(content) == on_disk and "exercises/__init__.py" in content
    assert manifest["file_count"] == len(content) and manifest["total_bytes"] == sum(map(len, content.values()))


def test_the_grader_accepts_the_zip_as_written(handed_in, tmp_path):
    with opened(Submission("s", handed_in.zip, "zip"), tmp_path) as folder:
        assert (folder / MANIFEST_NAME).is_file() and (folder / "exercises" / "__init__.py").is_file()
    unpacked = tmp_path / "unpacked"  # what Gradescope makes of an uploaded zip
    safe_extract(handed_in.zip, unpacked)
    assert verify_manifest(unpacked)["student"] == "Ada Lovelace"


def test_only_allowed_regular_files_go_in(tmp_path):
    folder = course(tmp_path)
    package = folder / "exercises"
    (package / "__pycache__").mkdir(exist_ok=True)
    (package / "__pycache__" / "world.cpython-311.pyc").write_bytes(b"\0")
    (package / "stray.pyc").write_bytes(b"\0")
    (package / ".ipynb_checkpoints").mkdir()
    (package / ".ipynb_checkpoints" / "world-checkpoint.py").write_text("x = 1\n")
    (package / ".secret.json").write_text("{}")
    (package / "notes.md").write_text("# my notes\n")
    (package / "data.csv").write_text("1,2\n")
    (package / "response" / "plot.png").write_bytes(b"\x89PNG")
    files, left_out = collect_files(package)
    names = [name for name, _ in files]
    assert "notes.md" in names and "response/momentum_1d.py" in names
    assert not [n for n in names if "__pycache__" in n or n.endswith(".pyc") or "/." in "/" + n]
    assert left_out == ["data.csv", "response/plot.png"]
    out = io.StringIO()
    with redirect_stdout(out):
        result = submit(package=package, out=tmp_path / "zips")
    text = out.getvalue()
    assert "wrote " in text and result.path.name in text
    assert "2 other files left out" in text and "data.csv, response/plot.png" in text
    assert "exercises/data.csv" not in members(result.path)


def test_a_symbolic_link_is_refused_by_name(tmp_path):
    folder = course(tmp_path)
    package = folder / "exercises"
    os.symlink(package / "vector.py", package / "response" / "linked.py")
    with pytest.raises(SubmitError, match=r"symbolic link.*exercises/response/linked\.py"):
        write_submission(package, tmp_path)
    (package / "response" / "linked.py").unlink()
    os.symlink(tmp_path, package / "elsewhere")  # a link to a folder, too
    with pytest.raises(SubmitError, match=r"exercises/elsewhere"):
        write_submission(package, tmp_path)
    assert not list(tmp_path.glob("*.zip")) and not list(tmp_path.glob(".*.tmp"))
    err = io.StringIO()
    with redirect_stderr(err):
        assert cli_main(["submit", "--package", str(package), "--out", str(tmp_path)]) == 2
    assert "exercises/elsewhere" in err.getvalue() and "symbolic link" in err.getvalue()


def test_caps_on_files_and_bytes(tmp_path, monkeypatch):
    package = course(tmp_path) / "exercises"
    monkeypatch.setattr(submit_module, "MAX_FILES", 5)
    with pytest.raises(SubmitError, match="at most 4 are accepted"):
        write_submission(package, tmp_path)
    monkeypatch.setattr(submit_module, "MAX_FILES", 2000)
    monkeypatch.setattr(submit_module, "MAX_TOTAL_BYTES", 1000)
    with pytest.raises(SubmitError, match="add up to"):
        write_submission(package, tmp_path)


def test_zip_name_and_where_it_goes(tmp_path, monkeypatch):
    assert re.fullmatch(r"submission-Jose_Garcia-20250301-140509\.zip",
                        zip_name("José García", (2025, 3, 1, 14, 5, 9, 0, 0, 0)))
    monkeypatch.setattr(submit_module.getpass, "getuser", lambda: "ada")
    assert zip_name(None).startswith("submission-ada-")
    folder = course(tmp_path)
    monkeypatch.chdir(folder)  # found as `grader check` finds it: ./exercises
    result = submit(show=False)
    assert result.path.parent == folder and result.path.name.startswith("submission-ada-")
    assert result.manifest["student"] is None
    exact = submit(out=tmp_path / "handin" / "mine.zip", show=False)
    assert exact.path == tmp_path / "handin" / "mine.zip" and exact.path.is_file()


def test_submit_is_exported_for_notebooks_and_runs_the_checks_when_asked(tmp_path, monkeypatch):
    assert grader.submit is submit and "submit" in grader.__all__
    calls = []

    class Report:
        score, max_score = 4.0, 6.0

        def summary(self):
            return "Score 4/6 points: 2 passed, 1 failed."

    def fake_run_check(exercise, package):
        calls.append((exercise, Path(package)))
        return Report()

    monkeypatch.setattr(submit_module, "run_check", fake_run_check)
    package = course(tmp_path) / "exercises"
    out = io.StringIO()
    with redirect_stdout(out):
        code = cli_main(["submit", "--package", str(package), "--out", str(tmp_path), "--check", "--name", "ada"])
    assert code == 0 and calls == [(None, package)]
    text = out.getvalue()
    assert "public tests: Score 4/6 points" in text and "wrote " in text and "hand in this zip" in text
    assert len(list(tmp_path.glob("submission-ada-*.zip"))) == 1
    result = submit(package=package, out=tmp_path / "again", check=True, show=False)
    assert (result.check_score, result.check_max_score) == (4.0, 6.0)


# Tampering ---------------------------------------------------------------------------------------
def test_a_changed_file_is_refused_naming_it(handed_in, tmp_path):
    changed = rewrite(handed_in.zip, tmp_path / "changed.zip",
                      lambda n, d: None if n is None else d + b"# edited\n" if n == "exercises/vector.py" else d)
    message = refusal(changed, tmp_path)
    assert "exercises/vector.py" in message and "was changed after `bash run.sh submit` wrote the zip" in message
    assert "run `bash run.sh submit` again" in message


def test_an_added_or_removed_file_is_refused(handed_in, tmp_path):
    added = rewrite(handed_in.zip, tmp_path / "added.zip",
                    lambda n, d: [("exercises/extra.py", b"x = 1\n")] if n is None else d)
    assert "exercises/extra.py' is not in MANIFEST.json: it was added after" in refusal(added, tmp_path)
    removed = rewrite(handed_in.zip, tmp_path / "removed.zip",
                      lambda n, d: None if n in (None, "exercises/world.py") else d)
    assert "exercises/world.py' is listed in MANIFEST.json but missing" in refusal(removed, tmp_path)
    both = rewrite(handed_in.zip, tmp_path / "both.zip",
                   lambda n, d: [("exercises/extra.py", b"")] if n is None else None if n == "exercises/world.py"
                   else d)
    assert "(and 1 more difference)" in refusal(both, tmp_path)


def test_a_damaged_or_foreign_manifest_is_refused(handed_in, tmp_path):
    def with_manifest(text: bytes):
        return lambda n, d: None if n is None else text if n == MANIFEST_NAME else d

    broken = rewrite(handed_in.zip, tmp_path / "broken.zip", with_manifest(b"{ not json"))
    assert "MANIFEST.json is damaged" in refusal(broken, tmp_path)
    manifest = json.loads(members(handed_in.zip)[MANIFEST_NAME])
    foreign = rewrite(handed_in.zip, tmp_path / "foreign.zip",
                      with_manifest(json.dumps({**manifest, "course": "another-course"}).encode()))
    assert "written for the course 'another-course'" in refusal(foreign, tmp_path)
    escaping = {**manifest, "files": manifest["files"] + [{"path": "../outside.py", "sha256": "0", "size": 0}]}
    climbing = rewrite(handed_in.zip, tmp_path / "climbing.zip", with_manifest(json.dumps(escaping).encode()))
    assert "impossible path" in refusal(climbing, tmp_path)


def test_an_unpacked_submission_with_a_manifest_is_checked_too(handed_in, tmp_path):
    unpacked = tmp_path / "unpacked"
    safe_extract(handed_in.zip, unpacked)
    (unpacked / "exercises" / "__pycache__").mkdir()
    (unpacked / "exercises" / "__pycache__" / "x.cpython-311.pyc").write_bytes(b"\0")  # never read: ignored
    with opened(Submission("u", unpacked, "folder")) as folder:
        assert folder == unpacked
    os.symlink(unpacked / "exercises" / "vector.py", unpacked / "exercises" / "alias.py")
    with pytest.raises(SubmissionRefused, match="alias.py' is a symbolic link"):
        verify_manifest(unpacked)
    (unpacked / "exercises" / "alias.py").unlink()
    (unpacked / "exercises" / "body.py").write_text("# rewritten\n")
    with pytest.raises(SubmissionRefused, match="body.py' was changed after"):
        with opened(Submission("u", unpacked, "folder")):
            pass
    with opened(Submission("u", unpacked, "folder"), verify=False) as folder:  # what similarity reads
        assert folder == unpacked


def test_zips_without_a_manifest_are_opened_as_before(tmp_path):
    plain = tmp_path / "plain.zip"
    with zipfile.ZipFile(plain, "w") as archive:
        archive.writestr("exercises/__init__.py", b"")
        archive.writestr("exercises/notes.md", b"my notes\n")
    with opened(Submission("p", plain, "zip"), tmp_path) as folder:
        assert verify_manifest(folder) is None and (folder / "exercises" / "notes.md").is_file()
    with zipfile.ZipFile(plain, "a") as archive:  # only source, manifest or not
        archive.writestr("exercises/anything.bin", b"\0\1")
    assert "'exercises/anything.bin' (not source)" in refusal(plain, tmp_path)


# Grading -------------------------------------------------------------------------------------------
def test_a_submitted_zip_grades_and_a_tampered_one_is_refused(handed_in, tmp_path):
    momentum = [t for t in load_spec() if t.exercise == "momentum"]
    assert momentum, "the momentum tests are the graded tests this batch runs"
    subs = tmp_path / "subs"
    subs.mkdir()
    good = shutil.copy(handed_in.zip, subs / "ada.zip")
    tampered = rewrite(handed_in.zip, subs / "eve.zip", lambda n, d: None if n is None else
                       d.replace(b"return", b"return  ", 1) if n == "exercises/response/momentum_1d.py" else d)
    gradescope = subs / "gradescope"  # Gradescope unpacks an uploaded zip into the submission folder
    safe_extract(handed_in.zip, gradescope)
    (gradescope / "exercises" / "response" / "momentum_1d.py").write_text("# lost my work\n")
    rows = {r["id"]: r for r in grade_submissions([good, tampered, gradescope], tmp_path / "out", jobs=2,
                                                  tests=momentum, progress=False, html=False)}
    assert rows["ada"]["state"] == "graded"
    assert rows["ada"]["score"] == pytest.approx(sum(t.points for t in momentum)) == rows["ada"]["max_score"]
    for name in ("eve", "gradescope"):
        assert rows[name]["state"] == "refused" and rows[name]["score"] == 0
        assert "exercises/response/momentum_1d.py' was changed after `bash run.sh submit` wrote the zip" \
            in rows[name]["message"]


# Issue 24: only source, refusals in bounded time ---------------------------------------------------
def test_bytecode_and_archives_in_the_package_are_refused_naming_them(tmp_path):
    folder = course(tmp_path)
    package = folder / "exercises"
    with opened(Submission("s", folder, "folder"), tmp_path):
        pass  # the reference as it is: source only
    (package / "__pycache__").mkdir(exist_ok=True)
    (package / "__pycache__" / "world.cpython-311.pyc").write_bytes(b"\0litter")  # never read nor copied
    with opened(Submission("s", folder, "folder"), tmp_path):
        pass
    for name, data in (("response/momentum_1d.pyc", b"\xa7\r\r\n" + bytes(12)), ("fast.cpython-311-x86_64-linux-gnu.so",
                       b"\x7fELF"), ("hook.pth", b"import os\n"), ("notes.txt", b"PK\x05\x06" + bytes(18))):
        (package / name).write_bytes(data)
        with pytest.raises(SubmissionRefused, match="only source is graded") as refused:
            with opened(Submission("s", folder, "folder"), tmp_path):
                pass
        assert f"exercises/{name}" in str(refused.value)
        (package / name).unlink()


def test_a_pyc_counts_in_the_manifest_and_the_fingerprint(handed_in, tmp_path):
    from grader.batch.submissions import fingerprint
    unpacked = tmp_path / "unpacked"
    safe_extract(handed_in.zip, unpacked)
    before = fingerprint(unpacked)
    (unpacked / "exercises" / "vector.pyc").write_bytes(b"\0")
    assert fingerprint(unpacked) != before
    with pytest.raises(SubmissionRefused, match="vector.pyc' is not in MANIFEST.json"):
        verify_manifest(unpacked)


def _extra_field_zip(path: Path, members: int) -> Path:
    """Members whose 64 KiB extra fields hold 4-byte records: zipfile parses each in
    time quadratic in its length."""
    extra = b"\xaa\xaa\x00\x00" * (65532 // 4)
    with zipfile.ZipFile(path, "w") as archive:
        for n in range(members):
            info = zipfile.ZipInfo(f"exercises/f{n}.py")
            info.extra = extra
            archive.writestr(info, b"")
    return path


def test_zip_directories_over_the_caps_are_refused_before_zipfile_parses_them(tmp_path):
    import time
    slow = _extra_field_zip(tmp_path / "slow.zip", 60)  # 3.9 MB of directory: under the size cap
    started = time.perf_counter()
    zipfile.ZipFile(slow).close()
    parse_seconds = time.perf_counter() - started
    started = time.perf_counter()
    assert "extra field or comment of 65532 bytes" in refusal(slow, tmp_path)
    refuse_seconds = time.perf_counter() - started
    assert refuse_seconds < 0.2 and refuse_seconds < parse_seconds / 5, (refuse_seconds, parse_seconds)
    # An end record claiming more entries, or a larger directory, than the caps: read from it alone.
    for count, size, words in ((70_000, 1000, "70000 entries"), (10, 50 * 1024**2, "takes 50.0 MiB")):
        fake = tmp_path / f"fake-{count}.zip"
        fake.write_bytes(b"PK\x05\x06" + struct.pack("<HHHHIIH", 0, 0, count & 0xFFFF, count & 0xFFFF, size, 0, 0)
                         if count < 0x10000 else _zip64_end(count, size))
        started = time.perf_counter()
        assert words in refusal(fake, tmp_path)
        assert time.perf_counter() - started < 0.1


def _zip64_end(count: int, size: int) -> bytes:
    record = b"PK\x06\x06" + struct.pack("<QHHIIQQQQ", 44, 45, 45, 0, 0, count, count, size, 0)
    locator = b"PK\x06\x07" + struct.pack("<IQI", 0, 0, 1)
    end = b"PK\x05\x06" + struct.pack("<HHHHIIH", 0, 0, 0xFFFF, 0xFFFF, 0xFFFFFFFF, 0xFFFFFFFF, 0)
    return record + locator + end


def test_a_deeply_nested_manifest_is_refused_not_a_grader_error(handed_in, tmp_path):
    unpacked = tmp_path / "unpacked"
    safe_extract(handed_in.zip, unpacked)
    for text in ("[" * 200_000 + "]" * 200_000, '{"format": ' + '{"a": ' * 100_000 + "1" + "}" * 100_001):
        (unpacked / MANIFEST_NAME).write_text(text)
        with pytest.raises(SubmissionRefused, match="nests .* levels deep; a manifest nests at most 8"):
            verify_manifest(unpacked)
