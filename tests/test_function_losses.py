"""The per-function loss table (tools/function_losses.py): which bugs lose less than half
of the points of the tests reaching their functions, and which failed tests keep more."""
from __future__ import annotations

from grader.samples.example_class import BUGGY_SAMPLES, exercise_functions_flat
from grader.samples.shortcuts import SHORTCUTS
from tools import function_losses


def bug(name: str, at_stake: float, lost: float, keeping=()) -> dict:
    return {"name": name, "functions": ["narrowphase.polygon_polygon.reference_face_manifold"], "at_stake": at_stake,
            "lost": lost, "tests_lost": {}, "failed_tests_keeping_more_than_half": list(keeping)}


def test_a_bug_under_half_and_a_test_keeping_more_than_half_are_problems():
    data = {"functions": {"narrowphase.polygon_polygon.reference_face_manifold": 22.0},
            "bugs": [bug("half", 22, 11), bug("under", 22, 10.5), bug("keeps", 22, 22, ["contacts.face_face"])]}
    found = function_losses.problems(data)
    assert found == ["under loses 10.5 of 22: less than half", "keeps: contacts.face_face keeps more than half its points"]
    table = function_losses.format_tables(data)
    assert "| under | polygon_polygon.reference_face_manifold | 22 | 10.5 | 48% **under half** |" in table
    assert "| polygon_polygon.reference_face_manifold | 22 | 3 | 10.5 of 22 (under) |" in table


def test_every_sample_and_shortcut_rewrites_exercise_functions():
    bugs = function_losses.systematic_bugs()
    assert len(bugs) == len(BUGGY_SAMPLES) + len(SHORTCUTS)
    functions = set(exercise_functions_flat())
    for sample in bugs:
        rewritten = {f"{r.module}.{r.qualname}" for r in sample.replacements}
        assert rewritten <= functions, (sample.name, rewritten - functions)
