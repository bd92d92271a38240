"""Batch grading (``grader grade``): scores, resuming, results files, gradebook, bad input.

The reference engine (``solutions/``, handed in as a student's ``exercises``) must get
full marks and the stubs (``exercises/``) zero.  Hostile archives are refused before a
byte of them is written.  Kept short: a handful of submissions, most of them stubs.
"""
from __future__ import annotations

import csv
import json
import math
import os
import shutil
import signal
import stat
import subprocess
import sys
import time
import types
import warnings
import zipfile
from pathlib import Path
from types import SimpleNamespace

import pytest

from grader.errors import GradingError
from grader.batch.grade import grade_submissions
from grader.batch.gradebook import spec_hash, write_gradebook
from grader.harness.outcome import Outcome
from grader.harness.outcome import TestResult as Result
from grader.reports import results as gs_results
from grader.harness import run as grader_run
from grader.harness.results_model import leaderboard, plain
from grader.reports.results import build_results, check_results
from grader.sandbox.process import Limits
from grader.harness.spec import VISIBILITIES
from grader.harness.run import load_spec
from grader.batch.submissions import (MAX_FILES, Submission, SubmissionPathError, SubmissionRefused, discover,
                                fingerprint, opened, safe_extract, submission_id)

REPO = Path(__file__).resolve().parent.parent
REFERENCE = REPO / "solutions"
STUBS = REPO / "exercises"
IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc")


# Building submissions --------------------------------------------------------------------
def folder_submission(path: Path, package: Path = STUBS) -> Path:
    shutil.copytree(package, path / "exercises", ignore=IGNORE)
    return path


def zip_submission(path: Path, package: Path = STUBS, prefix: str = "exercises") -> Path:
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        for file in sorted(package.rglob("*")):
            if file.is_file() and "__pycache__" not in file.parts:
                name = file.relative_to(package).as_posix()
                archive.write(file, f"{prefix}/{name}" if prefix else name)
    return path


def stub_zip_with(path: Path, *extra: tuple[zipfile.ZipInfo | str, bytes]) -> Path:
    """The stubs as a zip, plus hostile members."""
    zip_submission(path)
    with zipfile.ZipFile(path, "a") as archive:
        for info, data in extra:
            archive.writestr(info, data)
    return path


def symlink_member(name: str, target: str) -> zipfile.ZipInfo:
    info = zipfile.ZipInfo(name)
    info.create_system = 3
    info.external_attr = (stat.S_IFLNK | 0o777) << 16
    return info


def bomb(path: Path, megabytes: int = 70) -> Path:
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("exercises/__init__.py", b"")
        with archive.open("exercises/padding.py", "w", force_zip64=True) as member:
            zeros = bytes(1 << 20)
            for _ in range(megabytes):
                member.write(zeros)
    return path


def total_points(tests) -> float:
    return sum(t.points for t in tests)


@pytest.fixture(scope="module")
def spec():
    return load_spec()


@pytest.fixture(scope="module")
def batch(tmp_path_factory, spec):
    """One graded class: reference folder, stub zips, and every kind of bad submission."""
    root = tmp_path_factory.mktemp("class")
    subs = root / "subs"
    subs.mkdir()
    paths = {
        "alice": folder_submission(subs / "alice", REFERENCE),
        "bob": zip_submission(subs / "bob.zip"),
        "flat": zip_submission(subs / "flat.zip", prefix=""),  # the package's files at the top
        "carol": subs / "carol",
        "dave": subs / "dave.zip",
        "dotdot": stub_zip_with(subs / "dotdot.zip", ("exercises/../../escaped.py", b"x = 1\n")),
        "absolute": stub_zip_with(subs / "absolute.zip", ("/tmp/escaped.py", b"x = 1\n")),
        "symlink": stub_zip_with(subs / "symlink.zip", (symlink_member("exercises/link.py", "/etc/passwd"),
                                                        b"/etc/passwd")),
        "bomb": bomb(subs / "bomb.zip"),
    }
    paths["carol"].mkdir()
    (paths["carol"] / "readme.txt").write_text("my answers are in my head\n")
    paths["dave"].write_text("this is not a zip\n")
    out = root / "out"
    started = time.perf_counter()
    rows = grade_submissions(list(paths.values()), out, jobs=2, progress=False)
    return SimpleNamespace(root=root, paths=paths, out=out, rows={r["id"]: r for r in rows},
                           order=[r["id"] for r in rows], seconds=time.perf_counter() - started, spec=spec)


