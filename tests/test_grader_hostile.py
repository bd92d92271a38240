"""The grader against broken and hostile submissions (grader/hostile_cases.py).

Every case of :mod:`grader.hostile_cases` is graded in ONE batch, with a clean copy of
the reference and of the stubs, through ``grade_submissions`` with two parallel jobs.
Each case must get what its honest work earns with a message saying what happened;
the clean submissions must be graded exactly as when graded alone; nothing outside
the output and temporary folders may change; no process may be left behind.  A
second batch is killed at a random point and rerun: each submission is graded once.

Kept short: a subset of the spec (every exercise, the speed test that also runs the
reference in a sandbox), and a call timeout of 6 s for the hanging cases (enough for a busy machine).
"""
from __future__ import annotations

import csv
import hashlib
import json
import os
import random
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import textwrap
import time
import zipfile
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from grader import codec
from grader import hostile_cases as hc
from grader.grade import LOG_NAME, grade_submissions, read_grading_log
from grader.results import check_results, write_results
from grader.sandbox import (RESPONSE_LIMIT, SANDBOX_UID_BASE, Limits, Sandbox, bwrap_available, processes_of,
                            stray_processes, uid_in_use)
from grader.spec import load_spec

REPO = Path(__file__).resolve().parent.parent
IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc")
#: A test of every exercise, the ones the cases poison, and grid.speed (reference sandbox too).
TEST_NAMES = ("momentum.elastic", "momentum.restitution", "momentum.perfectly_inelastic", "grid.every_cell.random",
              "sat.project_vertices", "sat.project_circle", "sat.intervals_overlap", "sat.circles_overlap",
              "contacts.circle_circle", "impulse.apply_impulse", "grid.speed")
LIMITS = Limits(call_timeout=6.0)
PER_TEST_SECONDS = 20.0
PER_SUBMISSION_SECONDS = 60.0
#: Folders of the repository that running the tests may change (caches, builds, outputs).
GENERATED = {".git", ".venv", "out", "_build", "__pycache__", ".pytest_cache", ".hypothesis", ".ipynb_checkpoints",
             "collision_course.egg-info", "_vendor", ".jupyter_cache", "build", "dist"}
needs_sandbox = pytest.mark.skipif(not bwrap_available(),
                                   reason="the hostile batch needs bubblewrap and root (as on CI and Gradescope)")


# Helpers ------------------------------------------------------------------------------------
def snapshot(root: Path, skip: set[str] = GENERATED) -> dict[str, str]:
    """sha256 of every file under ``root`` (generated folders left out), by relative path."""
    found = {}
    for folder, dirs, files in os.walk(root):
        dirs[:] = [d for d in dirs if d not in skip]
        for name in files:
            path = Path(folder) / name
            try:
                found[str(path.relative_to(root))] = hashlib.sha256(path.read_bytes()).hexdigest() \
                    if not path.is_symlink() else "link:" + os.readlink(path)
            except OSError as exc:
                found[str(path.relative_to(root))] = f"unreadable: {exc.errno}"
    return found


def changed(before: dict[str, str], after: dict[str, str]) -> list[str]:
    return sorted(k for k in set(before) | set(after) if before.get(k) != after.get(k))


def processes_mentioning(text: str) -> list[str]:
    """Command lines of live processes that mention ``text`` (grading workers, bwrap)."""
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit() or int(entry) == os.getpid():
            continue
        try:
            with open(f"/proc/{entry}/cmdline", "rb") as handle:
                command = handle.read().replace(b"\0", b" ").decode("utf-8", "replace")
            with open(f"/proc/{entry}/stat") as handle:
                state = handle.read().rsplit(")", 1)[1].split()[0]
        except OSError:
            continue
        if text in command and state != "Z":
            found.append(f"{entry}: {command[:200]}")
    return found


