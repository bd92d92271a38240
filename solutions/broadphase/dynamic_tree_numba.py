"""Dynamic AABB tree compiled with numba: the readable tree's steps on flat arrays.

:class:`DynamicTreeNumba` is the compiled twin of
:class:`solutions.broadphase.dynamic_tree.DynamicTree`: the same fat leaves, the same
branch-and-bound choice of sibling (same visiting order, same tie rule), the same
height rotations, the same query of every body's partners by its tight box.  Read that
module for why each step is right.  Here, as in Box2D's ``b2DynamicTree``, the nodes
live in parallel arrays indexed by node number (``-1`` = none), a freed node goes on
a free list (linked through ``parent``), and each body's leaf is ``leaf_of[body]``.
Bodies are ``0 .. N - 1``, fixed when the tree is built.

One step more than the readable class, as Box2D and Chipmunk do: the pairs of
overlapping *fat* boxes are kept from frame to frame (``candidates``).  A pair of two
bodies that were not reinserted keeps its fat boxes, so it stays a candidate or not;
only the reinserted bodies search the tree, by their new fat box.  The pairs of a
frame are the candidates whose tight boxes meet: the work of a frame grows with the
bodies that left their fat boxes, not with N.

The same operations in the same order build the same tree as the readable class (node
numbers aside): tests/test_dynamic_tree.py checks the pairs, the reinserted bodies,
the heights and the cost on random moving scenes.

Compiled with ``@njit(cache=True)``: the first call in a fresh checkout compiles (a few
seconds) and stores the machine code in ``__pycache__``.
"""
from __future__ import annotations

### INSTRUCTOR ONLY: not in the student edition (a compiled copy of the dynamic-tree exercise).

import numpy as np
from numba import njit

from .aabb_array import validate_aabbs
from .dynamic_tree import AABB_MARGIN, check_margin
from ..compiled_cache import forget_stale_machine_code

NULL = -1
#: meta[ROOT] is the root node, meta[FREE] the first free node, meta[COUNT] the nodes ever used.
ROOT, FREE, COUNT = 0, 1, 2
#: The pair buffer starts with room for this many pairs per body, then doubles.
INITIAL_PAIRS_PER_BODY = 4


