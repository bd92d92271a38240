"""The grader against broken and hostile submissions (grader/samples/hostile_cases.py).

Every case of :mod:`grader.samples.hostile_cases` is graded in ONE batch, with a clean copy of
the reference and of the stubs, through ``grade_submissions`` with two parallel jobs
-- but the cases of ``hc.SIZES``, whose answers are enormous, which go to a second,
small batch of their own tests, timed and with the grading process's peak memory
measured.  Each case must get what its honest work earns with a message saying what
happened; the clean submissions must be graded exactly as when graded alone; nothing
outside the output and temporary folders may change; no process may be left behind.
A third batch is killed at a random point and rerun: each submission is graded once.

Kept short: a subset of the spec (every exercise, the speed test that also runs the
reference in a sandbox), and a call timeout of 6 s for the hanging cases (enough for a
busy machine).  Under pytest-xdist each batch is graded once for the whole session
(the first worker to need it grades it, under a file lock; the other reads its record).
``GRADER_HOSTILE_FULL_SPEC=1`` grades the main batch on the whole spec instead (some
minutes): how the test sets of the cases were derived, and how to check them again.
"""
from __future__ import annotations

import contextlib
import csv
import fcntl
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
import threading
import time
import zipfile
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from grader.sandbox import codec
from grader.samples import hostile_cases as hc
from grader.batch.grade import grade_submissions
from grader.batch.gradebook import LOG_NAME, read_grading_log
from grader.reports.results import check_results, write_results
from grader.sandbox.isolation import bwrap_available
from grader.sandbox.process import (RESPONSE_LIMIT, SANDBOX_UID_BASE, Limits, Sandbox, processes_of,
                            stray_processes, uid_in_use)
from grader.harness.run import load_spec
from grader.batch.submissions import (MAX_FILES, Submission, SubmissionRefused, checked_path, discover, fingerprint,
                                hard_links, opened, scan_folder)

REPO = Path(__file__).resolve().parent.parent
IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc")
#: A test of every exercise, the ones the cases poison, and grid.speed (reference sandbox too).
TEST_NAMES = ("momentum.elastic", "momentum.restitution", "momentum.perfectly_inelastic", "grid.every_cell_random",
              "sat.project_vertices", "sat.project_circle", "sat.intervals_overlap", "sat.circles_overlap",
              "contacts.circle_circle", "impulse.apply_impulse", "grid.speed")
#: Every test when set: the main batch then takes minutes (how the case's test sets were derived).
FULL_SPEC = os.environ.get("GRADER_HOSTILE_FULL_SPEC", "") not in ("", "0")
LIMITS = Limits(call_timeout=6.0)
PER_TEST_SECONDS = 20.0
PER_SUBMISSION_SECONDS = 60.0 if not FULL_SPEC else 600.0
#: The cases whose answers are enormous, graded apart on the tests they reach (and one they do not).
SIZE_CASES = tuple(c.name for c in hc.SIZES)
SIZE_TEST_NAMES = ("contacts.circle_circle", "contacts.degenerate_shapes", "momentum.perfectly_inelastic",
                   "momentum.elastic", "impulse.scene")
#: Seconds a test of a size case may take (the reference takes about one; most of the rest is
#: the student's worker encoding its own enormous answer), and its whole submission.
SIZE_TEST_SECONDS = 20.0
SIZE_SUBMISSION_SECONDS = 40.0
#: Peak resident memory of a grading process (the parent of the sandboxes) over the size
#: batch.  Measured: about 130 MiB grading the reference, 450 MiB with the 8,000-ball scene
#: (parsing its 21 MB answer); a 8,000 x 8,000 distance matrix alone would be 1 GiB.
PARENT_MEMORY_BYTES = 768 * 1024**2
#: Longest list a figure kept in results.json may hold (grader.harness.figure_caps.FIGURE_CAPS).
FIGURE_LIST_CAP = 4000
#: What the hostile cases write (hostile-write-outside appends the first, hostile-write-results
#: writes the second): a repository file holding one was written by them.
HOSTILE_MARKERS = (b"pwned\n", b'"output": "full marks"')
#: Folders of the repository that running the tests may change (caches, builds, outputs).
GENERATED = {".git", ".venv", "out", "_build", "__pycache__", ".pytest_cache", ".hypothesis", ".ipynb_checkpoints",
             "collision_course.egg-info", "_vendor", ".jupyter_cache", "build", "dist"}
needs_sandbox = pytest.mark.skipif(not bwrap_available(),
                                   reason="the hostile batch needs bubblewrap and root (as on CI and Gradescope)")