def wait_for_no_leftovers(root: Path, seconds: float = 10.0) -> tuple[list, list]:
    deadline = time.monotonic() + seconds
    while True:
        strays, mentions = stray_processes(), processes_mentioning(str(root))
        if (not strays and not mentions) or time.monotonic() > deadline:
            return strays, mentions
        time.sleep(0.1)


def copy_submission(path: Path, package: Path) -> Path:
    shutil.copytree(package, path / "exercises", ignore=IGNORE)
    return path


def outcomes(data: dict) -> dict[str, tuple]:
    """Per test: status, score and fraction (what must not depend on the rest of the batch)."""
    return {t["extra_data"]["test"]: (t["extra_data"]["status"], t["score"], t["extra_data"]["fraction"])
            for t in data["tests"]}


@pytest.fixture(scope="module")
def tests():
    chosen = [t for t in load_spec() if t.name in TEST_NAMES]
    assert len(chosen) == len(TEST_NAMES)
    return chosen


@pytest.fixture(scope="module")
def batch(tmp_path_factory, tests):
    """Every case, the reference and the stubs, graded together (two jobs)."""
    if not bwrap_available():
        pytest.skip("the hostile batch needs bubblewrap and root")
    root = tmp_path_factory.mktemp("hostile")
    subs, out, sentinel = root / "subs", root / "out", root / "sentinel"
    sentinel.mkdir()
    (sentinel / "keep.txt").write_text("the sentinel's own file\n")
    os.chmod(sentinel, 0o777)  # writable by anyone: only the sandbox can keep a student out
    paths = hc.build_cases(subs, {"OUT": str(out), "SENTINEL": str(sentinel), "REPO": str(REPO)})
    paths["reference"] = copy_submission(subs / "reference", REPO / "solutions")
    paths["stubs"] = copy_submission(subs / "stubs", REPO / "exercises")
    assert not Path(hc.ESCAPED_FILE).exists()
    before = {"repo": snapshot(REPO), "sentinel": snapshot(sentinel), "subs": snapshot(subs)}
    strays_before = stray_processes()
    started = time.perf_counter()
    rows = grade_submissions(list(paths.values()), out, jobs=2, tests=tests, limits=LIMITS,
                             per_test_seconds=PER_TEST_SECONDS, per_submission_seconds=PER_SUBMISSION_SECONDS,
                             progress=False)
    seconds = time.perf_counter() - started
    strays, mentions = wait_for_no_leftovers(root)
    after = {"repo": snapshot(REPO), "sentinel": snapshot(sentinel), "subs": snapshot(subs)}
    return SimpleNamespace(root=root, subs=subs, out=out, sentinel=sentinel, paths=paths,
                           rows={r["id"]: r for r in rows}, seconds=seconds, before=before, after=after,
                           strays=strays, strays_before=strays_before, mentions=mentions)


def results_of(batch, name: str) -> dict:
    return json.loads((batch.out / name / "results.json").read_text(encoding="utf-8"))


# The cases ------------------------------------------------------------------------------------------
def test_the_cases_are_all_there_and_distinct():
    names = [c.name for c in hc.CASES]
    assert len(names) == len(set(names))
    spec = {t.name for t in load_spec()}
    for case in hc.CASES:
        assert case.category in ("broken", "hostile") and case.what and case.base in ("reference", "stubs")
        assert (case.refused is not None) == bool(case.archive and case.archive != "cp437-name")
        assert case.touched <= spec | {"*"}, case.name
        assert case.code or case.name == "copy-of-reference"
    covered = " ".join(names)
    for word in ("syntax", "import-error", "missing-module", "missing-function", "returns-none", "returns-string",
                 "wrong-length", "nan-inf", "exception", "recursion", "prints-megabytes", "non-utf8-source",
                 "infinite-loop", "memory-bomb", "fork-bomb", "sleep", "sys-exit", "os-exit", "kill-parent",
                 "segfault", "monkeypatch", "lying-objects", "import-reference", "import-by-path", "read-hidden",
                 "write-results", "write-outside", "leave-process", "dotdot", "absolute", "symlink", "zip-bomb",
                 "copy-of-reference"):
        assert word in covered, word


