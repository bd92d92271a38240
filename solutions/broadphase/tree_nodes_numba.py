"""Nodes of the compiled dynamic tree (:mod:`solutions.broadphase.dynamic_tree_numba`):
parallel arrays, a free list, refitting, and Box2D v3's enlarge-and-rebuild.

A node is an index into arrays ``box`` ``(capacity, 4)`` (m), ``parent``, ``child1``,
``child2``, ``height`` and ``body`` (``NULL`` = none; a leaf has no children and holds a
body).  ``meta[ROOT]`` is the root, ``meta[FREE]`` the first free node (free nodes are
linked through ``parent``), ``meta[COUNT]`` the nodes ever used, as in Box2D's
``b2DynamicTree``.

Moving many bodies at once (Box2D v3, ``dynamic_tree.c``): :func:`enlarge` gives a leaf
its new box in place and grows its ancestors to hold it, marking each *enlarged*
(``b2DynamicTree_EnlargeProxy``); once per frame :func:`rebuild` frees every enlarged
inner node and builds that part of the tree again top-down over the leaves and untouched
subtrees below it (``b2DynamicTree_Rebuild``), each group split by :func:`split_by_bins`.
"""
from __future__ import annotations

### INSTRUCTOR ONLY: not in the student edition (it serves the compiled dynamic tree).

import numpy as np
from numba import njit

from ..compiled_cache import forget_stale_machine_code

NULL = -1
#: meta[ROOT] is the root node, meta[FREE] the first free node, meta[COUNT] the nodes ever used.
ROOT, FREE, COUNT = 0, 1, 2
#: Bins along the split axis when the enlarged part of the tree is built again (Box2D's B2_BIN_COUNT).
BIN_COUNT = 8


@njit(cache=True)
def perimeter(x0, y0, x1, y1):
    """Perimeter (m) of the box ``(x0, y0, x1, y1)``: the 2D surface area of the SAH."""
    return 2.0 * ((x1 - x0) + (y1 - y0))


@njit(cache=True)
def allocate_node(parent, child1, child2, height, body, meta):
    """A node with no parent, children or body: the first free one, else a new one."""
    node = meta[FREE]
    if node != NULL:
        meta[FREE] = parent[node]
    else:
        node = meta[COUNT]
        meta[COUNT] += 1
    parent[node] = NULL
    child1[node] = NULL
    child2[node] = NULL
    height[node] = 0
    body[node] = NULL
    return node


@njit(cache=True)
def free_node(node, parent, height, meta):
    """Put ``node`` on the free list (height -1 marks it free)."""
    parent[node] = meta[FREE]
    height[node] = -1
    meta[FREE] = node


@njit(cache=True)
def refit(node, box, child1, child2, height):
    """Set inner ``node``'s box and height from its two children."""
    a, b = child1[node], child2[node]
    box[node, 0] = min(box[a, 0], box[b, 0])
    box[node, 1] = min(box[a, 1], box[b, 1])
    box[node, 2] = max(box[a, 2], box[b, 2])
    box[node, 3] = max(box[a, 3], box[b, 3])
    height[node] = 1 + max(height[a], height[b])


@njit(cache=True)
def enlarge(leaf, box, parent, enlarged):
    """Grow the ancestors of ``leaf`` to hold its (new) box and mark them enlarged, up to
    the root or to an ancestor already marked (b2DynamicTree_EnlargeProxy)."""
    node = parent[leaf]
    while node != NULL:
        changed = False
        for k in range(2):
            if box[leaf, k] < box[node, k]:
                box[node, k] = box[leaf, k]
                changed = True
            if box[leaf, k + 2] > box[node, k + 2]:
                box[node, k + 2] = box[leaf, k + 2]
                changed = True
        enlarged[node] = True
        node = parent[node]
        if not changed:          # this ancestor held the box already, so do the ones above it
            break
    while node != NULL and not enlarged[node]:
        enlarged[node] = True
        node = parent[node]