class DynamicTreeNumba:
    """A dynamic tree of the bodies ``0 .. N - 1`` of an ``(N, 4)`` array of tight boxes (m).

    Examples
    --------
    >>> tree = DynamicTreeNumba([[0, 0, 1, 1], [1, 0, 2, 1], [5, 5, 6, 6]], margin=0.1)
    >>> tree.pairs().tolist(), tree.height()
    ([[0, 1]], 2)
    >>> tree.move_all([[0, 0, 1, 1], [1.05, 0, 2.05, 1], [1.5, 0.5, 2.5, 1.5]]).tolist()   # body 2 left its fat box
    [2]
    """

    def __init__(self, aabbs, margin: float = AABB_MARGIN):
        boxes = validate_aabbs(aabbs)
        self.margin = check_margin(margin)
        n = len(boxes)
        capacity = max(2 * n, 1)
        self.box = np.zeros((capacity, 4))
        self.parent = np.full(capacity, NULL, np.int32)
        self.child1 = np.full(capacity, NULL, np.int32)
        self.child2 = np.full(capacity, NULL, np.int32)
        self.heights = np.zeros(capacity, np.int32)
        self.body = np.full(capacity, NULL, np.int32)
        self.meta = np.array([NULL, NULL, 0], np.int64)
        self.leaf_of = np.full(n, NULL, np.int32)
        self.tight = np.ascontiguousarray(boxes, dtype=np.float64).copy()
        _insert_all(self.tight, self.margin, *self._arrays())
        #: Every pair of bodies whose *fat* boxes overlap (i < j): the candidates of :meth:`pairs`.
        self.candidates = _fat_pairs(np.ones(n, np.bool_), np.empty((0, 2), np.int32), self.box, self.child1,
                                     self.child2, self.body, self.meta, self.leaf_of, self._root_height())

    def _arrays(self):
        return (self.box, self.parent, self.child1, self.child2, self.heights, self.body, self.meta, self.leaf_of)

    def move_all(self, aabbs) -> np.ndarray:
        """Move body ``i`` to tight box ``aabbs[i]`` (m) for every ``i``; returns the bodies
        reinserted (their tight box left their fat box), in increasing order."""
        boxes = np.ascontiguousarray(aabbs, dtype=np.float64)
        if boxes.shape != self.tight.shape:
            raise ValueError(f"move_all needs an array of shape {self.tight.shape}, got {boxes.shape}")
        moved = _move_all(boxes, self.margin, self.tight, *self._arrays())
        self.candidates = _fat_pairs(moved, self.candidates, self.box, self.child1, self.child2, self.body,
                                     self.meta, self.leaf_of, self._root_height())
        return np.flatnonzero(moved)

    def pairs(self) -> np.ndarray:
        """``(M, 2)`` int64 array of the pairs ``i < j`` whose tight boxes overlap or touch,
        sorted by ``i`` then ``j``."""
        found = self.pairs_unsorted()
        return found[np.lexsort((found[:, 1], found[:, 0]))]

    def pairs_unsorted(self) -> np.ndarray:
        """The pairs of :meth:`pairs` in no particular order: the candidates whose tight boxes meet."""
        return _tight_pairs(self.candidates, self.tight)

    def _root_height(self) -> int:
        return int(self.heights[self.meta[ROOT]]) if self.meta[ROOT] != NULL else 0

    def height(self) -> int:
        """Height of the root (0 for a single leaf, -1 for an empty tree)."""
        return int(self.heights[self.meta[ROOT]]) if self.meta[ROOT] != NULL else -1

    def cost(self) -> float:
        """Total perimeter of the inner nodes (m)."""
        return float(_cost(self.box, self.child1, self.child2, self.meta))


# ---------------------------------------------------------------- compiled steps
@njit(cache=True)
def _perimeter(x0, y0, x1, y1):
    return 2.0 * ((x1 - x0) + (y1 - y0))


@njit(cache=True)
def _union_perimeter(box, node, b):
    return _perimeter(min(box[node, 0], b[0]), min(box[node, 1], b[1]),
                      max(box[node, 2], b[2]), max(box[node, 3], b[3]))


@njit(cache=True)
def _allocate(parent, child1, child2, height, body, meta):
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
def _free(node, parent, height, meta):
    parent[node] = meta[FREE]
    height[node] = -1
    meta[FREE] = node


@njit(cache=True)
def _refit(node, box, child1, child2, height):
    a, b = child1[node], child2[node]
    box[node, 0] = min(box[a, 0], box[b, 0])
    box[node, 1] = min(box[a, 1], box[b, 1])
    box[node, 2] = max(box[a, 2], box[b, 2])
    box[node, 3] = max(box[a, 3], box[b, 3])
    height[node] = 1 + max(height[a], height[b])


@njit(cache=True)
def _replace_child(node, old, new, parent, child1, child2):
    if child1[node] == old:
        child1[node] = new
    else:
        child2[node] = new
    parent[new] = node


@njit(cache=True)
def _balance(node, box, parent, child1, child2, height, meta):
    if child1[node] == NULL or height[node] < 2:
        return node
    a, b = child1[node], child2[node]
    if abs(height[a] - height[b]) <= 1:
        return node
    if height[b] > height[a]:
        short, tall = a, b
    else:
        short, tall = b, a
    if height[child1[tall]] >= height[child2[tall]]:
        keep, give = child1[tall], child2[tall]
    else:
        keep, give = child2[tall], child1[tall]
    up = parent[node]
    if up == NULL:
        meta[ROOT] = tall
        parent[tall] = NULL
    else:
        _replace_child(up, node, tall, parent, child1, child2)
    child1[node], child2[node] = short, give
    parent[short] = node
    parent[give] = node
    child1[tall], child2[tall] = node, keep
    parent[node] = tall
    parent[keep] = tall
    _refit(node, box, child1, child2, height)
    _refit(tall, box, child1, child2, height)
    return tall