@needs_sandbox
@pytest.mark.parametrize("case", hc.CASES, ids=lambda c: c.name)
def test_each_case_earns_what_its_honest_work_earns(batch, tests, case):
    data = results_of(batch, case.name)
    assert hc.problems(case, data, tests) == []
    if case.refused is None:
        assert data["score"] >= hc.expected_score(case, tests) - 1e-9
        assert data["score"] <= hc.expected_score(case, tests) + sum(
            t.points for t in tests if (e := hc.expectation(case, t.name)) is not None and e.partial)
    else:
        assert batch.rows[case.name]["state"] == "refused"


@needs_sandbox
def test_clean_submissions_get_full_marks_and_zero(batch, tests):
    total = sum(t.points for t in tests)
    assert batch.rows["reference"]["score"] == pytest.approx(total)
    assert all(t["status"] == "passed" for t in results_of(batch, "reference")["tests"])
    assert batch.rows["stubs"]["score"] == 0
    assert {t["extra_data"]["status"] for t in results_of(batch, "stubs")["tests"]} == {"not_implemented"}


@needs_sandbox
def test_submissions_are_graded_as_they_are_alone(batch, tests, tmp_path):
    """The clean submissions, and two cases, away from the rest of the hostile batch."""
    names = ["reference", "stubs", "broken-exception", "hostile-kill-parent"]
    alone = grade_submissions([batch.paths[n] for n in names], tmp_path / "alone", jobs=2, tests=tests,
                              limits=LIMITS, per_test_seconds=PER_TEST_SECONDS,
                              per_submission_seconds=PER_SUBMISSION_SECONDS, progress=False, html=False)
    assert [row["id"] for row in alone] == names
    for row in alone:
        assert outcomes(row["results"]) == outcomes(results_of(batch, row["id"])), row["id"]


@needs_sandbox
def test_the_copy_of_the_reference_is_flagged_and_the_others_are_not(batch, tmp_path):
    from grader.similarity import REFERENCE_ID, find_similar

    names = ["copy-of-reference", "stubs", "hostile-lying-objects", "hostile-monkeypatch", "zip-cp437-name"]
    flags = {frozenset((p.a.id, p.b.id)) for p in find_similar([batch.paths[n] for n in names], tmp_path)}
    assert frozenset(("copy-of-reference", REFERENCE_ID)) in flags
    assert frozenset(("copy-of-reference", "zip-cp437-name")) in flags  # a zipped copy too
    assert not any({"stubs", "hostile-lying-objects", "hostile-monkeypatch"} & pair for pair in flags)


@needs_sandbox
def test_every_results_file_is_valid_gradescope_json(batch):
    for name in batch.paths:
        raw = (batch.out / name / "results.json").read_bytes()
        data = json.loads(raw.decode("utf-8"))  # valid UTF-8, whatever the student printed
        assert check_results(data) == [], name
        assert len(raw) < 400_000, f"{name}: results.json of {len(raw)} bytes"
        assert (batch.out / name / "report.html").is_file()


@needs_sandbox
def test_forged_results_and_gradebook_are_not_kept(batch, tests):
    forged = results_of(batch, "hostile-write-results")
    assert forged["score"] != 1000 and forged["tests"] and forged["output"] != "full marks"
    assert results_of(batch, "reference")["score"] == sum(t.points for t in tests)
    with open(batch.out / "gradebook.csv", newline="") as handle:
        rows = {r["submission"]: r for r in csv.DictReader(handle)}
    assert set(rows) == set(batch.paths)
    for name in batch.paths:
        assert float(rows[name]["score"]) == pytest.approx(results_of(batch, name)["score"])
    expected = {p.name for p in batch.out.iterdir()}
    assert expected == {*batch.paths, "gradebook.csv", "class_report.html", LOG_NAME, ".grader.lock"}, expected
    for name in batch.paths:
        assert {p.name for p in (batch.out / name).iterdir()} <= {"results.json", "report.html"}, name


