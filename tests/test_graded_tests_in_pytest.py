"""Graded tests are ordinary pytest tests: an instructor runs them directly, selects with
``-k``, gets JUnit XML; a new graded test is a few lines with markers."""
from __future__ import annotations

import shutil
import subprocess
import sys
import textwrap
import xml.etree.ElementTree as ElementTree
from pathlib import Path

import pytest

from grader.harness.credit import partial_points
from grader.harness.plugin import spec_of  # noqa: F401  (the module imports without a session)
from grader.harness.run import run_tests
from grader.harness.spec import SpecError
from grader.harness.run import load_spec

REPO = Path(__file__).resolve().parent.parent


def test_pytest_runs_the_public_tests_directly_with_selection_and_junit(tmp_path):
    report = tmp_path / "out.xml"
    completed = subprocess.run([sys.executable, "-m", "pytest", "grader/tests/public", "--student", "exercises",
                                "-k", "momentum", "-q", f"--junitxml={report}"], cwd=REPO, capture_output=True,
                               text=True, timeout=300)
    assert completed.returncode == 1, completed.stdout[-2000:]  # the stubs fail every test
    cases = ElementTree.parse(report).getroot().iter("testcase")
    properties = {case.get("name"): {p.get("name"): p.get("value") for p in case.iter("property")} for case in cases}
    momentum = [t for t in load_spec() if t.exercise == "momentum" and t.public]
    assert sorted(properties) == sorted(t.nodeid.rsplit("::", 1)[1] for t in momentum)
    for name, found in properties.items():
        assert found["status"] == "not_implemented" and float(found["score"]) == 0 and float(found["points"]) > 0


def test_a_new_graded_test_in_five_lines_is_collected_and_scored(tmp_path, monkeypatch):
    folder = tmp_path / "tests"
    shutil.copytree(REPO / "grader" / "tests", folder, ignore=shutil.ignore_patterns("public", "hidden", "__pycache__"))
    (folder / "extra").mkdir()
    (folder / "extra" / "__init__.py").write_text("")
    (folder / "extra" / "test_momentum.py").write_text(textwrap.dedent('''
        import pytest

        @pytest.mark.points(3)
        @pytest.mark.visibility("after_due_date")
        def test_head_on(student, picture):
            """Two equal masses swap velocities"""
            picture.attach({"kind": "pairs", "title": "not a real picture", "aabbs": [[0, 0, 1, 1]],
                            "cell_size": 0, "missed": [], "extra": []})
            got = student.call("response.momentum_1d", "elastic_collision_1d", 1.0, 2.0, 1.0, -1.0)
            assert got == [-1.0, 2.0], f"elastic_collision_1d(1, 2, 1, -1) should swap the velocities, got {got}"
        '''))
    tests = load_spec([folder / "extra"])
    assert [(t.name, t.points, t.visibility, t.title) for t in tests] == [
        ("momentum.head_on", 3.0, "after_due_date", "Two equal masses swap velocities")]
    passed = run_tests(REPO / "solutions", tests)
    assert passed[0].outcome.status == "passed" and passed[0].score == 3
    failed = run_tests(REPO / "exercises", tests)
    assert failed[0].outcome.status == "not_implemented" and failed[0].score == 0


def test_a_graded_test_without_points_is_refused(tmp_path):
    folder = tmp_path / "broken"
    folder.mkdir()
    (folder / "__init__.py").write_text("")
    (folder / "test_grid.py").write_text("def test_no_points(student):\n    pass\n")
    shutil.copy(REPO / "grader" / "tests" / "conftest.py", folder / "conftest.py")
    with pytest.raises(SpecError, match="points"):
        load_spec([folder])


def test_partial_credit_rule():
    assert partial_points(2.0, 0.89) == 0 and partial_points(2.0, 0.9) == 0.5
    assert partial_points(2.0, 0.95) == pytest.approx(0.75)


def test_a_failed_test_keeps_at_most_half_its_points():
    # The four failures of issue 24 kept 1.87/2, 2.5/3, 1.97/2 and 1.04/2.
    for points in (1.0, 2.0, 3.0):
        for fraction in (0.9, 0.95, 0.99, 0.999999, 1.0):
            assert partial_points(points, fraction) <= points / 2
