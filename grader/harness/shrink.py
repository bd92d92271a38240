"""A small failing case for a test whose seeded batch failed, found and shrunk by
Hypothesis.

A partial-credit test grades a batch of seeded random cases in one round trip (its
share of right cases is the credit).  When one is wrong, :func:`smallest_failure`
asks Hypothesis for a failing example drawn from the same category's strategy and
shrinks it, so the message and picture show a small case with round numbers instead
of the random one.  A stub, a timeout or a crash stops the search at once.
"""
from __future__ import annotations

from hypothesis import HealthCheck, Phase, find, settings
from hypothesis.errors import NoSuchExample

from .outcome import StudentCallFailed
from .student_code import output_of_the_case_found

#: No "explain" phase: it re-runs the student's code many times to annotate the example.
SHRINK_SETTINGS = settings(database=None, derandomize=True, max_examples=60, deadline=None,
                           phases=[Phase.generate, Phase.shrink], suppress_health_check=list(HealthCheck))


def smallest_failure(strategy, is_wrong):
    """A small example for which ``is_wrong(example)`` is true, or None if none is found.

    A call that raises in the student's code counts as wrong (StudentCallFailed); a
    stopped call (not implemented, timeout, crash) propagates and ends the search.
    What the examples tried printed is set aside: when one is found, the test's output
    is what its code prints when the test runs that example again.
    """
    def wrong(example) -> bool:
        try:
            return bool(is_wrong(example))
        except StudentCallFailed:
            return True

    with output_of_the_case_found() as search:
        try:
            example = find(strategy, wrong, settings=SHRINK_SETTINGS)
        except NoSuchExample:
            return None
        search["found"] = True
        return example
