"""Grade a class: every submission, every test of the spec, in parallel, resumable.

    grader grade SUBMISSIONS... --out DIR [--jobs N] [--regrade]

Writes, for each submission, ``DIR/<id>/results.json`` in Gradescope's format (and
``DIR/<id>/report.html`` when :mod:`grader.report` is there, the instructor's page of
every test), ``DIR/<id>/feedback.html`` (the student's page: only the tests Gradescope
would show now, see :mod:`grader.feedback`; ``--after-due-date`` and ``--published``
say what "now" is, ``--feedback-dir FEEDBACK`` adds a copy at
``FEEDBACK/<id>/feedback.html``), then ``DIR/gradebook.csv`` with one row per graded
submission in ``DIR``.  Feedback pages are written again on every run, for skipped
submissions too, so a rerun with ``--after-due-date`` releases more without regrading.

How a batch runs
----------------
The parent process hands submissions to ``--jobs`` grading workers, each a Python
process (``python -m grader.grade --worker``) with a sandbox slot of its own, so each
parallel job runs the student code as its own unprivileged user.  Parent and workers
talk in JSON lines; the parent alone writes files.  A worker streams each test's
result as soon as it is known, so the parent can enforce two hard limits itself:

- **per test** (``per_test_seconds``): a test that runs longer has its worker stopped
  (its sandboxes die with it), is scored as a timeout, and the submission goes on with
  its next test in a fresh worker;
- **per submission** (``per_submission_seconds``): tests not started in time are
  scored as timeouts ("not run").

Each call into student code also has its own timeout (``Limits.call_timeout``).  Both
limits are scaled by :func:`grader.calibration.slowdown`, measured when the batch
starts: on a loaded machine they grow (up to four times), so honest work is not cut off.

Resuming
--------
``results.json`` is written atomically the moment a submission is done, and records
the submission's fingerprint and the hash of the test spec.  A rerun of the same
command skips every submission whose results record the same two (``--regrade``
grades them again), so a batch killed at any point loses only the submissions that
were being graded.  A submission that cannot be graded (a damaged or unsafe archive,
a symbolic link anywhere in it, a folder over the size caps, no ``exercises`` package)
gets a results.json with 0 points saying why -- links and sizes are checked before any
of its files is read, even to fingerprint it (:mod:`grader.submissions`); a failure of
the grader itself writes nothing, is reported, and is retried by the next run.
Changing the checks' code does not change the spec hash: pass ``--regrade`` then.

Every results.json written is also recorded as one line of ``DIR/grading_log.jsonl``
(submission id, state, score, fingerprint, time), appended right after the file is in
place: an audit of what each run graded (a submission appears once per grading).

``--tests PATTERN[,PATTERN...]`` grades only the tests whose names match (shell-style
patterns: ``momentum.*``); the spec hash then covers those tests only.
"""
from __future__ import annotations

import argparse
import contextlib
import csv
import dataclasses
import fcntl
import fnmatch
import hashlib
import importlib
import io
import json
import os
import selectors
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator

from .calibration import slowdown
from .outcome import Outcome
from .results import (RESULTS_NAME, build_results, read_results, refused_results, write_results,
                      write_text_atomic)
from .sandbox import Limits, choose_isolation
from .spec import TestSpec, load_spec
from .submissions import (Submission, SubmissionPathError, SubmissionRefused, discover, find_package,
                          fingerprint, opened)

HERE = Path(__file__).resolve().parent
REPO_ROOT = HERE.parent
GRADEBOOK_NAME = "gradebook.csv"
LOG_NAME = "grading_log.jsonl"
REPORT_NAME = "report.html"
FEEDBACK_NAME = "feedback.html"
WORK_NAME = ".work"  # scratch folder of a run inside the output folder, removed after
LOCK_NAME = ".grader.lock"
#: Times a submission may lose its worker process before its remaining tests are given up.
MAX_WORKER_DEATHS = 2
DEFAULT_PER_TEST_SECONDS = 30.0
DEFAULT_PER_SUBMISSION_SECONDS = 60.0


class GradingError(RuntimeError):
    """The batch cannot start (output folder busy, sandbox unusable); the message says why."""


