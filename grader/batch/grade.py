"""Grade a class: every submission, every test of the spec, in parallel, resumable.

    grader grade SUBMISSIONS... --out DIR [--jobs N] [--regrade]

Writes, for each submission, ``DIR/<id>/results.json`` in Gradescope's format (and
``DIR/<id>/report.html`` when :mod:`grader.reports.instructor` is there, the instructor's page of
every test), ``DIR/<id>/feedback.html`` (the student's page: only the tests Gradescope
would show now, see :mod:`grader.reports.feedback`; ``--after-due-date`` and ``--published``
say what "now" is, ``--feedback-dir FEEDBACK`` adds a copy at
``FEEDBACK/<id>/feedback.html``), then ``DIR/gradebook.csv`` with one row per graded
submission in ``DIR``.  Feedback pages are written again on every run, for skipped
submissions too, so a rerun with ``--after-due-date`` releases more without regrading.

The batch is four parts: this module (the command line and :func:`grade_submissions`,
which fingerprints, skips what is graded, and hands the rest on),
:mod:`grader.sandbox.isolation` (bubblewrap or plain), :mod:`grader.batch.scheduler` (worker
processes, jobs, time limits) and :mod:`grader.batch.gradebook` (results, reports, feedback,
audit log, gradebook).

``--tests PATTERN[,PATTERN...]`` grades only the tests whose names match (shell-style
patterns: ``momentum.*``); the spec hash then covers those tests only.
"""
from __future__ import annotations

import argparse
import contextlib
import dataclasses
import fcntl
import fnmatch
import hashlib
import os
import shutil
import sys
from pathlib import Path
from typing import Iterator

from .calibration import slowdown
from ..errors import GradingError
from .gradebook import (FEEDBACK_NAME, GRADEBOOK_NAME, REPORT_NAME, FeedbackOptions, finish_job, log_graded,
                        row_of, spec_hash, write_class_report, write_feedback, write_gradebook,
                        write_student_report)
from ..sandbox.isolation import resolve_isolation
from ..harness.results_model import SubmissionResults, points
from ..reports.results import RESULTS_NAME, read_results, write_results
from ..sandbox.process import Limits
from .scheduler import Job, Worker, dismiss, run_jobs, run_order
from ..harness.spec import TestSpec
from ..harness.run import load_spec
from .submissions import SubmissionPathError, SubmissionRefused, discover, fingerprint, hard_links, library_hash
from ..harness.spec import SpecError

WORK_NAME = ".work"  # scratch folder of a run inside the output folder, removed after
LOCK_NAME = ".grader.lock"
DEFAULT_PER_TEST_SECONDS = 30.0
DEFAULT_PER_SUBMISSION_SECONDS = 60.0
#: The course's exercises package (stubs and library files, as students get them; never the
#: solutions): the library files every submission is graded with.
COURSE_LIBRARY = Path(__file__).resolve().parents[2] / "exercises"


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



