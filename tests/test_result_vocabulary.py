"""One result vocabulary: the grader says a status, writes points and styles a page one
way, from grader/harness/outcome.py (STATUS_MEANINGS) and grader/harness/results_model.py
(points, STYLE_SHEET).  These tests read grader/'s sources and fail when a second status
table, style sheet or points formatter appears elsewhere."""
from __future__ import annotations

import ast
import re
from pathlib import Path

from grader.harness.outcome import STATUS_MEANINGS, STATUSES, status_of
from grader.harness.results_model import (STYLE_SHEET, SubmissionResults, badge, html_page, points, status_word)

GRADER = Path(__file__).resolve().parent.parent / "grader"
VOCABULARY = {GRADER / "harness" / "outcome.py"}
STYLE_HOME = GRADER / "harness" / "results_model.py"
CSS_RULE = re.compile(r"[\w.#\]]\s*\{[^{}]*\b[a-z-]+\s*:\s*[^;{}]+;")


def sources() -> list[tuple[Path, ast.AST]]:
    return [(path, ast.parse(path.read_text(encoding="utf-8"))) for path in sorted(GRADER.rglob("*.py"))]


def test_no_second_status_table():
    """A dict keyed by three or more of the statuses, and by nothing else, is a table of them:
    only outcome.py has one.  (A table keyed by the worker's call statuses, some of which
    share a name, translates those: its keys are not all the grader's statuses.)"""
    found = []
    for path, tree in sources():
        if path in VOCABULARY:
            continue
        for node in ast.walk(tree):
            if isinstance(node, ast.Dict):
                keys = {k.value for k in node.keys if isinstance(k, ast.Constant) and isinstance(k.value, str)}
                if len(keys) >= 3 and keys <= set(STATUSES):
                    found.append(f"{path.relative_to(GRADER)}:{node.lineno}")
    assert not found, f"status tables outside grader/harness/outcome.py (use STATUS_MEANINGS): {found}"


def test_no_module_level_status_dict_but_the_one():
    """A module-level dict named for statuses (``STATUS_WORDS``, ``STATUS_COLORS``...) is a
    second vocabulary whatever its keys: only outcome.py's STATUS_MEANINGS is one."""
    found = []
    for path, tree in sources():
        for node in tree.body:
            targets = node.targets if isinstance(node, ast.Assign) else [node.target] \
                if isinstance(node, ast.AnnAssign) else []
            for target in targets:
                value = node.value
                is_dict = isinstance(value, (ast.Dict, ast.DictComp)) or (
                    isinstance(value, ast.Call) and isinstance(value.func, ast.Name) and value.func.id == "dict")
                if isinstance(target, ast.Name) and "STATUS" in target.id.upper() and is_dict \
                        and path not in VOCABULARY:
                    found.append(f"{path.relative_to(GRADER)}:{node.lineno} {target.id}")
    assert not found, f"status dicts outside grader/harness/outcome.py (use STATUS_MEANINGS): {found}"


def test_a_failed_call_ends_its_test_with_one_of_the_statuses():
    """A call's status (the sandbox's vocabulary) is not a test's: student_code.CALL_FAILURES
    says what each failed call means for its test, for every way a call can fail."""
    from grader.harness.student_code import CALL_FAILURES
    from grader.sandbox.process import CALL_STATUSES

    assert set(CALL_FAILURES) == set(CALL_STATUSES) - {"ok"}
    assert {status for status, _ in CALL_FAILURES.values()} <= set(STATUSES)


def test_no_second_style_sheet():
    """CSS rules (``selector { property: value; }``) live in STYLE_SHEET only; a page puts
    that sheet in its ``<style>`` element."""
    found = []
    for path, tree in sources():
        if path == STYLE_HOME:
            continue
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and CSS_RULE.search(node.value):
                found.append(f"{path.relative_to(GRADER)}:{node.lineno}")
    assert not found, f"style sheets outside grader/harness/results_model.py (use STYLE_SHEET): {found}"


def test_no_second_points_formatter():
    """No function named for points (``_points``, ``format_points``...) but results_model.points."""
    found = []
    for path, tree in sources():
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name.strip("_") in (
                    "points", "format_points", "fmt_points", "show_points") and path != STYLE_HOME:
                found.append(f"{path.relative_to(GRADER)}:{node.lineno} {node.name}")
    assert not found, f"points formatters outside grader/harness/results_model.py (use points): {found}"


def test_every_status_has_words_a_label_and_a_colour():
    for status in STATUSES:
        said = status_of(status)
        assert said.word and said.label and said.colour.startswith("#") and said.ansi.isdigit(), status
    assert len({s.label for s in STATUS_MEANINGS.values()}) == len(STATUSES)  # labels tell statuses apart
    assert status_word("failed", 1.0, 2.0) == "partly right" and status_word("failed", 0.0, 2.0) == "wrong answer"
    assert status_of("made_up").word == "made up"  # a status from elsewhere is said as written
    assert points(1.5) == "1.5" and points(2.0) == "2" and points(None) == "–"