@needs_sandbox
def test_each_submission_is_graded_once(batch):
    log = read_grading_log(batch.out)
    assert sorted(entry["submission"] for entry in log) == sorted(batch.paths)


@needs_sandbox
def test_no_file_outside_the_output_changes(batch):
    for where in ("repo", "sentinel", "subs"):
        assert changed(batch.before[where], batch.after[where]) == [], where
    assert not Path(hc.ESCAPED_FILE).exists()
    assert not (batch.root / "escaped.py").exists() and not (batch.subs.parent / "escaped.py").exists()
    assert not list(batch.root.rglob("pwned*"))


@needs_sandbox
def test_no_process_is_left_running(batch):
    assert batch.strays_before == [] or set(batch.strays) <= set(batch.strays_before)
    assert batch.strays == [], f"processes of sandbox users nobody holds: {batch.strays}"
    assert batch.mentions == [], batch.mentions
    assert not (batch.out / ".work").exists()


@needs_sandbox
def test_the_batch_takes_a_reasonable_time(batch):
    assert batch.seconds < 150, f"the hostile batch took {batch.seconds:.0f} s"


# Killed and rerun ------------------------------------------------------------------------------------
KILL_TESTS = "momentum.*,sat.project_circle"


def grade_cli(*args, **kwargs) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "grader.grade", *map(str, args)], cwd=REPO,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kwargs)


@needs_sandbox
def test_a_hostile_batch_killed_at_a_random_point_is_graded_once_on_rerun(tmp_path):
    seed = int.from_bytes(os.urandom(4), "little")
    rng = random.Random(seed)
    out = tmp_path / "out"
    paths = hc.build_cases(tmp_path / "subs", {"OUT": str(out), "SENTINEL": str(tmp_path / "sentinel")})
    paths["reference"] = copy_submission(tmp_path / "subs" / "reference", REPO / "solutions")
    subs = list(paths.values())
    options = ["--out", out, "--jobs", "2", "--no-progress", "--no-html", "--tests", KILL_TESTS,
               "--timeout-call", "6", "--timeout-test", "15"]
    process = grade_cli(*subs, *options, start_new_session=True)
    deadline = time.monotonic() + 120
    try:
        while not list(out.glob("*/results.json")):
            assert process.poll() is None, process.communicate()
            assert time.monotonic() < deadline, "no results.json appeared in 120 s"
            time.sleep(0.02)
        time.sleep(rng.uniform(0.0, 6.0))
    finally:
        os.killpg(process.pid, signal.SIGKILL)
        process.communicate()
    done = {p.parent.name: p.stat().st_mtime_ns for p in out.glob("*/results.json")}
    strays, mentions = wait_for_no_leftovers(tmp_path)
    assert strays == [] and mentions == [], f"seed {seed}: left running after the kill: {strays} {mentions}"
    assert 1 <= len(done) < len(subs), f"seed {seed}: the batch was not killed half-way ({len(done)} done)"
    process = grade_cli(*subs, *options)
    stdout, stderr = process.communicate(timeout=300)
    assert process.returncode == 0, f"seed {seed}: {stderr}"
    assert f"{len(subs)} submissions:" in stdout and f"{len(done)} skipped" in stdout, f"seed {seed}: {stdout}"
    tests = [t for t in load_spec() if t.name.startswith("momentum.") or t.name == "sat.project_circle"]
    for name in paths:
        path = out / name / "results.json"
        assert path.exists(), f"seed {seed}: {name} has no results"
        if name in done:
            assert path.stat().st_mtime_ns == done[name], f"seed {seed}: {name} was graded twice"
        case = next((c for c in hc.CASES if c.name == name), None)
        if case is not None:
            assert hc.problems(case, json.loads(path.read_text()), tests) == [], f"seed {seed}: {name}"
    log = read_grading_log(out)
    counts = {name: sum(1 for e in log if e["submission"] == name) for name in paths}
    # One line per grading; a run killed between a results.json and its log line leaves none.
    assert all(c <= 1 for c in counts.values()), f"seed {seed}: graded more than once: {counts}"
    assert all(counts[n] == 1 for n in paths if n not in done), f"seed {seed}: {counts}"
    assert sum(counts.values()) >= len(paths) - 1, f"seed {seed}: {counts}"
    assert not list(out.rglob("*.tmp")) and not (out / ".work").exists()
    strays, mentions = wait_for_no_leftovers(tmp_path)
    assert strays == [] and mentions == []


