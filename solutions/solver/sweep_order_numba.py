"""The sweep order compiled: the twin of :func:`solutions.solver.sweep_order.sweep_order`.

The same batches (each manifold after the last one of either movable body, or the
first colour neither body has) stably sorted, written into caller's arrays without
allocating, for the compiled soft step (:mod:`solutions.response.soft_step_numba`).
Tested equal to the readable order (``tests/test_soft_step_numba.py``).
"""
from __future__ import annotations

### INSTRUCTOR ONLY: not in the student edition (the compiled soft step's sweep order).

from numba import njit

from ..compiled_cache import forget_stale_machine_code


@njit(cache=True, _nrt=False)     # (without reference counts: see soft_step_numba._step_on_pairs)
def sweep_order(body_a, body_b, movable, colours, work, order):
    """:func:`solutions.solver.sweep_order.sweep_order`'s order (its batches, stably
    sorted) into ``order``; ``work`` holds ``2 * m + n + 2`` integers for ``m``
    manifolds and ``n`` bodies."""
    m, n = body_a.shape[0], movable.shape[0]
    batch, per_body, start = work[:m], work[m:m + n], work[m + n:2 * m + n + 2]
    per_body[:] = 0
    start[:] = 0
    if colours:
        used = per_body     # bit c: the body has colour c
        for k in range(m):
            i, j = body_a[k], body_b[k]
            taken = (used[i] if movable[i] else 0) | (used[j] if movable[j] else 0)
            c = 0
            while (taken >> c) & 1:
                c += 1
            if c > 62:
                raise ValueError("a body touches more than 62 colours of manifolds")
            batch[k] = c
            if movable[i]:
                used[i] |= 1 << c
            if movable[j]:
                used[j] |= 1 << c
    else:
        after = per_body    # the first batch after the body's last manifold
        for k in range(m):
            i, j = body_a[k], body_b[k]
            c = max(after[i] if movable[i] else 0, after[j] if movable[j] else 0)
            batch[k] = c
            if movable[i]:
                after[i] = c + 1
            if movable[j]:
                after[j] = c + 1
    # A stable sort by batch (a counting sort: batches are small numbers; numba's
    # mergesort took 15 us for 590 manifolds, this 1 us).
    for k in range(m):
        start[batch[k] + 1] += 1
    for c in range(1, m + 2):
        start[c] += start[c - 1]
    for k in range(m):
        order[start[batch[k]]] = k
        start[batch[k]] += 1


# Cached machine code compiled from older sources is forgotten (solutions.compiled_cache).
forget_stale_machine_code(globals())
