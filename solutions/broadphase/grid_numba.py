"""Grid broad phase compiled with numba: the same pairs as the numpy grid, faster.

:func:`pairs_grid_numba` is the compiled twin of
:func:`solutions.broadphase.sorted_grid_numpy.pairs_grid_numpy`: the same horizontal
strips of height ``cell_size`` swept along x, written as loops (numba compiles them
to machine code) instead of whole-array steps.  Read that module for why the method
is right; in short:

1. Rank the bodies by ``min_x`` (numpy's ``argsort``, faster than numba's).
2. A body enters every strip ``floor(y / cell_size)`` its closed y-interval overlaps.
   The entries are bucketed by strip with a counting sort that visits the bodies in
   rank order, so each strip's entries come out sorted by rank (by ``min_x``).  If the
   strips span far more numbers than there are entries (bodies scattered over a huge
   height), the occupied strips are numbered in order first (a body occupies every
   strip between its lowest and highest, so its strips stay consecutive, and the
   numbering keeps the order that the home-strip rule compares).  Each entry's data
   is copied in strip order, so that the sweep reads memory front to back.
3. In each strip, each entry meets the next entries while their ``min_x`` is at most
   its ``max_x`` (the x-sweep), then the exact closed y-test, then the *home strip*
   rule (the strip of ``max(min_y_i, min_y_j)``) keeps each pair exactly once.
4. Bodies spanning more than ``max_strips_per_body`` strips are not put in the strips
   but tested directly against every body (no memory beyond the pairs).
5. The pairs are sorted as the numpy grid returns them, by two stable counting sorts
   (by second index, then by first): O(N + M), no comparison sort.

Memory is O(N + entries + pairs): no candidate list and nothing O(N^2); the pair
buffers grow by doubling.  Time is O(N log N + candidates), as the numpy grid.

Compiled with ``@njit(cache=True)``: the first call in a fresh checkout compiles (a
few seconds) and stores the machine code in ``__pycache__``; later processes load it.
"""
from __future__ import annotations

### INSTRUCTOR ONLY: not in the student edition (the world's backend="numba" is the instructor's; students step the readable stages).

import math

import numpy as np
from numba import njit

from .aabb_array import MAX_X, MAX_Y, MIN_X, MIN_Y, validate_aabbs
from .sorted_grid_numpy import DEFAULT_MAX_STRIPS_PER_BODY, MAX_STRIP_INDEX, pairs_grid_numpy
from .uniform_grid import check_cell_size, suggest_cell_size
from ..compiled_cache import forget_stale_machine_code

#: The strips are counted directly when their numbers span at most this many per entry
#: (plus 1024); otherwise the occupied strips are numbered first (step 2).
DENSE_STRIPS_PER_ENTRY = 4
#: The pair buffers start with room for this many pairs per body, then double.
INITIAL_PAIRS_PER_BODY = 4
#: Body indices are int32 inside the kernels (less memory to touch); larger inputs
#: (more than 64 GB of boxes) go to the numpy grid.
MAX_BODIES = 2**31 - 1
#: From this many boxes on, the median extent is found through a sample (see _median).
MEDIAN_SAMPLE_FROM = 2048


