"""HTML reports for instructors: one per submission, and one for the whole class.

Both are views of :class:`grader.harness.results_model.SubmissionResults`: the one the
grading process made, or Gradescope ``results.json`` files (:mod:`grader.reports.results`)
read back into it, so they work on any folder of results, old or new, complete or not:

- :func:`write_student_report`: every test with its visibility, score, status and the
  text the student reads, the picture of each failing case, the leaderboard figures.
- :func:`write_class_report`: reads every ``*/results.json`` under a folder and shows
  the score distribution, the tests sorted by how often they fail, for each speed
  test a scatter of speed (time relative to the reference engine measured in the same
  run) against error, summary figures, and the list of submissions.

Pages are self-contained: the one style sheet inline in the page, figures as base64 PNG, no
JavaScript and nothing fetched from elsewhere, so a report can be mailed or opened
from a zip.  Everything read from a results file is escaped before it is written.
A file that cannot be read, a test without a status, a metric that is missing or not
a number: each is skipped (and counted where it matters), never fatal.
"""
from __future__ import annotations

import statistics
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ..harness.figures import GOT_COLOR, EXPECTED_COLOR, figure_png_base64
from ..harness.outcome import TestResult
from ..harness.results_model import SubmissionResults, badge, escaped as _e, html_page, number_or as _number, points
from ..harness.results_model import leaderboard_table, picture_html, status_word, student_text
from ..sandbox.isolation import isolation_words
from .results import read_submission_results

RESULTS_NAME = "results.json"
CLASS_REPORT_NAME = "class_report.html"
STUDENT_REPORT_NAME = "report.html"
#: Error measures of speed tests, most specific first: (metric keys summed, axis label).
ERROR_MEASURES = (
    (("missed_pairs", "extra_pairs"), "pairs missed + pairs returned but apart"),
    (("distance_from_reference",), "distance from the reference engine at the end (m)"),
    (("max_penetration",), "largest penetration (m)"),
    (("distance_from_pymunk",), "distance from pymunk at the end (m)"),
)
#: Every point of a scatter is named when there are at most this many (failed ones always are).
MAX_LABELLED_POINTS = 8

def _img(data: str, alt: str) -> str:
    return f'<img alt="{_e(alt)}" src="data:image/png;base64,{data}">'


def _write(path: Path, text: str) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(f".{path.name}.tmp")
    temporary.write_text(text, encoding="utf-8")
    temporary.replace(path)
    return path


def _new_figure(width: float = 6.4, height: float = 4.2) -> tuple[Figure, object]:
    fig = Figure(figsize=(width, height), dpi=100)
    FigureCanvasAgg(fig)
    return fig, fig.add_subplot()