# Gradescope ------------------------------------------------------------------------------------------
@needs_sandbox
def test_gradescope_locks_the_solutions_away_before_grading(tmp_path):
    from grader.gradescope import build_autograder_zip

    archive = build_autograder_zip(tmp_path / "autograder.zip")
    base = Path(tempfile.mkdtemp(prefix="grader-gradescope-", dir="/tmp"))
    try:
        os.chmod(base, 0o755)  # reachable by any user, like /autograder
        root = base / "autograder"
        (root / "source").mkdir(parents=True)
        with zipfile.ZipFile(archive) as handle:
            handle.extractall(root / "source")
        shutil.copy(root / "source" / "run_autograder", root / "run_autograder")
        case = next(c for c in hc.CASES if c.name == "hostile-read-hidden-spec")
        hc.build_package(case, root / "submission" / "exercises", {"REPO": str(root / "source")})
        hidden = root / "source" / "grader" / "spec" / "hidden.toml"

        def read_as_another_user() -> subprocess.CompletedProcess:
            return subprocess.run(["setpriv", "--reuid=62500", "--regid=62500", "--clear-groups", "cat", str(hidden)],
                                  capture_output=True, text=True)

        assert read_as_another_user().returncode == 0  # what the plain fallback could read before
        env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
        env.update(AUTOGRADER_ROOT=str(root), AUTOGRADER_PYTHON=sys.executable)
        completed = subprocess.run(["bash", str(root / "run_autograder")], cwd=root, env=env, capture_output=True,
                                   text=True, timeout=240)
        assert completed.returncode == 0, completed.stdout + completed.stderr
        denied = read_as_another_user()
        assert denied.returncode != 0 and "Permission denied" in denied.stderr
        assert stat.S_IMODE((root / "source").stat().st_mode) == 0o700
        assert stat.S_IMODE((root / "results").stat().st_mode) == 0o755
        data = json.loads((root / "results" / "results.json").read_text())
        by_name = {t["extra_data"]["test"]: t for t in data["tests"]}
        stolen = by_name["momentum.perfectly_inelastic"]
        assert stolen["extra_data"]["status"] == "error" and stolen["score"] == 0
        assert "No such file" in stolen["output"] or "Permission denied" in stolen["output"]
        assert all(t["status"] == "passed" for n, t in by_name.items() if n != "momentum.perfectly_inelastic")
    finally:
        shutil.rmtree(base, ignore_errors=True)


# The grader's own defences, one at a time -----------------------------------------------------------
class LyingFloat(float):
    def __eq__(self, other):
        return True

    def __float__(self):
        return 1e300

    def __index__(self):
        return 7

    __hash__ = float.__hash__


class LyingInt(int):
    def __index__(self):
        return 99

    def __int__(self):
        return 99


class LyingList(list):
    def __len__(self):
        return 2

    def __iter__(self):
        return iter([1.0, 2.0])

    def __getitem__(self, index):
        return 1.0


class LyingStr(str):
    def __str__(self):
        return "lie"