@njit(cache=True)
def split_by_bins(items, start, end, box, bins, counts, right_cost):
    """Reorder ``items[start:end]`` (nodes) into two non-empty groups and return where the
    second starts: the plane between BIN_COUNT bins of their centres along the longer
    axis of the centres' bounds with the least left count x left perimeter + right count
    x right perimeter (binned SAH, Box2D's b2PartitionSAH)."""
    count = end - start
    if count == 2:
        return start + 1
    low_x = low_y = np.inf
    high_x = high_y = -np.inf
    for k in range(start, end):
        node = items[k]
        cx, cy = box[node, 0] + box[node, 2], box[node, 1] + box[node, 3]     # twice the centre
        low_x, high_x = min(low_x, cx), max(high_x, cx)
        low_y, high_y = min(low_y, cy), max(high_y, cy)
    axis, low, extent = (0, low_x, high_x - low_x) if high_x - low_x > high_y - low_y else (1, low_y, high_y - low_y)
    if extent <= 0.0:                       # every centre at one point: halve the group
        return start + count // 2
    scale = BIN_COUNT / extent
    for b in range(BIN_COUNT):               # bins, counts, right_cost: the caller's scratch arrays
        bins[b, 0] = bins[b, 1] = np.inf
        bins[b, 2] = bins[b, 3] = -np.inf
        counts[b] = 0
    for k in range(start, end):
        node = items[k]
        b = min(int(scale * (box[node, axis] + box[node, axis + 2] - low)), BIN_COUNT - 1)
        counts[b] += 1
        for c in range(2):
            bins[b, c] = min(bins[b, c], box[node, c])
            bins[b, c + 2] = max(bins[b, c + 2], box[node, c + 2])
    # right_cost[p]: count x perimeter of bins p+1 .. BIN_COUNT-1 (the right side of plane p)
    rx0 = ry0 = np.inf
    rx1 = ry1 = -np.inf
    right_count = 0
    for p in range(BIN_COUNT - 2, -1, -1):
        b = p + 1
        rx0, ry0 = min(rx0, bins[b, 0]), min(ry0, bins[b, 1])
        rx1, ry1 = max(rx1, bins[b, 2]), max(ry1, bins[b, 3])
        right_count += counts[b]
        right_cost[p] = right_count * perimeter(rx0, ry0, rx1, ry1) if right_count else 0.0
    best_plane, best_cost = -1, np.inf
    lx0 = ly0 = np.inf
    lx1 = ly1 = -np.inf
    left_count = 0
    for p in range(BIN_COUNT - 1):
        lx0, ly0 = min(lx0, bins[p, 0]), min(ly0, bins[p, 1])
        lx1, ly1 = max(lx1, bins[p, 2]), max(ly1, bins[p, 3])
        left_count += counts[p]
        if left_count == 0 or left_count == count:
            continue
        cost = left_count * perimeter(lx0, ly0, lx1, ly1) + right_cost[p]
        if cost < best_cost:
            best_plane, best_cost = p, cost
    if best_plane < 0:                       # all in one bin (cannot happen with extent > 0)
        return start + count // 2
    i, j = start, end                        # Hoare partition: bins <= best_plane first
    while i < j:
        node = items[i]
        if min(int(scale * (box[node, axis] + box[node, axis + 2] - low)), BIN_COUNT - 1) <= best_plane:
            i += 1
        else:
            j -= 1
            items[i], items[j] = items[j], items[i]
    return i


@njit(cache=True)
def rebuild(box, parent, child1, child2, height, body, meta, enlarged, items):
    """Free every enlarged inner node and build that part of the tree again, top-down by
    :func:`split_by_bins`, over the leaves and unenlarged subtrees below it
    (b2DynamicTree_Rebuild); boxes and heights of the new nodes from their children."""
    root = meta[ROOT]
    if root == NULL or not enlarged[root]:
        return
    count = 0
    pending = np.empty(2 * len(items) + 2, np.int64)
    top = 1
    pending[0] = root
    while top > 0:
        top -= 1
        node = pending[top]
        if child1[node] == NULL or not enlarged[node]:
            items[count] = node
            count += 1
            parent[node] = NULL
            continue
        pending[top], pending[top + 1] = child1[node], child2[node]
        top += 2
        enlarged[node] = False
        free_node(node, parent, height, meta)
    if count == 1:
        meta[ROOT] = items[0]
        return
    # Work list: (node, start, end) of the groups still to split; made nodes in order.
    work = np.empty((count, 3), np.int64)
    made = np.empty(count, np.int64)
    bins, counts, right_cost = np.empty((BIN_COUNT, 4)), np.empty(BIN_COUNT, np.int64), np.empty(BIN_COUNT - 1)
    new_root = allocate_node(parent, child1, child2, height, body, meta)
    meta[ROOT] = new_root
    work[0, 0], work[0, 1], work[0, 2] = new_root, 0, count
    top, n_made = 1, 0
    while top > 0:
        top -= 1
        node, start, end = work[top, 0], work[top, 1], work[top, 2]
        made[n_made] = node
        n_made += 1
        split = split_by_bins(items, start, end, box, bins, counts, right_cost)
        for side in range(2):
            first, last = (start, split) if side == 0 else (split, end)
            if last - first == 1:
                child = items[first]
            else:
                child = allocate_node(parent, child1, child2, height, body, meta)
                work[top, 0], work[top, 1], work[top, 2] = child, first, last
                top += 1
            if side == 0:
                child1[node] = child
            else:
                child2[node] = child
            parent[child] = node
    for k in range(n_made - 1, -1, -1):        # children were made after their parents
        refit(made[k], box, child1, child2, height)


# Cached machine code compiled from older sources is forgotten (solutions.compiled_cache).
forget_stale_machine_code(globals())
