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

import html
import json
import math
import os
import re
from pathlib import Path

from .results import STATUS_WORDS, format_metrics, output_text, picture_html, plain, write_text_atomic

FEEDBACK_NAME = "feedback.html"
#: The meta tag naming what a page releases beyond the visible tests (see the module docstring).
LEVEL_META = "course-feedback-level"
LEVELS = ("after_due_date", "published")
STATUS_COLORS = {"passed": "#1a7f37", "failed": "#cf222e", "not_implemented": "#6e7781", "not_run": "#6e7781",
                 "forbidden": "#8250df"}

STYLE = """
body { font-family: system-ui, -apple-system, "Segoe UI", sans-serif; font-size: 14px; color: #1f2328;
       max-width: 1000px; margin: 24px auto; padding: 0 16px; }
h1 { font-size: 22px; } h2 { font-size: 18px; margin-top: 28px; border-bottom: 1px solid #d0d7de; }
table { border-collapse: collapse; margin: 8px 0; width: 100%; }
th, td { text-align: left; vertical-align: top; padding: 6px 9px; border-bottom: 1px solid #d0d7de; }
th { background: #f6f8fa; }
td.num { text-align: right; white-space: nowrap; }
pre { white-space: pre-wrap; margin: 0 0 6px 0; font-size: 12.5px; }
.badge { color: white; border-radius: 4px; padding: 1px 7px; font-weight: 600; white-space: nowrap; }
.muted { color: #6e7781; }
img { max-width: 100%; }
"""


def is_shown(visibility: str, after_due_date: bool = False, published: bool = False) -> bool:
    """Whether Gradescope shows a test of this visibility to the student now."""
    return (visibility == "visible" or (visibility == "after_due_date" and after_due_date)
            or (visibility == "after_published" and published))


def _e(value) -> str:
    return html.escape(str(value), quote=True)


def _number(value, default=None):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return default
    return float(value) if math.isfinite(value) else default


def _points(value) -> str:
    return "–" if value is None else f"{value:g}"


def _visibility(entry: dict, data: dict) -> str:
    """A test's visibility: its own, else the results' top-level one, else visible."""
    value = entry.get("visibility") or data.get("visibility") or "visible"
    return value if isinstance(value, str) else "hidden"


def _badge(status: str, score: float, max_score: float | None) -> str:
    word = STATUS_WORDS.get(status, status.replace("_", " ").capitalize())
    if status == "failed" and max_score and 0 < score < max_score:
        word = "Partly right"
    colour = STATUS_COLORS.get(status, "#bc4c00")
    return f'<span class="badge" style="background:{colour}">{_e(word)}</span>'


def _test_row(entry: dict) -> str:
    extra = entry.get("extra_data") if isinstance(entry.get("extra_data"), dict) else {}
    title = str(entry.get("name") or extra.get("test") or "test")
    score = _number(entry.get("score"), 0.0)
    max_score = _number(entry.get("max_score"))
    status = extra.get("status") if isinstance(extra.get("status"), str) else entry.get("status")
    status = status if isinstance(status, str) else ("passed" if max_score is not None and score >= max_score
                                                     else "failed")
    parts = []
    if isinstance(extra.get("message"), str):  # what the test found, then figures, then what was printed
        message = extra["message"].strip()
        if message:
            parts.append(f"<pre>{_e(message)}</pre>")
        metrics = format_metrics(plain(extra.get("metrics") if isinstance(extra.get("metrics"), dict) else {}))
        if metrics:
            parts.append(f"<pre>{_e(chr(10).join(metrics))}</pre>")
        printed = extra.get("printed")
        if isinstance(printed, str) and printed.strip() and status != "passed":
            parts.append(f"<p class='muted'>Your code printed:</p><pre>{_e(printed.rstrip())}</pre>")
    else:  # results written before messages were kept apart: the whole text
        text = output_text(entry).strip()
        if text:
            parts.append(f"<pre>{_e(text)}</pre>")
    figure = extra.get("figure") if isinstance(extra.get("figure"), dict) else None
    if status != "passed" and figure:
        parts.append(picture_html(figure, f"the failing case of {title}"))
    return (f"<tr><td>{_e(title)}</td><td>{_badge(status, score, max_score)}</td>"
            f"<td class='num'>{_points(score)} / {_points(max_score)}</td>"
            f"<td>{''.join(parts) or '<span class=muted>–</span>'}</td></tr>")


