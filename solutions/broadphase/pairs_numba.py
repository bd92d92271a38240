"""Candidate pairs of the compiled soft step: the twin of :meth:`World.broad_phase` for its boxes and discs.

:meth:`solutions.world.World.broad_phase` finds the pairs whose AABBs, widened by the
speculative margin, overlap, with the readable grid; the compiled soft step
(:mod:`solutions.response.soft_step_numba`) finds the same pairs in the same sorted
``(i, j)`` order with a sort-and-sweep on the wider axis (a few bodies, or bodies
scattered over great heights) or the compiled strip grid
(:mod:`solutions.broadphase.grid_numba`, from ``STRIP_GRID_MIN_BODIES`` bodies), and
keeps neither static-static pairs nor joined pairs.  Tested equal to the brute force
(``tests/test_soft_step_numba.py``).

Conventions: SI units; an AABB row is (min x, min y, max x, max y); a pair key is
``i * n + j`` for ``i < j`` among ``n`` bodies.
"""
from __future__ import annotations

### INSTRUCTOR ONLY: not in the student edition (a twin of the compiled soft step).

import math

import numpy as np
from numba import njit

from .grid_numba import (DENSE_STRIPS_PER_ENTRY, body_strips, check_and_measure, counting_sort_pairs, grid_pairs,
                         grown_buffer, sorted_pairs)
from .sorted_grid_numpy import DEFAULT_MAX_STRIPS_PER_BODY, MAX_STRIP_INDEX
from ..narrowphase.box_pairs_numba import faces_of_boxes
from ..compiled_cache import forget_stale_machine_code
from ..compiled_views import contiguous_view


#: The candidate pairs come from the strip grid of
#: :mod:`~solutions.broadphase.grid_numba` from this many bodies on (a sort-and-sweep
#: on x below, and for bodies scattered over heights far larger than they are):
#: measured, the sweep is faster up to about that many bodies and the grid beyond (on
#: a 20-base pyramid, the sweep meets about ten times as many pairs as it keeps).
STRIP_GRID_MIN_BODIES = 64


#: Up to this many values, the candidate pairs' sorts are insertion sorts.
INSERTION_SORT_MAX = 64


@njit(cache=True, inline="always")     # (returns views: inlined, also into soft_step_numba._step_on_pairs)
def faces_and_aabbs(position, angle, half, margin, circles, corner_rounding, work_floats):
    """The boxes' corners and normals (:func:`faces_of_boxes`; not for discs) and every
    body's widened AABB (:func:`aabbs`), made at the start of the work space
    ``work_floats`` (16 n and 4 n values), as views (n, 2, 4, 2) and (n, 4)."""
    n = position.shape[0]
    faces = contiguous_view(work_floats[:16 * n], (n, 2, 4, 2))
    aabb = contiguous_view(work_floats[16 * n:20 * n], (n, 4))
    if not circles:
        faces_of_boxes(position, half, angle, corner_rounding, faces)
    aabbs(position, half, faces, margin, circles, aabb)
    return faces, aabb


@njit(cache=True, _nrt=False)     # (without reference counts: see soft_step_numba._step_on_pairs)
def aabbs(position, half, faces, margin, circles, aabb):
    """Each body's AABB widened by ``margin / 2`` into ``aabb`` (n, 4: min x, min y, max x,
    max y): boxes of corners ``faces[:, 0]``, or discs of radius ``half[:, 0]``."""
    grow = 0.5 * margin
    for i in range(position.shape[0]):
        if circles:
            r = half[i, 0]
            aabb[i, 0], aabb[i, 1] = (position[i, 0] - r) + (-grow), (position[i, 1] - r) + (-grow)
            aabb[i, 2], aabb[i, 3] = (position[i, 0] + r) + grow, (position[i, 1] + r) + grow
            continue
        for c in range(2):      # corners 0..3 of faces[i, 0]
            aabb[i, c] = min(faces[i, 0, 0, c], faces[i, 0, 1, c], faces[i, 0, 2, c], faces[i, 0, 3, c]) + (-grow)
            aabb[i, 2 + c] = max(faces[i, 0, 0, c], faces[i, 0, 1, c], faces[i, 0, 2, c], faces[i, 0, 3, c]) + grow