@njit(cache=True)
def _best_sibling(b, box, child1, child2, meta, stack_nodes, stack_costs):
    root = meta[ROOT]
    b_perimeter = _perimeter(b[0], b[1], b[2], b[3])
    best, best_cost = root, _union_perimeter(box, root, b)
    stack_nodes[0], stack_costs[0] = root, 0.0
    top = 1
    while top > 0:
        top -= 1
        node, inherited = stack_nodes[top], stack_costs[top]
        joined = _union_perimeter(box, node, b)
        if joined + inherited < best_cost:
            best, best_cost = node, joined + inherited
        if child1[node] == NULL:
            continue
        inherited += joined - _perimeter(box[node, 0], box[node, 1], box[node, 2], box[node, 3])
        if b_perimeter + inherited < best_cost:
            if top + 2 > len(stack_nodes):
                return -2 - best          # the caller grows the stack and asks again
            stack_nodes[top], stack_costs[top] = child1[node], inherited
            stack_nodes[top + 1], stack_costs[top + 1] = child2[node], inherited
            top += 2
    return best


@njit(cache=True)
def _insert_leaf(leaf, box, parent, child1, child2, height, body, meta, stacks):
    if meta[ROOT] == NULL:
        meta[ROOT] = leaf
        parent[leaf] = NULL
        return stacks
    stack_nodes, stack_costs = stacks
    sibling = _best_sibling(box[leaf], box, child1, child2, meta, stack_nodes, stack_costs)
    while sibling < NULL:
        stack_nodes = np.empty(2 * len(stack_nodes), np.int64)
        stack_costs = np.empty(2 * len(stack_costs))
        sibling = _best_sibling(box[leaf], box, child1, child2, meta, stack_nodes, stack_costs)
    old_parent = parent[sibling]
    new_parent = _allocate(parent, child1, child2, height, body, meta)
    child1[new_parent], child2[new_parent] = sibling, leaf
    height[new_parent] = height[sibling] + 1     # as the readable tree: balance reads it first
    if old_parent == NULL:
        meta[ROOT] = new_parent
    else:
        _replace_child(old_parent, sibling, new_parent, parent, child1, child2)
    parent[sibling] = new_parent
    parent[leaf] = new_parent
    node = new_parent
    while node != NULL:
        node = _balance(node, box, parent, child1, child2, height, meta)
        _refit(node, box, child1, child2, height)
        node = parent[node]
    return (stack_nodes, stack_costs)


@njit(cache=True)
def _remove_leaf(leaf, box, parent, child1, child2, height, meta):
    if leaf == meta[ROOT]:
        meta[ROOT] = NULL
        return
    up = parent[leaf]
    sibling = child2[up] if child1[up] == leaf else child1[up]
    grandparent = parent[up]
    parent[leaf] = NULL
    _free(up, parent, height, meta)
    if grandparent == NULL:
        meta[ROOT] = sibling
        parent[sibling] = NULL
        return
    _replace_child(grandparent, up, sibling, parent, child1, child2)
    node = grandparent
    while node != NULL:
        node = _balance(node, box, parent, child1, child2, height, meta)
        _refit(node, box, child1, child2, height)
        node = parent[node]


@njit(cache=True)
def _set_fat(leaf, tight_box, margin, box):
    box[leaf, 0] = tight_box[0] - margin
    box[leaf, 1] = tight_box[1] - margin
    box[leaf, 2] = tight_box[2] + margin
    box[leaf, 3] = tight_box[3] + margin


@njit(cache=True)
def _insert_all(tight, margin, box, parent, child1, child2, height, body, meta, leaf_of):
    stacks = (np.empty(64, np.int64), np.empty(64))
    for i in range(tight.shape[0]):
        leaf = _allocate(parent, child1, child2, height, body, meta)
        body[leaf] = i
        leaf_of[i] = leaf
        _set_fat(leaf, tight[i], margin, box)
        stacks = _insert_leaf(leaf, box, parent, child1, child2, height, body, meta, stacks)


