"""Student feedback: one submission's results as Gradescope would show them to the student.

``grader grade`` writes ``feedback.html`` beside the instructor's ``report.html`` (and,
with ``--feedback-dir DIR``, a copy at ``DIR/<submission id>/feedback.html``, one
folder per student to hand back).  The page reads ``results.json`` and shows only the
tests Gradescope shows a student at that time (its autograder specification):

- ``visible`` tests, always;
- ``after_due_date`` tests, once the due date has passed (``--after-due-date``);
- ``after_published`` tests, once the grades are published (``--published``);
- ``hidden`` tests, never: neither their title, nor their message, output or picture.
  A test with a visibility this module does not know is treated as hidden.

The total score follows Gradescope too: "if test cases are hidden, students will not be
able to see their total score".  While some tests are not shown and the grades are not
published, the page gives the points of the tests it shows, labelled as such, and says
plainly that more tests count; once published (``--published``) it gives the total score,
which counts the tests not shown, and says so.  Leaderboard values appear only for
leaderboard columns of tests shown.

For each test shown: its title, status, points, what the test found (the message and
the speed and error figures), what the student's code printed (under a test that did
not pass), and the picture of a failing case.  Everything read from the results file is escaped; the page is
self-contained (styles inline, pictures as base64 PNG, no JavaScript).

Feedback never goes back: a page records what it releases in a tag
``<meta name="course-feedback-level" content="after_due_date published">``, and a page
written again keeps at least that (a rerun without ``--after-due-date`` does not take
back the tests a student has seen) unless the instructor asks for less
(``lower=True``, ``grader grade --lower-feedback-level``).  A page without the tag
counts as showing the visible tests only.
"""
from __future__ import annotations

import os
import re
from pathlib import Path

from ..harness.outcome import TestResult
from ..harness.results_model import (SubmissionResults, badge, escaped, format_metrics, html_page,
                                     leaderboard_table, picture_html, plain, points)
from .results import read_submission_results, write_text_atomic

FEEDBACK_NAME = "feedback.html"
#: The meta tag naming what a page releases beyond the visible tests (see the module docstring).
LEVEL_META = "course-feedback-level"
LEVELS = ("after_due_date", "published")


def is_shown(visibility: str, after_due_date: bool = False, published: bool = False) -> bool:
    """Whether Gradescope shows a test of this visibility to the student now."""
    return (visibility == "visible" or (visibility == "after_due_date" and after_due_date)
            or (visibility == "after_published" and published))


def _test_row(result: TestResult) -> str:
    test, outcome = result.test, result.outcome
    score, passed = result.score, outcome.status == "passed"
    if result.recorded_text is not None:  # results written before messages were kept apart: the whole text
        said = [result.recorded_text.strip()]
    else:  # what the test found, then its figures, then what the code printed
        said = [outcome.message.strip(), "\n".join(format_metrics(plain(outcome.metrics)))]
    parts = [f"<pre>{escaped(text)}</pre>" for text in said if text]
    if outcome.output.strip() and not passed and result.recorded_text is None:
        parts.append(f"<p class='muted'>Your code printed:</p><pre>{escaped(outcome.output.rstrip())}</pre>")
    if not passed and outcome.figure:
        parts.append(picture_html(outcome.figure, f"the failing case of {test.title}"))
    return (f"<tr><td>{escaped(test.title)}</td><td>{badge(outcome.status, score, test.points)}</td>"
            f"<td class='num'>{points(score)} / {points(test.points)}</td>"
            f"<td>{''.join(parts) or '<span class=muted>–</span>'}</td></tr>")