def results_of(batch, name: str) -> dict:
    return json.loads((batch.out / name / "results.json").read_text())


# Scores ------------------------------------------------------------------------------------
def test_reference_scores_full_marks_and_stubs_zero(batch, spec):
    assert batch.rows["alice"]["state"] == "graded"
    assert batch.rows["alice"]["score"] == pytest.approx(total_points(spec))
    alice = results_of(batch, "alice")
    assert all(t["status"] == "passed" for t in alice["tests"]), [t["output"] for t in alice["tests"]
                                                                  if t["status"] != "passed"]
    for name in ("bob", "flat"):
        assert batch.rows[name]["state"] == "graded"
        assert batch.rows[name]["score"] == 0
        assert batch.rows[name]["max_score"] == pytest.approx(total_points(spec))
        statuses = {t["extra_data"]["status"] for t in results_of(batch, name)["tests"]}
        assert statuses == {"not_implemented"}


def test_rows_follow_the_order_given(batch):
    assert batch.order == list(batch.paths)


def test_folder_and_zip_submissions_find_their_package(batch):
    assert results_of(batch, "alice")["extra_data"]["package"] == "exercises"
    assert results_of(batch, "bob")["extra_data"]["package"] == "exercises"
    assert results_of(batch, "flat")["extra_data"]["package"] == "."


def test_every_test_is_reported_once_in_spec_order(batch, spec):
    for name in ("alice", "bob", "carol"):
        assert [t["extra_data"]["test"] for t in results_of(batch, name)["tests"]] == [t.name for t in spec]


def test_output_says_what_went_wrong_without_grader_tracebacks(batch):
    for test in results_of(batch, "bob")["tests"]:
        assert test["output"].startswith("Not implemented yet: 0 / ")
        assert "Traceback" not in test["output"] and "grader/" not in test["output"]


# Bad and hostile submissions ----------------------------------------------------------------
@pytest.mark.parametrize("name, words", [
    ("carol", "no exercises package found"),
    ("dave", "not a zip archive"),
    ("dotdot", "'..'"),
    ("absolute", "absolute path"),
    ("symlink", "symbolic link"),
    ("bomb", "zip bomb"),
])
def test_bad_submissions_get_zero_and_a_reason(batch, spec, name, words):
    row = batch.rows[name]
    assert row["state"] == "refused"
    data = results_of(batch, name)
    assert data["score"] == 0 and data["max_score"] == pytest.approx(total_points(spec))
    assert words in data["output"]
    assert data["extra_data"]["state"] == "refused" and words in data["extra_data"]["reason"]
    assert all(t["score"] == 0 for t in data["tests"]) and len(data["tests"]) == len(spec)


def test_hostile_archives_write_nothing_outside(batch):
    assert not (batch.root / "escaped.py").exists()
    assert not (batch.out / "escaped.py").exists()
    assert not list(batch.out.rglob("link.py"))


def test_refused_carol_lists_what_she_handed_in(batch):
    assert "readme.txt" in results_of(batch, "carol")["output"]


