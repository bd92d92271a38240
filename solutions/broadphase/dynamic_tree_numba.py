"""Dynamic AABB tree compiled with numba: the readable tree's steps on flat arrays, and
Box2D v3's way of moving many bodies at once.

:class:`DynamicTreeNumba` is the compiled twin of
:class:`solutions.broadphase.dynamic_tree.DynamicTree`: the same fat leaves, the same
branch-and-bound choice of sibling (same visiting order, same tie rule) and height
rotations when it is built, the same rule for which bodies a move reinserts.  Read that
module for why each step is right.  Here, as in Box2D's ``b2DynamicTree``, the nodes
live in parallel arrays indexed by node number (:mod:`solutions.broadphase.tree_nodes_numba`),
and each body's leaf is ``leaf_of[body]``.  Bodies are ``0 .. N - 1``, fixed when the
tree is built.

Moving every body (:meth:`DynamicTreeNumba.move_all`) is Box2D v3's step, not N
reinsertions.  A body whose tight box left its fat box gets its new fat box in place and
its ancestors grow to hold it, each marked *enlarged* (``b2DynamicTree_EnlargeProxy``);
then the enlarged part of the tree is built again in one pass
(``b2DynamicTree_Rebuild``): every enlarged inner node is freed, and the leaves and the
untouched subtrees hanging below them are split top-down, each group by the plane of 8
bins along its centres' longer axis that gives the least count times perimeter on the
two sides (the binned surface-area heuristic of Wald, "On fast construction of SAH-based
bounding volume hierarchies", 2007; ``b2PartitionSAH``; Box2D builds by a median split
unless ``B2_TREE_HEURISTIC`` is set).  At 10k drifting boxes, 1 300 of them leaving their
fat box a frame, the moves and the rebuild (about 5 500 leaves and kept subtrees) take
1.0 ms where 1 300 reinsertions took 3.2 ms, and the tree costs 5 % less.  The tree is
not the one the readable class's moves build (its nodes and heights differ); its
invariants are the same, and so are its pairs.

One step more than the readable class, as Box2D and Chipmunk do: the pairs of
overlapping *fat* boxes are kept from frame to frame (``candidates``).  A pair of two
bodies that were not reinserted keeps its fat boxes, so it stays a candidate or not;
only the reinserted bodies search the tree, by their new fat box.  The pairs of a
frame are the candidates whose tight boxes meet: the work of a frame grows with the
bodies that left their fat boxes, not with N.

tests/test_dynamic_tree.py checks the built tree equal to the readable class's (heights
and cost), and on random moving scenes the pairs and the reinserted bodies equal to it,
the moved tree's invariants by :mod:`grader.oracles.aabb_tree_shape` and its cost near
the readable tree's.

Compiled with ``@njit(cache=True)``: the first call in a fresh checkout compiles (a few
seconds) and stores the machine code in ``__pycache__``.
"""
from __future__ import annotations

### INSTRUCTOR ONLY: not in the student edition (a compiled copy of the dynamic-tree exercise).

import numpy as np
from numba import njit

from .aabb_array import validate_aabbs
from .dynamic_tree import AABB_MARGIN, check_margin
from .tree_nodes_numba import NULL, ROOT, allocate_node, enlarge, perimeter, rebuild, refit
from ..compiled_cache import forget_stale_machine_code

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
        #: True for an inner node whose box grew since the last rebuild (it and all its ancestors).
        self.enlarged = np.zeros(capacity, np.bool_)
        self._rebuild_items = np.empty(max(n, 1), np.int32)     # the rebuild's leaves and kept subtrees
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
        moved, self.candidates = _step(boxes, self.margin, self.tight, *self._arrays(), self.enlarged,
                                       self._rebuild_items, self.candidates)
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

    def structure(self) -> dict:
        """The tree as plain data, in the form of :meth:`DynamicTree.structure
        <solutions.broadphase.dynamic_tree.DynamicTree.structure>` (root first, depth-first,
        child1 first), for the checks of :mod:`grader.oracles.aabb_tree_shape`."""
        order, stack = [], [int(self.meta[ROOT])] if self.meta[ROOT] != NULL else []
        while stack:
            node = stack.pop()
            order.append(node)
            if self.child1[node] != NULL:
                stack.extend((int(self.child2[node]), int(self.child1[node])))
        number = {node: k for k, node in enumerate(order)}
        nodes = [{"box": self.box[node].tolist(), "height": int(self.heights[node]),
                  "body": None if self.body[node] == NULL else int(self.body[node]),
                  "parent": None if self.parent[node] == NULL else number.get(int(self.parent[node]), -1),
                  "children": [] if self.child1[node] == NULL else [number[int(self.child1[node])],
                                                                    number[int(self.child2[node])]]}
                 for node in order]
        return {"margin": self.margin, "nodes": nodes}


# ---------------------------------------------------------------- compiled steps
@njit(cache=True)
def _union_perimeter(box, node, b):
    return perimeter(min(box[node, 0], b[0]), min(box[node, 1], b[1]),
                      max(box[node, 2], b[2]), max(box[node, 3], b[3]))


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
    refit(node, box, child1, child2, height)
    refit(tall, box, child1, child2, height)
    return tall


@njit(cache=True)
def _best_sibling(b, box, child1, child2, meta, stack_nodes, stack_costs):
    root = meta[ROOT]
    b_perimeter = perimeter(b[0], b[1], b[2], b[3])
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
        inherited += joined - perimeter(box[node, 0], box[node, 1], box[node, 2], box[node, 3])
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
    new_parent = allocate_node(parent, child1, child2, height, body, meta)
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
        refit(node, box, child1, child2, height)
        node = parent[node]
    return (stack_nodes, stack_costs)


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
        leaf = allocate_node(parent, child1, child2, height, body, meta)
        body[leaf] = i
        leaf_of[i] = leaf
        _set_fat(leaf, tight[i], margin, box)
        stacks = _insert_leaf(leaf, box, parent, child1, child2, height, body, meta, stacks)


@njit(cache=True)
def _move_all(new_tight, margin, tight, box, parent, child1, child2, height, body, meta, leaf_of, enlarged):
    """New tight boxes; a body that left its fat box gets a new one, its ancestors enlarged."""
    moved = np.zeros(tight.shape[0], np.bool_)
    for i in range(tight.shape[0]):
        for k in range(4):
            tight[i, k] = new_tight[i, k]
        leaf = leaf_of[i]
        if (box[leaf, 0] <= tight[i, 0] and tight[i, 2] <= box[leaf, 2]
                and box[leaf, 1] <= tight[i, 1] and tight[i, 3] <= box[leaf, 3]):
            continue
        moved[i] = True
        _set_fat(leaf, tight[i], margin, box)
        enlarge(leaf, box, parent, enlarged)
    return moved


@njit(cache=True)
def _step(new_tight, margin, tight, box, parent, child1, child2, height, body, meta, leaf_of, enlarged, items,
          candidates):
    """One frame of :meth:`DynamicTreeNumba.move_all` in one compiled call (a call from
    Python costs tens of microseconds): move, rebuild, new fat-box candidates."""
    moved = _move_all(new_tight, margin, tight, box, parent, child1, child2, height, body, meta, leaf_of, enlarged)
    rebuild(box, parent, child1, child2, height, body, meta, enlarged, items)
    root_height = height[meta[ROOT]] if meta[ROOT] != NULL else 0
    return moved, _fat_pairs(moved, candidates, box, child1, child2, body, meta, leaf_of, root_height)


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