@njit(cache=True, _nrt=False)     # (without reference counts: see soft_step_numba._step_on_pairs)
def few_candidate_pairs(aabb, dynamic, jointed, work, swept, keys, key_i, key_j):
    """:func:`candidate_pairs` for fewer than ``STRIP_GRID_MIN_BODIES`` bodies, which it
    sweeps as :func:`swept_pairs` does, without allocating: the pairs into ``keys``,
    ``key_i`` and ``key_j`` (of the same length, the capacity ``C``).  ``work`` holds
    ``2 * n + 3 * C + 1`` integers and ``swept`` is (n, 4).  Returns the number of pairs,
    or -1 if the buffers ran short: the sweep wants room for the pairs found so far and
    every possible partner of the next box (``C >= pairs + n`` is always enough)."""
    n, capacity = aabb.shape[0], keys.shape[0]
    rank, first, second = work[:n], work[n:n + capacity], work[n + capacity:n + 2 * capacity]
    by_second, start = work[n + 2 * capacity:n + 3 * capacity], work[n + 3 * capacity:2 * n + 3 * capacity + 1]
    axis = _sweep_axis(aabb)
    _insertion_rank(aabb, axis, rank)
    _swept_boxes(aabb, rank, axis, swept)
    found, r = _sweep(swept, rank, first, second, 0, 0)
    if r < n:
        return -1
    if found <= INSERTION_SORT_MAX:
        _insertion_sort_pairs(first, second, found, key_i, key_j)
    else:
        counting_sort_pairs(first, second, found, by_second, start, key_i, key_j)
    return kept_pairs(key_i, key_j, found, dynamic, jointed, keys, key_i, key_j)


@njit(cache=True)
def kept_pairs(first, second, found, dynamic, jointed, keys, key_i, key_j):
    """Of the first ``found`` sorted pairs, those not both static (``dynamic``: per body,
    True or a nonzero inverse mass for a dynamic one) and not joined (``jointed``:
    sorted keys, padded with ``NO_PAIR``) into ``keys`` (``i * n + j``),
    ``key_i`` and ``key_j`` (which may be ``first`` and ``second``: written at or before
    each pair read); returns how many."""
    n = dynamic.shape[0]
    kept = 0
    joined = 0          # both the pairs and the joined keys are sorted: walk them together
    for k in range(found):
        i, j = first[k], second[k]
        key = i * n + j
        keys[kept], key_i[kept], key_j[kept] = key, i, j
        while joined < jointed.shape[0] and jointed[joined] < key:
            joined += 1
        keep = (dynamic[i] != 0 or dynamic[j] != 0) and not (joined < jointed.shape[0] and jointed[joined] == key)
        kept += 1 if keep else 0
    return kept


@njit(cache=True)
def candidate_pairs(aabb, dynamic, jointed):
    """Pairs ``i < j`` of bodies whose AABBs ``aabb`` (:func:`aabbs`) overlap or touch,
    not both static and not joined (``jointed``: sorted keys, padded with ``NO_PAIR``),
    as sorted keys ``i * n + j`` and their ``i`` and ``j``: the strip grid's from
    ``STRIP_GRID_MIN_BODIES`` bodies on, otherwise (and for wide scatters) swept."""
    n = aabb.shape[0]
    valid, cell_size, lowest_y, highest_y = check_and_measure(aabb)
    pairs = np.empty((0, 2), dtype=np.int64)
    swept = True
    if valid and n >= STRIP_GRID_MIN_BODIES and 0.0 < cell_size < math.inf:
        bottom, top = math.floor(lowest_y / cell_size), math.floor(highest_y / cell_size)
        if max(abs(bottom), abs(top)) < MAX_STRIP_INDEX:
            lowest, highest, entries = body_strips(aabb, cell_size, DEFAULT_MAX_STRIPS_PER_BODY)
            if not (entries and top - bottom >= DENSE_STRIPS_PER_ENTRY * entries + 1024):
                pairs = grid_pairs(aabb, np.argsort(aabb[:, 0]), lowest, highest, DEFAULT_MAX_STRIPS_PER_BODY)
                swept = False
    if swept:
        pairs = swept_pairs(aabb)
    # Not both static, not joined.
    m = pairs.shape[0]
    kept_block = np.empty((3, m), dtype=np.int64)
    keys, key_i, key_j = kept_block[0], kept_block[1], kept_block[2]
    kept = kept_pairs(pairs[:, 0], pairs[:, 1], m, dynamic, jointed, keys, key_i, key_j)
    return keys[:kept], key_i[:kept], key_j[:kept]