# One submission -------------------------------------------------------------------------------
def write_student_report(results_json: SubmissionResults | Path, out_html: Path, figures: dict | None = None) -> Path:
    """An HTML page of one submission's results.

    Parameters
    ----------
    results_json : SubmissionResults or Path
        The submission's results, or its Gradescope results file to read back (see
        :mod:`grader.reports.results`).
    out_html : Path
        Page to write (folders created).
    figures : dict, optional
        Pictures to show, by test name (the spec name or the title): plain figure data
        (:mod:`grader.harness.figures`); they replace those stored in the results file.

    Returns
    -------
    Path
        ``out_html``.
    """
    out_html = Path(out_html)
    submission = results_json if isinstance(results_json, SubmissionResults) else read_submission_results(results_json)
    figures = figures or {}
    if submission is None:
        body = ["<h1>Submission report</h1>",
                f"<p>The results file <code>{_e(results_json)}</code> is missing or cannot be read.</p>"]
        return _write(out_html, html_page("Submission report", body))
    body = [f"<h1>Submission {_e(submission.id)}</h1>",
            f"<p><b>{points(submission.score)} / {points(submission.max_score)} points</b>"
            + (f" &middot; graded in {submission.execution_time:.3g} s" if submission.execution_time is not None
               else "")
            + (f" &middot; state: {_e(submission.state)}" if submission.state != "graded" else "") + "</p>"]
    if submission.isolation:
        body.append(f"<p class='muted'>{_e(isolation_words(submission.isolation))}</p>")
    if submission.output:
        body.append(f"<pre>{_e(submission.output)}</pre>")
    if submission.reason:
        body.append(f"<p><b>Not graded:</b> {_e(submission.reason)}</p>")

    # Most frequent first; ties keep the order of first appearance.
    counts = sorted(submission.counts().items(), key=lambda status_count: -status_count[1])
    if counts:
        body.append("<p>" + ", ".join(f"{badge(s)} {n}" for s, n in counts) + "</p>")

    if submission.leaderboard:
        body += ["<h2>Leaderboard</h2>", *leaderboard_table(submission.leaderboard)]

    body += ["<h2>Tests</h2>",
             "<table><tr><th>Test</th><th>Exercise</th><th>Visibility</th><th>Result</th>"
             "<th class='num'>Points</th><th>Output</th></tr>"]
    for test in submission.tests:
        spec = test.test
        figure = figures.get(spec.name, figures.get(spec.title, test.outcome.figure))
        picture = "" if test.passed else picture_html(figure, f"failing case of {spec.name}")
        body.append(
            f"<tr><td>{_e(spec.title)}<br><code>{_e(spec.name)}</code></td><td>{_e(spec.exercise)}</td>"
            f"<td>{_e(spec.visibility)}</td><td>{badge(test.outcome.status)}</td>"
            f"<td class='num'>{points(test.score)} / {points(spec.points)}</td>"
            f"<td><pre>{_e(student_text(test))}</pre>{picture}</td></tr>")
    body.append("</table>")
    if not submission.tests:
        body.append("<p class='muted'>No tests in this results file.</p>")
    return _write(out_html, html_page(f"Submission {submission.id}", body))


# The class ----------------------------------------------------------------------------------
@dataclass
class Tally:
    """How one test went across the class."""

    name: str
    title: str
    exercise: str
    visibility: str
    runs: int = 0
    failures: int = 0
    score_sum: float = 0.0
    max_score: float | None = None
    statuses: Counter = field(default_factory=Counter)

    @property
    def failure_rate(self) -> float:
        return self.failures / self.runs if self.runs else 0.0


def read_class(out_dir: Path) -> tuple[list[SubmissionResults], list[Path]]:
    """Every readable ``*/results.json`` under ``out_dir`` (sorted), and the unreadable ones."""
    submissions, unreadable = [], []
    for path in sorted(Path(out_dir).glob(f"*/{RESULTS_NAME}")):
        submission = read_submission_results(path)
        if submission is None:
            unreadable.append(path)
        else:
            submissions.append(submission)
    return submissions, unreadable


def tally_tests(submissions: list[SubmissionResults]) -> list[Tally]:
    """One summary per test, most often failed first (then most failures, then name).

    Only graded submissions count: a refused one ran no test.
    """
    table: dict[str, Tally] = {}
    for submission in submissions:
        if submission.state == "refused":
            continue
        for test in submission.tests:
            spec = test.test
            summary = table.setdefault(spec.name, Tally(spec.name, spec.title, spec.exercise, spec.visibility))
            summary.runs += 1
            summary.failures += not test.passed
            summary.score_sum += test.score
            summary.max_score = spec.points if spec.points is not None else summary.max_score
            summary.statuses[test.outcome.status] += 1
    return sorted(table.values(), key=lambda s: (-s.failure_rate, -s.failures, s.name))


def score_histogram(submissions: list[SubmissionResults]) -> Figure:
    """Histogram of the scores: points if every submission has the same maximum, else percent."""
    fig, ax = _new_figure()
    maxima = {s.max_score for s in submissions}
    same_max = len(maxima) == 1 and None not in maxima and next(iter(maxima)) > 0
    if same_max:
        top = next(iter(maxima))
        values = [s.score for s in submissions]
        ax.set_xlabel("score (points)")
    else:
        top = 100.0
        values = [100.0 * s.score / s.max_score for s in submissions if s.max_score]
        ax.set_xlabel("score (% of the maximum)")
    bins = np.linspace(0.0, top, min(21, max(2, int(round(top)) + 1)) if top >= 1 else 11)
    ax.hist(np.clip(values, 0.0, top), bins=bins, color="#0072B2", edgecolor="white")
    if values:
        mean = float(np.mean(values))
        ax.axvline(mean, color=GOT_COLOR, linestyle="--", label=f"mean {mean:.3g}")
        ax.legend(frameon=False)
    ax.set_xlim(0.0, top)
    ax.set_ylabel("submissions")
    ax.set_title(f"Score distribution ({len(values)} graded submissions)")
    ax.yaxis.get_major_locator().set_params(integer=True)
    fig.tight_layout()
    return fig