# Helpers ------------------------------------------------------------------------------------
def snapshot(root: Path, skip: set[str] = GENERATED) -> dict[str, str]:
    """sha256 of every file under ``root`` (generated folders left out), by relative path;
    links by their target, files over 1 MiB (the sparse case's 2 GiB) by size and time."""
    found = {}
    for folder, dirs, files in os.walk(root):
        dirs[:] = [d for d in dirs if d not in skip]
        for name in files + [d for d in dirs if os.path.islink(os.path.join(folder, d))]:
            path = Path(folder) / name
            try:
                info = path.lstat()
                if stat.S_ISLNK(info.st_mode):
                    found[str(path.relative_to(root))] = "link:" + os.readlink(path)
                elif info.st_size > 1 << 20:
                    found[str(path.relative_to(root))] = f"size:{info.st_size}:{info.st_mtime_ns}"
                else:
                    found[str(path.relative_to(root))] = hashlib.sha256(path.read_bytes()).hexdigest()
            except OSError as exc:
                found[str(path.relative_to(root))] = f"unreadable: {exc.errno}"
    return found


def changed(before: dict[str, str], after: dict[str, str]) -> list[str]:
    return sorted(k for k in set(before) | set(after) if before.get(k) != after.get(k))


def written_by_hostile_code(root: Path, names: list[str]) -> list[str]:
    """Of the files of ``root`` that changed, those the hostile cases wrote: holding one of
    their markers, or new and named like what they forge.  (The repository is shared:
    people may edit it while the batch runs; a student's write shows its marker.)"""
    found = []
    for name in names:
        path = root / name
        forged = path.name in ("results.json", "gradebook.csv", "grading_log.jsonl") or path.name.startswith("pwned")
        try:
            data = path.read_bytes() if path.is_file() and path.stat().st_size < 1 << 24 else b""
        except OSError:
            data = b""
        if forged or data.endswith(HOSTILE_MARKERS[0]) or HOSTILE_MARKERS[1] in data:
            found.append(name)
    return found


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


def spec_tests(names) -> list:
    chosen = [t for t in load_spec() if names is None or t.name in names]
    assert names is None or len(chosen) == len(names)
    return chosen


@pytest.fixture(scope="module")
def tests():
    return spec_tests(None if FULL_SPEC else TEST_NAMES)


@pytest.fixture(scope="module")
def size_tests():
    return spec_tests(SIZE_TEST_NAMES)


def once_per_session(tmp_path_factory, name: str, build, meanwhile=None) -> SimpleNamespace:
    """``build(folder)`` (a JSON-able dict) run once for the whole test session: under
    pytest-xdist the first worker to get here builds it holding a file lock, the
    others wait for it and read its record (calling ``meanwhile()`` first, when given:
    another batch to grade while they wait).  Paths come back as Path."""
    base = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        base = base.parent  # shared by the workers of this session
    record = base / f"{name}.json"
    with open(base / f"{name}.lock", "w") as lock:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            if meanwhile is not None:
                meanwhile()
            fcntl.flock(lock, fcntl.LOCK_EX)
        if not record.exists():
            folder = base / name
            shutil.rmtree(folder, ignore_errors=True)
            folder.mkdir()
            record.write_text(json.dumps(build(folder)))
        data = json.loads(record.read_text())
    for key in ("root", "subs", "out", "sentinel"):
        if key in data:
            data[key] = Path(data[key])
    data["paths"] = {k: Path(v) for k, v in data["paths"].items()}
    return SimpleNamespace(**data)


class PeakMemory:
    """The peak resident memory (VmHWM, bytes) of this process's child processes whose
    command line holds ``pattern`` (the grading workers), polled while in use."""

    def __init__(self, pattern: str = "grader.batch.scheduler"):
        self.pattern = pattern
        self.peak = 0
        self.seen: set[int] = set()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _children(self) -> list[str]:
        found = []
        for task in os.listdir("/proc/self/task"):
            try:
                found += open(f"/proc/self/task/{task}/children").read().split()
            except OSError:
                pass
        return found

    def _run(self) -> None:
        while not self._stop.is_set():
            for pid in self._children():
                try:
                    if self.pattern not in open(f"/proc/{pid}/cmdline").read().replace("\0", " "):
                        continue
                    with open(f"/proc/{pid}/status") as handle:
                        fields = dict(line.split(":", 1) for line in handle if ":" in line)
                    self.peak = max(self.peak, int(fields["VmHWM"].split()[0]) * 1024)
                    self.seen.add(int(pid))
                except (OSError, KeyError, ValueError):
                    pass
            self._stop.wait(0.05)

    def __enter__(self) -> "PeakMemory":
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join()