@njit(cache=True)
def swept_pairs(aabb):
    """Every pair ``i < j`` of the boxes ``aabb`` (rows min x, min y, max x, max y) that
    overlap or touch, sorted: a sort-and-sweep along the axis over which the boxes'
    minimum corners spread wider (a hanging chain or a stack is swept along y), for the
    few bodies or the wide scatters that the strip grid does not take.  A few bodies or
    pairs are sorted by insertion (numba's sorts cost about 0.3 us even for three values)."""
    n = aabb.shape[0]
    axis = _sweep_axis(aabb)
    if n <= INSERTION_SORT_MAX:
        rank = np.empty(n, dtype=np.int64)
        _insertion_rank(aabb, axis, rank)
    else:
        rank = np.argsort(aabb[:, axis])
    swept = np.empty((n, 4))
    _swept_boxes(aabb, rank, axis, swept)
    first = np.empty(4 * n + 16, dtype=np.int64)
    second = np.empty(4 * n + 16, dtype=np.int64)
    found, r = _sweep(swept, rank, first, second, 0, 0)
    while r < n:            # the buffers ran short: larger ones, and on from box r
        first, second = grown_buffer(first, found + n - r), grown_buffer(second, found + n - r)
        found, r = _sweep(swept, rank, first, second, found, r)
    if found > INSERTION_SORT_MAX:
        return sorted_pairs(first[:found], second[:found], n)
    pairs = np.empty((found, 2), dtype=np.int64)
    _insertion_sort_pairs(first, second, found, pairs[:, 0], pairs[:, 1])
    return pairs


@njit(cache=True)
def _sweep_axis(aabb):
    """The axis (0: x, 1: y) over which the boxes' minimum corners spread wider: the
    sweep runs along it and tests the other."""
    low_x, high_x, low_y, high_y = math.inf, -math.inf, math.inf, -math.inf
    for i in range(aabb.shape[0]):
        low_x, high_x = min(low_x, aabb[i, 0]), max(high_x, aabb[i, 0])
        low_y, high_y = min(low_y, aabb[i, 1]), max(high_y, aabb[i, 1])
    return 1 if high_y - low_y > high_x - low_x else 0


@njit(cache=True)
def _insertion_rank(aabb, axis, rank):
    """The boxes in order of their minimum along ``axis`` into ``rank``, by insertion,
    taking them from the end if they come in descending order (a chain hanging from its
    first link): nearly sorted input costs O(n) then."""
    n = aabb.shape[0]
    descending = n > 0 and aabb[n - 1, axis] < aabb[0, axis]
    for t in range(n):
        r = n - 1 - t if descending else t
        q = t - 1
        while q >= 0 and aabb[rank[q], axis] > aabb[r, axis]:
            rank[q + 1] = rank[q]
            q -= 1
        rank[q + 1] = r


@njit(cache=True)
def _swept_boxes(aabb, rank, axis, swept):
    """The boxes in ``rank`` order into ``swept`` (contiguous): columns min and max along
    ``axis``, then along the other.  (The sweep does not branch on the other axis's test:
    every pair in the window is written, and counted if the boxes overlap there too.)"""
    other = 1 - axis
    for r in range(rank.shape[0]):
        swept[r, 0], swept[r, 1] = aabb[rank[r], axis], aabb[rank[r], axis + 2]
        swept[r, 2], swept[r, 3] = aabb[rank[r], other], aabb[rank[r], other + 2]


@njit(cache=True)
def _insertion_sort_pairs(first, second, found, sorted_first, sorted_second):
    """The first ``found`` pairs sorted by (first, second) into ``sorted_*``, by insertion."""
    for k in range(found):
        i, j = first[k], second[k]
        q = k - 1
        while q >= 0 and (sorted_first[q] > i or (sorted_first[q] == i and sorted_second[q] > j)):
            sorted_first[q + 1], sorted_second[q + 1] = sorted_first[q], sorted_second[q]
            q -= 1
        sorted_first[q + 1], sorted_second[q + 1] = i, j


@njit(cache=True)
def _sweep(swept, rank, first, second, found, start):
    """The sweep of :func:`swept_pairs` from box ``start`` (in sweep order) on, writing
    pairs from ``found``; stops at the first box for whose every possible partner the
    buffers have no room.  Returns the pairs written and where it stopped (``n``: done).
    (A separate function: growing the buffers inside the loop made the whole sweep
    three times slower.)"""
    n = rank.shape[0]
    for r in range(start, n):
        if found + n - r > first.shape[0]:          # room for every pair this box can add
            return found, r
        i, reach, low, high = rank[r], swept[r, 1], swept[r, 2], swept[r, 3]
        for s in range(r + 1, n):
            if swept[s, 0] > reach:
                break
            j = rank[s]
            first[found], second[found] = min(i, j), max(i, j)
            found += 0 if (swept[s, 2] > high) | (low > swept[s, 3]) else 1
    return found, n


# Cached machine code compiled from older sources is forgotten (solutions.compiled_cache).
forget_stale_machine_code(globals())
