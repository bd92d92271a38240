"""Instructor reports built from synthetic results.json files (no grading runs here)."""
from __future__ import annotations

import base64
import io
import json
import re
from pathlib import Path

import matplotlib.image
import numpy as np
import pytest

from grader.harness.outcome import Outcome
from grader.harness import run, spec
from grader.reports.instructor import CLASS_REPORT_NAME, read_class, speed_points, tally_tests, write_class_report, \
    write_student_report
from grader.reports.results import build_results, write_results

PAIRS_FIGURE = {"kind": "pairs", "title": "pairs_grid_every_cell: touching", "cell_size": 1.0,
                "aabbs": [[0, 0, 1, 1], [1, 0, 2, 1]], "missed": [[0, 1]], "extra": []}
SHAPES_FIGURE = {"kind": "shapes", "title": "collide_circle_circle", "shapes": [
    {"$shape": "Circle", "center": [0.0, 0.0], "radius": 1.0}, {"$shape": "Circle", "center": [0.0, 1.5], "radius": 1.0}],
    "expected": {"$contact": True, "normal": [0.0, 1.0], "depth": 0.5, "points": [[0.0, 0.75]]},
    "got": {"$contact": True, "normal": [0.0, -1.0], "depth": 0.5, "points": [[0.0, 0.75]]}}


def entry(name: str, status: str = "passed", score: float | None = None, max_score: float = 2.0,
          metrics: dict | None = None, figure: dict | None = None, visibility: str = "visible",
          output: str = "") -> dict:
    """One test in the layout of grader.reports.results (Gradescope keys + extra_data)."""
    score = (max_score if status == "passed" else 0.0) if score is None else score
    return {"name": f"Title of {name}", "score": score, "max_score": max_score,
            "status": "passed" if status == "passed" else "failed", "output": output or f"{status}: {name}",
            "visibility": visibility, "tags": [name.split(".")[0]],
            "extra_data": {"test": name, "exercise": name.split(".")[0], "status": status,
                           "metrics": metrics or {}, "figure": figure}}


def results(tests: list[dict], **meta) -> dict:
    return {"score": sum(t["score"] for t in tests), "max_score": sum(t["max_score"] for t in tests),
            "execution_time": 3.5, "output": "graded", "tests": tests, "leaderboard": meta.pop("leaderboard", []),
            "extra_data": {"state": "graded", **meta}}


def speed(seconds: float, reference: float, missed: int = 0, extra: int = 0) -> dict:
    return {"seconds": seconds, "reference_seconds": reference, "missed_pairs": missed, "extra_pairs": extra}


@pytest.fixture()
def class_dir(tmp_path) -> Path:
    """Seven results files; failure rates: grid.touching 4/5, contacts.circle 2/4, grid.speed 2/4,
    sat.axes 1/4, momentum.elastic 0/5."""
    def write(student: str, data) -> None:
        folder = tmp_path / student
        folder.mkdir()
        text = data if isinstance(data, str) else json.dumps(data)
        (folder / "results.json").write_text(text)

    write("ada", results([entry("momentum.elastic"), entry("grid.touching"), entry("contacts.circle"),
                          entry("sat.axes"), entry("grid.speed", metrics=speed(0.02, 0.04))],
                         leaderboard=[{"name": "grid time (s)", "value": 0.02, "order": "asc"}]))
    write("bob", results([entry("momentum.elastic"), entry("grid.touching", "failed", figure=PAIRS_FIGURE),
                          entry("contacts.circle", "failed", figure=SHAPES_FIGURE), entry("sat.axes"),
                          entry("grid.speed", "failed", metrics=speed(0.01, 0.04, missed=7, extra=2))]))
    write("cy", results([entry("momentum.elastic"), entry("grid.touching", "not_implemented"),
                         entry("contacts.circle", "error"), entry("sat.axes", "failed", score=1.0),
                         entry("grid.speed", "not_implemented")]))
    write("dee", results([entry("momentum.elastic"), entry("grid.touching", "timeout"), entry("contacts.circle"),
                          entry("sat.axes"), entry("grid.speed", metrics=speed(0.08, 0.04))]))
    # Refused (no tests ran), damaged, and partial (no extra_data, no max_score) results.
    write("eve", {"score": 0.0, "max_score": 10.0, "output": "could not be graded", "tests": [],
                  "extra_data": {"state": "refused", "reason": "no exercises package"}})
    write("fay", "{ this is not json")
    write("gus", {"tests": [{"name": "momentum.elastic", "score": 2.0, "status": "passed"}, "junk",
                            {"name": "grid.touching", "score": 0, "max_score": 2}]})
    return tmp_path


def png_pixels(data: bytes) -> np.ndarray:
    assert data.startswith(b"\x89PNG")
    return matplotlib.image.imread(io.BytesIO(data), format="png")[..., :3]


def images(page: str) -> dict[str, np.ndarray]:
    return {alt: png_pixels(base64.b64decode(data))
            for alt, data in re.findall(r'<img alt="([^"]*)"[^>]* src="data:image/png;base64,([A-Za-z0-9+/=]+)"', page)}