def grade_cases(folder: Path, cases, tests, reference: bool = True, stubs: bool = True,
                measure: bool = False) -> dict:
    """Build ``cases`` (and clean submissions) in ``folder`` and grade them in one batch."""
    root = folder
    subs, out, sentinel = root / "subs", root / "out", root / "sentinel"
    sentinel.mkdir()
    (sentinel / "keep.txt").write_text("the sentinel's own file\n")
    os.chmod(sentinel, 0o777)  # writable by anyone: only the sandbox can keep a student out
    key = f"grader-hostile-{os.getpid()}-{secrets_token()}"
    paths = hc.build_cases(subs, {"OUT": str(out), "SENTINEL": str(sentinel), "REPO": str(REPO), "KEY": key},
                           tuple(cases))
    if reference:
        paths["reference"] = copy_submission(subs / "reference", REPO / "solutions")
    if stubs:
        paths["stubs"] = copy_submission(subs / "stubs", REPO / "exercises")
    assert not Path(hc.ESCAPED_FILE).exists()
    before = {"repo": snapshot(REPO), "sentinel": snapshot(sentinel), "subs": snapshot(subs)}
    strays_before = stray_processes()
    started = time.perf_counter()
    memory = PeakMemory()
    with memory if measure else contextlib.nullcontext():
        rows = grade_submissions(list(paths.values()), out, jobs=2, tests=tests, limits=LIMITS,
                                 per_test_seconds=PER_TEST_SECONDS, per_submission_seconds=PER_SUBMISSION_SECONDS,
                                 progress=False)
    seconds = time.perf_counter() - started
    strays, mentions = wait_for_no_leftovers(root)
    after = {"repo": snapshot(REPO), "sentinel": snapshot(sentinel), "subs": snapshot(subs)}
    return dict(root=str(root), subs=str(subs), out=str(out), sentinel=str(sentinel),
                paths={k: str(v) for k, v in paths.items()}, rows={r["id"]: r for r in rows}, seconds=seconds,
                before=before, after=after, strays=strays, strays_before=strays_before, mentions=mentions,
                peak_memory=memory.peak, grading_processes=len(memory.seen))


def secrets_token() -> str:
    return os.urandom(4).hex()


@pytest.fixture(scope="module")
def batch(request, tmp_path_factory, tests):
    """Every case but the size cases, the reference and the stubs, graded together (two jobs)."""
    if not bwrap_available():
        pytest.skip("the hostile batch needs bubblewrap and root")
    cases = [c for c in hc.CASES if c.name not in SIZE_CASES]
    return once_per_session(tmp_path_factory, "hostile-full" if FULL_SPEC else "hostile",
                            lambda folder: grade_cases(folder, cases, tests),
                            meanwhile=lambda: request.getfixturevalue("size_batch"))


@pytest.fixture(scope="module")
def size_batch(tmp_path_factory, size_tests):
    """The size cases and the reference, on the tests the cases reach, timed, with the
    grading processes' peak memory measured."""
    if not bwrap_available():
        pytest.skip("the hostile batch needs bubblewrap and root")
    return once_per_session(tmp_path_factory, "hostile-sizes",
                            lambda folder: grade_cases(folder, hc.SIZES, size_tests, stubs=False, measure=True))


def results_of(batch, name: str) -> dict:
    return json.loads((batch.out / name / "results.json").read_text(encoding="utf-8"))


# The cases ------------------------------------------------------------------------------------------
def test_the_cases_are_all_there_and_distinct():
    names = [c.name for c in hc.CASES]
    assert len(names) == len(set(names)) and len(names) == 59
    spec = {t.name for t in load_spec()}
    for case in hc.CASES:
        assert case.category in ("broken", "hostile") and case.what and case.base in ("reference", "stubs")
        assert (case.refused is not None) == bool(case.layout or (case.archive and case.archive != "cp437-name"))
        assert case.touched <= spec | {"*"}, case.name
        assert case.code or case.name == "copy-of-reference"
    covered = " ".join(names)
    for word in ("syntax", "import-error", "missing-module", "missing-function", "returns-none", "returns-string",
                 "wrong-length", "nan-inf", "exception", "recursion", "prints-megabytes", "non-utf8-source",
                 "infinite-loop", "memory-bomb", "fork-bomb", "sleep", "sys-exit", "os-exit", "kill-parent",
                 "segfault", "monkeypatch", "lying-objects", "import-reference", "import-by-path", "read-hidden",
                 "write-results", "write-outside", "leave-process", "dotdot", "absolute", "symlink", "zip-bomb",
                 "copy-of-reference", "keyring-store", "keyring-fetch", "memfd", "disk-filler", "fork-memory",
                 "huge-contact", "huge-message", "driver-swap", "link-exercises", "link-to-friend-folder",
                 "link-to-friend-zip", "link-as-submission", "sparse-file", "many-files", "sealed-payload",
                 "huge-integer", "sourceless-bytecode", "zip-import-in-notes"):
        assert word in covered, word
    # The key is stored before it is looked for: the batch grades in this order.
    assert names.index("hostile-keyring-fetch") == len(names) - 1
    assert SIZE_CASES and set(SIZE_CASES) <= set(names)
    for name in SIZE_CASES:  # a size case reaches tests of the size batch only
        touched = next(c for c in hc.CASES if c.name == name).touched
        assert touched & set(SIZE_TEST_NAMES), name


@needs_sandbox
@pytest.mark.parametrize("case", hc.CASES, ids=lambda c: c.name)
def test_each_case_earns_what_its_honest_work_earns(request, case):
    sizes = case.name in SIZE_CASES
    batch = request.getfixturevalue("size_batch" if sizes else "batch")
    tests = request.getfixturevalue("size_tests" if sizes else "tests")
    data = results_of(batch, case.name)
    assert hc.problems(case, data, tests) == []
    if case.refused is None:
        assert data["score"] >= hc.expected_score(case, tests) - 1e-9
        assert data["score"] <= hc.expected_score(case, tests) + sum(
            t.points for t in tests if (e := hc.expectation(case, t.name)) is not None and e.partial)
    else:
        assert batch.rows[case.name]["state"] == "refused"