def feedback_html(results: SubmissionResults | dict, after_due_date: bool = False, published: bool = False,
                  submission_id: str | None = None) -> str:
    """The feedback page of ``results`` (the model, or results.json data read back into
    it; see the module docstring)."""
    if isinstance(results, dict):
        results = SubmissionResults.from_json(results)
    who = submission_id or results.meta.get("submission_id") or "your submission"
    shown = [r for r in results.tests if is_shown(r.test.visibility, after_due_date, published)]
    unshown = [r for r in results.tests if not is_shown(r.test.visibility, after_due_date, published)]
    later_due = sum(1 for r in unshown if r.test.visibility == "after_due_date")
    later_published = sum(1 for r in unshown if r.test.visibility == "after_published")

    body = [f"<h1>Feedback on {escaped(who)}</h1>"]
    shown_score = sum(r.score for r in shown)
    shown_max = sum(r.test.points or 0.0 for r in shown)
    if not unshown:
        body.append(f"<p><b>Score: {points(shown_score)} / {points(shown_max)} points</b></p>")
    elif published:
        maximum = results.max_score if results.max_score is not None else \
            shown_max + sum(r.test.points or 0.0 for r in unshown)
        body.append(f"<p><b>Score: {points(results.score)} / {points(maximum)} points</b></p>"
                    "<p class='muted'>This total also counts tests that are not shown on this page.</p>")
    else:
        later = []
        if later_due:
            later.append(f"{later_due} test{'s' if later_due != 1 else ''} shown after the due date")
        if later_published:
            later.append(f"{later_published} test{'s' if later_published != 1 else ''} shown when grades "
                         "are published")
        detail = f" (among them {' and '.join(later)})" if later else ""
        body.append(f"<p><b>Points of the tests shown here: {points(shown_score)} / {points(shown_max)}</b></p>"
                    f"<p>More tests count toward your score than are shown here{detail}. Your total score is "
                    "shown when grades are published.</p>")
    if results.output.strip():
        body.append(f"<pre>{escaped(results.output.strip())}</pre>")

    columns = {r.test.leaderboard for r in shown}
    board = [e for e in results.leaderboard if e["name"] in columns]
    if board:
        body += ["<h2>Leaderboard</h2>", *leaderboard_table(board, "Your value")]

    body.append("<h2>Tests</h2>")
    if shown:
        body.append("<table><tr><th>Test</th><th>Result</th><th>Points</th><th>What happened</th></tr>")
        body += [_test_row(r) for r in shown]
        body.append("</table>")
    else:
        body.append("<p class='muted'>No test results are shown yet.</p>")
    return html_page(f"Feedback on {who}", body, level_tag(after_due_date, published))


def level_tag(after_due_date: bool, published: bool) -> str:
    """The meta tag recording what a page releases (read back by :func:`page_level`)."""
    level = " ".join(name for name, on in zip(LEVELS, (after_due_date, published)) if on)
    return f'<meta name="{LEVEL_META}" content="{level}">'


def page_level(path: str | os.PathLike) -> set[str]:
    """What the feedback page at ``path`` releases beyond the visible tests (a subset of
    :data:`LEVELS`, read from its meta tag); empty when there is no page or no tag."""
    try:
        with open(path, encoding="utf-8", errors="replace") as page:
            head = page.read(4096)
    except OSError:
        return set()
    match = re.search(rf'<meta name="{LEVEL_META}" content="([a-z_ ]*)">', head)
    return set(match[1].split()) & set(LEVELS) if match else set()


def write_feedback_report(results_json: SubmissionResults | str | os.PathLike, out_html: str | os.PathLike,
                          after_due_date: bool = False, published: bool = False, lower: bool = False) -> Path:
    """Write the feedback page of ``results_json`` (the model, or the path of a
    results.json to read back) to ``out_html`` (atomically; folders
    created) and return its path.  A page already there keeps showing what it showed
    (its level, see the module docstring) unless ``lower``.  A missing or unreadable
    results file gives a page that says so."""
    out_html = Path(out_html)
    if not lower:
        kept = page_level(out_html)
        after_due_date, published = after_due_date or "after_due_date" in kept, published or "published" in kept
    out_html.parent.mkdir(parents=True, exist_ok=True)
    results = results_json if isinstance(results_json, SubmissionResults) else read_submission_results(results_json)
    if results is None:
        page = html_page("Feedback", ["<p>No results to show yet.</p>"], level_tag(after_due_date, published))
    else:
        page = feedback_html(results, after_due_date, published, None)
    write_text_atomic(out_html, page)
    return out_html