def error_measure(tests: list[TestResult]) -> tuple[tuple[str, ...], str] | None:
    """The error measure of a speed test: the first of ERROR_MEASURES its results carry."""
    for keys, label in ERROR_MEASURES:
        if any(all(_number(t.outcome.metrics.get(k)) is not None for k in keys) for t in tests):
            return keys, label
    return None


def speed_points(submissions: list[SubmissionResults]) -> dict[str, dict]:
    """For each speed test (its results have ``seconds`` and ``reference_seconds``):
    ``{"title", "label", "points": [(submission id, time ratio, error, passed)], "skipped"}``."""
    timed = {t.test.name for s in submissions for t in s.tests
             if "seconds" in t.outcome.metrics and "reference_seconds" in t.outcome.metrics}
    by_test: dict[str, list[tuple[str, TestResult]]] = {}
    for submission in submissions:
        for test in submission.tests:
            if test.test.name in timed:
                by_test.setdefault(test.test.name, []).append((submission.id, test))
    out = {}
    for name, runs in by_test.items():
        measure = error_measure([t for _, t in runs])
        if measure is None:
            continue
        keys, label = measure
        scatter, skipped = [], 0
        for submission_id, test in runs:
            metrics = test.outcome.metrics
            seconds = _number(metrics.get("seconds"))
            reference = _number(metrics.get("reference_seconds"))
            values = [_number(metrics.get(k)) for k in keys]
            if seconds is None or not reference or reference <= 0 or seconds <= 0 or None in values:
                skipped += 1
                continue
            scatter.append((submission_id, seconds / reference, float(sum(values)), test.passed))
        if scatter:
            out[name] = {"title": runs[0][1].test.title, "label": label, "points": scatter, "skipped": skipped}
    return out


def speed_scatter(name: str, data: dict) -> Figure:
    """Time relative to the reference (log x) against error, one point per submission."""
    fig, ax = _new_figure()
    scatter = data["points"]
    for passed, colour, marker, word in ((True, EXPECTED_COLOR, "o", "passed"), (False, GOT_COLOR, "X", "failed")):
        chosen = [p for p in scatter if p[3] == passed]
        if chosen:
            ax.scatter([p[1] for p in chosen], [p[2] for p in chosen], c=colour, marker=marker, s=42,
                       label=f"{word} ({len(chosen)})", zorder=3, edgecolors="white", linewidths=0.5)
    # Name the failed submissions, and every one when there are few (names of a crowd overlap).
    for submission_id, x, y, passed in scatter:
        if not passed or len(scatter) <= MAX_LABELLED_POINTS:
            ax.annotate(submission_id, (x, y), xytext=(4, 4), textcoords="offset points", fontsize=7, color="#444444")
    ax.axvline(1.0, color="#6e7781", linestyle="--", linewidth=1, label="reference engine", zorder=1)
    ax.set_xscale("log")
    errors = np.array([p[2] for p in scatter])
    positive = errors[errors > 0]
    if len(positive) and positive.max() / positive.min() > 100:
        ax.set_yscale("symlog", linthresh=float(positive.min()))
    else:
        top = float(errors.max()) if len(errors) and errors.max() > 0 else 1.0
        ax.set_ylim(-0.05 * top, 1.1 * top)
    ratios = np.array([p[1] for p in scatter])
    low, high = min(ratios.min(), 1.0), max(ratios.max(), 1.0)
    ax.set_xlim(low / 1.6, high * 1.6)
    ax.set_xlabel("time / reference time (log scale; < 1 is faster than the reference)")
    ax.set_ylabel(data["label"])
    ax.set_title(f"{data['title']}\n[{name}]", fontsize=11)
    ax.legend(frameon=False, fontsize=8)
    fig.tight_layout()
    return fig


