"""Brute-force pairs of axis-aligned boxes: the oracle of every broad phase.

A box is a row ``[min_x, min_y, max_x, max_y]`` (m), closed: two boxes overlap when
their intervals overlap on both axes, ``a.max >= b.min and b.max >= a.min``, so boxes
that only touch (along an edge, at a corner, or a zero-width box lying on another's
edge) count as a pair.  A pair is written ``(i, j)`` with ``i < j``, each once.

Written here from that definition alone (numpy, no import of the reference engine):
the public graded tests ship to students.  Rows are compared with every later row in
blocks, so memory stays O(N * block) and 3000 boxes take a few tens of milliseconds.

Also here: :func:`pairs_figure` (the ``"pairs"`` picture of :mod:`grader.harness.figures`)
and :func:`smallest_wrong_scene`, which cuts a failing scene down to a few boxes that
still fail, so that a student reads a small case rather than a random one.
"""
from __future__ import annotations

from typing import Callable, Sequence

import numpy as np

#: Booleans held by one block of comparisons (4 MiB).
BLOCK_ELEMENTS = 2**22


def as_boxes(aabbs) -> np.ndarray:
    """``aabbs`` as an ``(N, 4)`` float array; ValueError unless finite with min <= max.

    An empty sequence is ``N = 0``.

    Examples
    --------
    >>> as_boxes([[0, 0, 1, 2]]).shape
    (1, 4)
    """
    boxes = np.asarray(aabbs, dtype=float)
    if boxes.size == 0:
        return np.zeros((0, 4))
    if boxes.ndim != 2 or boxes.shape[1] != 4:
        raise ValueError(f"boxes must be an (N, 4) array [min_x, min_y, max_x, max_y], got shape {boxes.shape}")
    if not np.all(np.isfinite(boxes)):
        raise ValueError("boxes must be finite")
    if np.any(boxes[:, 0] > boxes[:, 2]) or np.any(boxes[:, 1] > boxes[:, 3]):
        raise ValueError("every box needs min <= max on both axes")
    return boxes


def overlapping_pairs(aabbs) -> set[tuple[int, int]]:
    """Every pair ``(i, j)``, ``i < j``, of boxes that overlap or touch.

    Examples
    --------
    >>> sorted(overlapping_pairs([[0, 0, 1, 1], [1, 1, 2, 2], [3, 0, 4, 1], [1, 0, 1, 0.5]]))
    [(0, 1), (0, 3)]
    """
    boxes = as_boxes(aabbs)
    n = len(boxes)
    min_x, min_y, max_x, max_y = (np.ascontiguousarray(boxes[:, k]) for k in range(4))
    rows_per_block = max(1, BLOCK_ELEMENTS // max(n, 1))
    found_i, found_j = [], []
    for start in range(0, n, rows_per_block):
        stop = min(start + rows_per_block, n)
        rows, cols = slice(start, stop), slice(start, n)
        hits = (max_x[rows, None] >= min_x[None, cols]) & (max_x[None, cols] >= min_x[rows, None])
        hits &= (max_y[rows, None] >= min_y[None, cols]) & (max_y[None, cols] >= min_y[rows, None])
        hits &= np.arange(start, n)[None, :] > np.arange(start, stop)[:, None]   # j > i only
        block_i, block_j = np.nonzero(hits)
        found_i.append(block_i + start)
        found_j.append(block_j + start)
    if not found_i:
        return set()
    return set(zip(np.concatenate(found_i).tolist(), np.concatenate(found_j).tolist()))


def pairs_figure(aabbs, missed, extra, title: str, cell_size: float = 0.0, bounds=None) -> dict:
    """The ``"pairs"`` picture of :mod:`grader.harness.figures` for a failing scene.

    ``missed``: overlapping pairs the student's function did not return; ``extra``:
    pairs it returned whose boxes are apart.  ``cell_size > 0`` draws the grid,
    ``bounds`` the quadtree's root and first splitting lines.
    """
    figure = {"kind": "pairs", "title": title, "aabbs": as_boxes(aabbs).tolist(), "cell_size": float(cell_size),
              "missed": [list(p) for p in sorted(missed)], "extra": [list(p) for p in sorted(extra)]}
    if bounds is not None:
        figure["bounds"] = [float(b) for b in bounds]
    return figure


def smallest_wrong_scene(aabbs, wrong_many: Callable[[Sequence[np.ndarray]], list], max_rounds: int = 60
                         ) -> np.ndarray:
    """A small sub-scene of the failing scene ``aabbs`` on which the answer is still wrong.

    ``wrong_many(scenes)`` says for each scene (an ``(k, 4)`` array) whether the
    student's answer on it is wrong (one round trip for all of them).  Chunks of boxes
    are dropped while the answer stays wrong, halving the chunk size when no chunk can
    go (delta debugging); at most ``max_rounds`` round trips.  Boxes keep their order,
    so pairs are renumbered.  Returns ``aabbs`` itself when nothing smaller fails.
    """
    current = as_boxes(aabbs)
    chunk = max(1, len(current) // 2)
    for _ in range(max_rounds):
        if len(current) <= 1:
            break
        starts = range(0, len(current), chunk)
        candidates = [np.delete(current, np.arange(s, min(s + chunk, len(current))), axis=0) for s in starts]
        candidates = [c for c in candidates if len(c)]
        flags = wrong_many(candidates) if candidates else []
        smaller = next((c for c, flag in zip(candidates, flags) if flag), None)
        if smaller is not None:
            current = smaller
            chunk = min(chunk, max(1, len(current) // 2))
        elif chunk > 1:
            chunk //= 2
        else:
            break
    return current


def describe_boxes(aabbs, limit: int = 12) -> str:
    """The boxes as ``[[min_x, min_y, max_x, max_y], ...]`` with round numbers (at most ``limit``)."""
    rows = as_boxes(aabbs).tolist()
    text = ", ".join("[" + ", ".join(f"{v:.6g}" for v in row) + "]" for row in rows[:limit])
    more = f", ... ({len(rows)} boxes)" if len(rows) > limit else ""
    return f"[{text}{more}]"
