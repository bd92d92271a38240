"""The scheduler of a batch: grading worker processes, and the jobs handed to them.

How a batch runs
----------------
The parent process hands submissions to ``--jobs`` grading workers, each a Python
process (``python -m grader.batch.scheduler --worker``) with a sandbox slot of its own, so each
parallel job runs the student code as its own unprivileged user.  Parent and workers
talk in JSON lines; the parent alone writes files.  A worker streams each test's
result as soon as it is known, so the parent can enforce two hard limits itself:

- **per test** (``per_test_seconds``): a test that runs longer has its worker stopped
  (its sandboxes die with it), is scored as a timeout, and the submission goes on with
  its next test in a fresh worker;
- **per submission** (``per_submission_seconds``): tests not started in time are
  scored as timeouts ("not run").

Each call into student code also has its own timeout (``Limits.call_timeout``).  Both
limits are scaled by :func:`grader.batch.calibration.slowdown`, measured when the batch
starts: on a loaded machine they grow (up to four times), so honest work is not cut off.

The worker's side is :func:`worker_main`; the parent's handle on a worker is
:class:`Worker`; :func:`run_jobs` hands :class:`Job` s to the workers, enforces the
two hard limits and calls back with each finished job.  Writing what a job found is
:mod:`grader.batch.gradebook`'s.
"""
from __future__ import annotations

import contextlib
import json
import os
import selectors
import signal
import subprocess
import sys
import tempfile
import time
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from ..errors import GradingError
from ..harness.outcome import Outcome, TestResult
from ..sandbox.process import Limits
from ..harness.spec import TestSpec
from .source_audit import source_flags, suspicious_lines, withheld_functions
from .submissions import Submission, SubmissionRefused, submitted_package, opened, with_course_library

REPO_ROOT = Path(__file__).resolve().parents[2]
#: Times a submission may lose its worker process before its remaining tests are given up.
MAX_WORKER_DEATHS = 2


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
    (``index`` in the spec, ``result``: the test result's one serialised form,
    :meth:`~grader.harness.outcome.TestResult.to_dict`), ``refused`` or ``error`` (with
    ``reason``), and ``done``.
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

    from ..harness.run import run_tests  # deferred: pytest, heavy to import
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
            with opened(submission, workdir=config["tmp"]) as folder, contextlib.ExitStack() as stack:
                package = submitted_package(folder)
                where = package.relative_to(folder).as_posix() if package != folder else "."
                # Graded with the course's library files; the exercise files are the submission's.
                package, replaced = stack.enter_context(with_course_library(package, config.get("library"),
                                                                            config["tmp"]))
                # Read from the files, before any of them runs (grader.batch.source_audit).
                withheld = withheld_functions(package, config.get("library"))
                flags = source_flags(withheld, suspicious_lines(package, config.get("library")))
                send({"event": "started", "job": number, "package": where, "library_replaced": replaced,
                      "source_flags": flags})
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
                    send({"event": "test", "job": number, "index": index, "result": result.to_dict()})

                run_tests(package, [tests[i] for i in indices], limits, slot, config["isolation"],
                          budget_seconds=job["budget"], progress=progress, withheld=withheld)
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
                [sys.executable, "-m", "grader.batch.scheduler", "--worker"], stdin=subprocess.PIPE,
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


def dismiss(workers: list["Worker"]) -> None:
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



@dataclass
class Job:
    """One submission being graded, possibly over several worker attempts."""

    number: int
    submission: Submission
    fingerprint: str
    #: The spec's tests (a result's index is its place here).
    tests: list[TestSpec]
    remaining: list[int]
    #: What each test found, by index, as the worker sent it or as the parent decided.
    results: dict[int, TestResult] = field(default_factory=dict)
    used: float = 0.0  # seconds of earlier attempts
    deaths: int = 0
    package: str | None = None
    isolation: str | None = None   # bwrap or plain, as the batch resolved it
    library: str | None = None   # hash of the course's library files graded with (submissions.library_hash)
    library_replaced: list[str] = field(default_factory=list)   # the submission's that differed
    source_flags: dict | None = None  # what its source shows (grader.batch.source_audit.source_flags)
    hard_links: list[str] = field(default_factory=list)  # files shared with others (submissions.hard_links)
    refused: str | None = None
    error: str | None = None


def not_run(test: TestSpec) -> TestResult:
    """The result of a test a finished job has none for."""
    return TestResult(test, Outcome("not_run", message="this test did not run"), 0.0)


def run_order(tests: list[TestSpec]) -> list[int]:
    """Indices of ``tests`` in the order :func:`grader.harness.run.run_tests` runs them: module by
    module (paths sorted), each module's tests in spec order.  A job's ``remaining``
    keeps this order, so that its first item is the test a stopped worker was running."""
    return sorted(range(len(tests)), key=lambda i: (tests[i].path, i))



def run_jobs(todo: list[Job], started: list[Worker], config: dict, work: Path, per_test_seconds: float,
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
            job.results[index] = TestResult(job.tests[index], Outcome(status, message=reason), 0.0)
        job.remaining = []

    def interrupted(worker: Worker, job: Job, status: str, message: str) -> None:
        """The worker was stopped or died during the job's current test: score it, go on."""
        now = time.monotonic()
        job.used += now - worker.attempt_started
        if job.remaining:
            current = job.remaining.pop(0)
            job.results[current] = TestResult(job.tests[current], Outcome(status, message=message),
                                              now - worker.deadline + per_test_seconds)
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
        job.library_replaced = [str(name) for name in event.get("library_replaced") or []]
        job.source_flags = event.get("source_flags") if isinstance(event.get("source_flags"), dict) else None
        worker.deadline = now + per_test_seconds
    elif kind == "test":
        index = int(event["index"])
        data = event.get("result")
        job.results[index] = TestResult.from_dict(data if isinstance(data, dict) else {}, job.tests[index])
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
                job.results.setdefault(index, not_run(job.tests[index]))
            job.remaining = []
        finished(job, job.used)



if __name__ == "__main__":
    if sys.argv[1:] != ["--worker"]:
        sys.exit("usage: python -m grader.batch.scheduler --worker (started by `grader grade`)")
    sys.exit(worker_main())
