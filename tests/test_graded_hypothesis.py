"""Graded Hypothesis runs draw one fixed sequence of examples, whatever ran before them
in the process, and leave the process's Hypothesis as they found it; a grading process
replays the examples of a passing run (grader/harness/replay.py) with the same results.

The project's tests grade the example class inside pytest's own process, after other
property tests; a graded test's examples must not depend on which those were (a buggy
sample caught by one example in 300 was once caught on CI only)."""
from __future__ import annotations

import importlib
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.internal.conjecture import engine, providers

from grader.harness.plugin import HYPOTHESIS_PROFILE, register_hypothesis_profile, restore_hypothesis
from grader.harness.spec import PUBLIC_TESTS
from grader.harness.replay import replaying
from grader.harness.run import collect

ROOT = Path(__file__).resolve().parents[1]

DRAW_GRADED_EXAMPLES = """
import sys
sys.path.insert(0, sys.argv[1])
from tests.test_graded_hypothesis import graded_examples
print(graded_examples())
"""


def graded_examples() -> str:
    """The examples (their repr) a graded test of resolve_collision draws: bodies,
    contacts and materials, floats among them."""
    from grader.tests.public.test_impulse import resolve_inputs

    seen = []
    register_hypothesis_profile()
    try:
        @given(case=resolve_inputs())
        def graded(case):
            seen.append(case)

        graded()
    finally:
        restore_hypothesis()
    return repr(seen)


def fill_constants_cache() -> None:
    """A property test of the project's own on the same strategy (its own profile,
    local constants on, as tests/test_graded_strategies.py does): it leaves the float
    constants of every imported local module in Hypothesis's cache."""
    import grader.samples.example_class  # noqa: F401  (local modules full of constants)
    import solutions.world  # noqa: F401
    from grader.tests.public.test_impulse import resolve_inputs

    @settings(max_examples=200, database=None, derandomize=True, deadline=None)
    @given(case=resolve_inputs())
    def project_test(case):
        pass

    project_test()


def test_graded_examples_do_not_depend_on_earlier_tests():
    fill_constants_cache()
    assert len(providers.CONSTANTS_CACHE.cache) > 0
    here = graded_examples()
    fresh = subprocess.run([sys.executable, "-c", DRAW_GRADED_EXAMPLES, str(ROOT)], capture_output=True,
                           text=True, check=True, cwd=ROOT)
    assert here == fresh.stdout.strip()


def test_a_graded_run_puts_hypothesis_back():
    before = (settings._current_profile, providers._get_local_constants, engine.MAX_SHRINKS,
              engine.MAX_SHRINKING_SECONDS)
    register_hypothesis_profile()
    assert settings._current_profile == HYPOTHESIS_PROFILE
    assert settings.default.max_examples == 30 and settings.default.derandomize
    assert len(providers._get_local_constants()) == 0
    restore_hypothesis()
    after = (settings._current_profile, providers._get_local_constants, engine.MAX_SHRINKS,
             engine.MAX_SHRINKING_SECONDS)
    assert after == before


def test_a_graded_run_imports_its_tests_under_the_grading_profile():
    """A graded test module imported elsewhere first (the project's tests import them
    for their strategies) is imported again by the graded run, so its @given tests use
    the grading profile and not the settings of that other import."""
    name = "grader.tests.public.test_quadtree"

    def examples_of_coincident() -> int:
        return sys.modules[name].test_coincident._hypothesis_internal_use_settings.max_examples

    settings.register_profile("elsewhere", max_examples=100, derandomize=True)
    previous = settings._current_profile
    sys.modules.pop(name, None)
    settings.load_profile("elsewhere")
    try:
        importlib.import_module(name)
    finally:
        settings.load_profile(previous)
    assert examples_of_coincident() == 100
    collect([PUBLIC_TESTS / "test_quadtree.py"])
    assert examples_of_coincident() == 30
    assert settings._current_profile == previous


def graded_toy_test(seen: list, submission: dict | None = None):
    """A @given test under the grading profile whose body writes down what it is given
    and fails for the numbers ``submission["wrong_when"]`` picks (a submission's bug)."""
    submission = {} if submission is None else submission
    register_hypothesis_profile()
    try:
        @given(numbers=st.lists(st.integers(-1000, 1000), max_size=8), cell=st.sampled_from((0.25, 0.5, 1.0)))
        def toy(student, numbers, cell):
            seen.append((list(numbers), cell))
            wrong_when = submission.get("wrong_when", lambda n: False)
            assert not any(wrong_when(n) for n in numbers), f"wrong for {numbers}"
    finally:
        restore_hypothesis()
    return toy


def run_graded(test, **fixtures):
    register_hypothesis_profile()
    try:
        test(**fixtures)
    finally:
        restore_hypothesis()


def test_a_replay_gives_the_examples_hypothesis_draws():
    plain, replayed = [], []
    run_graded(graded_toy_test(plain), student=None)
    run = replaying(graded_toy_test(replayed))
    run_graded(run, student=None)                 # records
    first = list(replayed)
    replayed.clear()
    run_graded(run, student=None)                 # replays
    assert len(plain) == 30 and first == plain and replayed == plain


def test_a_failing_replay_fails_as_hypothesis_would():
    """A bug in numbers above 900: the replay meets it, and the test then fails with
    Hypothesis's own shrunk example, as it does when nothing was recorded."""
    def failure(run) -> str:
        with pytest.raises(AssertionError) as caught:
            run_graded(run, student=None)
        return str(caught.value).splitlines()[0]  # "wrong for [the shrunk numbers]"

    def buggy(n):
        return n > 900

    expected = failure(graded_toy_test([], {"wrong_when": buggy}))
    seen, submission = [], {}
    run = replaying(graded_toy_test(seen, submission))
    run_graded(run, student=None)                 # an honest submission records
    assert any(buggy(n) for numbers, _ in seen for n in numbers)
    submission["wrong_when"] = buggy
    seen.clear()
    assert failure(run) == expected
    assert len(seen) > 30                         # the replayed examples, then Hypothesis's
