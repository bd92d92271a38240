"""Gradescope's ``results.json`` for one submission, built from the tests' results.

The layout follows Gradescope's autograder specification::

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
the reports: ``test`` (the spec name), ``exercise``, ``status`` (the finer status),
``fraction``, ``seconds``, ``metrics``, ``figure`` (plain data for
:mod:`grader.harness.figures`, or None), ``message`` (what the test found), ``printed`` (what
the student's code printed) and, for an HTML output, ``output_text`` (the same output
as plain text).

The top-level ``max_score`` is not in Gradescope's list (it takes the total from the
assignment's settings); it is kept for the gradebook and reports.  A test of the spec
with a ``leaderboard`` column that passed and measured ``seconds`` adds that time to
``leaderboard`` (lower is better); a wrong answer, however fast, adds nothing.

Files are written atomically (a temporary file in the same folder, then
:func:`os.replace`): a reader, or a grader killed half-way, sees either the whole
previous file, the whole new one, or none.
"""
from __future__ import annotations

import html
import json
import math
import os
import re
import tempfile
import time
from pathlib import Path
from typing import Any

from ..harness.outcome import STATUS_MEANINGS, Outcome, TestResult, capped
from ..harness.spec import VISIBILITIES, TestSpec

#: Gradescope's test statuses.
GRADESCOPE_STATUSES = ("passed", "failed")
#: The first words of a test's output for each status of :mod:`grader.harness.outcome`.
STATUS_WORDS = {status: meaning.split(":")[0].capitalize() for status, meaning in STATUS_MEANINGS.items()}
STATUS_WORDS["failed"] = "Wrong answer"
#: Characters of one test's output kept (Gradescope shows it in a collapsed <pre>).
OUTPUT_LIMIT = 12_000
#: Largest figure (characters of JSON) kept in a test's extra_data.
FIGURE_LIMIT = 300_000
#: Largest picture (characters of base64 PNG) put into a test's HTML output.
PICTURE_LIMIT = 300_000
#: Gradescope's formats of an output string.
OUTPUT_FORMATS = ("text", "html", "simple_format", "md", "ansi")
RESULTS_NAME = "results.json"


def plain(value: Any) -> Any:
    """``value`` as strict JSON data: numpy scalars become numbers, NaN and infinities None."""
    if isinstance(value, dict):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, int):
        return value
    try:
        number = float(value)
    except (TypeError, ValueError):
        return str(value)
    if hasattr(value, "dtype") and getattr(value, "dtype").kind in "iu":
        return int(value)
    return number if math.isfinite(number) else None


def _duration(seconds: float) -> str:
    return f"{seconds * 1e3:.3g} ms" if seconds < 1 else f"{seconds:.3g} s"


def _number(value: Any) -> str:
    return f"{value:.4g}" if isinstance(value, float) else str(value)


def format_metrics(metrics: dict) -> list[str]:
    """Lines for a student: the speed and error figures of a test, with units."""
    metrics = dict(metrics)
    lines = []
    if isinstance(metrics.get("seconds"), (int, float)):
        line = f"time: {_duration(metrics.pop('seconds'))}"
        reference = metrics.pop("reference_seconds", None)
        if isinstance(reference, (int, float)):
            line += f" (reference engine in the same run: {_duration(reference)})"
        lines.append(line)
    if "missed_pairs" in metrics or "extra_pairs" in metrics:
        lines.append(f"pairs missed: {metrics.pop('missed_pairs', 0)}, pairs returned but apart: "
                     f"{metrics.pop('extra_pairs', 0)}")
    if isinstance(metrics.get("max_penetration"), (int, float)):
        line = f"largest penetration: {metrics.pop('max_penetration'):.4g} m"
        reference = metrics.pop("reference_max_penetration", None)
        if isinstance(reference, (int, float)):
            line += f" (reference: {reference:.4g} m)"
        lines.append(line)
    labels = {"energy_gain": ("kinetic energy gained", "J"),
              "distance_from_reference": ("distance from the reference engine at the end", "m"),
              "distance_from_pymunk": ("distance from pymunk at the end", "m")}
    for key, (label, unit) in labels.items():
        if isinstance(metrics.get(key), (int, float)):
            lines.append(f"{label}: {metrics.pop(key):.4g} {unit}")
    for key, value in metrics.items():
        if value is not None:
            lines.append(f"{key.replace('_', ' ')}: {_number(value)}")
    return lines