def test_codec_reads_builtin_subclasses_as_stored_never_through_their_methods():
    assert codec.encode_value(LyingFloat(0.5)) == 0.5 and type(codec.encode_value(LyingFloat(0.5))) is float
    assert codec.encode_value(LyingInt(3)) == 3 and type(codec.encode_value(LyingInt(3))) is int
    assert codec.encode_value(LyingList([LyingFloat(0.0)])) == [0.0]
    assert codec.encode_value((LyingFloat(1.5), LyingInt(2))) == [1.5, 2]
    assert codec.encode_value(LyingStr("truth")) == "truth" and type(codec.encode_value(LyingStr("x"))) is str
    assert codec.encode_value({LyingStr("k"): LyingFloat(2.0)}) == {"k": 2.0}


def test_codec_converts_numpy_explicitly_and_refuses_other_objects():
    assert codec.encode_value(np.float32(1.5)) == 1.5 and type(codec.encode_value(np.float32(1.5))) is float
    assert codec.encode_value(np.int64(4)) == 4 and codec.encode_value(np.bool_(True)) is True
    assert codec.encode_value(np.arange(3.0)) == {codec.ARRAY_TAG: [0.0, 1.0, 2.0]}

    class Sneaky(np.ndarray):
        def tolist(self):
            return "lie"

    assert codec.encode_value(np.arange(2.0).view(Sneaky)) == {codec.ARRAY_TAG: [0.0, 1.0]}
    with pytest.raises(codec.NotPlainData, match="complex"):
        codec.encode_value(np.zeros(2, dtype=complex))
    with pytest.raises(codec.NotPlainData, match="object"):
        codec.encode_value(object())
    nested = []
    for _ in range(200):
        nested = [nested]
    with pytest.raises(codec.NotPlainData, match="nested"):
        codec.encode_value(nested)


def test_the_parent_accepts_only_well_formed_plain_data():
    assert codec.plain_data({"a": [1, 2.5, None, True, "x\udcff"]}) == {"a": [1, 2.5, None, True, "x?"]}
    assert codec.plain_data({codec.ARRAY_TAG: [[1.0, 2.0]]}) == {codec.ARRAY_TAG: [[1.0, 2.0]]}
    for bad in ({codec.ARRAY_TAG: ["x"]}, {codec.CONTACT_TAG: True, "normal": "up", "depth": 1, "points": []},
                {codec.SHAPE_TAG: "Star"}, {codec.PAIRS_TAG: 3}, {codec.ARRAY_TAG: [], codec.PAIRS_TAG: []},
                {codec.BODY_TAG: True, "shape": None}):
        with pytest.raises(codec.NotPlainData):
            codec.plain_data(bad)


def test_results_with_lone_surrogates_are_written_as_valid_utf8(tmp_path):
    path = write_results({"score": 0, "tests": [], "output": "caf\udce9"}, tmp_path / "results.json")
    assert json.loads(path.read_bytes().decode("utf-8"))["output"] == "caf\udce9"


CHANNEL = '''
import json, os, sys

def _frame_with(name):
    frame = sys._getframe()
    while frame is not None and name not in frame.f_locals:
        frame = frame.f_back
    return frame.f_locals

def deep_forgery():
    """A forged answer with the right nonce, nested too deep for JSON, then the real one."""
    here = _frame_with("nonce")
    line = '{"id": %d, "nonce": "%s", "status": "ok", "value": ' % (here["number"], here["nonce"])
    os.write(int(sys.argv[1]), (line + "[" * 100_000 + "]" * 100_000 + "}\\n").encode())
    return 42

def malformed_forgery():
    """A forged answer with the right nonce but an unknown status and a value that is no array."""
    here = _frame_with("nonce")
    forged = {"id": here["number"], "nonce": here["nonce"], "status": "passed", "value": {"$array": "x"}}
    os.write(int(sys.argv[1]), (json.dumps(forged) + "\\n").encode())
    return 42

def flood():
    """More bytes than the grader accepts on the channel, none of them an answer."""
    chunk = b"x" * (1 << 20)
    for _ in range(80):
        os.write(int(sys.argv[1]), chunk)
    return 1

def hog_after_answering():
    """A thread that takes the interpreter lock for good (a C loop) once this call has answered."""
    import threading, time

    def hog():
        time.sleep(0.3)
        sum(range(10**15))

    threading.Thread(target=hog, daemon=True).start()
    return 1

def echo(value):
    return len(value)

def close_channel():
    os.close(int(sys.argv[1]))
    import time
    time.sleep(60)

def add(a, b):
    return a + b
'''