def feedback_html(data: dict, after_due_date: bool = False, published: bool = False,
                  submission_id: str | None = None) -> str:
    """The feedback page of the results.json data ``data`` (see the module docstring)."""
    meta = data.get("extra_data") if isinstance(data.get("extra_data"), dict) else {}
    who = submission_id or meta.get("submission_id") or "your submission"
    entries = [t for t in data.get("tests") or [] if isinstance(t, dict)]
    shown = [t for t in entries if is_shown(_visibility(t, data), after_due_date, published)]
    unshown = [t for t in entries if not is_shown(_visibility(t, data), after_due_date, published)]
    later_due = sum(1 for t in unshown if _visibility(t, data) == "after_due_date")
    later_published = sum(1 for t in unshown if _visibility(t, data) == "after_published")

    body = [f"<h1>Feedback on {_e(who)}</h1>"]
    shown_score = sum(_number(t.get("score"), 0.0) for t in shown)
    shown_max = sum(_number(t.get("max_score"), 0.0) for t in shown)
    if not unshown:
        body.append(f"<p><b>Score: {_points(shown_score)} / {_points(shown_max)} points</b></p>")
    elif published:
        total = _number(data.get("score"), shown_score + sum(_number(t.get("score"), 0.0) for t in unshown))
        maximum = _number(data.get("max_score"),
                          shown_max + sum(_number(t.get("max_score"), 0.0) for t in unshown))
        body.append(f"<p><b>Score: {_points(total)} / {_points(maximum)} points</b></p>"
                    "<p class='muted'>This total also counts tests that are not shown on this page.</p>")
    else:
        later = []
        if later_due:
            later.append(f"{later_due} test{'s' if later_due != 1 else ''} shown after the due date")
        if later_published:
            later.append(f"{later_published} test{'s' if later_published != 1 else ''} shown when grades "
                         "are published")
        detail = f" (among them {' and '.join(later)})" if later else ""
        body.append(f"<p><b>Points of the tests shown here: {_points(shown_score)} / {_points(shown_max)}</b></p>"
                    f"<p>More tests count toward your score than are shown here{detail}. Your total score is "
                    "shown when grades are published.</p>")
    if isinstance(data.get("output"), str) and data["output"].strip():
        body.append(f"<pre>{_e(data['output'].strip())}</pre>")

    columns = {(t.get("extra_data") or {}).get("leaderboard") for t in shown if isinstance(t.get("extra_data"), dict)}
    board = [e for e in data.get("leaderboard") or []
             if isinstance(e, dict) and isinstance(e.get("name"), str) and e["name"] in columns]
    if board:
        body += ["<h2>Leaderboard</h2>", "<table><tr><th>Column</th><th>Your value</th><th>Order</th></tr>"]
        for entry in board:
            value = _number(entry.get("value"))
            order = "lower is better" if entry.get("order", "desc") == "asc" else "higher is better"
            body.append(f"<tr><td>{_e(entry['name'])}</td><td class='num'>"
                        f"{f'{value:.4g}' if value is not None else _e(entry.get('value'))}</td><td>{order}</td></tr>")
        body.append("</table>")

    body.append("<h2>Tests</h2>")
    if shown:
        body.append("<table><tr><th>Test</th><th>Result</th><th>Points</th><th>What happened</th></tr>")
        body += [_test_row(t) for t in shown]
        body.append("</table>")
    else:
        body.append("<p class='muted'>No test results are shown yet.</p>")
    title = f"Feedback on {who}"
    return "\n".join(["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
                      level_tag(after_due_date, published),
                      f"<title>{_e(title)}</title>", f"<style>{STYLE}</style></head><body>", *body,
                      "</body></html>", ""])


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


def write_feedback_report(results_json: str | os.PathLike, out_html: str | os.PathLike, after_due_date: bool = False,
                          published: bool = False, lower: bool = False) -> Path:
    """Write the feedback page of ``results_json`` to ``out_html`` (atomically; folders
    created) and return its path.  A page already there keeps showing what it showed
    (its level, see the module docstring) unless ``lower``.  A missing or unreadable
    results file gives a page that says so."""
    out_html = Path(out_html)
    if not lower:
        kept = page_level(out_html)
        after_due_date, published = after_due_date or "after_due_date" in kept, published or "published" in kept
    out_html.parent.mkdir(parents=True, exist_ok=True)
    try:
        data = json.loads(Path(results_json).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        data = None
    if not isinstance(data, dict):
        page = ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n"
                f"{level_tag(after_due_date, published)}\n<title>Feedback</title></head>"
                "<body><p>No results to show yet.</p></body></html>\n")
    else:
        page = feedback_html(data, after_due_date, published, None)
    write_text_atomic(out_html, page)
    return out_html