@needs_sandbox
def test_enormous_answers_cost_their_own_tests_quickly_and_the_grader_stays_small(size_batch, size_tests):
    """A 20,000-point contact, a 40 MB message, a 2,000-ball scene: each test they touch
    ends in seconds, and the grading process (which parses, stores and draws what comes
    back) keeps a bounded memory."""
    for name in SIZE_CASES:
        data = results_of(size_batch, name)
        case = next(c for c in hc.CASES if c.name == name)
        for test in data["tests"]:
            seconds = test["extra_data"]["seconds"]
            assert seconds < SIZE_TEST_SECONDS, f"{name}: {test['extra_data']['test']} took {seconds:.1f} s"
        assert data["execution_time"] < SIZE_SUBMISSION_SECONDS, f"{name}: {data['execution_time']} s"
        assert case.touched and all(hc.expectation(case, t.name) is None or t.name in case.touched
                                    for t in size_tests)
    assert size_batch.grading_processes >= 1, "no grading process was measured"
    assert 0 < size_batch.peak_memory < PARENT_MEMORY_BYTES, \
        f"a grading process reached {size_batch.peak_memory / 1024**2:.0f} MiB"
    reference = results_of(size_batch, "reference")
    assert reference["score"] == sum(t.points for t in size_tests)


def longest_list(value) -> int:
    if isinstance(value, dict):
        return max((longest_list(v) for v in value.values()), default=0)
    if isinstance(value, list):
        return max([len(value), *(longest_list(v) for v in value)])
    return 0


@needs_sandbox
def test_a_figure_kept_in_the_results_holds_no_list_longer_than_its_caps(size_batch):
    for name in SIZE_CASES:
        for test in results_of(size_batch, name)["tests"]:
            figure = test["extra_data"].get("figure")
            assert longest_list(figure) <= FIGURE_LIST_CAP, f"{name}: {test['extra_data']['test']}"


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
    from grader.batch.similarity import REFERENCE_ID, find_similar

    names = ["copy-of-reference", "stubs", "hostile-lying-objects", "hostile-monkeypatch", "zip-cp437-name"]
    flags = {frozenset((p.a.id, p.b.id)) for p in find_similar([batch.paths[n] for n in names], tmp_path)}
    assert frozenset(("copy-of-reference", REFERENCE_ID)) in flags
    assert frozenset(("copy-of-reference", "zip-cp437-name")) in flags  # a zipped copy too
    assert not any({"stubs", "hostile-lying-objects", "hostile-monkeypatch"} & pair for pair in flags)


@needs_sandbox
def test_every_results_file_is_valid_gradescope_json(batch, size_batch):
    for graded in (batch, size_batch):
        for name in graded.paths:
            raw = (graded.out / name / "results.json").read_bytes()
            data = json.loads(raw.decode("utf-8"))  # valid UTF-8, whatever the student printed
            assert check_results(data) == [], name
            # Each test's entry stays small whatever the code printed, raised or returned (a
            # picture is cut at 300 KB); the whole file too, on this batch's dozen tests.
            for test in data["tests"]:
                size = len(json.dumps(test))
                assert size < 350_000, f"{name}: {test['extra_data']['test']}'s entry is {size} bytes"
            assert FULL_SPEC or len(raw) < 400_000, f"{name}: results.json of {len(raw)} bytes"
            assert (graded.out / name / "report.html").is_file()


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
        assert {p.name for p in (batch.out / name).iterdir()} <= {"results.json", "report.html", "feedback.html"}, name


@needs_sandbox
def test_each_submission_is_graded_once(batch):
    log = read_grading_log(batch.out)
    assert sorted(entry["submission"] for entry in log) == sorted(batch.paths)


@needs_sandbox
def test_no_file_outside_the_output_changes(batch):
    for where in ("sentinel", "subs"):
        assert changed(batch.before[where], batch.after[where]) == [], where
    assert written_by_hostile_code(REPO, changed(batch.before["repo"], batch.after["repo"])) == []
    assert not Path(hc.ESCAPED_FILE).exists()
    assert not (batch.root / "escaped.py").exists() and not (batch.subs.parent / "escaped.py").exists()
    assert not list(batch.root.rglob("pwned*"))


@needs_sandbox
def test_no_process_is_left_running(batch, size_batch):
    for graded in (batch, size_batch):
        assert graded.strays == [], f"processes of sandbox users nobody holds: {graded.strays}"
        assert graded.mentions == [], graded.mentions
        assert not (graded.out / ".work").exists()


@needs_sandbox
def test_the_batch_takes_a_reasonable_time(batch, size_batch):
    assert FULL_SPEC or batch.seconds < 150, f"the hostile batch took {batch.seconds:.0f} s"
    assert size_batch.seconds < 90, f"the batch of enormous answers took {size_batch.seconds:.0f} s"
    refused = [c.name for c in hc.CASES if c.layout]
    for name in refused:  # refused from their stat alone, before any worker was busy
        assert results_of(batch, name)["execution_time"] == 0, name


