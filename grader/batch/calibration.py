"""How much slower than an idle machine this one runs now: time limits scale by it.

A per-test or per-submission limit in wall-clock seconds fails honest work when the
machine is loaded (other batches, a build).  :func:`slowdown` times a fixed piece of
work -- a pure-Python loop and small numpy operations, the mix graded code runs --
takes the fastest of a few runs, and divides it by the time the same work takes on an
idle reference machine (:data:`NOMINAL_SECONDS`, measured on this project's 2-core
machine).  ``grader grade`` multiplies its limits by the result, clamped to
[1, :data:`MAX_SLOWDOWN`]: never stricter than the nominal limits, never unbounded.
"""
from __future__ import annotations

import time

#: Seconds of :func:`reference_work` on an idle reference machine (fastest of five).
NOMINAL_SECONDS = 0.0125
MAX_SLOWDOWN = 4.0


def reference_work() -> float:
    """A fixed mix of interpreter and numpy work; returns a number so nothing is skipped."""
    import numpy as np

    total = 0.0
    for i in range(200_000):
        total += (i % 7) * 0.5
    a = np.arange(20_000, dtype=float)
    for _ in range(60):
        total += float(np.sqrt(a * a + 1.0).sum())
    return total


def slowdown(runs: int = 5) -> float:
    """The current slowdown factor, clamped to [1, MAX_SLOWDOWN]."""
    best = float("inf")
    for _ in range(runs):
        started = time.perf_counter()
        reference_work()
        best = min(best, time.perf_counter() - started)
    return min(MAX_SLOWDOWN, max(1.0, best / NOMINAL_SECONDS))
