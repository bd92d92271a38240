"""Shrinking a failing random case to a small one with Hypothesis.

The checks first run a batch of seeded random cases in one round trip.  When one
fails, :func:`smallest_failure` asks Hypothesis for a failing example and shrinks it,
so the student sees a small case (round numbers, few bodies) instead of the random one.
"""
from __future__ import annotations

from hypothesis import HealthCheck, Phase, find, settings
from hypothesis.errors import NoSuchExample

from ..outcome import StudentCallFailed

# No "explain" phase: it re-runs the student's code many times to annotate the example,
# which multiplied the grading time of a failing submission by ten.
SHRINK_SETTINGS = settings(database=None, derandomize=True, max_examples=150, deadline=None,
                           phases=[Phase.generate, Phase.shrink], suppress_health_check=list(HealthCheck))


class _Abort(Exception):
    pass


def smallest_failure(strategy, is_wrong):
    """A small example for which ``is_wrong(example)`` is true, or None if none is found.

    A call that fails with an exception counts as wrong; a timeout or a crash stops
    the search at once (raised again as StudentCallFailed).
    """
    stopped: list[StudentCallFailed] = []

    def wrong(example) -> bool:
        if stopped:
            raise _Abort
        try:
            return bool(is_wrong(example))
        except StudentCallFailed as failure:
            if failure.outcome.status in ("timeout", "crashed"):
                stopped.append(failure)
                raise _Abort from None
            return True

    try:
        return find(strategy, wrong, settings=SHRINK_SETTINGS)
    except NoSuchExample:
        return None
    except _Abort:
        raise stopped[0] from None
