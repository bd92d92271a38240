"""What a graded test raises to fail with more than a plain ``assert``: a share of right
cases (partial credit) and a picture of the failing case.

A plain ``assert`` fails a test with no credit.  A test over many cases calls
:func:`check_cases`, which fails with the share of right cases; that share earns
points only when the test is marked ``@pytest.mark.partial_credit`` and only above
:data:`PARTIAL_CREDIT_FLOOR`, and never more than :data:`FAILED_TEST_CAP` of them: a failed
test keeps at most half its points, a systematic bug (one that breaks a whole category
of cases) loses them all, and a constant answer earns nothing.
"""
from __future__ import annotations

from typing import Callable, Iterable

#: Below this share of right cases a partial-credit test earns nothing at all.
PARTIAL_CREDIT_FLOOR = 0.9
#: Points earned at the floor, as a share of the test's points (rises linearly towards
#: :data:`FAILED_TEST_CAP` as the share of right cases reaches 1).
SHARE_AT_FLOOR = 0.25
#: The most a failed test keeps, as a share of its points: a test that finds a bug
#: costs at least half its points, however rare the failing cases.
FAILED_TEST_CAP = 0.5


class GradedFailure(AssertionError):
    """A failed graded test: the message, the share of right cases, a picture."""

    def __init__(self, message: str, fraction: float = 0.0, figure: dict | None = None):
        super().__init__(message)
        self.fraction = float(fraction)
        self.figure = figure


def fail(message: str, fraction: float = 0.0, figure: dict | None = None):
    """Fail the running graded test (never returns)."""
    raise GradedFailure(message, fraction, figure)


def partial_points(points: float, fraction: float) -> float:
    """Points of a failed partial-credit test that got ``fraction`` of its cases right.

    Nothing below :data:`PARTIAL_CREDIT_FLOOR`; from :data:`SHARE_AT_FLOOR` of the
    points at the floor rising linearly to :data:`FAILED_TEST_CAP` (half) at 1.
    """
    if not fraction >= PARTIAL_CREDIT_FLOOR:
        return 0.0
    fraction = min(1.0, fraction)
    rise = (fraction - PARTIAL_CREDIT_FLOOR) / (1 - PARTIAL_CREDIT_FLOOR)
    share = SHARE_AT_FLOOR + (FAILED_TEST_CAP - SHARE_AT_FLOOR) * rise
    return round(points * min(share, FAILED_TEST_CAP), 6)


def check_cases(cases: Iterable, problem_of: Callable, label: str, describe: Callable | None = None,
                figure_of: Callable | None = None, smaller: Callable | None = None,
                category: Callable | None = None) -> int:
    """Fail unless ``problem_of(case)`` is None for every case; return the count.

    ``problem_of(case)`` returns None for a right answer, else a sentence saying what
    is wrong.  The failure names how many cases were wrong, shows the first one
    (``describe(case)``, default ``repr``) with its problem, draws it
    (``figure_of(case)``) and carries the share of right cases.  ``smaller()``, when
    given, returns a small wrong case of the same category (or None) to show instead
    (:func:`grader.harness.shrink.smallest_failure`).  ``category(case)``, when given, names
    each case's category (a kind of input, a function): the share carried is then the
    worst category's, so a bug that breaks one whole category earns no partial credit.
    """
    cases = list(cases)
    wrong = []
    for case in cases:
        problem = problem_of(case)
        if problem is not None:
            wrong.append((case, problem))
    if not wrong:
        return len(cases)
    fraction = 1 - len(wrong) / len(cases)
    if category is not None:  # the share of the worst category: one systematic bug costs it all
        totals: dict = {}
        for case in cases:
            key = category(case)
            totals[key] = totals.get(key, 0) + 1
        misses: dict = {}
        for case, _ in wrong:
            key = category(case)
            misses[key] = misses.get(key, 0) + 1
        fraction = min(1 - misses.get(key, 0) / total for key, total in totals.items())
    case, problem = wrong[0]
    if smaller is not None:  # a small case of the same category, shrunk by Hypothesis
        found = smaller()
        if found is not None:
            case = found
            problem = problem_of(case) or problem
    shown = describe(case) if describe is not None else repr(case)
    figure = figure_of(case) if figure_of is not None else None
    fail(f"{label}: {len(wrong)} of {len(cases)} cases wrong, e.g. {shown}: {problem}",
         fraction=fraction, figure=figure)