def test_class_report_histogram_most_failed_table_and_scatter(class_dir):
    path = write_class_report(class_dir)
    assert path == class_dir / CLASS_REPORT_NAME
    page = path.read_text()
    pictures = images(page)
    assert set(pictures) == {"score histogram", "speed against error for grid.speed"}
    assert all(image.std() > 0.05 for image in pictures.values())  # not blank
    table = page.split("<table id='most-failed'>")[1].split("</table>")[0]
    order = re.findall(r"data-test='([^']+)'", table)
    assert order == ["grid.touching", "contacts.circle", "grid.speed", "sat.axes", "momentum.elastic"]
    assert "4 / 5" in table and "80%" in table  # grid.touching: failed by bob, cy, dee and gus's partial entry
    assert "not implemented yet 1" in table and "timed out 1" in table  # the words of STATUS_MEANINGS
    # Summary statistics, leaderboard, every submission, the refused and the unreadable.
    for text in ("standard deviation", "median", "6 results files", "5 graded", "1 not gradable", "1 unreadable",
                 "grid time (s)", "refused: no exercises package", "fay/results.json"):
        assert text in page, text
    # Self-contained: no script, no stylesheet or image fetched from elsewhere.
    assert "<script" not in page and "http://" not in page and "https://" not in page


def test_speed_scatter_data(class_dir):
    submissions, unreadable = read_class(class_dir)
    assert [p.name for p in unreadable] == ["results.json"] and unreadable[0].parent.name == "fay"
    points = speed_points(submissions)["grid.speed"]
    assert points["label"] == "pairs missed + pairs returned but apart"
    assert sorted(points["points"]) == [("ada", 0.5, 0.0, True), ("bob", 0.25, 9.0, False), ("dee", 2.0, 0.0, True)]
    assert points["skipped"] == 1  # cy has no time
    summaries = {s.name: s for s in tally_tests(submissions)}
    assert summaries["sat.axes"].failures == 1 and summaries["sat.axes"].score_sum == 7.0


def test_class_report_of_an_empty_folder(tmp_path):
    page = write_class_report(tmp_path).read_text()
    assert "No graded submission yet" in page and "No test results" in page and "<img" not in page


def test_student_report_lists_tests_with_pictures_and_escapes_output(class_dir, tmp_path):
    data = json.loads((class_dir / "bob" / "results.json").read_text())
    data["tests"][0]["output"] = "<script>alert('x')</script>"
    data["tests"][1]["visibility"] = "after_due_date"
    data["leaderboard"] = [{"name": "grid time (s)", "value": 0.0123, "order": "asc"}]
    source = tmp_path / "bob.json"
    source.write_text(json.dumps(data))
    page = write_student_report(source, tmp_path / "out" / "report.html").read_text()
    assert "<script>" not in page and "&lt;script&gt;alert(&#x27;x&#x27;)&lt;/script&gt;" in page
    assert "after_due_date" in page and "0 / 2" in page and "2 / 2" in page
    assert "grid time (s)" in page and "0.0123" in page and "lower is better" in page
    pictures = images(page)
    assert set(pictures) == {"failing case of grid.touching", "failing case of contacts.circle"}
    assert all(image.std() > 0.05 for image in pictures.values())
    # Pictures passed in replace the stored ones; a damaged one leaves a note, not an error.
    page = write_student_report(source, tmp_path / "other.html",
                                figures={"grid.touching": {"kind": "omitted", "reason": "too large"},
                                         "Title of contacts.circle": {"kind": "pairs", "aabbs": "junk"}}).read_text()
    # The same words as the student's feedback page (results_model.picture_html).
    assert "No picture of the failing case: too large." in page and "could not be drawn (" in page
    assert "<img" not in page


def test_student_report_of_results_written_by_the_grader(tmp_path):
    timed = spec.TestSpec("grid.speed", "grid", "Grid speed", 2.0, "after_published", leaderboard="grid time (s)")
    failing = spec.TestSpec("contacts.circle_circle", "contacts", "Two circles", 2.0, "visible")
    outcomes = [run.TestResult(timed, Outcome.passed("fast", seconds=0.01, reference_seconds=0.02, missed_pairs=0,
                                                extra_pairs=0), 0.1),
                run.TestResult(failing, Outcome.failed("the normal points from B to A", SHAPES_FIGURE), 0.2)]
    path = write_results(build_results(outcomes, 1.0, submission_id="s1"), tmp_path / "s1" / "results.json")
    page = write_student_report(path, tmp_path / "s1" / "report.html").read_text()
    assert "Submission s1" in page and "2 / 4 points" in page and "the normal points from B to A" in page
    assert set(images(page)) == {"failing case of contacts.circle_circle"}
    assert "after_published" in page and "grid time (s)" in page
    class_page = write_class_report(tmp_path).read_text()
    assert "speed against error for grid.speed" in class_page and "href='s1/report.html'" in class_page


def test_student_report_of_a_missing_file(tmp_path):
    page = write_student_report(tmp_path / "nothing.json", tmp_path / "r.html").read_text()
    assert "missing or cannot be read" in page


def test_the_isolation_used_is_shown_and_a_plain_fallback_stands_out(tmp_path):
    test = spec.TestSpec("contacts.circle_circle", "contacts", "Two circles", 2.0, "visible")
    outcomes = [run.TestResult(test, Outcome.passed("ok"), 0.1)]
    for name, isolation in (("a", "bwrap"), ("b", "plain"), ("c", "plain"), ("d", None)):
        write_results(build_results(outcomes, 1.0, submission_id=name, isolation=isolation),
                      tmp_path / name / "results.json")
    assert "isolation: bubblewrap" in write_student_report(tmp_path / "a" / "results.json",
                                                           tmp_path / "a" / "report.html").read_text()
    plain = write_student_report(tmp_path / "b" / "results.json", tmp_path / "b" / "report.html").read_text()
    assert "isolation: plain" in plain and "bubblewrap could not start" in plain
    assert "isolation" not in write_student_report(tmp_path / "d" / "results.json",
                                                   tmp_path / "d" / "report.html").read_text().lower()
    page = write_class_report(tmp_path).read_text()
    assert "2 graded with isolation: plain" in page and "1 graded with isolation: bubblewrap" in page
    assert "class='warning'>2 graded with isolation: plain" in page
