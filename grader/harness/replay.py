"""Replay, for the next submission, the examples a Hypothesis test drew for a passing one.

Graded Hypothesis runs are derandomized (:func:`grader.harness.plugin.register_hypothesis_profile`):
until a test fails, the examples it draws depend only on its strategies, never on the
code under test.  So a run that passes has drawn exactly the examples any other
submission will be given, in the same order, up to its first failure.  Drawing them
costs more processor time than many students' functions take to answer them (about a
third of a warm grading run of the reference), so a grading process draws them once:

- the first run of a test that passes records the keyword arguments Hypothesis drew
  (explicit ``@example`` cases included), in call order;
- later runs of that test call it on those arguments, without Hypothesis;
- if a replayed example fails, the test runs under Hypothesis from the start, which
  finds the same failure and shrinks it, so a failing submission gets the very message
  it would have got without the replay.

The record is kept per test function object, in this process only: a graded test
module imported again (a changed test, :func:`grader.harness.plugin.forget_tests_imported_elsewhere`)
starts a new record.
"""
from __future__ import annotations

import copy
import functools
from typing import Callable

from .outcome import StudentCallStopped
from .student_code import forget_output

#: Per Hypothesis test function: the drawn keyword arguments of a passing run, in order.
_RECORDED: dict[Callable, list[dict]] = {}


def is_hypothesis_test(function) -> bool:
    return callable(function) and getattr(function, "is_hypothesis_test", False)


def replaying(test: Callable) -> Callable:
    """``test`` (a ``@given`` test) that replays recorded examples when it has some."""
    handle = test.hypothesis

    @functools.wraps(test)
    def run(*args, **fixtures):
        inner = handle.inner_test
        examples = _RECORDED.get(test)
        if examples is not None:
            try:
                for drawn in examples:
                    forget_output()  # a test's output is its last example's (the failing one)
                    inner(*args, **fixtures, **copy.deepcopy(drawn))
                return None
            except StudentCallStopped:
                raise  # a time or memory limit: running it all again would only cost more
            except Exception:  # noqa: BLE001 - any failure: Hypothesis finds and shrinks it
                pass
        calls = []

        # Hypothesis seeds a derandomized run from the source and signature of the
        # inner test: the recorder must look like it, or it would draw other examples.
        @functools.wraps(inner)
        def recording(*inner_args, **arguments):
            drawn = {name: copy.deepcopy(value) for name, value in arguments.items() if name not in fixtures}
            # Hypothesis runs the shrunk failing example last: the output kept is what it printed.
            forget_output()
            result = inner(*inner_args, **arguments)
            calls.append(drawn)
            return result

        handle.inner_test = recording
        try:
            result = test(*args, **fixtures)
        finally:
            handle.inner_test = inner
        _RECORDED[test] = calls  # reached only when every example passed
        return result

    return run
