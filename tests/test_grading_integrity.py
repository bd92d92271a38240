"""Issue 24, items 5 and 6: exercises that cannot be bypassed through the library, and
points that follow the harm.

Each test builds a submission the way a determined student would (the reference with
one function rewritten, :mod:`grader.samples.example_class`), grades it with the real
graded tests in a real sandbox, and checks the points and the message.
"""
from __future__ import annotations

import os
from pathlib import Path

import pytest

from grader.harness.run import load_spec, run_tests
from grader.samples.example_class import SOLUTIONS_DIR, BuggySample, Replacement, build_buggy_sample


def sandbox_slot() -> int:
    """A sandbox user per xdist worker (30, 31...), apart from the example class's 20s."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "gw0")
    return 30 + int(worker[2:]) if worker[2:].isdigit() else 30


def graded(tmp_path: Path, replacements: tuple[Replacement, ...], names: set[str]) -> dict:
    """Results by test name of the tests ``names`` on the reference with ``replacements``."""
    sample = BuggySample(name="integrity", mistake="a shortcut", erratum=0, replacements=replacements,
                         expected_failures=frozenset())
    folder = build_buggy_sample(sample, tmp_path, SOLUTIONS_DIR)
    tests = [t for t in load_spec() if t.name in names]
    assert {t.name for t in tests} == names, "a test named here is not in the spec"
    return {r.test.name: r for r in run_tests(folder, tests, slot=sandbox_slot())}


REFUSE_EVERYTHING = tuple(
    Replacement("response.momentum_1d", name, f'''
        def {name}({args}):
            raise ValueError("refused")
        ''') for name, args in (("collision_1d", "m1, v1, m2, v2, restitution"),
                                ("elastic_collision_1d", "m1, v1, m2, v2"),
                                ("perfectly_inelastic_1d", "m1, v1, m2, v2")))


def test_refusing_every_input_does_not_pass_the_test_of_refusals(tmp_path):
    results = graded(tmp_path, REFUSE_EVERYTHING, {"momentum.rejects_bad_input"})
    result = results["momentum.rejects_bad_input"]
    assert result.score == 0, result.outcome.message
    assert "allowed input" in result.outcome.message and "ValueError" in result.outcome.message
