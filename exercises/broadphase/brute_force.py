# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/broadphase/brute_force.py on the instructor's
# side.
"""Brute force broad phase: test all C(N, 2) = N (N - 1) / 2 pairs.

This is the oracle every other broad phase is tested against.  Its cost is quadratic:
10 000 bodies make 49 995 000 pair tests per frame (walking the list of bodies itself
takes well under a millisecond; the pairs are what cost).

Two boxes overlap when their closed intervals overlap on both axes::

    a.max_x >= b.min_x and b.max_x >= a.min_x   (and the same for y)

so boxes that only touch, along an edge or at a corner, count as a pair.
"""
from __future__ import annotations

import numpy as np

from .aabb_array import MAX_X, MAX_Y, MIN_X, MIN_Y, validate_aabbs

#: Number of box-vs-box comparisons (elements of one boolean block) the chunked
#: numpy version holds in memory at a time: 2**22 booleans is 4 MiB per block.
BRUTE_FORCE_BLOCK_ELEMENTS = 2**22


def aabbs_overlap(a, b) -> bool:
    """True when boxes ``a`` and ``b`` overlap or touch (closed intervals).

    Parameters
    ----------
    a, b : sequence of 4 floats
        ``[min_x, min_y, max_x, max_y]`` (m).

    Returns
    -------
    bool
        ``a.max >= b.min and b.max >= a.min`` on both axes.

    Examples
    --------
    >>> aabbs_overlap([0, 0, 1, 1], [1, 1, 2, 2])   # corners touch
    True
    >>> aabbs_overlap([0, 0, 1, 1], [1.5, 0, 2, 1])
    False
    """
    return a[2] >= b[0] and b[2] >= a[0] and a[3] >= b[1] and b[3] >= a[1]


def pairs_brute_force(aabbs) -> set[tuple[int, int]]:
    """All pairs ``(i, j)``, ``i < j``, whose AABBs overlap or touch, by a double loop.

    Parameters
    ----------
    aabbs : array_like, shape (N, 4)
        Boxes ``[min_x, min_y, max_x, max_y]`` (m).

    Returns
    -------
    set of tuple of int
        Every overlapping-or-touching pair, each once, with ``i < j``.

    Examples
    --------
    >>> sorted(pairs_brute_force([[0, 0, 1, 1], [1, 0, 2, 1], [5, 5, 6, 6]]))
    [(0, 1)]
    """
    boxes = validate_aabbs(aabbs).tolist()
    pairs = set()
    for i in range(len(boxes)):
        for j in range(i + 1, len(boxes)):
            if aabbs_overlap(boxes[i], boxes[j]):
                pairs.add((i, j))
    return pairs


def pairs_brute_force_numpy(aabbs, block_elements: int = BRUTE_FORCE_BLOCK_ELEMENTS) -> set[tuple[int, int]]:
    """Same result as :func:`pairs_brute_force`, vectorised in row blocks.

    Rows ``i`` in ``[start, stop)`` are compared with every ``j > start`` at once; the
    block height is chosen so that one boolean block holds about ``block_elements``
    entries.  Memory is O(N * block height), never O(N^2); time is still O(N^2)
    (about a second for 20 000 boxes).

    Parameters
    ----------
    aabbs : array_like, shape (N, 4)
        Boxes ``[min_x, min_y, max_x, max_y]`` (m).
    block_elements : int, optional
        Target number of comparisons per block (>= 1); smaller uses less memory.

    Returns
    -------
    set of tuple of int
        Every overlapping-or-touching pair ``(i, j)`` with ``i < j``.

    Examples
    --------
    >>> sorted(pairs_brute_force_numpy([[0, 0, 1, 1], [1, 1, 2, 2], [0.5, 0.5, 0.6, 0.6]]))
    [(0, 1), (0, 2)]
    """
    boxes = validate_aabbs(aabbs)
    if int(block_elements) < 1:
        raise ValueError(f"block_elements must be >= 1, got {block_elements}")
    n = len(boxes)
    min_x, min_y, max_x, max_y = (boxes[:, k] for k in (MIN_X, MIN_Y, MAX_X, MAX_Y))
    found_i, found_j = [], []
    rows_per_block = max(1, int(block_elements) // max(n, 1))
    for start in range(0, n, rows_per_block):
        stop = min(start + rows_per_block, n)
        rows = slice(start, stop)
        # Columns start at `start`: earlier columns were already paired with these rows.
        cols = slice(start, n)
        hits = max_x[rows, None] >= min_x[None, cols]
        hits &= max_x[None, cols] >= min_x[rows, None]
        hits &= max_y[rows, None] >= min_y[None, cols]
        hits &= max_y[None, cols] >= min_y[rows, None]
        # Keep j > i only: the strict upper triangle of the block.
        hits &= np.arange(start, n)[None, :] > np.arange(start, stop)[:, None]
        block_i, block_j = np.nonzero(hits)
        found_i.append(block_i + start)
        found_j.append(block_j + start)
    if not found_i:
        return set()
    return set(zip(np.concatenate(found_i).tolist(), np.concatenate(found_j).tolist()))
