"""Does a broad phase do the work of its algorithm?  The growth of its CPU time with N.

A grid or a quadtree on a *sparse* scene (boxes about 1 m wide, one per 4 m^2 whatever
N, so the number of overlapping pairs grows like N) does about N units of work (N log N
for a quadtree): multiplying N by :data:`GROWTH_FACTOR` multiplies the work by about
that factor.  A brute force tests all N (N - 1) / 2 pairs: its work grows with the
square of N, whatever library function or numpy trick performs it, so a grid function
that returns the shipped brute force answers right and still fails here.

Measured as CPU time of the sandbox's processes (:meth:`grader.sandbox.process.Sandbox.cpu_seconds`,
read by the trusted process from /proc, so other jobs on the machine do not count), for
the small scene called ``GROWTH_FACTOR * REPEATS`` times and the large one ``REPEATS``
times inside the worker: the same number of boxes either way, so a linear algorithm's
two times are about equal and a quadratic one's differ by about ``GROWTH_FACTOR``.
The ratio limit :data:`MAX_GROWTH` lies between them; a ratio above it is measured
again and the smaller ratio kept.
"""
from __future__ import annotations

import math
import weakref
from typing import Callable

import numpy as np

from ..harness.outcome import StudentCallFailed
from .random_cases import random_aabbs

#: Boxes in the small scene, and how many times more in the large one.  From 1000 to
#: 16 000 boxes a brute force stands well apart from a grid's or a quadtree's growth
#: (at 8 times more from 2000 they came too close: below); the small scene is small
#: because the library's numpy brute force is fast there.
SMALL_SCENE = 1000
GROWTH_FACTOR = 16
#: Calls of the large scene in one timed request (the small one: GROWTH_FACTOR times more).
REPEATS = 1
#: Largest accepted ratio (large scene's CPU time / small scene's, same number of boxes
#: processed).  Measured on this project's 2-core machine under load
#: (grader.oracles.scaling.growth): from 1000 to 16 000 boxes the reference grids 1.5
#: to 2.0, the library's numpy brute force returned by a grid 6.4 to 7.3; the reference
#: quadtree 1.20 to 1.24, a quadtree whose pairs test every pair with numpy 7.2 (from
#: 2000 to 16 000 boxes: 1.24 against 4.7 to 4.8, too close to the limit; at 8 times
#: more from 4000 the brute force runs out of memory, which also fails the check).
MAX_GROWTH = 4.5
#: Most measurements of one function while its ratio stays above MAX_GROWTH (the
#: smallest is kept): on a machine loaded by two test runs and an image build, the
#: reference grid once measured 3.6.
MEASUREMENTS = 3
#: The large scene's call may take at most this many times the small one's (and at least
#: MIN_TIMEOUT seconds) before it is stopped: a pure-Python brute force on 32 000 boxes
#: would take minutes.
TIMEOUT_RATIO = 12.0
MIN_TIMEOUT = 5.0

#: The measured verdict per package under test and function: one measurement a session.
_VERDICTS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def sparse_scene(count: int, seed: int) -> np.ndarray:
    """``count`` boxes 0.1 to 1 m wide spread at a constant density (one per 4 m^2)."""
    return random_aabbs(np.random.default_rng(seed), count, world=2.0 * math.sqrt(count), size=1.0)


def timed_cpu(student, module: str, function: str, args: tuple, repeat: int, timeout: float) -> float | None:
    """CPU seconds of ``repeat`` calls in one request (wall clock where CPU time cannot
    be read); None if the call timed out.  A call that fails otherwise raises, as
    :meth:`~grader.harness.student_code.StudentCode.call` does."""
    before = student.sandbox.cpu_seconds()
    result = student.raw(module, function, *args, repeat=repeat, timeout=timeout)
    after = student.sandbox.cpu_seconds()
    if result.status == "timeout":
        return None
    if repeat:
        student.value_of(result, f"{module}.{function}")
    if before is None or after is None or after < before:
        return result.elapsed
    return after - before