def test_pages_and_badges_use_the_one_style_sheet():
    page = html_page("t", [badge("timeout")])
    assert STYLE_SHEET in page and '<body class="report">' in page
    assert STATUS_MEANINGS["timeout"].colour in page and "Timed out" in page


def test_results_json_round_trips_through_the_model():
    """from_json(to_json()) gives back what the views read: statuses, points, messages."""
    from grader.harness.outcome import Outcome, TestResult
    from grader.harness.spec import TestSpec

    tests = [TestSpec("grid.a", "grid", "A", 2.0, "visible"), TestSpec("grid.b", "grid", "B", 3.0, "hidden",
                                                                       partial_credit=True)]
    made = SubmissionResults.graded([TestResult(tests[0], Outcome.passed(), 0.1),
                                     TestResult(tests[1], Outcome.failed("off by one", fraction=0.95), 0.2)],
                                    1.0, "ada")
    back = SubmissionResults.from_json(made.to_json())
    assert (back.id, back.score, back.max_score) == ("ada", made.score, 5.0)
    assert [(r.test.name, r.outcome.status, r.score, r.outcome.message, r.test.visibility) for r in back.tests] == \
        [(r.test.name, r.outcome.status, r.score, r.outcome.message, r.test.visibility) for r in made.tests]
    assert 0 < back.tests[1].score < 3.0 and back.summary() == made.summary()


def test_a_test_result_has_one_serialised_form():
    """A grading worker's event and results.json's ``extra_data`` carry the same form of a
    test result (TestResult.to_dict), read back by TestResult.from_dict; the batch's
    parent reads the event into the model the results file is written from."""
    import json
    from pathlib import Path
    from types import SimpleNamespace

    from grader.batch.scheduler import Job, _handle_event
    from grader.batch.submissions import Submission
    from grader.harness.outcome import Outcome, TestResult
    from grader.harness.results_model import result_of_entry, results_entry
    from grader.harness.spec import TestSpec

    test = TestSpec("contacts.circle", "contacts", "Circles", 2.0, "visible", partial_credit=True)
    figure = {"kind": "pairs", "title": "t", "cell_size": 1.0, "aabbs": [[0, 0, 1, 1]], "missed": [], "extra": []}
    result = TestResult(test, Outcome("failed", 0.95, "the normal points from B to A", figure, {"seconds": 0.01},
                                      "printed\n"), 0.25)
    event = json.loads(json.dumps({"event": "test", "job": 0, "index": 0, "result": result.to_dict()}))
    assert TestResult.from_dict(event["result"], test) == result
    entry = json.loads(json.dumps(results_entry(test, result.outcome, result.seconds)))
    assert {key: entry["extra_data"][key] for key in event["result"]} == event["result"]
    back = result_of_entry(entry, 1)
    assert (back.outcome, back.seconds, back.score) == (result.outcome, result.seconds, result.score) and 0 < back.score
    job = Job(0, Submission("ada", Path("ada"), "folder"), "fingerprint", [test], [0])
    worker = SimpleNamespace(job=job, deadline=0.0, attempt_started=0.0, ready=True)
    _handle_event(worker, event, 10.0, lambda job, used: None)
    assert job.results == {0: result} and job.remaining == []
    unknown = TestResult.from_dict({**event["result"], "status": "exploded", "seconds": "soon"}, test)
    assert (unknown.outcome.status, unknown.seconds) == ("error", 0.0)


def test_no_second_serialised_form_of_a_result():
    """to_dict/from_dict (one test's result, its outcome) are defined in outcome.py only."""
    found = [f"{path.relative_to(GRADER)}:{node.lineno} {node.name}" for path, tree in sources()
             if path not in VOCABULARY for node in ast.walk(tree)
             if isinstance(node, ast.FunctionDef) and node.name in ("to_dict", "from_dict", "as_dict")]
    assert not found, f"serialised forms outside grader/harness/outcome.py (use TestResult.to_dict): {found}"


def test_no_second_byte_size_formatter():
    """Sizes in bytes are written by grader.student.manifest.byte_size only: no f-string
    elsewhere divides by 1024 (or a power of it) to print KiB, MiB or GiB."""
    from grader.student.manifest import byte_size

    def kibi(node) -> bool:
        if isinstance(node, ast.Constant):
            return node.value == 1024
        return isinstance(node, ast.BinOp) and isinstance(node.op, ast.Pow) and kibi(node.left)

    found = []
    for path, tree in sources():
        if path == GRADER / "student" / "manifest.py":
            continue
        for node in ast.walk(tree):
            if isinstance(node, ast.FormattedValue):
                for inner in ast.walk(node.value):
                    if isinstance(inner, ast.BinOp) and isinstance(inner.op, ast.Div) and kibi(inner.right):
                        found.append(f"{path.relative_to(GRADER)}:{node.lineno}")
    assert not found, f"byte sizes formatted outside grader/student/manifest.py (use byte_size): {found}"
    assert [byte_size(n) for n in (512, 12 * 1024, 64 * 1024**2, 2 * 1024**3)] == \
        ["512 bytes", "12 KiB", "64.0 MiB", "2.0 GiB"]
