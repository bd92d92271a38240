"""Where a submission's processor time goes: the grading of one submission, phase by phase.

Grades submissions in this process, the steps of a grading worker's job
(:func:`grader.batch.scheduler.worker_main`) one by one, and of its parent's
(:func:`grader.batch.gradebook.finish_job`), each timed:

- ``opened``: the submission checked and opened, its fingerprint, the course's
  library files put in (:mod:`grader.batch.submissions`);
- ``source audit``: stubs and suspicious lines read from the files
  (:mod:`grader.batch.source_audit`);
- ``sandboxed processes``: the student's worker and the reference's (speed tests), from
  the cgroup (:mod:`cgroup_cpu`) less this process's own time;
- the tests in this, the trusted process, split by what its main thread was running
  (a sampler thread reads the main thread's CPU clock every few milliseconds and
  charges the time since the last sample to the innermost frame of a known kind):
  starting sandboxes (mounts, copies, bubblewrap), the channel to the sandboxes
  (requests encoded, answers read and checked), the trusted oracles (the reference
  engine, sympy, pymunk), the comparisons and credit, the tests' own code (case
  building, scene stepping), Hypothesis and pytest;
- ``stepped scenes``: the trusted time of the tests that step a scene with the
  student's functions (those calling ``StudentCode.run_program``), a second view of
  the same seconds;
- ``results and reports``: results.json, the instructor's report and the feedback
  page written.

The first submission warms the process (imports, test collection); the figures are
those of the last one.
"""
from __future__ import annotations

import collections
import contextlib
import sys
import sysconfig
import threading
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from grader.batch.gradebook import FeedbackOptions, finish_job, spec_hash  # noqa: E402
from grader.batch.grade import COURSE_LIBRARY  # noqa: E402
from grader.batch.scheduler import Job  # noqa: E402
from grader.batch.source_audit import source_flags, suspicious_lines, withheld_functions  # noqa: E402
from grader.batch.submissions import (Submission, fingerprint, opened, submitted_package,  # noqa: E402
                                      with_course_library)
from grader.harness import student_code  # noqa: E402
from grader.harness.run import load_spec, run_tests  # noqa: E402

#: Seconds between two samples of the main thread.
SAMPLE_PERIOD = 0.004
#: Kinds of the trusted process's code, the first whose rule a frame meets (innermost
#: frame first; standard-library and numpy frames are passed through to their caller).
KINDS = [
    ("sandbox start (mounts, copy, bubblewrap)",
     lambda path, name: "grader/sandbox/mounts.py" in path
     or ("grader/sandbox/process.py" in path and name in ("start", "_prepare", "_mounts", "_command", "copy_package"))),
    ("channel to the sandboxes (requests encoded, answers read and checked)",
     lambda path, name: "grader/sandbox/" in path or "grader/harness/student_code.py" in path),
    ("trusted oracles (reference engine, sympy, pymunk)",
     lambda path, name: any(part in path for part in ("grader/oracles/", "/solutions/", "/sympy/", "/pymunk/",
                                                      "/mpmath/"))),
    ("comparisons, credit and pictures",
     lambda path, name: any(f"grader/harness/{n}.py" in path for n in ("compare", "credit", "figures", "outcome",
                                                                     "shrink", "replay"))),
    ("the tests' own code (cases, scene stepping)", lambda path, name: "grader/tests/" in path),
    ("hypothesis", lambda path, name: "/hypothesis/" in path),
    ("pytest and the grader's plugin", lambda path, name: any(part in path for part in ("/_pytest/", "/pluggy/",
                                                                                       "grader/harness/"))),
]
OTHER = "other"
_STDLIB = sysconfig.get_paths()["stdlib"]


def kind_of(frame) -> str:
    """The kind (a label of :data:`KINDS`) of the code ``frame`` runs."""
    while frame is not None:
        path = frame.f_code.co_filename
        if not ((path.startswith(_STDLIB) and "site-packages" not in path) or "/numpy/" in path
                or path.startswith("<")):
            for label, rule in KINDS:
                if rule(path, frame.f_code.co_name):
                    return label
        frame = frame.f_back
    return OTHER