def pairs_grid_numba(aabbs, cell_size: float | None = None, margin: float = 0.0, *,
                     max_strips_per_body: int = DEFAULT_MAX_STRIPS_PER_BODY) -> np.ndarray:
    """Pairs of boxes that overlap, touch or are at most ``margin`` apart, sorted.

    Equal to ``pairs_grid_numpy(grown, cell_size)`` (and so to the brute force on
    ``grown``), where ``grown`` is every box grown by ``margin / 2`` on each side,
    ``aabbs + 0.5 * margin * [-1, -1, 1, 1]``, exactly as the world's broad phase grows
    them: two boxes are paired when their gap along x and their gap along y are both
    at most ``margin`` (up to that rounding).  ``margin = 0`` gives the plain
    overlapping-or-touching pairs (boxes are closed).

    Parameters
    ----------
    aabbs : array_like, shape (N, 4)
        Boxes ``[min_x, min_y, max_x, max_y]`` (m).
    cell_size : float, optional
        Height of a strip (m), finite and > 0.  None:
        :func:`~solutions.broadphase.uniform_grid.suggest_cell_size` of the grown
        boxes (twice their median extent), as the numpy grid would choose.  Any cell
        size gives the same pairs; it only changes the speed.
    margin : float, optional
        Largest gap (m) between two paired boxes along each axis, finite and >= 0.
    max_strips_per_body : int, optional
        Bodies overlapping more strips are tested directly against every body (>= 1).

    Returns
    -------
    numpy.ndarray
        ``(M, 2)`` int64, rows ``(i, j)`` with ``i < j``, sorted lexicographically, no
        duplicates: the numpy grid's array, element for element.

    Raises
    ------
    ValueError
        For a bad AABB array, a cell size that is not finite and > 0, a margin that is
        not finite and >= 0, ``max_strips_per_body < 1``, or a cell size so small that
        strip indices would not be exact integers (the numpy grid's checks).

    Examples
    --------
    >>> pairs_grid_numba([[0, 0, 1, 1], [1, 0, 2, 1], [5, 5, 6, 6], [0.5, 0.5, 5, 5]])
    array([[0, 1],
           [0, 3],
           [1, 3],
           [2, 3]])
    >>> pairs_grid_numba([[0, 0, 1, 1], [1.01, 0, 2, 1]], margin=0.02).tolist()
    [[0, 1]]
    """
    boxes = _box_array(aabbs)
    margin = float(margin)
    if margin > 0.0 and math.isfinite(margin):
        boxes = boxes + 0.5 * margin * np.array([-1.0, -1.0, 1.0, 1.0])
    # The checks of the numpy grid, in its order (then the margin's).
    valid, twice_median_extent, lowest_y, highest_y = check_and_measure(boxes)
    if not valid:
        validate_aabbs(aabbs)          # raises the numpy grid's error for a bad box
    max_strips_per_body = int(max_strips_per_body)
    if max_strips_per_body < 1:
        raise ValueError("max_strips_per_body must be >= 1")
    if not (math.isfinite(margin) and margin >= 0.0):
        raise ValueError(f"margin must be a finite length >= 0 (m), got {margin!r}")
    if not valid:
        validate_aabbs(boxes)          # growing by the margin overflowed to inf
    if cell_size is None:
        cell_size = twice_median_extent             # suggest_cell_size's first choice
        if not (cell_size > 0 and math.isfinite(cell_size)):
            cell_size = suggest_cell_size(boxes)    # its fallbacks (mostly points, no boxes)
    else:
        cell_size = check_cell_size(cell_size)
    if len(boxes) < 2:
        return np.empty((0, 2), dtype=np.int64)
    if len(boxes) > MAX_BODIES:
        return pairs_grid_numpy(boxes, cell_size, max_strips_per_body=max_strips_per_body)
    # floor is monotonic: the extreme strips are those of the lowest and highest y.
    bottom, top = math.floor(lowest_y / cell_size), math.floor(highest_y / cell_size)
    if max(abs(bottom), abs(top)) >= MAX_STRIP_INDEX:
        raise ValueError(f"cell_size {cell_size} is too small for y coordinates up to "
                         f"{np.abs(boxes[:, [MIN_Y, MAX_Y]]).max():.3g} m: strip indices would not be exact integers")

    lowest, highest, entry_count = body_strips(boxes, cell_size, max_strips_per_body)
    if entry_count and top - bottom >= DENSE_STRIPS_PER_ENTRY * entry_count + 1024:
        lowest, highest = _numbered_strips(lowest, highest, highest - lowest < max_strips_per_body)
    body_of_rank = np.argsort(boxes[:, MIN_X])
    return grid_pairs(boxes, body_of_rank, lowest, highest, max_strips_per_body)


def _box_array(aabbs) -> np.ndarray:
    """``aabbs`` as a C-contiguous (N, 4) float64 array (values not checked yet), or
    ``validate_aabbs``'s answer for anything else (its error, or an empty (0, 4))."""
    try:
        boxes = np.ascontiguousarray(aabbs, dtype=np.float64)
    except (TypeError, ValueError):
        return validate_aabbs(aabbs)
    if boxes.ndim == 2 and boxes.shape[1] == 4:
        return boxes
    return validate_aabbs(aabbs)