# Killed and rerun ------------------------------------------------------------------------------------
KILL_TESTS = "momentum.elastic,momentum.restitution,momentum.perfectly_inelastic,sat.project_circle"
#: The cases of the killed batch: quick ones, those that leave processes or forge, refusals,
#: and two that hang (graded last: whenever the kill comes, something is still running).
KILL_CASES = ("broken-syntax-error", "broken-returns-none", "broken-exception", "hostile-memory-bomb",
              "hostile-fork-bomb", "hostile-sys-exit", "hostile-os-exit", "hostile-kill-parent", "hostile-segfault",
              "hostile-write-results", "hostile-leave-process", "hostile-forge-answers", "hostile-huge-answer",
              "broken-nan-inf", "zip-dotdot", "link-to-friend-folder", "folder-sparse-file", "copy-of-reference")
KILL_LAST = ("hostile-sleep", "hostile-ignore-signals")


def grade_cli(*args, **kwargs) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "grader.batch.grade", *map(str, args)], cwd=REPO,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kwargs)


@needs_sandbox
def test_a_hostile_batch_killed_at_a_random_point_is_graded_once_on_rerun(tmp_path):
    seed = int.from_bytes(os.urandom(4), "little")
    rng = random.Random(seed)
    out = tmp_path / "out"
    cases = tuple(c for c in hc.CASES if c.name in KILL_CASES) + tuple(c for c in hc.CASES if c.name in KILL_LAST)
    paths = hc.build_cases(tmp_path / "subs", {"OUT": str(out), "SENTINEL": str(tmp_path / "sentinel")}, cases)
    paths["reference"] = copy_submission(tmp_path / "subs" / "reference", REPO / "solutions")
    paths = {name: paths[name] for name in sorted(paths, key=lambda n: n in KILL_LAST)}
    subs = list(paths.values())
    refused_at_once = {c.name for c in cases if c.layout}  # refused before any worker starts
    options = ["--out", out, "--jobs", "2", "--no-progress", "--no-html", "--tests", KILL_TESTS,
               "--timeout-call", "6", "--timeout-test", "15"]
    process = grade_cli(*subs, *options, start_new_session=True)
    deadline = time.monotonic() + 120
    try:
        while not [p for p in out.glob("*/results.json") if p.parent.name not in refused_at_once]:
            assert process.poll() is None, process.communicate()
            assert time.monotonic() < deadline, "no results.json appeared in 120 s"
            time.sleep(0.02)
        time.sleep(rng.uniform(0.0, 5.0))
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
    tests = [t for t in load_spec() if t.name in KILL_TESTS.split(",")]
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
    from grader.release.gradescope import build_autograder_zip

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
        hidden = root / "source" / "grader" / "tests" / "hidden" / "test_grid.py"

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
        for name, test in by_name.items():  # what the case's code reaches earns nothing, the rest passes
            assert test["score"] == 0 if name in case.touched else test["status"] == "passed", name
        # An upload whose exercises is a link to the reference: root would read the
        # solutions before any sandbox starts; it is refused instead.
        shutil.rmtree(root / "submission")
        (root / "submission").mkdir()
        (root / "submission" / "exercises").symlink_to(root / "source" / "solutions", target_is_directory=True)
        completed = subprocess.run(["bash", str(root / "run_autograder")], cwd=root, env=env, capture_output=True,
                                   text=True, timeout=240)
        assert completed.returncode == 0, completed.stdout + completed.stderr
        data = json.loads((root / "results" / "results.json").read_text())
        assert data["score"] == 0 and data["extra_data"]["state"] == "refused", data["output"]
        assert "'exercises' is a symbolic link" in data["output"], data["output"]
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


def plain_contact(points, feature_ids="absent") -> dict:
    data = {codec.CONTACT_TAG: True, "normal": [0.0, 1.0], "depth": 0.5, "points": points}
    if feature_ids != "absent":
        data["feature_ids"] = feature_ids
    return data


def test_contact_feature_ids_cross_as_json_and_come_back_as_tuples():
    import solutions.contact

    points = [(0.0, 0.75), (1.0, 0.75)]
    for ids in ((("A", 2, 0, 0), ("A", 2, 0, 1)), (0, 1), ("left", "right"), ((("face", 1), 2), (None, True)),
                ((), (1.5, ("x", ("y", 3))))):
        contact = solutions.contact.Contact((0.0, 1.0), 0.5, points, feature_ids=ids)
        data = codec.encode_value(contact)
        back = codec.decode_contact(codec.plain_data(json.loads(json.dumps(data))), solutions.contact)
        assert back.feature_ids == ids and type(back.feature_ids) is tuple
        assert [type(v) for v in back.feature_ids] == [type(v) for v in ids]
    # A tuple travels as a JSON list; a string or an int as itself: ("a",) and "a" stay apart.
    one = codec.encode_contact(solutions.contact.Contact((0.0, 1.0), 0.5, [(0.0, 0.0)], feature_ids=(("a",),)))
    assert one["feature_ids"] == [["a"]]
    assert codec.decode_feature_ids(one["feature_ids"]) == (("a",),) != codec.decode_feature_ids(["a"])
    # Without ids (None) the contact is sent as before: no key, and None comes back.
    bare = codec.encode_contact(solutions.contact.Contact((0.0, 1.0), 0.5, points))
    assert "feature_ids" not in bare and codec.decode_contact(bare, solutions.contact).feature_ids is None