@njit(cache=True)
def _move_all(new_tight, margin, tight, box, parent, child1, child2, height, body, meta, leaf_of):
    stacks = (np.empty(64, np.int64), np.empty(64))
    moved = np.zeros(tight.shape[0], np.bool_)
    for i in range(tight.shape[0]):
        for k in range(4):
            tight[i, k] = new_tight[i, k]
        leaf = leaf_of[i]
        if (box[leaf, 0] <= tight[i, 0] and tight[i, 2] <= box[leaf, 2]
                and box[leaf, 1] <= tight[i, 1] and tight[i, 3] <= box[leaf, 3]):
            continue
        moved[i] = True
        _remove_leaf(leaf, box, parent, child1, child2, height, meta)
        _set_fat(leaf, tight[i], margin, box)
        stacks = _insert_leaf(leaf, box, parent, child1, child2, height, body, meta, stacks)
    return moved


@njit(cache=True)
def _fat_pairs(moved, old, box, child1, child2, body, meta, leaf_of, root_height):
    """The pairs of overlapping fat boxes: the old pairs of bodies that did not move (their
    fat boxes are unchanged), and the partners found for each moved body in the tree."""
    n = len(moved)
    out = np.empty((max(16, len(old) + INITIAL_PAIRS_PER_BODY * int(moved.sum())), 2), np.int32)
    count = 0
    for k in range(len(old)):
        if not moved[old[k, 0]] and not moved[old[k, 1]]:
            out[count, 0], out[count, 1] = old[k, 0], old[k, 1]
            count += 1
    root = meta[ROOT]
    if root == NULL:
        return out[:count]
    stack = np.empty(2 * root_height + 4, np.int64)    # depth-first: at most one waiting node per level
    for i in range(n):
        if not moved[i]:
            continue
        leaf = leaf_of[i]
        x0, y0, x1, y1 = box[leaf, 0], box[leaf, 1], box[leaf, 2], box[leaf, 3]
        stack[0] = root
        top = 1
        while top > 0:
            top -= 1
            node = stack[top]
            if box[node, 0] > x1 or x0 > box[node, 2] or box[node, 1] > y1 or y0 > box[node, 3]:
                continue
            if child1[node] != NULL:
                stack[top] = child1[node]
                stack[top + 1] = child2[node]
                top += 2
                continue
            j = body[node]
            # A pair of two moved bodies is met from both sides: kept from the smaller's.
            if j == i or (moved[j] and j < i):
                continue
            if count == len(out):
                bigger = np.empty((2 * len(out), 2), np.int32)
                bigger[:count] = out[:count]
                out = bigger
            out[count, 0], out[count, 1] = min(i, j), max(i, j)
            count += 1
    return out[:count]


@njit(cache=True)
def _tight_pairs(candidates, tight):
    out = np.empty((len(candidates), 2), np.int64)
    count = 0
    for k in range(len(candidates)):
        i, j = candidates[k, 0], candidates[k, 1]
        if not (tight[j, 0] > tight[i, 2] or tight[i, 0] > tight[j, 2]
                or tight[j, 1] > tight[i, 3] or tight[i, 1] > tight[j, 3]):
            out[count, 0], out[count, 1] = i, j
            count += 1
    return out[:count]


@njit(cache=True)
def _cost(box, child1, child2, meta):
    total = 0.0
    if meta[ROOT] == NULL:
        return total
    stack = [meta[ROOT]]
    while len(stack) > 0:
        node = stack.pop()
        if child1[node] != NULL:
            total += 2.0 * ((box[node, 2] - box[node, 0]) + (box[node, 3] - box[node, 1]))
            stack.append(child1[node])
            stack.append(child2[node])
    return total


# Cached machine code compiled from older sources is forgotten (solutions.compiled_cache).
forget_stale_machine_code(globals())