def spec_hash(tests: list[TestSpec]) -> str:
    """sha256 (hex) of the test spec: names, exercises, titles, points, visibility, leaderboard."""
    text = json.dumps([dataclasses.asdict(t) for t in tests], sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def bwrap_works() -> bool:
    """True when bubblewrap can build the worker's sandbox here (it may be installed but
    refused by the kernel or a container, as in many Docker setups)."""
    command = ["bwrap", "--unshare-pid", "--unshare-net", "--unshare-ipc", "--unshare-uts", "--unshare-cgroup-try",
               "--die-with-parent", "--new-session", "--ro-bind", "/", "/", "--proc", "/proc", "--dev", "/dev",
               "--tmpfs", "/tmp", "--", "setpriv", "--reuid=61000", "--regid=61000", "--clear-groups",
               "--no-new-privs", "--bounding-set=-all", "--inh-caps=-all", "/bin/true"]
    try:
        return subprocess.run(command, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL, timeout=20).returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        return False


def resolve_isolation(requested: str = "auto", warn: Callable[[str], None] | None = None) -> str:
    """``"bwrap"`` or ``"plain"``: :func:`grader.sandbox.choose_isolation`, then a trial run.

    ``"auto"`` falls back to ``"plain"`` (with a warning) when bubblewrap is installed
    but cannot start a sandbox; an explicit ``"bwrap"`` raises GradingError then.
    """
    try:
        chosen = choose_isolation(requested)
    except ValueError as exc:
        raise GradingError(str(exc)) from None
    if chosen == "bwrap" and not bwrap_works():
        if requested == "bwrap":
            raise GradingError("bubblewrap is installed but cannot create a sandbox on this machine "
                               "(no user or mount namespaces here?); use --isolation plain")
        if warn is not None:
            warn("warning: bubblewrap cannot create a sandbox here; grading with --isolation plain "
                 "(student code runs as this user and can read the grader's files)")
        return "plain"
    return chosen


# The worker process ------------------------------------------------------------------------
def _die_with_parent() -> None:
    """Ask Linux to send SIGTERM to this process when its parent dies."""
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGTERM, 0, 0, 0)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


def worker_main() -> int:
    """A grading worker: import the checks, read a config line, then one job per line.

    Job: ``{"job": n, "id": ..., "path": ..., "kind": ..., "tests": [indices], "budget": s}``.
    Events: ``ready``; per job ``started`` (with ``package``), one ``test`` per test
    (``index``, ``outcome``, ``seconds``), ``refused`` or ``error`` (with ``reason``),
    and ``done``.
    """
    channel = os.fdopen(os.dup(1), "w", encoding="utf-8")
    os.dup2(2, 1)  # anything else printed goes to the log, not into the protocol
    _die_with_parent()

    def stop(signum, frame):
        raise SystemExit(128 + signum)

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, signal.SIG_IGN)

    def send(event: dict) -> None:
        channel.write(json.dumps(event, allow_nan=True, default=str) + "\n")
        channel.flush()

    from .run import run_tests  # the slow part (pytest): imported while the parent loads the spec
    line = sys.stdin.readline()
    if not line:
        os._exit(0)  # the parent found nothing to grade
    config = json.loads(line)
    slot = int(config["slot"])
    tests = [TestSpec(**t) for t in config["tests"]]
    limits = Limits(**config["limits"])
    tempfile.tempdir = config["tmp"]
    send({"event": "ready", "slot": slot})
    for line in sys.stdin:
        job = json.loads(line)
        number = job["job"]
        indices = list(job["tests"])
        submission = Submission(job["id"], Path(job["path"]), job["kind"])
        try:
            with opened(submission, workdir=config["tmp"]) as folder:
                package = find_package(folder)
                where = package.relative_to(folder).as_posix() if package != folder else "."
                send({"event": "started", "job": number, "package": where})
                # pytest runs the tests in its own order (module paths sorted: hidden/ before
                # public/), not the spec's: each result finds its index by the test's name.
                index_of = {tests[i].name: i for i in indices}
                unclaimed = list(indices)

                def progress(result, index_of=index_of, unclaimed=unclaimed):
                    index = index_of.get(result.test.name)
                    if index not in unclaimed:
                        index = unclaimed[0] if unclaimed else None
                    if index is None:
                        return
                    unclaimed.remove(index)
                    send({"event": "test", "job": number, "index": index,
                          "outcome": result.outcome.to_dict(), "seconds": result.seconds})

                run_tests(package, [tests[i] for i in indices], limits, slot, config["isolation"],
                          budget_seconds=job["budget"], progress=progress)
        except SubmissionRefused as exc:
            send({"event": "refused", "job": number, "reason": str(exc)})
        except Exception as exc:  # the grader's own failure: the parent reports it, writes nothing
            send({"event": "error", "job": number, "reason": f"{type(exc).__name__}: {exc}"})
        send({"event": "done", "job": number})
    channel.flush()
    os._exit(0)  # every sandbox is closed; skip the slow teardown of the imported modules