class OwnContact(SimpleNamespace):
    """A student's own contact class (the codec knows contacts by their class name)."""


OwnContact.__name__ = "Contact"


def test_feature_ids_are_read_without_calling_student_methods():
    import collections

    import solutions.contact

    Named = collections.namedtuple("Named", "ref face")
    ids = (Named(LyingStr("A"), LyingInt(2)), (np.int64(3), np.str_("v"), np.float32(0.5), np.bool_(True)))
    contact = solutions.contact.Contact((0.0, 1.0), 0.5, [(0.0, 0.0), (1.0, 0.0)], feature_ids=ids)
    assert codec.encode_contact(contact)["feature_ids"] == [["A", 2], [3, "v", 0.5, True]]
    # Contact objects of the student's own: the same rules, the count checked by the codec.
    for bad, words in ((("a", ["list"]), "not a list"), (("a", {1, 2}), "not a set"),
                       (("a", object()), "not a object"), (("a", b"bytes"), "not a bytes"),
                       (("a", np.array([1, 2])), "not a ndarray"), ({"a": 1, "b": 2}, "got a dict"),
                       (("a",), "2 point\\(s\\) has 1 feature id"), (("a", "b", "c"), "has 3 feature id")):
        contact = OwnContact(normal=(0.0, 1.0), depth=0.5, points=[(0.0, 0.0), (1.0, 0.0)], feature_ids=bad)
        with pytest.raises(codec.NotPlainData, match=words):
            codec.encode_value(contact)


def test_hostile_feature_ids_are_refused_on_both_sides():
    huge_text = "x" * (codec.MAX_FEATURE_ID_TEXT + 1)
    wide = tuple(range(codec.MAX_FEATURE_ID_ITEMS + 1))
    many = tuple((k, (k, (k, k))) for k in range(codec.MAX_FEATURE_ID_ITEMS))   # 4 values each: 64 in all
    deep = "v"
    for _ in range(codec.MAX_FEATURE_ID_DEPTH + 1):
        deep = (deep,)
    very_deep = "v"
    for _ in range(100_000):   # deeper than the recursion limit: refused before it is walked
        very_deep = (very_deep,)
    for bad, words in ((huge_text, "longer than"), (wide, "more than"), (many, "more than"), (deep, "deep"),
                       (very_deep, "deep"), ("x" * 10**7, "longer than"), (tuple(range(10**6)), "more than")):
        fake = SimpleNamespace(normal=(0.0, 1.0), depth=0.5, points=[(0.0, 0.0)], feature_ids=(bad,))
        with pytest.raises(codec.NotPlainData, match=words):
            codec.encode_contact(fake)
        # The same id forged as JSON by a worker that skipped the encoder.
        forged = codec.decode_feature_ids([bad]) if bad is not very_deep else None
        if forged is not None:
            data = json.loads(json.dumps(plain_contact([[0.0, 0.0]], [list(forged[0]) if isinstance(forged[0], tuple)
                                                                      else forged[0]])))
            with pytest.raises(codec.NotPlainData, match=words):
                codec.plain_data(data)
    # Forged JSON the encoder never writes: objects in an id, the wrong count, not a list.
    for ids, words in (([{"a": 1}], "not a dict"), ([[{"$shape": "Circle"}]], "not a dict"), (["a", "b"], "1 point"),
                       ([], "1 point"), ("a", "must be a list"), ({"0": "a"}, "must be a list"),
                       ([[[[[["a"]]]]]], "deep")):
        with pytest.raises(codec.NotPlainData, match=words):
            codec.plain_data(plain_contact([[0.0, 0.0]], ids))
    # Well-formed ids pass (JSON null for "no ids" too), and a lone surrogate is cleaned.
    assert codec.plain_data(plain_contact([[0.0, 0.0]], [["A", 1, 2.5, True, None]]))["feature_ids"] == [
        ["A", 1, 2.5, True, None]]
    assert codec.plain_data(plain_contact([[0.0, 0.0]], None))["feature_ids"] is None
    assert codec.plain_data(plain_contact([[0.0, 0.0]], ["x\udcff"]))["feature_ids"] == ["x?"]


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

def forge_then_flood():
    """An answer with the real nonce (taken at once), then, a moment later, lines of junk
    that fill the channel, nobody reading it between two calls."""
    import time
    here = _frame_with("nonce")
    forged = {"id": here["number"], "nonce": here["nonce"], "status": "ok", "value": 1}
    os.write(int(sys.argv[1]), (json.dumps(forged) + "\\n").encode())
    time.sleep(0.5)
    for _ in range(100):
        os.write(int(sys.argv[1]), b"junk " * 20_000 + b"\\n")
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