# results.json: Gradescope's format -----------------------------------------------------------
def assert_gradescope_results(data: dict) -> None:
    """Gradescope's autograder specification, written out independently of grader.reports.results."""
    def number(x):
        return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)

    json.dumps(data, allow_nan=False)
    assert number(data["score"]) and number(data["max_score"]) and number(data["execution_time"])
    assert isinstance(data["output"], str) and isinstance(data["extra_data"], dict)
    assert isinstance(data["tests"], list) and data["tests"]
    for test in data["tests"]:
        assert {"name", "score", "max_score", "status", "output", "visibility"} <= set(test)
        assert isinstance(test["name"], str) and isinstance(test["output"], str)
        assert number(test["score"]) and number(test["max_score"]) and 0 <= test["score"] <= test["max_score"]
        assert test["status"] in ("passed", "failed")
        assert test["visibility"] in ("visible", "hidden", "after_due_date", "after_published")
        assert test.get("output_format", "text") in ("text", "html", "simple_format", "md", "ansi")
        assert isinstance(test.get("extra_data", {}), dict)
    assert data["score"] == pytest.approx(sum(t["score"] for t in data["tests"]))
    for entry in data.get("leaderboard", []):
        assert isinstance(entry["name"], str) and number(entry["value"]) and entry.get("order") in ("asc", "desc")


def test_results_match_gradescope_format(batch):
    for name in batch.paths:
        data = results_of(batch, name)
        assert_gradescope_results(data)
        assert check_results(data) == []


def test_visibility_comes_from_the_spec(batch, spec):
    tests = results_of(batch, "alice")["tests"]
    assert [t["visibility"] for t in tests] == [t.visibility for t in spec]
    assert {t["visibility"] for t in tests} <= set(VISIBILITIES)
    assert {"visible", "hidden"} <= {t["visibility"] for t in tests}


def test_leaderboard_has_the_speed_tests_that_passed(batch, spec):
    board = results_of(batch, "alice")["leaderboard"]
    assert sorted(e["name"] for e in board) == sorted(t.leaderboard for t in spec if t.leaderboard)
    assert all(e["value"] > 0 and e["order"] == "asc" for e in board)
    assert results_of(batch, "bob")["leaderboard"] == []


def test_speed_figures_are_in_output_and_extra_data(batch):
    speed = next(t for t in results_of(batch, "alice")["tests"] if t["extra_data"]["test"] == "grid.speed")
    assert speed["extra_data"]["metrics"]["seconds"] > 0
    assert "time:" in speed["output"] and "reference engine" in speed["output"]


def test_results_record_fingerprint_and_spec(batch, spec):
    meta = results_of(batch, "bob")["extra_data"]
    assert meta["fingerprint"] == fingerprint(batch.paths["bob"])
    assert meta["spec_hash"] == spec_hash(spec)
    assert meta["submission_id"] == "bob"


