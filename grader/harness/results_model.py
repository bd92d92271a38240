"""One submission's results, and the one way each thing about them is said.

:class:`SubmissionResults` holds a submission's :class:`~grader.harness.outcome.TestResult`
records and what is known of the grading (score, time, the message above the tests, the
``meta`` of results.json's top-level ``extra_data``).  The grading process makes it once
(:meth:`SubmissionResults.graded`, :meth:`SubmissionResults.refused`) and serialises it
once (:meth:`SubmissionResults.to_json`: Gradescope's results.json, see
:mod:`grader.reports.results`); the instructor's pages, the student's feedback page,
the gradebook row and ``grader check``'s table are views of it.  A results.json is read
back into one (:meth:`SubmissionResults.from_json`) only when a batch resumes or a page
is rebuilt from disk.

Every page and table says things the same way, from here: a status's words, label and
colour come from :data:`grader.harness.outcome.STATUS_MEANINGS` (:func:`status_word`,
:func:`badge`), points are written by :func:`points`, and every HTML page uses the one
style sheet :data:`STYLE_SHEET` (:func:`html_page`).
"""
from __future__ import annotations

import html
import json
import math
import re
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .outcome import Outcome, TestResult, capped, status_of
from .spec import TestSpec

#: Characters of one test's output kept (Gradescope shows it in a collapsed <pre>).
OUTPUT_LIMIT = 12_000
#: Largest figure (characters of JSON) kept in a test's extra_data.
FIGURE_LIMIT = 300_000
#: Largest picture (characters of base64 PNG) put into a test's HTML output.
PICTURE_LIMIT = 300_000
#: The word of a failed partial-credit test that earned some of its points.
PARTLY_RIGHT = "partly right"

#: The one style sheet of every HTML page the grader writes (instructor's reports,
#: feedback pages, the similarity report, ``grader check``'s notebook table).  Rules
#: apply inside an element of class ``report`` (a page's ``<body>``, the notebook's
#: ``<div>``), so that a table shown in a notebook does not restyle the notebook.
STYLE_SHEET = """
.report { font-family: system-ui, -apple-system, "Segoe UI", sans-serif; font-size: 14px; color: #1f2328;
          max-width: 1200px; margin: 24px auto; padding: 0 16px; }
.report.inline { margin: 0; padding: 0; max-width: none; }
.report h1 { font-size: 22px; }
.report h2 { font-size: 18px; margin-top: 28px; border-bottom: 1px solid #d0d7de; }
.report table { border-collapse: collapse; margin: 8px 0; }
.report th, .report td { text-align: left; vertical-align: top; padding: 5px 9px; border-bottom: 1px solid #d0d7de; }
.report th { background: #f6f8fa; }
.report td.num, .report th.num { text-align: right; white-space: nowrap; }
.report pre { white-space: pre-wrap; margin: 0 0 6px 0; font-size: 12.5px; max-width: 640px; background: none; }
.report code { font-size: 12px; }
.report .badge { color: white; border-radius: 4px; padding: 1px 7px; font-weight: 600; white-space: nowrap; }
.report .bar { display: inline-block; height: 10px; background: #cf222e; vertical-align: middle; }
.report .muted, .report .n { color: #6e7781; }
.report .warning { color: #9a6700; font-weight: 600; }
.report .stats td { border: none; padding: 2px 12px 2px 0; }
.report img { max-width: 100%; }
.report table.side { width: 100%; table-layout: fixed; margin-bottom: 2em; }
.report td.code { width: 50%; }
.report mark { background: #ffe08a; }
.report .where { font-weight: bold; font-size: 0.85em; margin-bottom: 0.3em; }
"""


# Saying things ------------------------------------------------------------------------------
def points(value: float | None) -> str:
    """Points as the grader writes them everywhere: ``2``, ``1.5``, ``–`` when unknown."""
    return "–" if value is None else f"{value:g}"


def escaped(value: Any) -> str:
    """``value`` as text safe inside HTML (attributes too)."""
    return html.escape(str(value), quote=True)


def status_word(status: str, score: float | None = None, max_score: float | None = None) -> str:
    """The words of a status (:data:`grader.harness.outcome.STATUS_MEANINGS`); a failed
    test that earned some of its points is "partly right"."""
    if status == "failed" and score and max_score and 0 < score < max_score:
        return PARTLY_RIGHT
    return status_of(status).word