def work_cpu(student, module: str, function: str, args: tuple, repeat: int, timeout: float) -> float | None:
    """CPU seconds of ``repeat`` calls less that of a request that calls nothing (the
    worker's reading of the scene: it grows with N however the function works).  The
    scene, a kept argument (:meth:`~grader.harness.student_code.StudentCode.kept`), is
    sent by a first request that calls nothing, untimed: both timed requests then
    decode the worker's copy, so the one calling nothing reads what the other reads."""
    student.raw(module, function, *args, repeat=0, timeout=60.0)
    spent = timed_cpu(student, module, function, args, repeat, timeout)
    if spent is None:
        return None
    reading = timed_cpu(student, module, function, args, 0, timeout=60.0) or 0.0
    return max(spent - reading, 1e-6)


def growth(student, module: str, function: str, args_of: Callable[[np.ndarray], tuple],
           factor: int = GROWTH_FACTOR, small_scene: int = SMALL_SCENE) -> tuple[float, str]:
    """(ratio, how it was measured) for one measurement; ratio inf when the large scene
    timed out."""
    small, large = sparse_scene(small_scene, 1), sparse_scene(small_scene * factor, 2)
    student.call(module, function, *args_of(small[:20]))                  # imports and first-call costs
    # Sent to the worker once (several functions and measurements read the same scenes).
    small, large = student.kept(small), student.kept(large)
    small_time = work_cpu(student, module, function, args_of(small), factor * REPEATS, timeout=60.0)
    if small_time is None:
        return math.inf, f"{factor * REPEATS} calls on {small_scene} boxes took longer than 60 s"
    limit = max(MIN_TIMEOUT, TIMEOUT_RATIO * small_time)
    shown = (f"{factor * REPEATS} calls on {small_scene} boxes took {small_time:.3f} s of CPU time, "
             f"{REPEATS} calls on {small_scene * factor} boxes ")
    try:
        large_time = work_cpu(student, module, function, args_of(large), REPEATS, timeout=limit)
    except StudentCallFailed as exc:   # worked on the small scene: the large one is the algorithm's to bear
        said = (exc.outcome.message or exc.outcome.status).strip().splitlines()
        return math.inf, shown + f"failed ({said[-1][:200] if said else exc.outcome.status})"
    if large_time is None:
        return math.inf, shown + f"did not finish in {limit:.1f} s"
    return large_time / small_time, shown + f"took {large_time:.3f} s"


def growth_problem(student, module: str, function: str, args_of: Callable[[np.ndarray], tuple],
                   algorithm: str, factor: int = GROWTH_FACTOR, small_scene: int = SMALL_SCENE) -> str | None:
    """None when ``function`` does the work of ``algorithm`` (a sentence: "a grid visits
    the cells a box overlaps"), else why not; measured once per package and function.

    ``args_of(boxes)`` gives the call's arguments for a scene.  A stub is not judged here
    (None: the test's own calls report it); a call that fails on the measured scenes fails
    the check, saying so (else failing only there would skip the measurement).
    """
    verdicts = _VERDICTS.setdefault(student, {})
    key = (module, function)
    if key not in verdicts:
        try:
            ratio, how = growth(student, module, function, args_of, factor, small_scene)
            for _ in range(MEASUREMENTS - 1):   # measured again: a busy moment must not cost the points
                if ratio <= MAX_GROWTH:
                    break
                again, again_how = growth(student, module, function, args_of, factor, small_scene)
                if again < ratio:
                    ratio, how = again, again_how
        except StudentCallFailed as exc:
            if exc.outcome.status == "not_implemented":   # a stub: the test's own calls say so
                verdicts[key] = None
                return None
            # Failing only on the measured scenes must not skip the measurement.
            said = (exc.outcome.message or exc.outcome.status).strip().splitlines()
            verdicts[key] = (f"{function} failed on a sparse scene of {small_scene} boxes (the check that it does "
                             f"the work of {algorithm}): {said[-1][:200] if said else exc.outcome.status}")
            return verdicts[key]
        verdicts[key] = None if ratio <= MAX_GROWTH else (
            f"{function} does the work of a brute force, not of {algorithm}: on sparse scenes (boxes about 1 m "
            f"wide at a constant density, so the pairs grow like N), {factor} times more boxes took "
            f"{'too long' if math.isinf(ratio) else f'{ratio:.1f} times more CPU time per box'} (at most "
            f"{MAX_GROWTH:g} times allowed; {algorithm} needs about the same time per box whatever N). {how}. "
            f"Testing every pair (or calling a brute force) gives the right pairs but is not the exercise.")
    return verdicts[key]