def _points(value: float) -> str:
    return f"{value:g}"


def student_output(outcome: Outcome, score: float, max_score: float) -> str:
    """The text a student reads for one test: status and points, then what was found."""
    status = outcome.status
    word = STATUS_WORDS.get(status, status.replace("_", " ").capitalize())
    if status == "failed" and 0 < score < max_score:
        word = "Partly right"
    lines = [f"{word}: {_points(score)} / {_points(max_score)} points"]
    message = (outcome.message or "").strip()
    if message:
        lines.append(message)
    lines += format_metrics(plain(outcome.metrics or {}))
    printed = (getattr(outcome, "output", "") or "").rstrip()
    if printed and status != "passed":  # shown under failing tests only
        lines.append("Your code printed:\n" + printed)
    text = "\n".join(lines)
    if len(text) > OUTPUT_LIMIT:
        text = text[:OUTPUT_LIMIT] + f"\n[... {len(text) - OUTPUT_LIMIT} more characters not shown]"
    return text


def _figure(figure: dict | None) -> dict | None:
    if figure is None:
        return None
    data = plain(figure)
    if len(json.dumps(data)) > FIGURE_LIMIT:
        return {"kind": "omitted", "title": str(figure.get("title", "")),
                "reason": "the failing case is too large to draw"}
    return data


def picture_html(figure: dict | None, alt: str, limit: int | None = None) -> str:
    """The picture of a failing case as an ``<img>`` with an inline base64 PNG, or a
    sentence saying why there is none (omitted, larger than ``limit`` characters of
    base64 (default :data:`PICTURE_LIMIT`), could not be drawn).  Empty for no figure."""
    if not figure:
        return ""
    limit = PICTURE_LIMIT if limit is None else limit
    if figure.get("kind") == "omitted":
        reason = str(figure.get("reason") or "it was left out")
        return f"<p><em>No picture of the failing case: {html.escape(reason, quote=False)}.</em></p>"
    try:
        from ..harness.figures import figure_png_base64  # deferred: matplotlib, heavy to import

        data = figure_png_base64(figure)
    except Exception as exc:  # a damaged figure must not cost the output
        return (f"<p><em>The picture of the failing case could not be drawn "
                f"({html.escape(type(exc).__name__, quote=False)}).</em></p>")
    if len(data) > limit:
        return (f"<p><em>The picture of the failing case was omitted: at {len(data) / 1000:.0f} KB it is "
                f"larger than the {limit / 1000:.0f} KB allowed here.</em></p>")
    return (f'<p>The failing case:</p><img alt="{html.escape(alt)}" style="max-width:100%" '
            f'src="data:image/png;base64,{data}">')


def html_output(text: str, figure: dict | None, alt: str) -> str:
    """A test's output as HTML for Gradescope: the text (escaped, in ``<pre>``), then the picture."""
    return f"<pre>{html.escape(text, quote=False)}</pre>\n{picture_html(figure, alt)}"


def output_text(entry: dict) -> str:
    """The plain-text output of a results.json test entry, whatever its ``output_format``."""
    output = str(entry.get("output") or "")
    if entry.get("output_format", "text") != "html":
        return output
    extra = entry.get("extra_data") if isinstance(entry.get("extra_data"), dict) else {}
    if isinstance(extra.get("output_text"), str):
        return extra["output_text"]
    return html.unescape(re.sub(r"<[^>]*>", "", output)).strip()  # HTML written by someone else