def badge(status: str, score: float | None = None, max_score: float | None = None, label: bool = False) -> str:
    """A status as an HTML badge in its colour: its words (capitalised), or its label (``label``)."""
    said = status_of(status)
    text = said.label if label else status_word(status, score, max_score).capitalize()
    return f'<span class="badge" style="background:{said.colour}">{escaped(text)}</span>'


def html_page(title: str, body: list[str], head: str = "") -> str:
    """A self-contained HTML page with the one style sheet; ``head`` is put in its <head>."""
    return "\n".join(["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">', *([head] if head else []),
                      f"<title>{escaped(title)}</title>", f"<style>{STYLE_SHEET}</style></head>",
                      '<body class="report">', *body, "</body></html>", ""])


def leaderboard_table(entries: list[dict], value_heading: str = "Value") -> list[str]:
    """Leaderboard entries (results.json's) as the lines of an HTML table: the column,
    the value (4 significant digits) and which way is better."""
    lines = [f"<table><tr><th>Column</th><th class='num'>{escaped(value_heading)}</th><th>Order</th></tr>"]
    for entry in entries:
        value = number_or(entry.get("value"))
        shown = f"{value:.4g}" if value is not None else escaped(entry.get("value"))
        order = "lower is better" if entry.get("order", "desc") == "asc" else "higher is better"
        lines.append(f"<tr><td>{escaped(entry['name'])}</td><td class='num'>{shown}</td><td>{order}</td></tr>")
    return lines + ["</table>"]


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


def number_or(value: Any, default: float | None = None) -> float | None:
    """``value`` as a finite float, else ``default`` (booleans are not numbers)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return default
    value = float(value)
    return value if math.isfinite(value) else default


def _duration(seconds: float) -> str:
    return f"{seconds * 1e3:.3g} ms" if seconds < 1 else f"{seconds:.3g} s"


def _figure_text(value: Any) -> str:
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
            lines.append(f"{key.replace('_', ' ')}: {_figure_text(value)}")
    return lines


def student_output(outcome: Outcome, score: float, max_score: float) -> str:
    """The text a student reads for one test: status and points, then what was found."""
    word = status_word(outcome.status, score, max_score).capitalize()
    lines = [f"{word}: {points(score)} / {points(max_score)} points"]
    message = (outcome.message or "").strip()
    if message:
        lines.append(message)
    lines += format_metrics(plain(outcome.metrics or {}))
    printed = (outcome.output or "").rstrip()
    if printed and outcome.status != "passed":  # shown under failing tests only
        lines.append("Your code printed:\n" + printed)
    return capped("\n".join(lines), OUTPUT_LIMIT)


def student_text(result: TestResult) -> str:
    """What the student reads for one result: the text recorded, else :func:`student_output`."""
    if result.recorded_text is not None:
        return result.recorded_text
    return student_output(result.outcome, result.score, result.test.points)


def kept_figure(figure: dict | None) -> dict | None:
    """A figure as kept in results.json: plain data, or a note when it is too large."""
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
        from .figures import figure_png_base64  # deferred: matplotlib, heavy to import

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


# results.json: one test ---------------------------------------------------------------------
def results_entry(test: TestSpec, outcome: Outcome, seconds: float = 0.0) -> dict:
    """One entry of results.json's ``tests``: Gradescope's keys plus ``extra_data`` for the reports.

    The score follows the test's credit rule (:attr:`grader.harness.outcome.TestResult.score`):
    full points for a pass, partial points only for a test marked partial_credit.  A
    failed test with a figure gets an HTML output holding its picture (see
    :mod:`grader.reports.results`); every other test a text output.
    """
    score = round(TestResult(test, outcome, seconds).score, 6)
    text = student_output(outcome, score, test.points)
    figure = kept_figure(outcome.figure)
    # The result's one serialised form (TestResult.to_dict), within this file's limits.
    kept = Outcome(outcome.status, max(0.0, min(1.0, float(outcome.fraction))),
                   capped(outcome.message or "", OUTPUT_LIMIT), figure, plain(outcome.metrics or {}),
                   (outcome.output or "")[:OUTPUT_LIMIT])
    entry = {
        "name": test.title,
        "score": score,
        "max_score": float(test.points),
        "status": "passed" if outcome.status == "passed" else "failed",
        "output": text,
        "output_format": "text",
        "visibility": test.visibility,
        "tags": [test.exercise],
        "extra_data": {**TestResult(test, kept, round(float(seconds), 4)).to_dict(), "leaderboard": test.leaderboard},
    }
    if figure is not None and outcome.status != "passed":
        entry["output"] = html_output(text, figure, f"the failing case of {test.title}")
        entry["output_format"] = "html"
        entry["extra_data"]["output_text"] = text
    return entry


def leaderboard(results: list[TestResult]) -> list[dict]:
    """Gradescope leaderboard entries: passed tests with a leaderboard column and a time."""
    board = []
    for result in results:
        test, outcome = result.test, result.outcome
        seconds = (outcome.metrics or {}).get("seconds")
        if test.leaderboard and outcome.status == "passed" and isinstance(seconds, (int, float)) \
                and math.isfinite(seconds):
            board.append({"name": test.leaderboard, "value": round(float(seconds), 6), "order": "asc"})
    return board


def _dict(value: Any) -> dict:
    return value if isinstance(value, dict) else {}


def result_of_entry(entry: dict, number: int, visibility: str = "visible") -> TestResult:
    """A results.json test entry read back; whatever is missing gets a default (the
    title names the test, the finer status falls back on Gradescope's or on the points,
    a visibility that is not a string reads as hidden).  ``visibility`` is the
    file's top-level one, the default of its tests."""
    extra = _dict(entry.get("extra_data"))
    title = str(entry.get("name") or extra.get("test") or f"test {number}")
    name = str(extra.get("test") or title)
    tags = entry.get("tags") if isinstance(entry.get("tags"), list) else []
    exercise = str(extra.get("exercise") or (tags[0] if tags else "") or name.split(".")[0])
    score = number_or(entry.get("score"), 0.0)
    max_score = number_or(entry.get("max_score"))
    status = extra.get("status") if isinstance(extra.get("status"), str) else entry.get("status")
    if not isinstance(status, str):
        status = "passed" if max_score is not None and score >= max_score else "failed"
    shown = entry.get("visibility") or visibility or "visible"
    board = extra.get("leaderboard") if isinstance(extra.get("leaderboard"), str) else None
    # The text the student read follows from the rest, unless the file was written before
    # messages were kept apart (or by something else): then it is kept as written.
    text = None if isinstance(extra.get("message"), str) else output_text(entry)
    spec = TestSpec(name=name, exercise=exercise, title=title, points=max_score,
                    visibility=shown if isinstance(shown, str) else "hidden", leaderboard=board)
    # extra_data is TestResult.to_dict's form; files written before it was kept what the
    # code printed under "printed".
    printed = extra["output"] if isinstance(extra.get("output"), str) else extra.get("printed")
    result = TestResult.from_dict({**extra, "status": status, "output": printed if isinstance(printed, str) else ""},
                                  spec)
    result.recorded_score, result.recorded_text = score, text
    return result