class Worker:
    """The parent's handle on one grading worker process (one sandbox slot)."""

    def __init__(self, slot: int, work: Path):
        self.slot = slot
        self.folder = work / f"slot-{slot}"
        self.folder.mkdir(exist_ok=True)
        self.log_path = work / f"slot-{slot}.log"
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join([str(REPO_ROOT)] + [p for p in [env.get("PYTHONPATH")] if p])
        env.setdefault("MPLBACKEND", "Agg")
        with open(self.log_path, "ab") as log:
            self.process = subprocess.Popen(
                [sys.executable, "-m", "grader.grade", "--worker"], stdin=subprocess.PIPE,
                stdout=subprocess.PIPE, stderr=log, cwd=self.folder, env=env, start_new_session=True)
        os.set_blocking(self.process.stdout.fileno(), False)
        self.buffer = bytearray()
        self.ready = False
        self.closed = False
        self.job: Job | None = None
        self.deadline = float("inf")
        self.attempt_started = 0.0

    def configure(self, config: dict) -> "Worker":
        """Send the run's settings (tests, limits, isolation); the worker then says ``ready``."""
        self.send({**config, "slot": self.slot, "tmp": str(self.folder)})
        return self

    def send(self, message: dict) -> bool:
        try:
            self.process.stdin.write((json.dumps(message) + "\n").encode())
            self.process.stdin.flush()
            return True
        except (BrokenPipeError, OSError):
            return False

    def events(self) -> list[dict]:
        """Complete event lines received so far; sets ``closed`` at end of file."""
        while True:
            try:
                chunk = os.read(self.process.stdout.fileno(), 1 << 16)
            except BlockingIOError:
                break
            except OSError:
                chunk = b""
            if not chunk:
                self.closed = True
                break
            self.buffer += chunk  # a bytearray: appending is linear in what arrives
        events = []
        start = 0
        while True:
            end = self.buffer.find(b"\n", start)
            if end < 0:
                break
            try:
                events.append(json.loads(self.buffer[start:end]))
            except ValueError:
                pass
            start = end + 1
        del self.buffer[:start]
        return events

    @property
    def alive(self) -> bool:
        return not self.closed and self.process.poll() is None

    def log_tail(self, characters: int = 1500) -> str:
        try:
            with open(self.log_path, "rb") as log:  # only the end: the log may be large
                log.seek(max(0, log.seek(0, os.SEEK_END) - 4 * characters))
                return log.read().decode("utf-8", errors="replace")[-characters:].strip()
        except OSError:
            return ""

    def terminate(self) -> None:
        """Ask the worker to stop now: on SIGTERM it closes its sandboxes and exits."""
        if self.process.poll() is None:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(self.process.pid, signal.SIGTERM)

    def wait(self, grace: float) -> None:
        """Wait up to ``grace`` seconds for the worker to exit, then kill it."""
        process = self.process
        try:
            process.wait(timeout=max(0.0, grace))
        except subprocess.TimeoutExpired:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(process.pid, signal.SIGKILL)
            with contextlib.suppress(subprocess.TimeoutExpired):
                process.wait(timeout=10)
        for stream in (process.stdin, process.stdout):
            with contextlib.suppress(OSError):
                stream.close()

    def stop(self, grace: float = 3.0) -> None:
        """Ask the worker to stop (it closes its sandboxes), then kill it."""
        self.terminate()
        self.wait(grace)


def _dismiss(workers: list["Worker"]) -> None:
    """Stop workers that have no job (still importing, or idle) without waiting for each in turn."""
    for worker in workers:
        worker.terminate()
    for worker in workers:
        worker.wait(2.0)


def shutdown(workers: list["Worker"], grace: float = 5.0) -> None:
    """End every worker at once: idle ones get end of input, busy ones SIGTERM."""
    for worker in workers:
        if worker.job is None:
            with contextlib.suppress(OSError):
                worker.process.stdin.close()
        else:
            worker.terminate()
    deadline = time.monotonic() + grace
    for worker in workers:
        worker.wait(deadline - time.monotonic())


# The parent ------------------------------------------------------------------------------
@dataclass
class Job:
    """One submission being graded, possibly over several worker attempts."""

    number: int
    submission: Submission
    fingerprint: str
    remaining: list[int]
    outcomes: dict[int, tuple[Outcome, float]] = field(default_factory=dict)
    used: float = 0.0  # seconds of earlier attempts
    deaths: int = 0
    package: str | None = None
    refused: str | None = None
    error: str | None = None


class _PlainProgress:
    """Stand-in for tqdm: one line per submission on stderr."""

    def __init__(self, total: int, initial: int, disable: bool):
        self.total, self.n, self.disable = total, initial, disable

    def update(self, n: int = 1) -> None:
        self.n += n

    def set_postfix_str(self, text: str) -> None:
        if not self.disable:
            print(f"[{self.n}/{self.total}] {text}", file=sys.stderr, flush=True)

    def write(self, text: str) -> None:
        print(text, file=sys.stderr, flush=True)

    def close(self) -> None:
        pass


def _progress_bar(total: int, initial: int, enabled: bool):
    """A tqdm bar on a terminal; whole lines (one per submission) anywhere else, so a
    log or CI output holds no carriage returns."""
    if not (hasattr(sys.stderr, "isatty") and sys.stderr.isatty()):
        return _PlainProgress(total, initial, not enabled)
    try:
        from tqdm import tqdm
    except ImportError:
        return _PlainProgress(total, initial, not enabled)
    return tqdm(total=total, initial=initial, disable=not enabled, unit="submission", desc="grading",
                file=sys.stderr, dynamic_ncols=True)


def _report_module():
    """:mod:`grader.report` if it exists, else None."""
    try:
        return importlib.import_module("grader.report")
    except ModuleNotFoundError as exc:
        if exc.name in ("grader.report",):
            return None
        raise


def write_student_report(results_path: Path, warn: Callable[[str], None]) -> None:
    """``report.html`` next to ``results.json`` (when grader.report exists); never raises."""
    try:
        report = _report_module()
        if report is not None:
            report.write_student_report(results_path, results_path.parent / REPORT_NAME)
    except Exception as exc:  # a report must not cost a grade
        warn(f"warning: no HTML report for {results_path.parent.name}: {type(exc).__name__}: {exc}")