def _numbered_strips(lowest: np.ndarray, highest: np.ndarray, small: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Strip numbers replaced by their rank among the strips occupied by ``small``
    bodies (the others keep theirs; they are never put in strips)."""
    counts = highest[small] - lowest[small] + 1
    starts = np.repeat(lowest[small] - np.cumsum(counts) + counts, counts)
    occupied = np.unique(starts + np.arange(len(starts)))
    lowest, highest = lowest.copy(), highest.copy()
    lowest[small] = np.searchsorted(occupied, lowest[small])
    highest[small] = np.searchsorted(occupied, highest[small])
    return lowest, highest


@njit(cache=True)
def check_and_measure(boxes):
    """``(valid, 2 * median extent, lowest y, highest y)``: whether every box is finite
    with min <= max; twice the median of ``max(width, height)``, the float
    ``suggest_cell_size`` computes (the same middle values, averaged as numpy's
    median); the lowest ``min_y`` and highest ``max_y`` (m).  Zeros for no boxes."""
    n = boxes.shape[0]
    if n == 0:
        return True, 0.0, 0.0, 0.0
    extents = np.empty(n)
    lowest_y, highest_y = boxes[0, MIN_Y], boxes[0, MAX_Y]
    for i in range(n):
        for axis in range(2):
            low, high = boxes[i, MIN_X + axis], boxes[i, MAX_X + axis]
            if not (math.isfinite(low) and math.isfinite(high) and low <= high):
                return False, 0.0, 0.0, 0.0
        extents[i] = max(boxes[i, MAX_X] - boxes[i, MIN_X], boxes[i, MAX_Y] - boxes[i, MIN_Y])
        lowest_y = min(lowest_y, boxes[i, MIN_Y])
        highest_y = max(highest_y, boxes[i, MAX_Y])
    return True, 2.0 * _median(extents), lowest_y, highest_y


@njit(cache=True)
def _median(values):
    """numpy's median of ``values`` (the mean of the two middle values when their
    number is even, computed as numpy does), reordering ``values``.

    Large arrays first try one pass: two values ``low <= high`` read off a strided
    sample bracket the middle ranks with near certainty; the pass counts the values
    below ``low`` and gathers those in ``[low, high]`` (without branches), and the
    middle values are selected among the few gathered ones.  If the bracket missed
    (unlucky or periodic data), a quickselect on all values answers instead.
    """
    n = len(values)
    k = n // 2                                   # rank of the upper middle value
    if n >= MEDIAN_SAMPLE_FROM:
        sample_size = n // 8
        stride = n // sample_size
        sample = values[: sample_size * stride: stride].copy()
        centre = k * sample_size // n
        reach = 2 * int(math.sqrt(sample_size)) + 2
        low = _select(sample, max(0, centre - reach))
        high = _select(sample, min(sample_size - 1, centre + reach))
        gathered = np.empty(n)
        below = inside = 0
        for i in range(n):
            value = values[i]
            below += value < low
            gathered[inside] = value
            inside += (value >= low) & (value <= high)
        rank = k - below                         # of the upper middle among the gathered
        if 1 <= rank < inside:
            values = gathered[:inside]
            k = rank
    upper = _select(values, k)
    if n % 2:
        return upper
    lower = values[0]                            # the largest value left of the upper middle
    for i in range(1, k):
        lower = max(lower, values[i])
    return (lower + upper) / 2.0


@njit(cache=True)
def _select(values, k):
    """The ``k``-th smallest of ``values`` (0-based), moving it to ``values[k]`` with
    smaller-or-equal values before it and larger-or-equal after (quickselect with a
    three-way partition, so that many equal values cost no extra work)."""
    low, high = 0, len(values) - 1
    while low < high:
        a, b, c = values[low], values[(low + high) // 2], values[high]
        pivot = max(min(a, b), min(max(a, b), c))            # median of three
        below, i, above = low, low, high                      # [low, below) < pivot, (above, high] > pivot
        while i <= above:
            value = values[i]
            if value < pivot:
                values[i], values[below] = values[below], value
                below += 1
                i += 1
            elif value > pivot:
                values[i], values[above] = values[above], value
                above -= 1
            else:
                i += 1
        if k < below:
            high = below - 1
        elif k > above:
            low = above + 1
        else:
            return pivot
    return values[k]


@njit(cache=True)
def body_strips(boxes, cell_size, max_strips_per_body):
    """Lowest and highest strip of every body (floor, not int, so that negative y
    works, as the numpy grid), and how many entries the bodies that go into strips make."""
    n = boxes.shape[0]
    lowest, highest = np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64)
    entry_count = 0
    for i in range(n):
        lowest[i] = np.int64(np.floor(boxes[i, MIN_Y] / cell_size))
        highest[i] = np.int64(np.floor(boxes[i, MAX_Y] / cell_size))
        if highest[i] - lowest[i] < max_strips_per_body:
            entry_count += highest[i] - lowest[i] + 1
    return lowest, highest, entry_count


@njit(cache=True)
def grown_buffer(buffer, needed):
    """``buffer`` copied into one at least ``needed`` long (doubling)."""
    size = len(buffer)
    while size < needed:
        size *= 2
    bigger = np.empty(size, dtype=buffer.dtype)
    for i in range(len(buffer)):            # (a loop compiles much faster than a slice copy)
        bigger[i] = buffer[i]
    return bigger


@njit(cache=True)
def grid_pairs(boxes, body_of_rank, lowest, highest, max_strips_per_body):
    """Steps 1 to 5: the sorted (M, 2) int64 pairs.  Body indices are int32 inside
    (the caller sends more than 2**31 - 1 bodies to the numpy grid)."""
    n = boxes.shape[0]
    # Step 1: the bodies that go into strips, in rank order.
    small = np.empty(n, dtype=np.int32)
    small_count = entry_count = 0
    for r in range(n):
        body = body_of_rank[r]
        if highest[body] - lowest[body] < max_strips_per_body:
            small[small_count] = body
            small_count += 1
            entry_count += highest[body] - lowest[body] + 1

    # Room for INITIAL_PAIRS_PER_BODY pairs per body before the buffers grow.
    first = np.empty(max(16, INITIAL_PAIRS_PER_BODY * n), dtype=np.int32)
    second = np.empty(max(16, INITIAL_PAIRS_PER_BODY * n), dtype=np.int32)
    used = 0
    if small_count >= 2:
        # Step 2: entries grouped by strip (a counting sort over the strip numbers);
        # visiting the bodies in rank order leaves each group in rank order.
        base, top = lowest[small[0]], highest[small[0]]
        for s in range(small_count):
            base = min(base, lowest[small[s]])
            top = max(top, highest[small[s]])
        strips = top - base + 1
        group_start = np.zeros(strips + 1, dtype=np.int64)
        for s in range(small_count):
            body = small[s]
            for strip in range(lowest[body] - base, highest[body] - base + 1):
                group_start[strip + 1] += 1
        for strip in range(strips):
            group_start[strip + 1] += group_start[strip]
        # Each entry's data is copied in entry order, so that the sweep reads memory
        # front to back instead of jumping between bodies; an entry is "at home" in
        # the lowest strip of its body.
        entry_min_x, entry_max_x = np.empty(entry_count), np.empty(entry_count)
        entry_y = np.empty(2 * entry_count)                  # min_y, max_y of each entry
        entry_at_home, entry_body = np.empty(entry_count, dtype=np.bool_), np.empty(entry_count, dtype=np.int32)
        fill = group_start[:-1].copy()
        for s in range(small_count):
            body = small[s]
            for strip in range(lowest[body] - base, highest[body] - base + 1):
                e = fill[strip]
                fill[strip] += 1
                entry_min_x[e], entry_max_x[e] = boxes[body, MIN_X], boxes[body, MAX_X]
                entry_y[2 * e], entry_y[2 * e + 1] = boxes[body, MIN_Y], boxes[body, MAX_Y]
                entry_at_home[e], entry_body[e] = strip == lowest[body] - base, body
        # Step 3, resumed with larger buffers whenever they fill up.
        group, entry = 0, 0
        while True:
            used, group, entry = _sweep(entry_min_x, entry_max_x, entry_y, entry_at_home, entry_body, group_start,
                                        first, second, used, group, entry)
            if group == strips:
                break
            needed = used + group_start[group + 1] - entry
            first, second = grown_buffer(first, needed), grown_buffer(second, needed)

    # Step 4: oversized bodies against every body; a pair of two oversized bodies is
    # kept from the smaller index only.
    for i in range(n):
        if highest[i] - lowest[i] < max_strips_per_body:
            continue
        for j in range(n):
            if j == i or (j < i and highest[j] - lowest[j] >= max_strips_per_body):
                continue
            if (boxes[i, MAX_X] >= boxes[j, MIN_X] and boxes[j, MAX_X] >= boxes[i, MIN_X]
                    and boxes[i, MAX_Y] >= boxes[j, MIN_Y] and boxes[j, MAX_Y] >= boxes[i, MIN_Y]):
                if used == len(first):
                    first, second = grown_buffer(first, used + 1), grown_buffer(second, used + 1)
                first[used], second[used] = min(i, j), max(i, j)
                used += 1
    return sorted_pairs(first[:used], second[:used], n)


@njit(cache=True)
def _sweep(entry_min_x, entry_max_x, entry_y, entry_at_home, entry_body, group_start, first, second, used,
           group, entry):
    """Step 3 from entry ``entry`` of strip ``group`` on: each entry meets the next ones
    of its strip while they overlap it along x; a pair is kept when the boxes overlap
    along y and the strip is the home strip of one of them (the strip of
    ``max(min_y_i, min_y_j)``: both boxes are in it, and it is the lowest strip of the
    higher-starting one).

    Appends to ``first``/``second`` from ``used`` without branching on the test: room
    for every partner is checked first, then each candidate is written, and counted
    only if it passes.  Returns ``(used, group, entry)``: where it stopped because the
    buffers were too short, or ``group == len(group_start) - 1`` when done.
    """
    capacity = len(first)
    for g in range(group, len(group_start) - 1):
        stop = group_start[g + 1]
        for a in range(max(entry, group_start[g]), stop):
            if used + stop - a > capacity:
                return used, g, a
            reach, low, high = entry_max_x[a], entry_y[2 * a], entry_y[2 * a + 1]
            home, i = entry_at_home[a], entry_body[a]
            for b in range(a + 1, stop):
                if entry_min_x[b] > reach:
                    break
                j = entry_body[b]
                first[used], second[used] = min(i, j), max(i, j)
                used += (entry_y[2 * b + 1] >= low) & (high >= entry_y[2 * b]) & (home | entry_at_home[b])
    return used, len(group_start) - 1, 0


@njit(cache=True)
def sorted_pairs(first, second, n):
    """Step 5: the pairs as an (M, 2) array sorted by (first, second): a stable
    counting sort by ``second``, then one by ``first``."""
    m = len(first)
    if m > MAX_BODIES:
        raise MemoryError("more than 2**31 - 1 pairs (an output of over 32 GB)")
    pairs = np.empty((m, 2), dtype=np.int64)
    counting_sort_pairs(first, second, m, np.empty(m, dtype=np.int32), np.empty(n + 1, dtype=np.int64),
                         pairs[:, 0], pairs[:, 1])
    return pairs


@njit(cache=True)
def counting_sort_pairs(first, second, m, by_second, start, sorted_first, sorted_second):
    """The first ``m`` pairs ``(first, second)`` of bodies ``0 .. n - 1`` sorted by
    (first, second) into ``sorted_first`` and ``sorted_second``: a stable counting sort by
    ``second``, then one by ``first``.  ``by_second`` (m) and ``start`` (n + 1) are work space."""
    n = start.shape[0] - 1
    start[:] = 0
    for p in range(m):
        start[second[p] + 1] += 1
    for i in range(n):
        start[i + 1] += start[i]
    for p in range(m):                                  # positions of the pairs, by second
        by_second[start[second[p]]] = p
        start[second[p]] += 1
    start[:] = 0
    for p in range(m):
        start[first[p] + 1] += 1
    for i in range(n):
        start[i + 1] += start[i]
    for q in range(m):
        p = by_second[q]
        row = start[first[p]]
        start[first[p]] += 1
        sorted_first[row], sorted_second[row] = first[p], second[p]


# Cached machine code compiled from older sources is forgotten (solutions.compiled_cache).
forget_stale_machine_code(globals())
