"""What a batch writes: each submission's results.json, reports and feedback page, the
audit log and the class gradebook.

Resuming
--------
``results.json`` is written atomically the moment a submission is done, and records
the submission's fingerprint and the hash of the test spec.  A rerun of the same
command skips every submission whose results record the same two (``--regrade``
grades them again), so a batch killed at any point loses only the submissions that
were being graded.  A submission that cannot be graded (a damaged or unsafe archive,
a symbolic link anywhere in it, a folder over the size caps, no ``exercises`` package)
gets a results.json with 0 points saying why -- links and sizes are checked before any
of its files is read, even to fingerprint it (:mod:`grader.batch.submissions`); a failure of
the grader itself writes nothing, is reported, and is retried by the next run.
Changing the checks' code does not change the spec hash: pass ``--regrade`` then.

Every results.json written is also recorded as one line of ``DIR/grading_log.jsonl``
(submission id, state, score, fingerprint, time), appended right after the file is in
place: an audit of what each run graded (a submission appears once per grading).
"""
from __future__ import annotations

import contextlib
import csv
import dataclasses
import hashlib
import importlib
import io
import json
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from ..harness.results_model import SubmissionResults, points
from ..reports.results import RESULTS_NAME, read_results, read_submission_results, write_results, write_text_atomic
from .scheduler import Job, not_run
from ..harness.spec import TestSpec
from ..harness.run import load_spec
from .submissions import Submission, library_note
from ..reports.feedback import page_level, write_feedback_report

GRADEBOOK_NAME = "gradebook.csv"
LOG_NAME = "grading_log.jsonl"
REPORT_NAME = "report.html"
FEEDBACK_NAME = "feedback.html"