@dataclass(frozen=True)
class FeedbackOptions:
    """What the student feedback pages show, and where copies go.

    ``html``: write ``feedback.html`` beside each results.json; ``folder``: also write
    ``folder/<id>/feedback.html``; ``after_due_date`` and ``published``: show those
    tests (see :mod:`grader.feedback`).
    """

    html: bool = True
    folder: Path | None = None
    after_due_date: bool = False
    published: bool = False

    @property
    def wanted(self) -> bool:
        return self.html or self.folder is not None


def write_feedback(results_path: Path, submission_id: str, options: FeedbackOptions,
                   warn: Callable[[str], None]) -> None:
    """The student's ``feedback.html`` of one results.json (and its copy); never raises."""
    if not options.wanted:
        return
    try:
        from .feedback import write_feedback_report

        targets = []
        if options.html:
            targets.append(results_path.parent / FEEDBACK_NAME)
        if options.folder is not None:
            targets.append(options.folder / submission_id / FEEDBACK_NAME)
        for target in targets:
            write_feedback_report(results_path, target, options.after_due_date, options.published)
    except Exception as exc:  # feedback must not cost a grade
        warn(f"warning: no feedback page for {submission_id}: {type(exc).__name__}: {exc}")


@contextlib.contextmanager
def _locked(out_dir: Path) -> Iterator[None]:
    handle = open(out_dir / LOCK_NAME, "a")
    try:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        handle.close()
        raise GradingError(f"another `grader grade` is writing to {out_dir}; wait for it to finish "
                           "or choose another --out") from None
    try:
        yield
    finally:
        handle.close()


def _row(submission: Submission, state: str, data: dict | None, out_dir: Path, message: str = "") -> dict:
    return {"id": submission.id, "source": str(submission.path), "state": state,
            "score": None if data is None else data.get("score"),
            "max_score": None if data is None else data.get("max_score"),
            "results_path": None if data is None else str(out_dir / submission.id / RESULTS_NAME),
            "results": data, "message": message}