class Sampler:
    """Charges the main thread's processor time to the kind of code it runs."""

    def __init__(self):
        self.seconds: dict[str, float] = collections.Counter()
        self.main = threading.main_thread().ident
        self.clock = time.pthread_getcpuclockid(self.main)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        last = time.clock_gettime(self.clock)
        while not self._stop.wait(SAMPLE_PERIOD):
            now = time.clock_gettime(self.clock)
            frame = sys._current_frames().get(self.main)
            self.seconds[kind_of(frame)] += now - last
            last = now
            del frame

    def __enter__(self) -> "Sampler":
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join()


@contextlib.contextmanager
def counted_programs():
    """A Counter of ``StudentCode.run_program`` calls (by nobody's test but the running one)."""
    counts = collections.Counter()
    original = student_code.StudentCode.run_program

    def run_program(self, *args, **kwargs):
        counts["calls"] += 1
        return original(self, *args, **kwargs)

    student_code.StudentCode.run_program = run_program
    try:
        yield counts
    finally:
        student_code.StudentCode.run_program = original


def grade_one(submission: Submission, tests, meter, scratch: Path) -> dict:
    """Grade ``submission`` here, each step timed; the phases' processor seconds."""
    phases: dict[str, float] = {}
    per_test: list[tuple[str, float, float, bool]] = []   # name, trusted s, sandboxed s, stepped a scene
    library = str(COURSE_LIBRARY)
    clock = time.thread_time     # this (main) thread: the sampler's own time is not a phase's
    started = clock()
    digest = fingerprint(submission.path)
    with opened(submission, workdir=scratch) as folder, contextlib.ExitStack() as stack:
        package = submitted_package(folder)
        package, replaced = stack.enter_context(with_course_library(package, library, str(scratch)))
        phases["opened (checked, fingerprinted, course library put in)"] = clock() - started
        started = clock()
        withheld = withheld_functions(package, library)
        flags = source_flags(withheld, suspicious_lines(package, library))
        phases["source audit"] = clock() - started
        before = {"process": time.process_time(), "group": meter.seconds(), "thread": clock()}
        last = dict(before)

        with counted_programs() as programs, Sampler() as sampler:
            def progress(result):
                now = {"process": time.process_time(), "group": meter.seconds(), "thread": clock()}
                sandboxed = (now["group"] - last["group"]) - (now["process"] - last["process"]) \
                    if now["group"] is not None else 0.0
                per_test.append((result.test.name, now["thread"] - last["thread"], sandboxed, programs["calls"] > 0))
                programs.clear()
                last.update(now)

            results = run_tests(package, tests, progress=progress, withheld=withheld)
        after = {"process": time.process_time(), "group": meter.seconds(), "thread": clock()}
    trusted = after["thread"] - before["thread"]
    if after["group"] is not None:
        phases["sandboxed processes (student's and reference's workers)"] = \
            (after["group"] - before["group"]) - (after["process"] - before["process"])
    for label, seconds in sorted(sampler.seconds.items(), key=lambda item: -item[1]):
        # The sampler's shares of its own total, scaled to the tests' trusted time.
        phases[f"tests, trusted: {label}"] = trusted * seconds / max(sum(sampler.seconds.values()), 1e-9)
    phases["tests, trusted: the process's other threads (this sampler included)"] = \
        (after["process"] - before["process"]) - trusted
    job = Job(0, submission, digest, tests, [], results={i: r for i, r in enumerate(results)}, isolation="bwrap",
              source_flags=flags, library_replaced=replaced)
    started = clock()
    finish_job(job, 0.0, tests, spec_hash(tests), scratch / "out", True, lambda text: None, FeedbackOptions(True))
    phases["results and reports written"] = clock() - started
    return {"phases": phases, "per_test": per_test, "trusted": trusted,
            "passed": sum(r.outcome.status == "passed" for r in results), "count": len(results),
            "scenes": sum(t for _, t, _, stepped in per_test if stepped)}


def phase_split(paths: list[Path], meter, scratch: Path) -> dict:
    """The phases of the last of ``paths`` (the others warm the process up)."""
    meter.enter()
    scratch.mkdir(parents=True, exist_ok=True)
    tests = load_spec()
    found = {}
    for number, path in enumerate(paths):
        submission = Submission(f"phase{number}", Path(path).resolve(), "folder" if Path(path).is_dir() else "zip")
        found = grade_one(submission, tests, meter, scratch)
    return found