def spec_hash(tests: list[TestSpec]) -> str:
    """sha256 (hex) of the test spec: names, exercises, titles, points, visibility, leaderboard."""
    text = json.dumps([dataclasses.asdict(t) for t in tests], sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _report_module():
    """:mod:`grader.reports.instructor` if it exists, else None."""
    try:
        return importlib.import_module("grader.reports.instructor")
    except ModuleNotFoundError as exc:
        if exc.name in ("grader.reports.instructor",):
            return None
        raise


def write_student_report(results_path: Path, warn: Callable[[str], None],
                         results: SubmissionResults | None = None) -> None:
    """``report.html`` next to ``results.json`` (when grader.reports.instructor exists), of
    ``results`` (else of the file read back); never raises."""
    try:
        report = _report_module()
        if report is not None:
            report.write_student_report(results if results is not None else results_path,
                                        results_path.parent / REPORT_NAME)
    except Exception as exc:  # a report must not cost a grade
        warn(f"warning: no HTML report for {results_path.parent.name}: {type(exc).__name__}: {exc}")


@dataclass(frozen=True)
class FeedbackOptions:
    """What the student feedback pages show, and where copies go.

    ``html``: write ``feedback.html`` beside each results.json; ``folder``: also write
    ``folder/<id>/feedback.html``; ``after_due_date`` and ``published``: show those
    tests (see :mod:`grader.reports.feedback`); ``lower``: a page written before may show less
    than it did (else it keeps its level).  ``kept`` collects the ids whose page kept
    a higher level than asked for.
    """

    html: bool = True
    folder: Path | None = None
    after_due_date: bool = False
    published: bool = False
    lower: bool = False
    kept: list = dataclasses.field(default_factory=list, compare=False)

    @property
    def wanted(self) -> bool:
        return self.html or self.folder is not None


def write_feedback(results_path: Path, submission_id: str, options: FeedbackOptions,
                   warn: Callable[[str], None], results: SubmissionResults | None = None) -> None:
    """The student's ``feedback.html`` of one results.json (and its copy): of ``results``,
    else of the file read back once; never raises."""
    if not options.wanted:
        return
    try:

        targets = []
        if options.html:
            targets.append(results_path.parent / FEEDBACK_NAME)
        if options.folder is not None:
            targets.append(options.folder / submission_id / FEEDBACK_NAME)
        asked = {name for name, on in (("after_due_date", options.after_due_date), ("published", options.published))
                 if on}
        if not options.lower and any(page_level(target) - asked for target in targets):
            options.kept.append(submission_id)
        if results is None:
            results = read_submission_results(results_path)
        for target in targets:
            write_feedback_report(results if results is not None else results_path, target, options.after_due_date,
                                  options.published, options.lower)
    except Exception as exc:  # feedback must not cost a grade
        warn(f"warning: no feedback page for {submission_id}: {type(exc).__name__}: {exc}")


def row_of(submission: Submission, state: str, data: dict | None, out_dir: Path, message: str = "") -> dict:
    return {"id": submission.id, "source": str(submission.path), "state": state,
            "score": None if data is None else data.get("score"),
            "max_score": None if data is None else data.get("max_score"),
            "results_path": None if data is None else str(out_dir / submission.id / RESULTS_NAME),
            "results": data, "message": message}


def finish_job(job: Job, elapsed: float, tests: list[TestSpec], digest: str, out_dir: Path, html: bool,
            warn: Callable[[str], None], feedback: FeedbackOptions | None = None) -> dict:
    """Write a finished job's results.json (and report); its summary row."""
    submission = job.submission
    results_path = out_dir / submission.id / RESULTS_NAME
    if job.error is not None:
        warn(f"error: the grader failed on {submission.id} ({job.error}); nothing written, "
             "rerun to try again")
        return row_of(submission, "error", None, out_dir, job.error)
    if job.refused is not None:
        model = SubmissionResults.refused(tests, job.refused, elapsed, submission.id, job.fingerprint, digest)
    else:
        model = SubmissionResults.graded(
            [job.results.get(index) or not_run(test) for index, test in enumerate(tests)],
            elapsed, submission.id, job.fingerprint, digest, job.package, job.isolation)
        if job.library_replaced:
            model.output += "\n" + library_note(job.library_replaced)
            model.meta["library_replaced"] = list(job.library_replaced)
        # Issue 24: what the submitted source shows, for the instructor (grader.batch.source_audit),
        # and the files it shares with other submissions (grader.batch.submissions.hard_links).
        flags = {**(job.source_flags or {}), **({"hard_links": list(job.hard_links)} if job.hard_links else {})}
        if any(flags.values()):
            model.meta["source_flags"] = flags
    model.meta["library"] = job.library
    state = model.state
    data = model.to_json()
    write_results(data, results_path)
    log_graded(out_dir, submission.id, state, data)
    if html:
        write_student_report(results_path, warn, model)
    write_feedback(results_path, submission.id, feedback or FeedbackOptions(html), warn, model)
    return row_of(submission, state, data, out_dir, data["output"] if state == "refused" else "")


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
        results = SubmissionResults.from_json(data, path)
        scores = results.scores_by_test()
        extra_columns += [name for name in scores if name not in names and name not in extra_columns]
        rows.append(results)
    columns = names + sorted(extra_columns)
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["submission", "score", "max_score", *columns, "state", "note"])

    def cell(value: float | None) -> str:
        return "" if value is None else points(value)

    for results in rows:
        scores = results.scores_by_test()
        writer.writerow([results.id, cell(results.score), cell(results.max_score),
                         *(cell(scores.get(c)) for c in columns), results.meta.get("state", ""),
                         results.meta.get("reason", "")])
    path = out_dir / GRADEBOOK_NAME
    write_text_atomic(path, buffer.getvalue())
    return path


def write_class_report(out_dir: Path, warn: Callable[[str], None]) -> None:
    try:
        report = _report_module()
        if report is not None:
            report.write_class_report(out_dir)
    except Exception as exc:
        warn(f"warning: no class report: {type(exc).__name__}: {exc}")