def grade_submissions(paths: list[str | os.PathLike], out_dir: str | os.PathLike, jobs: int = 1,
                      regrade: bool = False, limits: Limits = Limits(), isolation: str = "auto",
                      per_submission_seconds: float = DEFAULT_PER_SUBMISSION_SECONDS,
                      per_test_seconds: float = DEFAULT_PER_TEST_SECONDS, progress: bool = True,
                      tests: list[TestSpec] | None = None, html: bool = True, after_due_date: bool = False,
                      published: bool = False, feedback_dir: str | os.PathLike | None = None,
                      calibrate: bool = True) -> list[dict]:
    """Grade every submission at ``paths`` into ``out_dir``; skip what is already graded.

    ``calibrate=False`` keeps the time limits as given (else they are scaled by how
    loaded the machine is, :mod:`grader.calibration`).

    Parameters
    ----------
    paths : list of path
        Each a submission: a folder or a zip archive holding ``exercises/``.
    out_dir : path
        Output folder: ``<id>/results.json`` per submission and ``gradebook.csv``.
    jobs : int
        Submissions graded at the same time (one worker process and sandbox slot each).
    regrade : bool
        Grade again even when ``results.json`` records the same submission and spec.
    limits : Limits
        Resource limits of the student's worker (and its per-call timeout, s).
    isolation : str
        ``"auto"``, ``"bwrap"`` or ``"plain"`` (see :mod:`grader.sandbox`).
    per_submission_seconds, per_test_seconds : float
        Wall-clock limits (s); see the module docstring.
    progress : bool
        Show a progress bar on stderr.
    tests : list of TestSpec, optional
        The tests to run (default: the whole spec, public and hidden).
    html : bool
        Also write the HTML reports: the instructor's (when :mod:`grader.report` is
        there) and the student's feedback page.
    after_due_date, published : bool
        The feedback pages also show the tests Gradescope shows after the due date,
        and after the grades are published (hidden tests: never).
    feedback_dir : path, optional
        Also write each feedback page to ``feedback_dir/<id>/feedback.html`` (even
        without ``html``).

    Returns
    -------
    list of dict
        One per submission, in the order given: ``id``, ``source``, ``state``
        (``graded``, ``skipped`` (already graded), ``refused`` (0 points, see
        ``message``) or ``error`` (the grader failed; nothing written)), ``score``,
        ``max_score``, ``results_path``, ``results`` (the results.json data) and
        ``message``.

    Raises
    ------
    SubmissionPathError
        A path does not exist (nothing is graded).
    GradingError
        The output folder is in use by another run, or the isolation asked for is not
        available.
    """
    if jobs < 1:
        raise ValueError(f"jobs must be at least 1, got {jobs}")
    submissions = discover(paths)
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise GradingError(f"--out {out_dir} exists and is not a folder")
    out_dir.mkdir(parents=True, exist_ok=True)
    out_dir = out_dir.resolve()
    if feedback_dir is not None:
        feedback_dir = Path(feedback_dir).expanduser()
        if feedback_dir.exists() and not feedback_dir.is_dir():
            raise GradingError(f"--feedback-dir {feedback_dir} exists and is not a folder")
        feedback_dir = feedback_dir.resolve()
    feedback = FeedbackOptions(html, feedback_dir, after_due_date, published)
    bar = _progress_bar(len(submissions), 0, progress)
    warn = bar.write
    rows: dict[str, dict] = {}
    workers: list[Worker] = []
    try:
        # Measured before the grading workers start importing, which would load the machine.
        factor = slowdown() if calibrate else 1.0
        with _locked(out_dir):
            work = out_dir / WORK_NAME
            shutil.rmtree(work, ignore_errors=True)
            work.mkdir()
            written = (RESULTS_NAME, REPORT_NAME, FEEDBACK_NAME)
            for stale in [*(p for name in written for p in out_dir.glob(f"*/.{name}.*.tmp")),
                          *out_dir.glob(f".{GRADEBOOK_NAME}.*.tmp")]:
                stale.unlink(missing_ok=True)  # left by a run killed while writing
            try:
                # Workers start importing now, while this process loads the spec and
                # fingerprints the submissions; they are sent away if nothing needs grading.
                workers = [Worker(slot, work) for slot in range(min(jobs, len(submissions)))]
                tests = load_spec() if tests is None else list(tests)
                digest = spec_hash(tests)
                todo: list[Job] = []
                for submission in submissions:
                    results_path = out_dir / submission.id / RESULTS_NAME
                    refusal = None
                    try:
                        # Checks links and sizes before reading a byte (grader.submissions).
                        submission_fingerprint = fingerprint(submission.path)
                    except SubmissionRefused as exc:
                        refusal = str(exc)
                        submission_fingerprint = "refused:" + hashlib.sha256(refusal.encode()).hexdigest()
                    except OSError as exc:
                        refusal = "the submission could not be read"
                        submission_fingerprint = f"unreadable:{exc.errno}"
                    previous = read_results(results_path)
                    meta = (previous or {}).get("extra_data") or {}
                    if (not regrade and previous is not None and meta.get("fingerprint") == submission_fingerprint
                            and meta.get("spec_hash") == digest):
                        rows[submission.id] = _row(submission, "skipped", previous, out_dir)
                        if html and not (results_path.parent / REPORT_NAME).exists():
                            write_student_report(results_path, warn)
                        write_feedback(results_path, submission.id, feedback, warn)
                        bar.update(1)
                        continue
                    if refusal is not None:
                        data = refused_results(tests, refusal, 0.0, submission.id, submission_fingerprint, digest)
                        write_results(data, results_path)
                        log_graded(out_dir, submission.id, "refused", data)
                        if html:
                            write_student_report(results_path, warn)
                        write_feedback(results_path, submission.id, feedback, warn)
                        rows[submission.id] = _row(submission, "refused", data, out_dir, data["output"])
                        bar.update(1)
                        continue
                    todo.append(Job(len(todo), submission, submission_fingerprint, run_order(tests)))
                workers, spare = workers[:len(todo)], workers[len(todo):]
                _dismiss(spare)
                if todo:
                    chosen = resolve_isolation(isolation, warn)
                    config = {"tests": [dataclasses.asdict(t) for t in tests], "limits": dataclasses.asdict(limits),
                              "isolation": chosen}
                    for worker in workers:
                        worker.configure(config)

                    def finished(job: Job, elapsed: float) -> None:
                        rows[job.submission.id] = _finish(job, elapsed, tests, digest, out_dir, html, warn,
                                                          feedback)
                        row = rows[job.submission.id]
                        score = f"{row['score']:g}/{row['max_score']:g}" if row["score"] is not None else row["state"]
                        bar.update(1)
                        bar.set_postfix_str(f"{job.submission.id}: {score}")

                    # Limits in wall-clock seconds, scaled by how loaded the machine is now
                    # (grader.calibration): a busy machine must not fail honest work.
                    if factor > 1.05:
                        warn(f"note: this machine runs {factor:.1f}x slower than an idle one now; time limits "
                             f"scaled to {per_test_seconds * factor:g} s per test and "
                             f"{per_submission_seconds * factor:g} s per submission")
                    _run_jobs(todo, workers, config, work, per_test_seconds * factor, per_submission_seconds * factor,
                              finished, warn)
                    workers = []
            finally:
                _dismiss(workers)  # those not handed to _run_jobs (nothing to grade, or an error)
                if tests is not None:
                    with contextlib.suppress(OSError):
                        write_gradebook(out_dir, tests)
                if html:
                    _class_report(out_dir, warn)
                shutil.rmtree(work, ignore_errors=True)
    finally:
        bar.close()
    return [rows[s.id] for s in submissions if s.id in rows]