def results_entry(test: TestSpec, outcome: Outcome, seconds: float = 0.0) -> dict:
    """One entry of ``tests``: Gradescope's keys plus ``extra_data`` for the reports.

    The score follows the test's credit rule (:attr:`grader.harness.outcome.TestResult.score`):
    full points for a pass, partial points only for a test marked partial_credit.  A
    failed test with a figure gets an HTML output holding its picture (see the module
    docstring); every other test a text output.
    """
    fraction = max(0.0, min(1.0, float(outcome.fraction)))
    score = round(TestResult(test, outcome, seconds).score, 6)
    text = student_output(outcome, score, test.points)
    figure = _figure(outcome.figure)
    entry = {
        "name": test.title,
        "score": score,
        "max_score": float(test.points),
        "status": "passed" if outcome.status == "passed" else "failed",
        "output": text,
        "output_format": "text",
        "visibility": test.visibility,
        "tags": [test.exercise],
        "extra_data": {
            "test": test.name,
            "exercise": test.exercise,
            "status": outcome.status,
            "fraction": fraction,
            "seconds": round(float(seconds), 4),
            "metrics": plain(outcome.metrics or {}),
            "figure": figure,
            "message": capped(outcome.message or "", OUTPUT_LIMIT),
            "printed": (getattr(outcome, "output", "") or "")[:OUTPUT_LIMIT],
            "leaderboard": test.leaderboard,
        },
    }
    if figure is not None and outcome.status != "passed":
        entry["output"] = html_output(text, figure, f"the failing case of {test.title}")
        entry["output_format"] = "html"
        entry["extra_data"]["output_text"] = text
    return entry


def leaderboard(entries: list[tuple[TestSpec, Outcome]]) -> list[dict]:
    """Gradescope leaderboard entries: passed tests with a leaderboard column and a time."""
    board = []
    for test, outcome in entries:
        seconds = (outcome.metrics or {}).get("seconds")
        if test.leaderboard and outcome.status == "passed" and isinstance(seconds, (int, float)) \
                and math.isfinite(seconds):
            board.append({"name": test.leaderboard, "value": round(float(seconds), 6), "order": "asc"})
    return board


def _metadata(submission_id, fingerprint, spec_hash, state, **more) -> dict:
    data = {"submission_id": submission_id, "fingerprint": fingerprint, "spec_hash": spec_hash,
            "state": state, "graded_at": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
    data.update(more)
    return data


def build_results(results: list, execution_time: float, submission_id: str | None = None,
                  fingerprint: str | None = None, spec_hash: str | None = None,
                  package: str | None = None, isolation: str | None = None) -> dict:
    """The results.json data of a graded submission.

    Parameters
    ----------
    results : list of grader.harness.run.TestResult
        One per test, in spec order.
    execution_time : float
        Wall-clock seconds spent grading the submission.
    submission_id, fingerprint, spec_hash : str, optional
        Kept in the top-level ``extra_data`` (the rerun compares the last two).
    package : str, optional
        Where the exercises package was found, relative to the submission.
    isolation : str, optional
        How the student's code was isolated (``bwrap`` or ``plain``, see
        :mod:`grader.sandbox.process`): kept for the instructor's report.
    """
    tests = [results_entry(r.test, r.outcome, r.seconds) for r in results]
    where = f" (found at '{package}')" if package and package != "." else ""
    data = {
        "score": round(sum(t["score"] for t in tests), 4),
        "max_score": round(sum(t["max_score"] for t in tests), 4),
        "execution_time": round(float(execution_time), 2),
        "output": f"Your exercises package{where} was graded: see each test below.",
        "tests": tests,
        "leaderboard": leaderboard([(r.test, r.outcome) for r in results]),
        "extra_data": _metadata(submission_id, fingerprint, spec_hash, "graded", package=package,
                                isolation=isolation),
    }
    return data


def refused_results(tests: list[TestSpec], reason: str, execution_time: float = 0.0,
                    submission_id: str | None = None, fingerprint: str | None = None,
                    spec_hash: str | None = None) -> dict:
    """The results.json data of a submission that could not be graded: 0 points, and why."""
    outcome = Outcome("not_run", message="The submission could not be graded: see the message above the tests.")
    entries = [results_entry(test, outcome) for test in tests]
    return {
        "score": 0.0,
        "max_score": round(sum(t["max_score"] for t in entries), 4),
        "execution_time": round(float(execution_time), 2),
        "output": f"Your submission could not be graded: {reason}",
        "tests": entries,
        "leaderboard": [],
        "extra_data": _metadata(submission_id, fingerprint, spec_hash, "refused", reason=reason),
    }


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