# One submission -----------------------------------------------------------------------------
@dataclass
class SubmissionResults:
    """One submission's results: the model every report, page and table is a view of.

    Attributes
    ----------
    tests : list of TestResult
        One per test, in spec order.
    score, max_score : float
        Points earned and possible (``max_score`` None when a file read back lacks it).
    execution_time : float or None
        Wall-clock seconds spent grading the submission.
    output : str
        The message above the tests (results.json's ``output``).
    meta : dict
        results.json's top-level ``extra_data``: ``submission_id``, ``fingerprint``,
        ``spec_hash``, ``state`` (graded or refused), ``graded_at``, and as the case may
        be ``reason``, ``package``, ``isolation``, ``library``, ``library_replaced``.
    leaderboard : list of dict
        Gradescope's leaderboard entries.
    path : Path or None
        The results.json it was read from (None: made by grading).
    """

    tests: list[TestResult]
    score: float
    max_score: float | None
    execution_time: float | None = 0.0
    output: str = ""
    meta: dict = field(default_factory=dict)
    leaderboard: list = field(default_factory=list)
    path: Path | None = None

    # Made by grading --------------------------------------------------------------------
    @classmethod
    def graded(cls, results: list[TestResult], execution_time: float, submission_id: str | None = None,
               fingerprint: str | None = None, spec_hash: str | None = None, package: str | None = None,
               isolation: str | None = None) -> "SubmissionResults":
        """A graded submission: ``results`` one per test; ``package`` where its exercises
        package was found (relative to the submission), ``isolation`` how its code was
        isolated (``bwrap`` or ``plain``, :mod:`grader.sandbox.process`)."""
        where = f" (found at '{package}')" if package and package != "." else ""
        return cls(list(results), round(sum(round(r.score, 6) for r in results), 4),
                   round(sum(float(r.test.points) for r in results), 4), round(float(execution_time), 2),
                   f"Your exercises package{where} was graded: see each test below.",
                   _metadata(submission_id, fingerprint, spec_hash, "graded", package=package, isolation=isolation),
                   leaderboard(results))

    @classmethod
    def refused(cls, tests: list[TestSpec], reason: str, execution_time: float = 0.0,
                submission_id: str | None = None, fingerprint: str | None = None,
                spec_hash: str | None = None) -> "SubmissionResults":
        """A submission that could not be graded: 0 points, and why."""
        outcome = Outcome("not_run", message="The submission could not be graded: see the message above the tests.")
        return cls([TestResult(test, outcome, 0.0) for test in tests], 0.0,
                   round(sum(float(test.points) for test in tests), 4), round(float(execution_time), 2),
                   f"Your submission could not be graded: {reason}",
                   _metadata(submission_id, fingerprint, spec_hash, "refused", reason=reason))

    # Views ----------------------------------------------------------------------------
    @property
    def id(self) -> str:
        """The submission's id: as recorded, else the name of the results file's folder."""
        recorded = self.meta.get("submission_id")
        return str(recorded or (self.path.parent.name if self.path is not None else ""))

    @property
    def state(self) -> str:
        return str(self.meta.get("state") or "graded")

    @property
    def reason(self) -> str:
        return str(self.meta.get("reason") or "")

    @property
    def isolation(self) -> str:
        return str(self.meta.get("isolation") or "")

    @property
    def passed(self) -> bool:
        return all(r.passed for r in self.tests)

    def counts(self) -> dict[str, int]:
        """How many tests ended with each status, in order of first appearance."""
        out: dict[str, int] = {}
        for result in self.tests:
            out[result.outcome.status] = out.get(result.outcome.status, 0) + 1
        return out

    def summary(self) -> str:
        """One line: the points and how many tests ended which way."""
        if self.tests and self.passed:
            head = f"all {len(self.tests)} tests passed"
        else:
            head = ", ".join(f"{status_word(status)} {n}" for status, n in self.counts().items())
        return f"Score {points(self.score)}/{points(self.max_score)} points: {head}"

    def scores_by_test(self) -> dict[str, float]:
        """Points of each test, by spec name (the gradebook's row)."""
        return {r.test.name: r.score for r in self.tests}

    def to_json(self) -> dict:
        """Gradescope's results.json (see :mod:`grader.reports.results`), with the
        grader's own data in ``extra_data``: the one serialisation of the model."""
        return {"score": self.score, "max_score": self.max_score, "execution_time": self.execution_time,
                "output": self.output, "tests": [results_entry(r.test, r.outcome, r.seconds) for r in self.tests],
                "leaderboard": list(self.leaderboard), "extra_data": dict(self.meta)}

    @classmethod
    def from_json(cls, data: dict, path: Path | None = None) -> "SubmissionResults":
        """A results.json read back (its data ``data``; ``path`` where it was read from).
        Lenient: a test that is not an object is skipped, whatever else is missing gets
        a default (see :func:`result_of_entry`)."""
        visibility = data.get("visibility") if isinstance(data.get("visibility"), str) else "visible"
        tests = data.get("tests")
        results = [result_of_entry(entry, number, visibility)
                   for number, entry in enumerate(tests if isinstance(tests, list) else [], start=1)
                   if isinstance(entry, dict)]
        score = number_or(data.get("score"))
        if score is None:
            score = sum(r.score for r in results)
        max_score = number_or(data.get("max_score"))
        if max_score is None and results and all(r.test.points is not None for r in results):
            max_score = sum(r.test.points for r in results)
        board = [e for e in data.get("leaderboard") or [] if isinstance(e, dict) and isinstance(e.get("name"), str)]
        return cls(results, score, max_score, number_or(data.get("execution_time")), str(data.get("output") or ""),
                   dict(_dict(data.get("extra_data"))), board, Path(path) if path is not None else None)


def _metadata(submission_id, fingerprint, spec_hash, state, **more) -> dict:
    data = {"submission_id": submission_id, "fingerprint": fingerprint, "spec_hash": spec_hash,
            "state": state, "graded_at": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
    data.update(more)
    return data