def _finish(job: Job, elapsed: float, tests: list[TestSpec], digest: str, out_dir: Path, html: bool,
            warn: Callable[[str], None], feedback: FeedbackOptions | None = None) -> dict:
    """Write a finished job's results.json (and report); its summary row."""
    from .plugin import TestResult

    submission = job.submission
    results_path = out_dir / submission.id / RESULTS_NAME
    if job.error is not None:
        warn(f"error: the grader failed on {submission.id} ({job.error}); nothing written, "
             "rerun to try again")
        return _row(submission, "error", None, out_dir, job.error)
    if job.refused is not None:
        data = refused_results(tests, job.refused, elapsed, submission.id, job.fingerprint, digest)
        state = "refused"
    else:
        results = []
        for index, test in enumerate(tests):
            outcome, seconds = job.outcomes.get(index, (Outcome("not_run", message="this test did not run"), 0.0))
            results.append(TestResult(test, outcome, seconds))
        data = build_results(results, elapsed, submission.id, job.fingerprint, digest, job.package)
        state = "graded"
    write_results(data, results_path)
    log_graded(out_dir, submission.id, state, data)
    if html:
        write_student_report(results_path, warn)
    write_feedback(results_path, submission.id, feedback or FeedbackOptions(html), warn)
    return _row(submission, state, data, out_dir, data["output"] if state == "refused" else "")


def log_graded(out_dir: Path, submission_id: str, state: str, data: dict) -> None:
    """Append one line to ``out_dir/grading_log.jsonl``: this submission was just graded.

    One ``write`` of one line to a file opened for appending: lines of concurrent
    writers never interleave, and a run killed before it leaves no partial line.
    """
    meta = data.get("extra_data") or {}
    line = json.dumps({"submission": submission_id, "state": state, "score": data.get("score"),
                       "fingerprint": meta.get("fingerprint"), "spec_hash": meta.get("spec_hash"),
                       "at": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "pid": os.getpid()}) + "\n"
    with contextlib.suppress(OSError):  # an audit line must never cost a grade
        fd = os.open(out_dir / LOG_NAME, os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_CLOEXEC, 0o644)
        try:
            os.write(fd, line.encode())
        finally:
            os.close(fd)


def read_grading_log(out_dir: str | os.PathLike) -> list[dict]:
    """The lines of ``out_dir/grading_log.jsonl`` (an empty list when there is none)."""
    try:
        text = (Path(out_dir) / LOG_NAME).read_text(encoding="utf-8")
    except OSError:
        return []
    entries = []
    for line in text.splitlines():
        with contextlib.suppress(ValueError):
            entries.append(json.loads(line))
    return entries


def run_order(tests: list[TestSpec]) -> list[int]:
    """Indices of ``tests`` in the order :func:`grader.run.run_tests` runs them: module by
    module (paths sorted), each module's tests in spec order.  A job's ``remaining``
    keeps this order, so that its first item is the test a stopped worker was running."""
    return sorted(range(len(tests)), key=lambda i: (tests[i].path, i))


def select_tests(tests: list[TestSpec], patterns: str | None) -> list[TestSpec]:
    """The tests whose names match one of the comma-separated shell-style ``patterns``."""
    if not patterns:
        return tests
    wanted = [p.strip() for p in patterns.split(",") if p.strip()]
    chosen = [t for t in tests if any(fnmatch.fnmatchcase(t.name, p) for p in wanted)]
    if not chosen:
        raise GradingError(f"--tests {patterns!r} matches no test (see `grader list`)")
    return chosen