def grade_submissions(paths: list[str | os.PathLike], out_dir: str | os.PathLike, jobs: int = 1,
                      regrade: bool = False, limits: Limits = Limits(), isolation: str = "auto",
                      per_submission_seconds: float = DEFAULT_PER_SUBMISSION_SECONDS,
                      per_test_seconds: float = DEFAULT_PER_TEST_SECONDS, progress: bool = True,
                      tests: list[TestSpec] | None = None, html: bool = True, after_due_date: bool = False,
                      published: bool = False, feedback_dir: str | os.PathLike | None = None,
                      calibrate: bool = True, library: str | os.PathLike | None = COURSE_LIBRARY,
                      lower_feedback_level: bool = False) -> list[dict]:
    """Grade every submission at ``paths`` into ``out_dir``; skip what is already graded.

    ``calibrate=False`` keeps the time limits as given (else they are scaled by how
    loaded the machine is, :mod:`grader.batch.calibration`).

    The library files of each submission's package are graded as the course released
    them: those of ``library`` (the course's ``exercises`` package, which students were
    given; :func:`grader.batch.submissions.with_course_library`), and the results say which of
    the submission's differed.  Only the exercise files (and files the student added)
    come from the submission.  ``library=None`` grades the submission as it is.

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
        ``"auto"``, ``"bwrap"`` or ``"plain"`` (see :mod:`grader.sandbox.process`).
    per_submission_seconds, per_test_seconds : float
        Wall-clock limits (s); see the module docstring.
    progress : bool
        Show a progress bar on stderr.
    tests : list of TestSpec, optional
        The tests to run (default: the whole spec, public and hidden).
    html : bool
        Also write the HTML reports: the instructor's (when :mod:`grader.reports.instructor` is
        there) and the student's feedback page.
    after_due_date, published : bool
        The feedback pages also show the tests Gradescope shows after the due date,
        and after the grades are published (hidden tests: never).
    feedback_dir : path, optional
        Also write each feedback page to ``feedback_dir/<id>/feedback.html`` (even
        without ``html``).
    lower_feedback_level : bool
        Feedback pages written before may show less than they did; without it a page
        keeps showing the tests it showed (a student never loses feedback they saw).

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
    # Files with two names are graded by content and flagged, never refused (submissions.hard_links).
    linked = hard_links(submissions)
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
    feedback = FeedbackOptions(html, feedback_dir, after_due_date, published, lower_feedback_level)
    bar = _progress_bar(len(submissions), 0, progress)
    warn = bar.write
    if library is not None and not Path(library).is_dir():
        warn(f"warning: no course exercises package at {library}: each submission's library files are graded "
             "as they were handed in")
        library = None
    library_digest = library_hash(library)
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
                        # Checks links and sizes before reading a byte (grader.batch.submissions).
                        submission_fingerprint = fingerprint(submission.path)
                    except SubmissionRefused as exc:
                        refusal = str(exc)
                        submission_fingerprint = "refused:" + hashlib.sha256(refusal.encode()).hexdigest()
                    except OSError as exc:
                        refusal = "the submission could not be read"
                        submission_fingerprint = f"unreadable:{exc.errno}"
                    # Read back only to resume: the results this run would make again.
                    previous_data = read_results(results_path)
                    previous = None if previous_data is None else SubmissionResults.from_json(previous_data,
                                                                                                results_path)
                    meta = previous.meta if previous is not None else {}
                    if (not regrade and previous is not None and meta.get("fingerprint") == submission_fingerprint
                            and meta.get("spec_hash") == digest and meta.get("library") == library_digest):
                        rows[submission.id] = row_of(submission, "skipped", previous_data, out_dir)
                        if html and not (results_path.parent / REPORT_NAME).exists():
                            write_student_report(results_path, warn, previous)
                        write_feedback(results_path, submission.id, feedback, warn, previous)
                        bar.update(1)
                        continue
                    if refusal is not None:
                        model = SubmissionResults.refused(tests, refusal, 0.0, submission.id, submission_fingerprint,
                                                          digest)
                        model.meta["library"] = library_digest
                        data = model.to_json()
                        write_results(data, results_path)
                        log_graded(out_dir, submission.id, "refused", data)
                        if html:
                            write_student_report(results_path, warn, model)
                        write_feedback(results_path, submission.id, feedback, warn, model)
                        rows[submission.id] = row_of(submission, "refused", data, out_dir, data["output"])
                        bar.update(1)
                        continue
                    todo.append(Job(len(todo), submission, submission_fingerprint, tests, run_order(tests)))
                    todo[-1].hard_links = linked.get(submission.id, [])
                workers, spare = workers[:len(todo)], workers[len(todo):]
                dismiss(spare)
                if todo:
                    chosen = resolve_isolation(isolation, warn)
                    for job in todo:
                        job.isolation = chosen
                        job.library = library_digest
                    config = {"tests": [dataclasses.asdict(t) for t in tests], "limits": dataclasses.asdict(limits),
                              "isolation": chosen, "library": None if library is None else str(Path(library).resolve())}
                    for worker in workers:
                        worker.configure(config)

                    def finished(job: Job, elapsed: float) -> None:
                        rows[job.submission.id] = finish_job(job, elapsed, tests, digest, out_dir, html, warn,
                                                          feedback)
                        row = rows[job.submission.id]
                        score = f"{points(row['score'])}/{points(row['max_score'])}" if row["score"] is not None \
                            else row["state"]
                        bar.update(1)
                        bar.set_postfix_str(f"{job.submission.id}: {score}")

                    # Limits in wall-clock seconds, scaled by how loaded the machine is now
                    # (grader.batch.calibration): a busy machine must not fail honest work.
                    if factor > 1.05:
                        warn(f"note: this machine runs {factor:.1f}x slower than an idle one now; time limits "
                             f"scaled to {per_test_seconds * factor:g} s per test and "
                             f"{per_submission_seconds * factor:g} s per submission")
                    run_jobs(todo, workers, config, work, per_test_seconds * factor, per_submission_seconds * factor,
                              finished, warn)
                    workers = []
            finally:
                dismiss(workers)  # those not handed to _run_jobs (nothing to grade, or an error)
                if tests is not None:
                    with contextlib.suppress(OSError):
                        write_gradebook(out_dir, tests)
                if html:
                    write_class_report(out_dir, warn)
                shutil.rmtree(work, ignore_errors=True)
                if feedback.kept:
                    count = len(feedback.kept)
                    warn(f"note: {count} feedback page{'s' if count != 1 else ''} (e.g. {feedback.kept[0]}) already "
                         "showed more tests than asked for now and keep showing them; --lower-feedback-level "
                         "to show less")
    finally:
        bar.close()
    return [rows[s.id] for s in submissions if s.id in rows]


def select_tests(tests: list[TestSpec], patterns: str | None) -> list[TestSpec]:
    """The tests whose names match one of the comma-separated shell-style ``patterns``."""
    if not patterns:
        return tests
    wanted = [p.strip() for p in patterns.split(",") if p.strip()]
    chosen = [t for t in tests if any(fnmatch.fnmatchcase(t.name, p) for p in wanted)]
    if not chosen:
        raise GradingError(f"--tests {patterns!r} matches no test (see `grader list`)")
    return chosen



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
    parser.add_argument("--lower-feedback-level", action="store_true",
                        help="feedback pages may show fewer tests than they showed before (by default a page "
                             "written with --after-due-date or --published keeps showing those tests)")


def main_grade(args: argparse.Namespace) -> int:
    """Run ``grader grade``; 0 when every submission has results, 1 if the grader failed on
    some (rerun to retry them), 2 for bad arguments."""

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
                                 feedback_dir=getattr(args, "feedback_dir", None),
                                 lower_feedback_level=getattr(args, "lower_feedback_level", False))
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
    parser = argparse.ArgumentParser(prog="python -m grader.batch.grade", description="Grade a class of submissions.")
    add_grade_arguments(parser)
    try:
        return main_grade(parser.parse_args(argv))
    except KeyboardInterrupt:
        print("interrupted: what was graded is kept; rerun the same command to finish", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