def test_a_channel_filled_after_the_answer_does_not_stall_the_next_large_request(channel_box):
    assert channel_box.call("exercises.channel", "forge_then_flood").value == 1
    result = channel_box.call("exercises.channel", "echo", ["x" * 2_000_000], timeout=3.0)
    assert result.status == "ok" and result.value == 2_000_000, result.message


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


# Submissions are checked before they are read --------------------------------------------------------
def stub_folder(path: Path) -> Path:
    (path / "exercises").mkdir(parents=True)
    (path / "exercises" / "__init__.py").write_text("")
    return path


def bytes_read() -> int:
    """Bytes this process has read with read() and the like so far (/proc/self/io)."""
    with open("/proc/self/io") as handle:
        return int(dict(line.split(": ") for line in handle.read().splitlines())["rchar"])


def refusal(path: Path, **kwargs) -> str:
    """The reason ``opened`` refuses the submission at ``path`` (it must), checked to be
    the reason ``fingerprint`` gives too (for a folder) -- links=skip only for opened."""
    submission = discover([path])[0]
    with pytest.raises(SubmissionRefused) as refused:
        with opened(submission, **kwargs):
            pass
    return str(refused.value)


def test_a_sparse_file_is_refused_from_its_size_before_any_byte_is_read(tmp_path):
    folder = stub_folder(tmp_path / "sparse")
    with open(folder / "exercises" / "data.bin", "wb") as handle:
        handle.truncate(2 * 1024**3)
    before, started = bytes_read(), time.perf_counter()
    with pytest.raises(SubmissionRefused, match=r"data.bin' alone is 2.0 GiB"):
        fingerprint(folder)
    assert bytes_read() - before < 64 * 1024 and time.perf_counter() - started < 1.0
    assert "at most 64.0 MiB" in refusal(folder)
    zipped = tmp_path / "sparse.zip"
    with open(zipped, "wb") as handle:  # an "archive" of 2 GiB: not even its bytes are hashed
        handle.truncate(2 * 1024**3)
    before = bytes_read()
    with pytest.raises(SubmissionRefused, match="the archive 'sparse.zip' is 2.0 GiB"):
        fingerprint(zipped)
    assert bytes_read() - before < 64 * 1024
    assert "is 2.0 GiB" in refusal(zipped)


def test_a_folder_is_capped_in_files_and_bytes(tmp_path):
    many = stub_folder(tmp_path / "many")
    for n in range(MAX_FILES):
        (many / "exercises" / f"f{n}.txt").touch()
    assert f"more than {MAX_FILES} files and folders" in refusal(many)
    heavy = stub_folder(tmp_path / "heavy")
    for n in range(3):
        (heavy / "exercises" / f"part{n}.bin").write_bytes(b"x" * 1000)
    with pytest.raises(SubmissionRefused, match="add up to more than"):
        scan_folder(heavy, max_total_bytes=2500)
    assert len(scan_folder(heavy)) == 4


def test_a_symbolic_link_anywhere_in_a_submission_is_refused_not_followed(tmp_path):
    friend = stub_folder(tmp_path / "friend")
    (friend / "exercises" / "secret.py").write_text("ANSWER = 42\n")
    shutil.make_archive(str(tmp_path / "friend"), "zip", friend)
    layouts = {
        "package": lambda f: (f / "exercises").symlink_to(REPO / "solutions", target_is_directory=True),
        "module": lambda f: (stub_folder(f) / "exercises" / "momentum.py").symlink_to(
            friend / "exercises" / "secret.py"),
        "nested": lambda f: (stub_folder(f) / "exercises" / "more").symlink_to(tmp_path, target_is_directory=True),
        "friend-link": lambda f: (f / "friend").symlink_to(Path("..") / "friend", target_is_directory=True),
        "zip": lambda f: (f / "friend.zip").symlink_to(tmp_path / "friend.zip"),
        "dangling": lambda f: (stub_folder(f) / "exercises" / "gone.py").symlink_to(tmp_path / "nothing"),
    }
    for name, make in layouts.items():
        folder = tmp_path / name
        folder.mkdir()
        make(folder)
        before = bytes_read()
        with pytest.raises(SubmissionRefused, match="is a symbolic link") as refused:
            fingerprint(folder)
        assert "never follows links" in str(refused.value) and bytes_read() - before < 64 * 1024, name
        assert "is a symbolic link" in refusal(folder), name
    # The submission's own path as a link: refused, named after the link, not its target.
    (tmp_path / "alias").symlink_to(friend, target_is_directory=True)
    (tmp_path / "alias.zip").symlink_to(tmp_path / "friend.zip")
    for alias in ("alias", "alias.zip"):
        submission = discover([tmp_path / alias])[0]
        assert submission.kind == "link" and submission.id == "alias" and submission.path == tmp_path / alias
        with pytest.raises(SubmissionRefused, match=f"the submission '{alias}' is a symbolic link"):
            checked_path(submission.path)
        assert f"the submission '{alias}' is a symbolic link" in refusal(tmp_path / alias)
    # What grader.batch.similarity reads (verify=False): a link inside is left out, never
    # followed; a link on the way to the package is refused all the same.
    with opened(discover([tmp_path / "module"])[0], verify=False) as folder:
        assert folder == tmp_path / "module"
    for name in ("package", "friend-link"):
        assert "is a symbolic link" in refusal(tmp_path / name, verify=False), name