def _run_jobs(todo: list[Job], started: list[Worker], config: dict, work: Path, per_test_seconds: float,
              per_submission_seconds: float, finished: Callable[[Job, float], None],
              warn: Callable[[str], None]) -> None:
    """Hand the jobs to the (configured) workers; enforce the hard limits; call ``finished``
    per job.  A worker stopped or dead is replaced by a new one in the same slot."""
    queue = deque(todo)
    workers: list[Worker | None] = list(started)

    def start(slot: int) -> Worker:
        return Worker(slot, work).configure(config)

    def give_up(job: Job, reason: str, status: str) -> None:
        for index in job.remaining:
            job.outcomes[index] = (Outcome(status, message=reason), 0.0)
        job.remaining = []

    def interrupted(worker: Worker, job: Job, status: str, message: str) -> None:
        """The worker was stopped or died during the job's current test: score it, go on."""
        now = time.monotonic()
        job.used += now - worker.attempt_started
        if job.remaining:
            current = job.remaining.pop(0)
            job.outcomes[current] = (Outcome(status, message=message), now - worker.deadline + per_test_seconds)
        if job.used >= per_submission_seconds:
            give_up(job, f"not run: the submission used up its {per_submission_seconds:g} s", "timeout")
        elif job.deaths > MAX_WORKER_DEATHS:
            give_up(job, "not run: the grading process kept stopping on this submission "
                         "(tell your instructor)", "crashed")
        if job.remaining:
            queue.appendleft(job)
        else:
            finished(job, job.used)

    try:
        with selectors.DefaultSelector() as selector:
            while queue or any(w is not None and w.job is not None for w in workers):
                for slot, worker in enumerate(workers):
                    if worker is not None and worker.ready and worker.job is None and queue:
                        job = queue.popleft()
                        worker.job = job
                        worker.attempt_started = time.monotonic()
                        worker.deadline = worker.attempt_started + per_test_seconds
                        worker.send({"job": job.number, "id": job.submission.id, "path": str(job.submission.path),
                                     "kind": job.submission.kind, "tests": job.remaining,
                                     "budget": max(0.0, per_submission_seconds - job.used)})
                live = [w for w in workers if w is not None]
                registered = {}
                for worker in live:
                    if not worker.closed:
                        with contextlib.suppress(ValueError, KeyError, OSError):
                            selector.register(worker.process.stdout, selectors.EVENT_READ, worker)
                            registered[worker.slot] = worker
                nearest = min((w.deadline for w in live if w.job is not None), default=time.monotonic() + 1.0)
                selector.select(timeout=max(0.01, min(1.0, nearest - time.monotonic())))
                for worker in registered.values():
                    with contextlib.suppress(ValueError, KeyError, OSError):
                        selector.unregister(worker.process.stdout)
                for slot, worker in enumerate(workers):
                    if worker is None:
                        continue
                    for event in worker.events():
                        _handle_event(worker, event, per_test_seconds, finished)
                    job = worker.job
                    if not worker.alive:
                        worker.stop()
                        if job is not None:
                            job.deaths += 1
                            tail = worker.log_tail()
                            warn(f"warning: the grading worker stopped while grading {job.submission.id}"
                                 + (f":\n{tail}" if tail else ""))
                            worker.job = None
                            interrupted(worker, job, "crashed",
                                        "this test could not be completed: the grading process stopped "
                                        "unexpectedly (tell your instructor)")
                        elif not worker.ready:
                            tail = worker.log_tail()
                            raise GradingError("a grading worker could not start" + (f":\n{tail}" if tail else ""))
                        workers[slot] = start(slot) if queue else None
                    elif job is not None and time.monotonic() > worker.deadline:
                        worker.stop()
                        worker.job = None
                        interrupted(worker, job, "timeout",
                                    f"took longer than {per_test_seconds:g} s (wall clock) and was stopped")
                        workers[slot] = start(slot) if queue else None
    finally:
        shutdown([w for w in workers if w is not None])


def _handle_event(worker: Worker, event: dict, per_test_seconds: float,
                  finished: Callable[[Job, float], None]) -> None:
    kind = event.get("event")
    if kind == "ready":
        worker.ready = True
        return
    job = worker.job
    if job is None or event.get("job") != job.number:
        return
    now = time.monotonic()
    if kind == "started":
        job.package = event.get("package")
        worker.deadline = now + per_test_seconds
    elif kind == "test":
        index = int(event["index"])
        data = event["outcome"]
        outcome = Outcome.from_dict(data if isinstance(data, dict) else {})
        job.outcomes[index] = (outcome, float(event.get("seconds", 0.0)))
        if index in job.remaining:
            job.remaining.remove(index)
        worker.deadline = now + per_test_seconds
    elif kind == "refused":
        job.refused = str(event.get("reason"))
    elif kind == "error":
        job.error = str(event.get("reason"))
    elif kind == "done":
        job.used += now - worker.attempt_started
        worker.job = None
        worker.deadline = float("inf")
        if job.refused is None and job.error is None:
            for index in job.remaining:  # run_tests answers for every test it is given
                job.outcomes.setdefault(index, (Outcome("not_run", message="this test did not run"), 0.0))
            job.remaining = []
        finished(job, job.used)


# Gradebook and class report -------------------------------------------------------------------
def write_gradebook(out_dir: str | os.PathLike, tests: list[TestSpec] | None = None) -> Path:
    """``out_dir/gradebook.csv`` from every ``*/results.json`` there, written atomically.

    Columns: ``submission``, ``score``, ``max_score``, one per test (its spec name; the
    spec's order, then tests only older results have), ``state`` (graded or refused)
    and ``note`` (why a submission was refused).
    """
    out_dir = Path(out_dir)
    tests = load_spec() if tests is None else tests
    rows = []
    extra_columns: list[str] = []
    names = [t.name for t in tests]
    for path in sorted(out_dir.glob(f"*/{RESULTS_NAME}")):
        data = read_results(path)
        if data is None:
            continue
        meta = data.get("extra_data") or {}
        scores = {}
        for entry in data["tests"]:
            name = (entry.get("extra_data") or {}).get("test") or entry.get("name")
            scores[name] = entry.get("score")
            if name not in names and name not in extra_columns:
                extra_columns.append(name)
        rows.append((meta.get("submission_id") or path.parent.name, data, scores, meta))
    columns = names + sorted(extra_columns)
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["submission", "score", "max_score", *columns, "state", "note"])

    def cell(value: Any) -> str:
        return "" if value is None else f"{value:g}" if isinstance(value, (int, float)) else str(value)

    for submission, data, scores, meta in rows:
        writer.writerow([submission, cell(data.get("score")), cell(data.get("max_score")),
                         *(cell(scores.get(c)) for c in columns), meta.get("state", ""), meta.get("reason", "")])
    path = out_dir / GRADEBOOK_NAME
    write_text_atomic(path, buffer.getvalue())
    return path


