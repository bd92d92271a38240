"""The reference's runs of the speed tests, kept per grading process.

A speed test shows the student's time beside the reference's, measured in the same run
in the reference's own sandbox (``reference`` fixture).  The reference's inputs and
answers are the same for every submission, so its run is kept in the grading process
and served to the next submissions; its time is measured again side by side every
:data:`REFERENCE_RUNS_KEPT` submissions, and whenever the student's time is more than
:data:`SLOWER_THAN_KEPT` times the kept figure, so that a load that rose since the
reference was timed does not make the student look slow.  A run whose time could not
be measured is not kept.
"""
from __future__ import annotations

from typing import Any, Callable

#: Submissions one reference run serves before it is measured again.
REFERENCE_RUNS_KEPT = 8
#: A student's time over this many times the kept reference time has the reference measured again.
SLOWER_THAN_KEPT = 1.5

#: {(reference package folder, run name): [value, seconds, submissions served]}.
_KEPT: dict[tuple[str, str], list] = {}


def kept_reference_run(reference, name: str, student_seconds: float | None,
                       run: Callable[[], tuple[Any, float | None]]) -> tuple[Any, float | None]:
    """``run()``'s (value, seconds) with the reference's code, or the kept ones (see the
    module's docstring); ``name`` tells the test's runs apart, ``student_seconds`` is the
    student's time on the same work (None: not measured)."""
    key = (str(reference.sandbox.package_dir.resolve()), name)
    kept = _KEPT.get(key)
    if (kept is None or kept[2] >= REFERENCE_RUNS_KEPT
            or (student_seconds is not None and student_seconds > SLOWER_THAN_KEPT * kept[1])):
        value, seconds = run()
        if seconds is None:
            _KEPT.pop(key, None)
            return value, None
        kept = _KEPT[key] = [value, seconds, 0]
    kept[2] += 1
    return kept[0], kept[1]
