"""Gradescope's ``results.json`` for one submission, built from the tests' results.

The data is :class:`grader.harness.results_model.SubmissionResults` serialised
(:meth:`~grader.harness.results_model.SubmissionResults.to_json`); its layout follows
Gradescope's autograder specification::

    {"score": 61.0, "max_score": 70.0, "execution_time": 4.3, "output": "...",
     "tests": [{"name": "...", "score": 2.0, "max_score": 2.0, "status": "passed",
                "output": "...", "output_format": "text", "visibility": "visible",
                "tags": ["momentum"], "extra_data": {...}}, ...],
     "leaderboard": [{"name": "grid time (s)", "value": 0.021, "order": "asc"}],
     "extra_data": {"submission_id": ..., "fingerprint": ..., "spec_hash": ...}}

``status`` is Gradescope's ``"passed"`` or ``"failed"``; the grader's finer status (not
implemented yet, wrong answer, timeout, crashed, ...) leads the test's ``output``, a
text a student can read: what was expected against what came back, and the speed and
error figures, never a traceback of the grader.  A failed test with a picture of its
failing case has that text as HTML instead (``"output_format": "html"``, which
Gradescope renders): the text in a ``<pre>``, escaped, then the picture as an inline
base64 PNG (left out, with a sentence saying so, when larger than
:data:`PICTURE_LIMIT`).  Each test's ``extra_data`` keeps the data behind that text for
the reports: the test result's one serialised form
(:meth:`grader.harness.outcome.TestResult.to_dict`, the form a grading worker sends
too): ``test`` (the spec name), ``exercise``, ``seconds``, ``status`` (the finer
status), ``fraction``, ``message`` (what the test found), ``figure`` (plain data for
:mod:`grader.harness.figures`, or None), ``metrics`` and ``output`` (what the student's
code printed); then ``leaderboard`` and, for an HTML output, ``output_text`` (the same
output as plain text).

The top-level ``max_score`` is not in Gradescope's list (it takes the total from the
assignment's settings); it is kept for the gradebook and reports.  A test of the spec
with a ``leaderboard`` column that passed and measured ``seconds`` adds that time to
``leaderboard`` (lower is better); a wrong answer, however fast, adds nothing.

Files are written atomically (a temporary file in the same folder, then
:func:`os.replace`): a reader, or a grader killed half-way, sees either the whole
previous file, the whole new one, or none.
"""
from __future__ import annotations

import json
import math
import os
import tempfile
from pathlib import Path

from ..harness.outcome import TestResult
from ..harness.results_model import PICTURE_LIMIT, SubmissionResults, results_entry
from ..harness.spec import VISIBILITIES, TestSpec

__all__ = ["PICTURE_LIMIT", "results_entry", "build_results", "refused_results", "write_results",
           "write_text_atomic", "read_results", "read_submission_results", "check_results"]

#: Gradescope's test statuses.
GRADESCOPE_STATUSES = ("passed", "failed")
#: Gradescope's formats of an output string.
OUTPUT_FORMATS = ("text", "html", "simple_format", "md", "ansi")
RESULTS_NAME = "results.json"


def build_results(results: list[TestResult], execution_time: float, submission_id: str | None = None,
                  fingerprint: str | None = None, spec_hash: str | None = None,
                  package: str | None = None, isolation: str | None = None) -> dict:
    """The results.json data of a graded submission (:meth:`SubmissionResults.graded`
    serialised; the parameters are its)."""
    return SubmissionResults.graded(results, execution_time, submission_id, fingerprint, spec_hash, package,
                                    isolation).to_json()


def refused_results(tests: list[TestSpec], reason: str, execution_time: float = 0.0,
                    submission_id: str | None = None, fingerprint: str | None = None,
                    spec_hash: str | None = None) -> dict:
    """The results.json data of a submission that could not be graded: 0 points, and why."""
    return SubmissionResults.refused(tests, reason, execution_time, submission_id, fingerprint, spec_hash).to_json()


