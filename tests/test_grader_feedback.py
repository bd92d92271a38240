"""Student feedback pages (``feedback.html``) that follow Gradescope's visibility, and
failure pictures in Gradescope's test output.

Results data is built directly (grader.reports.results.build_results on TestResult records, no
sandbox); one end-to-end ``grader grade`` run grades two small folder submissions on the
momentum tests.
"""
from __future__ import annotations

import base64
import io
import json
import re
import shutil
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path


from grader.harness import results_model
from grader.reports import results as gs_results
from grader.cli import main as cli_main
from grader.harness.run import load_spec
from grader.reports.feedback import FEEDBACK_NAME, feedback_html, is_shown, page_level, write_feedback_report
from grader.harness.outcome import Outcome
from grader.harness.outcome import TestResult as Result
from grader.reports.instructor import write_student_report
from grader.reports.results import build_results, check_results, results_entry, write_results
from grader.harness.spec import TestSpec as Spec

REPO = Path(__file__).resolve().parent.parent
IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc")
PAIRS_FIGURE = {"kind": "pairs", "title": "pairs_grid_every_cell: touching", "cell_size": 1.0,
                "aabbs": [[0, 0, 1, 1], [1, 0, 2, 1]], "missed": [[0, 1]], "extra": []}
SHAPES_FIGURE = {"kind": "shapes", "title": "collide_circle_circle", "shapes": [
    {"$shape": "Circle", "center": [0.0, 0.0], "radius": 1.0}, {"$shape": "Circle", "center": [0.0, 1.5], "radius": 1.0}],
    "expected": {"$contact": True, "normal": [0.0, 1.0], "depth": 0.5, "points": [[0.0, 0.75]]},
    "got": {"$contact": True, "normal": [0.0, -1.0], "depth": 0.5, "points": [[0.0, 0.75]]}}

# Titles and messages that must appear only when their test is shown.
VISIBLE_FAIL = ("Visible circles touching", "VISIBLE-MSG the normal points from B to A")
AFTER_DUE = ("Due-date grid corner cases", "DUE-MSG a pair across the cell border was missed")
AFTER_PUBLISHED = ("Published speed test", "PUBLISHED-MSG too slow")
HIDDEN = ("Secret hidden separating axes", "HIDDEN-MSG axis of the second box skipped")


def spec(name: str, title: str, visibility: str, points: float = 2.0, leaderboard: str | None = None) -> Spec:
    return Spec(name=name, exercise=name.split(".")[0], title=title, points=points, visibility=visibility,
                    leaderboard=leaderboard)


def sample_results() -> dict:
    """Five tests, one per visibility (two visible), each failing with its own words."""
    visible_pass = Result(spec("momentum.elastic", "Visible elastic collision", "visible"),
                              Outcome.passed(), 0.1)
    visible_fail = Outcome.failed(VISIBLE_FAIL[1] + " <b>not bold</b>", SHAPES_FIGURE)
    visible_fail.output = "debug: normal = (0, -1) <script>alert(1)</script>"
    results = [
        visible_pass,
        Result(spec("contacts.circle_circle", VISIBLE_FAIL[0], "visible"), visible_fail, 0.2),
        Result(spec("grid.touching", AFTER_DUE[0], "after_due_date", 3.0),
                   Outcome.failed(AFTER_DUE[1], PAIRS_FIGURE), 0.2),
        Result(spec("grid.speed", AFTER_PUBLISHED[0], "after_published", 1.0, leaderboard="grid time (s)"),
                   Outcome.failed(AFTER_PUBLISHED[1], seconds=0.5, reference_seconds=0.1), 0.6),
        Result(spec("sat.axes", HIDDEN[0], "hidden", 4.0, leaderboard="sat time (s)"),
                   Outcome.passed(HIDDEN[1], seconds=0.01), 0.1),
    ]
    return build_results(results, 1.5, submission_id="ada")