def test_a_hard_link_is_graded_by_content_and_flagged_for_both_never_refused(tmp_path):
    """A hard link's two names are one file: nothing says which student made it, so the
    classmate whose file was linked to must lose nothing (it was refused, with the linker:
    0 of 134).  Each is graded by its content, and both are flagged, naming the other."""
    friend = stub_folder(tmp_path / "friend")
    (friend / "exercises" / "momentum.py").write_text("ANSWER = 42\n")
    shutil.make_archive(str(tmp_path / "classmate"), "zip", friend)
    linked = stub_folder(tmp_path / "linked")
    os.link(friend / "exercises" / "momentum.py", linked / "exercises" / "momentum.py")
    assert fingerprint(linked) == fingerprint(friend)  # read by content, as a copy would be
    with opened(discover([linked])[0]) as folder:
        assert (folder / "exercises" / "momentum.py").read_text() == "ANSWER = 42\n"
    os.link(tmp_path / "classmate.zip", tmp_path / "copycat.zip")
    checked_path(tmp_path / "copycat.zip")
    flags = hard_links(discover([friend, linked, tmp_path / "copycat.zip", tmp_path / "classmate.zip"]))
    assert flags["friend"] == ["'exercises/momentum.py' is a hard link: the same file as linked's "
                               "'exercises/momentum.py'"]
    assert flags["linked"] == ["'exercises/momentum.py' is a hard link: the same file as friend's "
                               "'exercises/momentum.py'"]
    assert "the same file as classmate's 'classmate.zip'" in flags["copycat"][0]
    alone = hard_links(discover([linked]))
    assert alone["linked"] == ["'exercises/momentum.py' is a hard link: the same file as 1 name(s) outside this batch"]
    assert not hard_links(discover([stub_folder(tmp_path / "honest")]))


@needs_sandbox
def test_the_kernel_keyring_and_memfd_are_refused_in_every_sandbox(tmp_path):
    """What a later submission under another uid could read: nothing is ever stored."""
    package = tmp_path / "exercises"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "kernel.py").write_text(textwrap.dedent(KERNEL))
    with Sandbox(package, slot=6) as first, Sandbox(package, slot=7) as second:
        assert first.uid != second.uid
        stored = first.call("exercises.kernel", "store", ["grader-hostile-direct"])
        assert stored.status == "ok" and stored.value == {"add_key": 1, "keyctl": 1, "memfd": 1}, stored
        found = second.call("exercises.kernel", "fetch", ["grader-hostile-direct"])
        assert found.status == "ok" and found.value == {"search": -1, "keys": 0}, found


KERNEL = '''
import ctypes, errno, os

def _libc():
    libc = ctypes.CDLL(None, use_errno=True)
    libc.syscall.restype = ctypes.c_long
    return libc

def store(description):
    """errno of add_key, of keyctl (a read), and of memfd_create."""
    libc = _libc()
    data = b"def perfectly_inelastic_1d(m1, v1, m2, v2): ..."
    out = {}
    result = libc.syscall(248, b"user", description.encode(), data, ctypes.c_size_t(len(data)), ctypes.c_int(-4))
    out["add_key"] = ctypes.get_errno() if result < 0 else 0
    result = libc.syscall(250, ctypes.c_int(0), ctypes.c_int(-4), ctypes.c_int(0))  # KEYCTL_GET_KEYRING_ID
    out["keyctl"] = ctypes.get_errno() if result < 0 else 0
    try:
        os.close(os.memfd_create("hog"))
        out["memfd"] = 0
    except OSError as exc:
        out["memfd"] = exc.errno
    return out

def fetch(description):
    libc = _libc()
    found = libc.syscall(250, ctypes.c_int(10), ctypes.c_int(-4), b"user", description.encode(), ctypes.c_int(0))
    try:
        with open("/proc/keys") as handle:
            keys = sum(1 for line in handle if description in line)
    except OSError:
        keys = 0
    return {"search": found if found > 0 else -1, "keys": keys}
'''


def test_a_withheld_function_is_answered_not_implemented_alone_or_in_a_program(tmp_path):
    """Issue 24: the trusted side answers a call of a function whose source is still the
    stub, also inside a program of calls (the scenes), without asking the worker."""
    package = tmp_path / "exercises"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "mod.py").write_text("def answer():\n    return 42\n\ndef other():\n    return 1\n")
    with Sandbox(package, slot=9, isolation="plain", withheld={"exercises.mod:answer": "still the stub"}) as box:
        alone = box.call("exercises.mod", "answer", [])
        assert alone.status == "not_implemented" and "answer: still the stub" in alone.message
        assert box.call("exercises.mod", "other", []).value == 1
        program = {"functions": [["exercises.mod", "other"], ["exercises.mod", "answer"]], "registers": {},
                   "calls": [[1, [], ["x"]]], "results": ["x"]}
        inside = box.call("", "", program=program)
        assert inside.status == "not_implemented" and "answer: still the stub" in inside.message