def write_results(data: dict, path: str | os.PathLike) -> Path:
    """Write ``data`` as JSON to ``path`` atomically (temporary file, fsync, os.replace).

    Text that is not valid Unicode (a lone surrogate a student's code printed) is
    written as a JSON escape, so that the file is always valid UTF-8.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    text = json.dumps(data, indent=1, allow_nan=False, ensure_ascii=False)
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        text = json.dumps(data, indent=1, allow_nan=False, ensure_ascii=True)
    write_text_atomic(path, text + "\n")
    return path


def write_text_atomic(path: Path, text: str) -> None:
    """Replace ``path`` by ``text`` in one step; a crash leaves the old file or the new one.

    Characters UTF-8 cannot hold (lone surrogates) are written as ``?``.
    """
    handle, temporary = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(handle, "w", encoding="utf-8", errors="replace", newline="") as stream:
            stream.write(text)
            stream.flush()
            os.fsync(stream.fileno())
        os.chmod(temporary, 0o644)
        os.replace(temporary, path)
    except BaseException:
        try:
            os.unlink(temporary)
        except OSError:
            pass
        raise


def read_results(path: str | os.PathLike) -> dict | None:
    """The results.json at ``path``, or None if it is missing or not a results file."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) and isinstance(data.get("tests"), list) else None


def read_submission_results(path: str | os.PathLike) -> SubmissionResults | None:
    """The results.json at ``path`` read back into the model (a page rebuilt from disk),
    or None if it is missing or not a JSON object; an object without tests reads as a
    submission with none."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return SubmissionResults.from_json(data, Path(path)) if isinstance(data, dict) else None


def check_results(data: dict) -> list[str]:
    """What is wrong with ``data`` as a Gradescope results.json (an empty list: nothing)."""
    problems = []

    def number(value) -> bool:
        return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)

    if not isinstance(data, dict):
        return ["results must be a JSON object"]
    try:
        json.dumps(data, allow_nan=False)
    except (TypeError, ValueError) as exc:
        problems.append(f"not strict JSON: {exc}")
    for key in ("score", "execution_time"):
        if key in data and not number(data[key]):
            problems.append(f"{key} must be a number, got {data[key]!r}")
    if "output" in data and not isinstance(data["output"], str):
        problems.append("output must be a string")
    if "visibility" in data and data["visibility"] not in VISIBILITIES:
        problems.append(f"visibility {data['visibility']!r} is not one of {VISIBILITIES}")
    if "extra_data" in data and not isinstance(data["extra_data"], dict):
        problems.append("extra_data must be an object")
    tests = data.get("tests")
    if not isinstance(tests, list):
        problems.append("tests must be a list")
        tests = []
    if "score" not in data and not all(isinstance(t, dict) and "score" in t for t in tests):
        problems.append("score is required at the top or on every test")
    for number_, test in enumerate(tests, start=1):
        where = f"tests[{number_}]"
        if not isinstance(test, dict):
            problems.append(f"{where} must be an object")
            continue
        for key in ("score", "max_score"):
            if key in test and not number(test[key]):
                problems.append(f"{where}.{key} must be a number")
        if not isinstance(test.get("name"), str):
            problems.append(f"{where}.name must be a string")
        if "status" in test and test["status"] not in GRADESCOPE_STATUSES:
            problems.append(f"{where}.status {test['status']!r} is not one of {GRADESCOPE_STATUSES}")
        if "output" in test and not isinstance(test["output"], str):
            problems.append(f"{where}.output must be a string")
        if "output_format" in test and test["output_format"] not in OUTPUT_FORMATS:
            problems.append(f"{where}.output_format {test['output_format']!r} is not one of {OUTPUT_FORMATS}")
        if "visibility" in test and test["visibility"] not in VISIBILITIES:
            problems.append(f"{where}.visibility {test['visibility']!r} is not one of {VISIBILITIES}")
        if "tags" in test and not (isinstance(test["tags"], list) and all(isinstance(t, str) for t in test["tags"])):
            problems.append(f"{where}.tags must be a list of strings")
    board = data.get("leaderboard", [])
    if not isinstance(board, list):
        problems.append("leaderboard must be a list")
        board = []
    for entry in board:
        if not (isinstance(entry, dict) and isinstance(entry.get("name"), str) and "value" in entry):
            problems.append(f"leaderboard entry {entry!r} needs a name and a value")
        elif entry.get("order", "desc") not in ("asc", "desc"):
            problems.append(f"leaderboard entry {entry['name']!r}: order must be asc or desc")
    return problems