def page(tmp_path: Path, **flags) -> str:
    path = write_results(sample_results(), tmp_path / "ada" / "results.json")
    return write_feedback_report(path, tmp_path / "ada" / FEEDBACK_NAME, **flags).read_text(encoding="utf-8")


def test_visibility_rule_is_gradescope_s():
    assert is_shown("visible") and not is_shown("hidden", True, True)
    assert not is_shown("after_due_date") and is_shown("after_due_date", after_due_date=True)
    assert not is_shown("after_published", after_due_date=True) and is_shown("after_published", published=True)
    assert not is_shown("sometimes", True, True)  # unknown visibilities stay hidden


def test_before_the_due_date_only_visible_tests_show(tmp_path):
    text = page(tmp_path)
    assert "Visible elastic collision" in text and VISIBLE_FAIL[0] in text and "VISIBLE-MSG" in text
    for title, message in (AFTER_DUE, AFTER_PUBLISHED, HIDDEN):
        assert title not in text and message.split()[0] not in text
    assert "sat time (s)" not in text and "grid time (s)" not in text  # their leaderboard columns too
    # The total is held back, as on Gradescope; the points shown count only the tests shown.
    assert "Points of the tests shown here: 2 / 4" in text and "Score:" not in text
    assert "More tests count toward your score than are shown here" in text
    assert "1 test shown after the due date" in text and "1 test shown when grades are published" in text


def test_after_the_due_date_the_after_due_date_tests_show(tmp_path):
    text = page(tmp_path, after_due_date=True)
    assert AFTER_DUE[0] in text and "DUE-MSG" in text and 'alt="the failing case of Due-date grid corner cases"' in text
    for title, message in (AFTER_PUBLISHED, HIDDEN):
        assert title not in text and message.split()[0] not in text
    assert "Points of the tests shown here: 2 / 7" in text
    assert "shown after the due date" not in text and "1 test shown when grades are published" in text


def test_once_published_the_total_shows_and_hidden_tests_still_do_not(tmp_path):
    text = page(tmp_path, after_due_date=True, published=True)
    assert AFTER_PUBLISHED[0] in text and "PUBLISHED-MSG" in text and "grid time (s)" not in text  # failed: no time
    assert "time: 500 ms (reference engine in the same run: 100 ms)" in text
    assert HIDDEN[0] not in text and "HIDDEN-MSG" not in text and "sat.axes" not in text
    assert "sat time (s)" not in text
    # Gradescope's total after publication counts the hidden test (4 points passed) and says so.
    assert "Score: 6 / 12 points" in text and "also counts tests that are not shown" in text
    published_only = page(tmp_path / "fresh", published=True)
    assert AFTER_PUBLISHED[0] in published_only and AFTER_DUE[0] not in published_only


def test_a_page_keeps_showing_what_it_showed_unless_asked_for_less(tmp_path):
    target = tmp_path / "ada" / FEEDBACK_NAME
    assert page(tmp_path, after_due_date=True) and page_level(target) == {"after_due_date"}
    again = page(tmp_path)  # a later run that forgot --after-due-date
    assert AFTER_DUE[1] in again and AFTER_PUBLISHED[1] not in again and page_level(target) == {"after_due_date"}
    published = page(tmp_path, published=True)
    assert AFTER_DUE[1] in published and AFTER_PUBLISHED[1] in published
    assert page_level(target) == {"after_due_date", "published"}
    assert AFTER_PUBLISHED[1] in page(tmp_path) and HIDDEN[1] not in page(tmp_path)
    lowered = page(tmp_path, lower=True)
    assert AFTER_DUE[1] not in lowered and AFTER_PUBLISHED[1] not in lowered and page_level(target) == set()
    # A page without the tag (or no page) releases the visible tests only.
    target.write_text("<html><body>an old page</body></html>")
    assert page_level(target) == set() and page_level(tmp_path / "none.html") == set()
    assert AFTER_DUE[1] not in page(tmp_path)