def _stats(values: list[float]) -> dict[str, float]:
    if not values:
        return {}
    return {"mean": statistics.fmean(values), "median": statistics.median(values), "min": min(values),
            "max": max(values), "standard deviation": statistics.pstdev(values)}


# Issue 24: what the submitted source shows (grader.batch.source_audit, grader.batch.submissions.hard_links).
def source_flags_section(submissions: list[SubmissionResults]) -> list[str]:
    """The class report's "Source to read" section: per submission, the exercise functions
    graded as stubs, the lines that run code the source does not show or look for the
    grader (file:line), and the files it shares with other submissions by a hard link."""
    # Stubs alone are unfinished work, not a reason to read: a row needs a line or a hard link.
    flagged = [(s.id, s.meta.get("source_flags")) for s in submissions
               if isinstance(s.meta.get("source_flags"), dict)
               and (s.meta["source_flags"].get("lines") or s.meta["source_flags"].get("hard_links"))]
    if not flagged:
        return []
    body = ["<h2 id='source-flags'>Source to read</h2>",
            "<p>What the trusted side read in these submissions' files before grading them: a reason to read "
            "the code, not a verdict (functions still the stub scored nothing).</p>",
            "<table><tr><th>Submission</th><th>Still the stub</th><th>Lines</th><th>Hard links</th></tr>"]
    for sid, flags in sorted(flagged):
        stubs = "<br>".join(_e(str(w).split(": ")[0]) for w in flags.get("withheld") or [])
        lines = "<br>".join(f"<code>{_e(f.get('file'))}:{_e(f.get('line'))}</code> {_e(f.get('what'))}"
                            for f in (flags.get("lines") or [])[:40] if isinstance(f, dict))
        links = "<br>".join(_e(str(link)) for link in flags.get("hard_links") or [])
        body.append(f"<tr data-flagged='{_e(sid)}'><td>{_e(sid)}</td><td>{stubs or '–'}</td><td>{lines or '–'}</td>"
                    f"<td>{links or '–'}</td></tr>")
    body.append("</table>")
    return body