# Gradebook ------------------------------------------------------------------------------------
def test_gradebook_has_one_row_per_submission(batch, spec):
    with open(batch.out / "gradebook.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert sorted(r["submission"] for r in rows) == sorted(batch.paths)
    header = list(rows[0])
    assert header[:3] == ["submission", "score", "max_score"]
    assert header[3:3 + len(spec)] == [t.name for t in spec]
    by_id = {r["submission"]: r for r in rows}
    assert float(by_id["alice"]["score"]) == pytest.approx(total_points(spec))
    assert float(by_id["bob"]["score"]) == 0
    for test in results_of(batch, "alice")["tests"]:
        assert float(by_id["alice"][test["extra_data"]["test"]]) == pytest.approx(test["score"])
    assert by_id["dave"]["state"] == "refused" and "not a zip" in by_id["dave"]["note"]


# Rerun, regrade, resume ------------------------------------------------------------------------
def test_rerun_skips_and_regrade_grades_again(batch):
    before = {name: (batch.out / name / "results.json").stat().st_mtime_ns for name in batch.paths}
    rows = grade_submissions(list(batch.paths.values()), batch.out, jobs=2, progress=False)
    assert {r["state"] for r in rows} == {"skipped"}
    assert {name: (batch.out / name / "results.json").stat().st_mtime_ns for name in batch.paths} == before
    again = grade_submissions([batch.paths["bob"], batch.paths["carol"]], batch.out, jobs=1, regrade=True,
                              progress=False)
    assert [r["state"] for r in again] == ["graded", "refused"]
    for name in ("bob", "carol"):
        assert (batch.out / name / "results.json").stat().st_mtime_ns > before[name]
    assert (batch.out / "alice" / "results.json").stat().st_mtime_ns == before["alice"]
    with open(batch.out / "gradebook.csv", newline="") as handle:  # still the whole class
        assert len(list(csv.DictReader(handle))) == len(batch.paths)


def test_a_changed_submission_or_spec_is_graded_again(tmp_path, spec):
    submission = folder_submission(tmp_path / "gina")
    out = tmp_path / "out"
    few = spec[:2]
    assert grade_submissions([submission], out, tests=few, progress=False)[0]["state"] == "graded"
    (submission / "exercises" / "__pycache__").mkdir(exist_ok=True)  # running it locally changes nothing
    (submission / "exercises" / "__pycache__" / "x.cpython-311.pyc").write_bytes(b"\0")
    assert grade_submissions([submission], out, tests=few, progress=False)[0]["state"] == "skipped"
    assert grade_submissions([submission], out, tests=spec[:3], progress=False)[0]["state"] == "graded"
    with open(submission / "exercises" / "vector.py", "a") as handle:
        handle.write("\n# edited\n")
    assert grade_submissions([submission], out, tests=spec[:3], progress=False)[0]["state"] == "graded"


def run_cli(*args, **kwargs):
    return subprocess.Popen([sys.executable, "-m", "grader.batch.grade", *map(str, args)], cwd=REPO,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kwargs)


def test_a_killed_batch_resumes_and_grades_each_submission_once(tmp_path):
    names = ["s1", "s2", "s3", "s4"]
    subs = [folder_submission(tmp_path / n) for n in names]
    out = tmp_path / "out"
    process = run_cli(*subs, "--out", out, "--jobs", "1", "--no-progress", start_new_session=True)
    deadline = time.monotonic() + 60
    try:
        while not list(out.glob("*/results.json")):
            assert process.poll() is None, process.communicate()
            assert time.monotonic() < deadline, "no results.json appeared in 60 s"
            time.sleep(0.02)
    finally:
        os.killpg(process.pid, signal.SIGKILL)
        process.communicate()
    done = {p.parent.name: p.stat().st_mtime_ns for p in out.glob("*/results.json")}
    assert 1 <= len(done) < len(names), "the batch ended before it could be killed"
    for name in done:
        assert json.loads((out / name / "results.json").read_text())["score"] == 0
    process = run_cli(*subs, "--out", out, "--jobs", "1", "--no-progress")
    stdout, stderr = process.communicate(timeout=120)
    assert process.returncode == 0, stderr
    assert f"{len(names) - len(done)} graded, {len(done)} skipped" in stdout
    for name in names:
        path = out / name / "results.json"
        assert path.exists()
        if name in done:
            assert path.stat().st_mtime_ns == done[name]
    assert not list(out.rglob("*.tmp")) and not (out / ".work").exists()


def test_html_reports_are_written_when_grader_report_exists(tmp_path, spec, monkeypatch):
    calls = []

    def write_student_report(results, html_path):
        assert results.tests and results.id == "lee"  # the model the grading made, not the file read back
        calls.append("student")
        Path(html_path).write_text("<html></html>")

    def broken(results_path, html_path):
        raise RuntimeError("no report today")

    fake = types.ModuleType("grader.reports.instructor")
    fake.write_student_report = write_student_report
    fake.write_class_report = lambda out_dir: calls.append(("class", Path(out_dir)))
    monkeypatch.setitem(sys.modules, "grader.reports.instructor", fake)
    submission = folder_submission(tmp_path / "lee")
    out = tmp_path / "out"
    grade_submissions([submission], out, tests=spec[:2], progress=False)
    assert (out / "lee" / "report.html").exists() and calls == ["student", ("class", out.resolve())]
    (out / "lee" / "report.html").unlink()  # killed between results.json and its report
    assert grade_submissions([submission], out, tests=spec[:2], progress=False)[0]["state"] == "skipped"
    assert (out / "lee" / "report.html").exists()
    fake.write_student_report = broken  # a failing report costs no grade
    row = grade_submissions([submission], out, tests=spec[:2], regrade=True, progress=False)[0]
    assert row["state"] == "graded" and (out / "lee" / "results.json").exists()


# Limits ---------------------------------------------------------------------------------------
def test_a_hanging_test_times_out_and_the_submission_goes_on(tmp_path, spec):
    submission = folder_submission(tmp_path / "harry")
    with open(submission / "exercises" / "response" / "momentum_1d.py", "a") as handle:
        handle.write("\n\ndef elastic_collision_1d(m1, v1, m2, v2):\n    while True:\n        pass\n\n\n"
                     "def collision_1d(m1, v1, m2, v2, restitution):\n    while True:\n        pass\n")
    tests = [t for t in spec if t.name in ("momentum.elastic", "momentum.restitution", "momentum.perfectly_inelastic")]
    row = grade_submissions([submission], tmp_path / "out", tests=tests, limits=Limits(call_timeout=60.0),
                            per_test_seconds=1.5, per_submission_seconds=2.5, progress=False, calibrate=False)[0]
    assert row["state"] == "graded" and row["score"] == 0
    by_name = {t["extra_data"]["test"]: t for t in row["results"]["tests"]}
    assert by_name["momentum.elastic"]["extra_data"]["status"] == "timeout"
    assert "longer than 1.5 s" in by_name["momentum.elastic"]["output"]
    assert by_name["momentum.restitution"]["extra_data"]["status"] == "timeout"
    assert by_name["momentum.perfectly_inelastic"]["extra_data"]["status"] == "timeout"
    assert "used up its 2.5 s" in by_name["momentum.perfectly_inelastic"]["output"]
    assert row["results"]["execution_time"] < 30


# Bad command lines ------------------------------------------------------------------------------
def test_a_missing_path_is_a_clear_error_and_writes_nothing(tmp_path):
    real = folder_submission(tmp_path / "ivy")
    with pytest.raises(SubmissionPathError, match="nothere"):
        grade_submissions([real, tmp_path / "nothere"], tmp_path / "out", progress=False)
    assert not (tmp_path / "out").exists()
    process = run_cli(real, tmp_path / "nothere", "--out", tmp_path / "out")
    stdout, stderr = process.communicate(timeout=60)
    assert process.returncode == 2
    assert "nothere: no such file or folder" in stderr and "Traceback" not in stderr
    assert not (tmp_path / "out").exists()


def test_out_must_be_a_folder(tmp_path):
    (tmp_path / "out").write_text("")
    with pytest.raises(GradingError, match="not a folder"):
        grade_submissions([folder_submission(tmp_path / "jo")], tmp_path / "out", progress=False)


def test_an_explicit_isolation_that_does_not_exist_is_refused(tmp_path):
    with pytest.raises(GradingError):
        grade_submissions([folder_submission(tmp_path / "kim")], tmp_path / "out", isolation="nonsense",
                          progress=False)


# Submissions: ids, discovery, fingerprints, extraction -----------------------------------------
@pytest.mark.parametrize("name, expected", [
    ("alice", "alice"), ("Alice Smith.zip", "Alice_Smith"), ("bob.ZIP", "bob"), ("../../etc", "etc"),
    ("..", "submission"), (".hidden", "hidden"), ("émile-dupont", "emile-dupont"), ("gradebook.csv", "submission_gradebook.csv"),
    ("a" * 200, "a" * 80),
])
def test_submission_ids_are_safe_folder_names(name, expected):
    assert submission_id(name) == expected


def test_same_names_get_distinct_stable_ids(tmp_path):
    a = folder_submission(tmp_path / "one" / "sam")
    b = folder_submission(tmp_path / "two" / "sam")
    first = [s.id for s in discover([a, b])]
    assert len(set(first)) == 2 and all(i.startswith("sam-") for i in first)
    assert [s.id for s in discover([b, a])] == first[::-1]


def test_every_missing_path_is_named(tmp_path):
    with pytest.raises(SubmissionPathError) as error:
        discover([tmp_path / "x", tmp_path / "y"])
    assert "x: no such file" in str(error.value) and "y: no such file" in str(error.value)


def test_folder_fingerprint_follows_contents_only(tmp_path):
    a = folder_submission(tmp_path / "a")
    b = folder_submission(tmp_path / "b")
    assert fingerprint(a) == fingerprint(b)
    (b / "exercises" / "notes.txt").write_text("x")
    assert fingerprint(a) != fingerprint(b)
    zip_path = zip_submission(tmp_path / "a.zip")
    assert fingerprint(zip_path) == fingerprint(zip_path) and len(fingerprint(zip_path)) == 64


def test_safe_extract_writes_the_regular_files(tmp_path):
    archive = zip_submission(tmp_path / "ok.zip")
    target = tmp_path / "x"
    target.mkdir()
    written = safe_extract(archive, target)
    assert (target / "exercises" / "__init__.py").is_file()
    assert len(written) == len([p for p in STUBS.rglob("*") if p.is_file() and "__pycache__" not in p.parts])


@pytest.mark.parametrize("members, words", [
    ([("../evil.py", b"")], "'..'"),
    ([("exercises\\..\\..\\evil.py", b"")], "'..'"),
    ([("/abs/evil.py", b"")], "absolute path"),
    ([("C:/evil.py", b"")], "absolute path"),
    ([(symlink_member("exercises/x.py", "/etc/passwd"), b"/etc/passwd")], "symbolic link"),
    ([("a.py", b"1"), ("a.py", b"2")], "twice"),
    ([("a", b"1"), ("a/b.py", b"2")], "both as a file and as a folder"),
])
def test_safe_extract_refuses_hostile_members_and_writes_nothing(tmp_path, members, words):
    archive = tmp_path / "evil.zip"
    with zipfile.ZipFile(archive, "w") as handle, warnings.catch_warnings():
        warnings.simplefilter("ignore")  # zipfile warns about the duplicate name
        handle.writestr("exercises/__init__.py", b"")
        for info, data in members:
            handle.writestr(info, data)
    target = tmp_path / "x"
    target.mkdir()
    with pytest.raises(SubmissionRefused, match=words.replace("(", r"\(")):
        safe_extract(archive, target)
    assert list(target.iterdir()) == []
    assert not (tmp_path / "evil.py").exists()


def test_safe_extract_caps_file_count_and_size(tmp_path):
    many = tmp_path / "many.zip"
    with zipfile.ZipFile(many, "w") as handle:
        for i in range(MAX_FILES + 1):
            handle.writestr(f"exercises/f{i}.py", b"")
    with pytest.raises(SubmissionRefused, match="entries"):
        safe_extract(many, tmp_path)
    target = tmp_path / "y"
    target.mkdir()
    with pytest.raises(SubmissionRefused, match="zip bomb"):
        safe_extract(bomb(tmp_path / "bomb.zip", megabytes=3), target, max_total_bytes=2 * 1024**2)
    assert list(target.iterdir()) == []


def test_safe_extract_refuses_an_archive_whose_header_lies(tmp_path):
    """A header that understates a member's size gets neither past the cap nor in."""
    archive = tmp_path / "liar.zip"
    with zipfile.ZipFile(archive, "w", zipfile.ZIP_STORED) as handle:
        handle.writestr("exercises/big.py", b"#" * 5000)
    data = bytearray(archive.read_bytes())
    # Patch the central directory's uncompressed size (offset 24 in the entry) down to 10 bytes.
    central = data.rfind(b"PK\x01\x02")
    data[central + 24:central + 28] = (10).to_bytes(4, "little")
    archive.write_bytes(bytes(data))
    target = tmp_path / "z"
    target.mkdir()
    with pytest.raises(SubmissionRefused):
        safe_extract(archive, target, max_total_bytes=1000)
    assert list(target.iterdir()) == []


def test_a_folder_holding_one_zip_is_graded_as_that_zip(tmp_path):
    folder = tmp_path / "upload"
    folder.mkdir()
    zip_submission(folder / "my_work.zip")
    with opened(Submission("upload", folder, "folder"), tmp_path) as where:
        assert (where / "exercises" / "__init__.py").is_file()
    assert not where.exists()


# Results: the Gradescope entries -----------------------------------------------------------
def test_partial_credit_and_strict_json(spec):
    partial = next(t for t in spec if t.partial_credit and t.points >= 2)
    strict = next(t for t in spec if not t.partial_credit and t.points >= 2)
    outcome = Outcome.failed("expected [0, 1], got [0, -1]", fraction=0.95, seconds=float("nan"), missed_pairs=2)
    entry = gs_results.results_entry(partial, outcome, 0.1)
    # 95 % right cases: a quarter of the points at 90 %, rising linearly to half at 100 % (never more).
    assert entry["score"] == pytest.approx(partial.points * 0.375) and entry["status"] == "failed"
    assert entry["output"].startswith(f"Partly right: {partial.points * 0.375:g} / {partial.points:g} points")
    assert "expected [0, 1], got [0, -1]" in entry["output"]
    assert entry["extra_data"]["metrics"]["seconds"] is None
    json.dumps(entry, allow_nan=False)
    assert plain({"a": float("inf"), "b": [1, 2.5]}) == {"a": None, "b": [1, 2.5]}
    # A test without partial credit, or a share below 90 %, earns nothing for a failure.
    assert gs_results.results_entry(strict, outcome, 0.1)["score"] == 0
    assert gs_results.results_entry(partial, Outcome.failed("x", fraction=0.89), 0.1)["score"] == 0


def test_a_wrong_answer_never_reaches_the_leaderboard(spec):
    speed = next(t for t in spec if t.leaderboard)
    assert leaderboard([Result(speed, Outcome.failed("wrong", seconds=0.001), 0.1)]) == []
    assert leaderboard([Result(speed, Outcome.passed("ok", seconds=0.5), 0.6)]) == [
        {"name": speed.leaderboard, "value": 0.5, "order": "asc"}]


def test_build_results_sums_scores(spec):
    results = [grader_run.TestResult(t, Outcome.passed("ok") if i % 2 else Outcome("timeout", message="slow"), 0.01)
               for i, t in enumerate(spec)]
    data = build_results(results, 1.234, "x", "f" * 64, "h" * 64, "exercises")
    assert data["score"] == pytest.approx(sum(t.points for i, t in enumerate(spec) if i % 2))
    assert data["max_score"] == pytest.approx(total_points(spec))
    assert check_results(data) == []
    assert_gradescope_results(data)


def test_gradebook_of_an_empty_folder_is_a_header(tmp_path, spec):
    path = write_gradebook(tmp_path, spec)
    assert path.read_text().splitlines() == [",".join(["submission", "score", "max_score",
                                                        *(t.name for t in spec), "state", "note"])]


def test_time_limits_scale_with_the_measured_slowdown(tmp_path, spec, monkeypatch):
    from grader.batch import calibration, grade

    assert 1.0 <= calibration.slowdown(runs=2) <= calibration.MAX_SLOWDOWN
    monkeypatch.setattr(grade, "slowdown", lambda: 2.0)  # a machine twice as slow as idle
    submission = folder_submission(tmp_path / "hana")
    with open(submission / "exercises" / "response" / "momentum_1d.py", "a") as handle:
        handle.write("\n\ndef elastic_collision_1d(m1, v1, m2, v2):\n    while True:\n        pass\n")
    tests = [t for t in spec if t.name == "momentum.elastic"]
    row = grade_submissions([submission], tmp_path / "out", tests=tests, limits=Limits(call_timeout=60.0),
                            per_test_seconds=1.0, per_submission_seconds=5.0, progress=False)[0]
    test = row["results"]["tests"][0]
    assert test["extra_data"]["status"] == "timeout" and "longer than 2 s" in test["output"]