def _class_report(out_dir: Path, warn: Callable[[str], None]) -> None:
    try:
        report = _report_module()
        if report is not None:
            report.write_class_report(out_dir)
    except Exception as exc:
        warn(f"warning: no class report: {type(exc).__name__}: {exc}")


# Command line -------------------------------------------------------------------------------
def add_grade_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``grader grade``."""
    parser.add_argument("submissions", nargs="+", metavar="SUBMISSION",
                        help="a folder or a .zip holding a copy of exercises/ (one per student; "
                             "use class/* for a folder of them)")
    parser.add_argument("--out", required=True, metavar="DIR", help="output folder (created if needed)")
    parser.add_argument("--jobs", "-j", type=int, default=os.cpu_count() or 1, metavar="N",
                        help="submissions graded in parallel (default: the number of cores, %(default)s)")
    parser.add_argument("--regrade", action="store_true",
                        help="grade again submissions whose results.json is up to date")
    parser.add_argument("--isolation", choices=("auto", "bwrap", "plain"), default="auto",
                        help="sandbox of the student code (default: bwrap when it works here)")
    parser.add_argument("--timeout-test", type=float, default=DEFAULT_PER_TEST_SECONDS, metavar="SECONDS",
                        help="wall-clock limit of one test (default %(default)g s)")
    parser.add_argument("--timeout-submission", type=float, default=DEFAULT_PER_SUBMISSION_SECONDS,
                        metavar="SECONDS", help="wall-clock limit of one submission's tests (default %(default)g s)")
    parser.add_argument("--timeout-call", type=float, default=Limits.call_timeout, metavar="SECONDS",
                        help="wall-clock limit of one call into student code (default %(default)g s)")
    parser.add_argument("--tests", default=None, metavar="PATTERNS",
                        help="grade only the tests matching these comma-separated patterns, e.g. 'momentum.*,sat.*'")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument("--no-html", action="store_true", help="no HTML reports")
    parser.add_argument("--after-due-date", action="store_true",
                        help="feedback pages also show the tests Gradescope shows after the due date")
    parser.add_argument("--published", action="store_true",
                        help="feedback pages also show the tests Gradescope shows once grades are published, "
                             "and the total score")
    parser.add_argument("--feedback-dir", default=None, metavar="DIR",
                        help="also write each student's feedback page to DIR/<submission id>/feedback.html")


def main_grade(args: argparse.Namespace) -> int:
    """Run ``grader grade``; 0 when every submission has results, 1 if the grader failed on
    some (rerun to retry them), 2 for bad arguments."""
    from .spec import SpecError

    if args.jobs < 1:
        print("grader grade: error: --jobs must be at least 1", file=sys.stderr)
        return 2
    limits = dataclasses.replace(Limits(), call_timeout=args.timeout_call)
    try:
        patterns = getattr(args, "tests", None)
        tests = select_tests(load_spec(), patterns) if patterns else None
        rows = grade_submissions(args.submissions, args.out, jobs=args.jobs, regrade=args.regrade, limits=limits,
                                 isolation=args.isolation, per_submission_seconds=args.timeout_submission,
                                 per_test_seconds=args.timeout_test, progress=not args.no_progress,
                                 html=not args.no_html, tests=tests,
                                 after_due_date=getattr(args, "after_due_date", False),
                                 published=getattr(args, "published", False),
                                 feedback_dir=getattr(args, "feedback_dir", None))
    except (SubmissionPathError, GradingError, SpecError) as exc:
        print(f"grader grade: error: {exc}", file=sys.stderr)
        return 2
    counts: dict[str, int] = {}
    for row in rows:
        counts[row["state"]] = counts.get(row["state"], 0) + 1
    parts = [f"{counts[s]} {s}" for s in ("graded", "skipped", "refused", "error") if counts.get(s)]
    print(f"{len(rows)} submissions: {', '.join(parts)} (skipped: already graded; --regrade to grade again)"
          if counts.get("skipped") else f"{len(rows)} submissions: {', '.join(parts)}")
    for row in rows:
        if row["state"] == "refused":
            print(f"  {row['id']}: refused: {row['message']}")
        elif row["state"] == "error":
            print(f"  {row['id']}: grader error (rerun to retry): {row['message']}")
    print(f"gradebook: {Path(args.out) / GRADEBOOK_NAME}")
    if getattr(args, "feedback_dir", None):
        shown = ["visible"] + (["after_due_date"] if args.after_due_date else []) \
            + (["after_published"] if args.published else [])
        print(f"feedback: {Path(args.feedback_dir) / '<submission>' / FEEDBACK_NAME} (tests shown: {', '.join(shown)})")
    return 1 if counts.get("error") else 0


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["--worker"]:
        return worker_main()
    parser = argparse.ArgumentParser(prog="python -m grader.grade", description="Grade a class of submissions.")
    add_grade_arguments(parser)
    try:
        return main_grade(parser.parse_args(argv))
    except KeyboardInterrupt:
        print("interrupted: what was graded is kept; rerun the same command to finish", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