def write_class_report(out_dir: Path) -> Path:
    """``out_dir/class_report.html`` from every ``*/results.json`` under ``out_dir``.

    Returns
    -------
    Path
        The page written.
    """
    out_dir = Path(out_dir)
    submissions, unreadable = read_class(out_dir)
    graded = [s for s in submissions if s.state != "refused"]
    refused = [s for s in submissions if s.state == "refused"]
    body = ["<h1>Class report</h1>",
            f"<p>{len(submissions)} results files in <code>{_e(out_dir)}</code>: {len(graded)} graded, "
            f"{len(refused)} not gradable, {len(unreadable)} unreadable.</p>"]

    isolations = Counter(s.isolation for s in graded if s.isolation)
    for isolation, count in sorted(isolations.items()):
        body.append(f"<p class='{'warning' if isolation == 'plain' else 'muted'}'>{count} graded with "
                    f"{_e(isolation_words(isolation))}</p>")
    body.append("<h2>Summary</h2>")
    scores = [s.score for s in graded]
    maxima = sorted({s.max_score for s in graded if s.max_score is not None})
    if scores:
        rows = "".join(f"<tr><td>{k}</td><td class='num'>{v:.3g}</td></tr>" for k, v in _stats(scores).items())
        top = ", ".join(points(m) for m in maxima) or "unknown"
        body.append(f"<table class='stats'><tr><td>submissions graded</td><td class='num'>{len(graded)}</td></tr>"
                    f"<tr><td>maximum score</td><td class='num'>{top}</td></tr>{rows}"
                    f"<tr><td>full marks</td><td class='num'>"
                    f"{sum(1 for s in graded if s.max_score and s.score >= s.max_score)}</td></tr></table>")
        times = [s.execution_time for s in graded if s.execution_time is not None]
        if times:
            body.append(f"<p class='muted'>grading time per submission: median {statistics.median(times):.3g} s, "
                        f"longest {max(times):.3g} s</p>")
        body += ["<h2>Score distribution</h2>", _img(figure_png_base64(score_histogram(graded)), "score histogram")]
    else:
        body.append("<p>No graded submission yet.</p>")

    summaries = tally_tests(submissions)
    body.append("<h2>Tests, most failed first</h2>")
    if summaries:
        body.append("<table id='most-failed'><tr><th>Test</th><th>Exercise</th><th>Visibility</th>"
                    "<th class='num'>Failed</th><th>Failure rate</th><th class='num'>Mean points</th>"
                    "<th>Ways it failed</th></tr>")
        for s in summaries:
            ways = ", ".join(f"{status_word(k)} {n}" for k, n in s.statuses.most_common() if k != "passed")
            mean = s.score_sum / s.runs if s.runs else 0.0
            body.append(
                f"<tr data-test='{_e(s.name)}'><td>{_e(s.title)}<br><code>{_e(s.name)}</code></td>"
                f"<td>{_e(s.exercise)}</td><td>{_e(s.visibility)}</td>"
                f"<td class='num'>{s.failures} / {s.runs}</td>"
                f"<td><span class='bar' style='width:{100 * s.failure_rate:.0f}px'></span> "
                f"{100 * s.failure_rate:.0f}%</td>"
                f"<td class='num'>{mean:.3g} / {points(s.max_score)}</td><td>{_e(ways) or '–'}</td></tr>")
        body.append("</table>")
    else:
        body.append("<p>No test results.</p>")

    body.append("<h2>Speed against error</h2>")
    speed = speed_points(submissions)
    if speed:
        body.append("<p>One point per submission: its time over the reference engine's time in the same run "
                    "(x, log scale) and its error (y). Lower left is best: faster than the reference, "
                    "and no error.</p>")
        for name, data in speed.items():
            body.append(_img(figure_png_base64(speed_scatter(name, data)), f"speed against error for {name}"))
            if data["skipped"]:
                body.append(f"<p class='muted'>{data['skipped']} submission(s) of {_e(name)} left out: "
                            "no time, no reference time or no error measure.</p>")
    else:
        body.append("<p class='muted'>No speed test with both the submission's and the reference's time.</p>")

    boards: dict[str, list[tuple[float, str, str]]] = {}
    for submission in submissions:
        for entry in submission.leaderboard:
            value = _number(entry.get("value"))
            if value is not None:
                boards.setdefault(str(entry["name"]), []).append((value, submission.id, entry.get("order", "desc")))
    if boards:
        body.append("<h2>Leaderboard</h2>")
        for name, entries in boards.items():
            ascending = entries[0][2] == "asc"
            ranked = sorted(entries, key=lambda e: e[0] if ascending else -e[0])[:10]
            body.append(f"<p><b>{_e(name)}</b> ({'lower' if ascending else 'higher'} is better)</p><table>"
                        + "".join(f"<tr><td class='num'>{k}</td><td>{_e(i)}</td><td class='num'>{v:.4g}</td></tr>"
                                  for k, (v, i, _) in enumerate(ranked, start=1)) + "</table>")

    body += source_flags_section(submissions)
    body += ["<h2>Submissions</h2>",
             "<table><tr><th>Submission</th><th class='num'>Points</th><th>State</th><th>Report</th></tr>"]
    for s in sorted(submissions, key=lambda s: (-s.score, s.id)):
        page = s.path.parent / STUDENT_REPORT_NAME
        link = (f"<a href='{_e(page.relative_to(out_dir).as_posix())}'>report</a>" if page.is_file() else "–")
        state = s.state + (f": {s.reason}" if s.reason else "")
        body.append(f"<tr><td>{_e(s.id)}</td><td class='num'>{points(s.score)} / {points(s.max_score)}</td>"
                    f"<td>{_e(state)}</td><td>{link}</td></tr>")
    body.append("</table>")
    if unreadable:
        body.append("<p><b>Unreadable results files:</b> "
                    + ", ".join(f"<code>{_e(p.relative_to(out_dir))}</code>" for p in unreadable) + "</p>")
    return _write(out_dir / CLASS_REPORT_NAME, html_page("Class report", body))