@pytest.fixture(scope="module")
def channel_box(tmp_path_factory):
    package = tmp_path_factory.mktemp("channel") / "exercises"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "channel.py").write_text(textwrap.dedent(CHANNEL))
    with Sandbox(package, Limits(call_timeout=10.0)) as box:
        yield box


def test_an_answer_nested_too_deep_is_skipped_for_the_real_one(channel_box):
    result = channel_box.call("exercises.channel", "deep_forgery")
    assert result.status == "ok" and result.value == 42


def test_a_malformed_answer_with_the_right_nonce_is_refused(channel_box):
    result = channel_box.call("exercises.channel", "malformed_forgery")
    assert result.status == "unreadable" and "not well-formed" in result.message
    assert channel_box.call("exercises.channel", "add", [1, 2]).value == 3


def test_a_flood_on_the_channel_stops_at_the_response_limit(channel_box):
    assert RESPONSE_LIMIT < 80 * (1 << 20)
    result = channel_box.call("exercises.channel", "flood")
    assert result.status == "unreadable" and "larger than the grader accepts" in result.message
    assert channel_box.call("exercises.channel", "add", [2, 2]).value == 4


def test_a_worker_that_stops_reading_its_requests_times_out(channel_box):
    assert channel_box.call("exercises.channel", "hog_after_answering").value == 1
    time.sleep(0.6)
    started = time.perf_counter()
    result = channel_box.call("exercises.channel", "echo", ["x" * 2_000_000], timeout=2.0)
    assert result.status == "timeout" and time.perf_counter() - started < 5
    assert channel_box.call("exercises.channel", "add", [1, 1]).value == 2


def test_a_worker_that_closes_its_channel_is_stopped(channel_box):
    started = time.perf_counter()
    result = channel_box.call("exercises.channel", "close_channel")
    assert result.status == "crashed" and time.perf_counter() - started < 8
    assert channel_box.call("exercises.channel", "add", [3, 3]).value == 6


@needs_sandbox
def test_concurrent_sandboxes_never_share_a_user(tmp_path):
    package = tmp_path / "exercises"
    package.mkdir()
    (package / "__init__.py").write_text("")
    with Sandbox(package, slot=5) as first, Sandbox(package, slot=5) as second:
        assert first.uid != second.uid and uid_in_use(first.uid) and uid_in_use(second.uid)
        assert SANDBOX_UID_BASE <= first.uid and SANDBOX_UID_BASE <= second.uid
        uid = first.uid
    assert not uid_in_use(uid) and processes_of([uid]) == []


PARTIAL = '''
import os, sys

def leave_a_partial_line():
    os.write(int(sys.argv[1]), b'{"id": 1, "nonce": "no newline after this')
    return 5

def add(a, b):
    return a + b
'''


def test_a_partial_line_left_on_the_channel_does_not_spoil_the_next_answer(tmp_path):
    package = tmp_path / "exercises"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "partial.py").write_text(textwrap.dedent(PARTIAL))
    with Sandbox(package, Limits(call_timeout=10.0)) as box:
        assert box.call("exercises.partial", "leave_a_partial_line").value == 5
        assert box.call("exercises.partial", "add", [2, 3]).value == 5