def test_every_shown_test_has_status_points_message_output_and_picture(tmp_path):
    text = page(tmp_path)
    row = text[text.index(VISIBLE_FAIL[0]):]
    row = row[:row.index("</tr>")]
    assert "Wrong answer" in row and "0 / 2" in row
    assert "VISIBLE-MSG the normal points from B to A &lt;b&gt;not bold&lt;/b&gt;" in row
    assert "Your code printed:" in row and "&lt;script&gt;alert(1)&lt;/script&gt;" in row and "<script>" not in text
    match = re.search(r'<img alt="the failing case of Visible circles touching"[^>]* '
                      r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"', row)
    assert match and base64.b64decode(match.group(1)).startswith(b"\x89PNG")
    passed = text[text.index("Visible elastic collision"):]
    assert "Passed" in passed[:passed.index("</tr>")] and "2 / 2" in passed[:passed.index("</tr>")]


def test_with_every_test_shown_the_page_gives_the_score(tmp_path):
    data = sample_results()
    data["tests"] = [t for t in data["tests"] if t["visibility"] == "visible"]
    text = feedback_html(data)
    assert "Score: 2 / 4 points" in text and "More tests" not in text


def test_a_refused_submission_says_why(tmp_path):
    data = gs_results.refused_results([spec("momentum.elastic", "Visible elastic", "visible"),
                                       spec("sat.axes", HIDDEN[0], "hidden")], "no exercises package found",
                                      submission_id="zed")
    text = feedback_html(data)
    assert "no exercises package found" in text and "Visible elastic" in text and HIDDEN[0] not in text
    missing = write_feedback_report(tmp_path / "nothing.json", tmp_path / "f.html").read_text()
    assert "No results to show yet" in missing


# Failure pictures on Gradescope ---------------------------------------------------------------
def test_a_failed_test_with_a_picture_has_html_output_with_the_png_inline():
    test = spec("contacts.circle_circle", "Two circles", "visible")
    entry = results_entry(test, Outcome.failed("expected <0, 1> & got <0, -1>", SHAPES_FIGURE), 0.1)
    assert entry["output_format"] == "html" and entry["status"] == "failed"
    output = entry["output"]
    assert output.startswith("<pre>Wrong answer: 0 / 2 points\nexpected &lt;0, 1&gt; &amp; got &lt;0, -1&gt;</pre>")
    data = re.search(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"', output).group(1)
    assert base64.b64decode(data).startswith(b"\x89PNG") and len(data) <= gs_results.PICTURE_LIMIT
    assert entry["extra_data"]["output_text"].startswith("Wrong answer: 0 / 2 points\nexpected <0, 1> & got")
    assert entry["extra_data"]["message"] == "expected <0, 1> & got <0, -1>"
    # Tests without a picture keep text; so does a passed one.
    assert results_entry(test, Outcome.failed("wrong"), 0.1)["output_format"] == "text"
    assert results_entry(test, Outcome.passed(), 0.1)["output_format"] == "text"
    assert check_results(build_results([Result(test, Outcome.failed("x", SHAPES_FIGURE), 0.1)], 1.0)) == []


def test_a_picture_too_large_is_left_out_saying_so(monkeypatch):
    monkeypatch.setattr(results_model, "PICTURE_LIMIT", 100)
    entry = results_entry(spec("grid.touching", "Grid", "visible"), Outcome.failed("missed", PAIRS_FIGURE), 0.1)
    assert entry["output_format"] == "html" and "<img" not in entry["output"]
    assert "The picture of the failing case was omitted" in entry["output"] and "larger than the 0 KB" in entry["output"]
    omitted = {"kind": "omitted", "title": "t", "reason": "the failing case is too large to draw"}
    entry = results_entry(spec("grid.touching", "Grid", "visible"), Outcome.failed("missed", omitted), 0.1)
    assert "No picture of the failing case: the failing case is too large to draw." in entry["output"]


def test_the_instructor_report_shows_the_text_of_an_html_output(tmp_path):
    path = write_results(sample_results(), tmp_path / "ada" / "results.json")
    text = write_student_report(path, tmp_path / "ada" / "report.html").read_text()
    assert "&lt;pre&gt;" not in text and "&lt;img" not in text and "VISIBLE-MSG" in text
    assert HIDDEN[0] in text  # the instructor sees every test


# End to end --------------------------------------------------------------------------------------
def test_grade_writes_feedback_pages_and_a_feedback_folder(tmp_path):
    subs = tmp_path / "subs"
    shutil.copytree(REPO / "solutions", subs / "ada" / "exercises", ignore=IGNORE)
    shutil.copytree(REPO / "exercises", subs / "bob" / "exercises", ignore=IGNORE)
    out, feedback = tmp_path / "out", tmp_path / "feedback"
    arguments = ["grade", str(subs / "ada"), str(subs / "bob"), "--out", str(out), "--tests", "momentum.*",
                 "--jobs", "2", "--no-progress", "--feedback-dir", str(feedback)]
    printed = io.StringIO()
    with redirect_stdout(printed):
        assert cli_main(arguments) == 0
    assert "2 submissions: 2 graded" in printed.getvalue() and "feedback: " in printed.getvalue()
    for name in ("ada", "bob"):
        assert (out / name / "report.html").is_file() and (out / name / FEEDBACK_NAME).is_file()
        assert (feedback / name / FEEDBACK_NAME).read_text() == (out / name / FEEDBACK_NAME).read_text()
    assert sorted(p.name for p in feedback.iterdir()) == ["ada", "bob"]
    ada = (feedback / "ada" / FEEDBACK_NAME).read_text()
    bob = (feedback / "bob" / FEEDBACK_NAME).read_text()
    momentum = [t for t in load_spec() if t.exercise == "momentum"]
    total = sum(t.points for t in momentum)
    assert f"Score: {total:g} / {total:g} points" in ada and ada.count("Passed") == len(momentum)
    assert f"Score: 0 / {total:g} points" in bob and bob.count("Not implemented yet") >= len(momentum)
    assert "1D elastic collision" in bob

    # The instructor marks a test after_due_date: a rerun regrades nothing but rewrites the pages.
    results_path = out / "bob" / "results.json"
    data = json.loads(results_path.read_text())
    title = data["tests"][0]["name"]
    data["tests"][0]["visibility"] = "after_due_date"
    write_results(data, results_path)
    with redirect_stdout(io.StringIO()) as rerun:
        assert cli_main(arguments) == 0
    assert "2 skipped" in rerun.getvalue()
    assert title not in (feedback / "bob" / FEEDBACK_NAME).read_text()
    shown = total - data["tests"][0]["max_score"]
    assert f"Points of the tests shown here: 0 / {shown:g}" in (out / "bob" / FEEDBACK_NAME).read_text()
    with redirect_stdout(io.StringIO()):
        assert cli_main(arguments + ["--after-due-date"]) == 0
    assert title in (feedback / "bob" / FEEDBACK_NAME).read_text()

    # Released feedback never goes back: a later run without --after-due-date keeps the test
    # shown (and says so), unless the instructor asks for less.
    with redirect_stdout(io.StringIO()), redirect_stderr(io.StringIO()) as said:
        assert cli_main(arguments) == 0
    for page_path in (feedback / "bob" / FEEDBACK_NAME, out / "bob" / FEEDBACK_NAME):
        assert title in page_path.read_text() and f"Score: 0 / {total:g} points" in page_path.read_text()
    assert "already showed more tests" in said.getvalue() and "--lower-feedback-level" in said.getvalue()
    with redirect_stdout(io.StringIO()), redirect_stderr(io.StringIO()):
        assert cli_main(arguments + ["--lower-feedback-level"]) == 0
    assert title not in (feedback / "bob" / FEEDBACK_NAME).read_text()
