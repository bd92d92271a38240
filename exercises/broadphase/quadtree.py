# Exercise file of the collision course: write the functions that raise NotImplementedError, then
# check them with `grader check quadtree`.
# Handed out with the course; generated from solutions/broadphase/quadtree.py on the instructor's
# side.
"""Quadtree broad phase: adaptive cells, small where bodies are dense.

Each node covers a rectangle ``bounds = (min_x, min_y, max_x, max_y)`` (m) and stores
a list of body indices.  An inner node has four children, its quarters, numbered::

      +--------+--------+ max_y
      |   2    |   3    |              y
      |  NW    |  NE    |              ^
      +--------+--------+ mid_y        |
      |   0    |   1    |              +--> x
      |  SW    |  SE    |
      +--------+--------+ min_y
    min_x    mid_x    max_x

The quarters do not overlap (apart from their shared edges) and together make the
parent: the two quadtree invariants of the notes.

Insertion by full containment
    A body goes down from the root while one child fully contains its AABB.  A body
    that straddles a splitting line (``mid_x`` or ``mid_y``) stays at the inner node.
    Because touching boxes count as a pair, a body that merely *touches* a splitting
    line also stays: otherwise two boxes touching across that line would sit in
    sibling subtrees and never be tested.  So two bodies in different children of a
    node are strictly separated by one of the node's splitting lines.

Splitting and the three stopping rules
    A leaf is split into four children when it holds more than
    ``max_bodies_per_node`` bodies, and its bodies move down where a child holds
    them.  A leaf is *not* split when

    - :data:`RULE_FEW_BODIES`: it holds at most ``max_bodies_per_node`` bodies;
    - :data:`RULE_MAX_DEPTH`: its depth (root = 0) has reached ``max_depth``;
    - :data:`RULE_MIN_AREA`: its children would have an area below ``min_node_area``.

    The depth and area rules are what make many bodies at one point terminate.

Pairs (erratum 5)
    A body can overlap bodies stored in its own node, in the node's descendants
    (smaller bodies inside its region) and in its ancestors (straddling bodies), not
    only in its own node.  Testing each body against the rest of its node and against
    the descendants whose regions its box touches meets every pair exactly once: a
    pair with an ancestor's body is found from the ancestor's side.  Pruning the
    descendants by region matters: a body on the root's splitting lines would
    otherwise be tested against every body in the scene.

Bodies outside the root
    :func:`pairs_quadtree` computes the root bounds from the data when ``bounds`` is
    None, so every body is inside.  With given bounds, a body not fully inside the root
    fits no child, so it stays at the root like a straddling body: it is tested against
    the root's other bodies and every subtree its box touches, so no pair is lost (but
    many such bodies make the root a long list tested pairwise).

This is the basic variant of the notes: bodies may live at inner nodes, and the
quarters are equal.  The notes also mention a balanced variant (quarters chosen so
that each holds about a quarter of the bodies) and a leaves-only variant (a
straddling body is stored in every leaf it overlaps, like the every-cell grid);
neither is implemented here.
"""
from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field

from .aabb_array import MAX_X, MAX_Y, MIN_X, MIN_Y, validate_aabbs
from .brute_force import aabbs_overlap

#: Stopping rule: the node holds at most ``max_bodies_per_node`` bodies.
RULE_FEW_BODIES = "few_bodies"
#: Stopping rule: the node's depth has reached ``max_depth``.
RULE_MAX_DEPTH = "max_depth"
#: Stopping rule: the node's children would be smaller than ``min_node_area``.
RULE_MIN_AREA = "min_node_area"

DEFAULT_MAX_BODIES_PER_NODE = 8
DEFAULT_MIN_NODE_AREA = 0.0
DEFAULT_MAX_DEPTH = 16


def box_inside(box, bounds) -> bool:
    """True when the closed ``box`` lies inside the closed rectangle ``bounds``.

    Both are ``[min_x, min_y, max_x, max_y]`` (m); sharing an edge is inside.

    Examples
    --------
    >>> box_inside([0, 0, 1, 1], [0, 0, 2, 2]), box_inside([1, 1, 3, 2], [0, 0, 2, 2])
    (True, False)
    """
    return (bounds[MIN_X] <= box[MIN_X] and box[MAX_X] <= bounds[MAX_X]
            and bounds[MIN_Y] <= box[MIN_Y] and box[MAX_Y] <= bounds[MAX_Y])


def scene_bounds(aabbs) -> tuple[float, float, float, float]:
    """Smallest rectangle holding every box, widened if it has zero width or height.

    A zero span (all bodies on one vertical or horizontal line, or at one point) is
    widened to the other axis' span, or to 1 m if both are zero.  It grows on the
    positive side only, so the data lie on the root's edge and never on a splitting
    line (bodies on a splitting line could not go down the tree).

    Examples
    --------
    >>> scene_bounds([[0, 0, 1, 1], [3, -1, 4, 0]])
    (0.0, -1.0, 4.0, 1.0)
    >>> scene_bounds([[2, 5, 2, 5]])
    (2.0, 5.0, 3.0, 6.0)
    """
    boxes = validate_aabbs(aabbs)
    if len(boxes) == 0:
        return (0.0, 0.0, 1.0, 1.0)
    lo_x, lo_y = float(boxes[:, MIN_X].min()), float(boxes[:, MIN_Y].min())
    hi_x, hi_y = float(boxes[:, MAX_X].max()), float(boxes[:, MAX_Y].max())
    fallback = max(hi_x - lo_x, hi_y - lo_y) or 1.0
    if hi_x == lo_x:
        hi_x = lo_x + fallback
    if hi_y == lo_y:
        hi_y = lo_y + fallback
    return (lo_x, lo_y, hi_x, hi_y)


@dataclass(eq=False)
class QuadtreeNode:
    """One node: its rectangle, its depth (root = 0), stored bodies and 0 or 4 children."""

    bounds: tuple[float, float, float, float]
    depth: int
    bodies: list[int] = field(default_factory=list)
    children: list["QuadtreeNode"] = field(default_factory=list)

    @property
    def is_leaf(self) -> bool:
        return not self.children

    @property
    def area(self) -> float:
        """Area of the node's rectangle (m^2)."""
        return (self.bounds[MAX_X] - self.bounds[MIN_X]) * (self.bounds[MAX_Y] - self.bounds[MIN_Y])

    def split_point(self) -> tuple[float, float]:
        """``(mid_x, mid_y)`` (m), where the node's two splitting lines cross."""
        return ((self.bounds[MIN_X] + self.bounds[MAX_X]) / 2, (self.bounds[MIN_Y] + self.bounds[MAX_Y]) / 2)

    def quarter_bounds(self) -> list[tuple[float, float, float, float]]:
        """Bounds of the four quarters in child order SW, SE, NW, NE."""
        lo_x, lo_y, hi_x, hi_y = self.bounds
        mid_x, mid_y = self.split_point()
        return [(lo_x, lo_y, mid_x, mid_y), (mid_x, lo_y, hi_x, mid_y),
                (lo_x, mid_y, mid_x, hi_y), (mid_x, mid_y, hi_x, hi_y)]


class Quadtree:
    """A quadtree over a fixed root rectangle; see the module docstring for the rules.

    Parameters
    ----------
    bounds : sequence of 4 floats
        Root rectangle ``[min_x, min_y, max_x, max_y]`` (m), finite, ``min < max``.
    max_bodies_per_node : int, optional
        A leaf holding more bodies than this is split (>= 1).
    min_node_area : float, optional
        No node is created with an area below this (m^2, >= 0; 0 turns the rule off).
    max_depth : int, optional
        No node deeper than this (root depth 0, >= 0).

    Examples
    --------
    >>> tree = Quadtree((0, 0, 4, 4), max_bodies_per_node=1)
    >>> tree.insert(0, (0.5, 0.5, 1.0, 1.0))
    >>> tree.insert(1, (2.5, 2.5, 3.0, 3.0))   # second body: the root splits
    >>> [(node.depth, node.bodies) for node in tree.nodes() if node.bodies]
    [(1, [0]), (1, [1])]
    >>> tree.pairs()
    set()
    """

    def __init__(self, bounds, max_bodies_per_node: int = DEFAULT_MAX_BODIES_PER_NODE,
                 min_node_area: float = DEFAULT_MIN_NODE_AREA, max_depth: int = DEFAULT_MAX_DEPTH):
        root_bounds = tuple(float(v) for v in bounds)
        if len(root_bounds) != 4 or not all(math.isfinite(v) for v in root_bounds):
            raise ValueError(f"bounds must be 4 finite numbers [min_x, min_y, max_x, max_y], got {bounds!r}")
        if not (root_bounds[MIN_X] < root_bounds[MAX_X] and root_bounds[MIN_Y] < root_bounds[MAX_Y]):
            raise ValueError(f"bounds must have min < max on both axes, got {root_bounds}")
        if int(max_bodies_per_node) != max_bodies_per_node or max_bodies_per_node < 1:
            raise ValueError(f"max_bodies_per_node must be an integer >= 1, got {max_bodies_per_node!r}")
        if not (math.isfinite(min_node_area) and min_node_area >= 0):
            raise ValueError(f"min_node_area must be a finite area >= 0 (m^2), got {min_node_area!r}")
        if int(max_depth) != max_depth or max_depth < 0:
            raise ValueError(f"max_depth must be an integer >= 0, got {max_depth!r}")
        self.max_bodies_per_node = int(max_bodies_per_node)
        self.min_node_area = float(min_node_area)
        self.max_depth = int(max_depth)
        self.root = QuadtreeNode(root_bounds, depth=0)
        #: Box of every inserted body, by index: ``boxes[i] = (min_x, min_y, max_x, max_y)``.
        self.boxes: dict[int, tuple[float, float, float, float]] = {}

    @classmethod
    def from_aabbs(cls, aabbs, bounds=None, **rules) -> "Quadtree":
        """Build a tree holding body ``i`` = row ``i`` of ``aabbs``.

        ``bounds=None`` uses :func:`scene_bounds` of the data; ``rules`` are the
        keyword arguments of the constructor.

        Examples
        --------
        >>> tree = Quadtree.from_aabbs([[0, 0, 1, 1], [1, 1, 2, 2]])
        >>> tree.root.bounds, tree.root.bodies
        ((0.0, 0.0, 2.0, 2.0), [0, 1])
        """
        boxes = validate_aabbs(aabbs)
        tree = cls(scene_bounds(boxes) if bounds is None else bounds, **rules)
        for index, box in enumerate(boxes.tolist()):
            tree.insert(index, box)
        return tree

    # ------------------------------------------------------------------ rules
    def stopping_rule(self, node: QuadtreeNode) -> str | None:
        """The rule that forbids splitting ``node`` now, or None if it should be split.

        Examples
        --------
        >>> tree = Quadtree((0, 0, 1, 1), max_bodies_per_node=2)
        >>> tree.stopping_rule(tree.root)
        'few_bodies'
        """
        if len(node.bodies) <= self.max_bodies_per_node:
            return RULE_FEW_BODIES
        if node.depth >= self.max_depth:
            return RULE_MAX_DEPTH
        if node.area / 4 < self.min_node_area:
            return RULE_MIN_AREA
        return None

    # -------------------------------------------------------- the exercises
    def child_holding(self, node: QuadtreeNode, box) -> QuadtreeNode | None:
        """The child of inner ``node`` that fully contains ``box``, else None.

        A box touching or crossing one of the node's splitting lines has no child,
        and neither has a box sticking out of the node.

        Examples
        --------
        >>> tree = Quadtree((0, 0, 4, 4))
        >>> tree.root.children = [QuadtreeNode(b, 1) for b in tree.root.quarter_bounds()]
        >>> tree.child_holding(tree.root, (3, 3, 4, 4)).bounds
        (2.0, 2.0, 4.0, 4.0)
        >>> print(tree.child_holding(tree.root, (1, 1, 2, 2)))   # touches mid_x = 2
        None
        """
        raise NotImplementedError("write Quadtree.child_holding(), then run `grader check quadtree`")

    def insert(self, index: int, box) -> None:
        """Store body ``index`` with AABB ``box`` (m) by full containment.

        The body goes down while a child fully contains it.  If it ends in a leaf that
        now holds too many bodies and no stopping rule applies, the leaf is split.
        A body not inside the root's bounds is stored at the root.  The box is
        checked and recorded in ``self.boxes[index]`` by :meth:`check_new_body`.

        Raises
        ------
        ValueError
            If ``index`` is already in the tree or ``box`` is not a valid AABB.

        Examples
        --------
        >>> tree = Quadtree((0, 0, 4, 4), max_bodies_per_node=1)
        >>> tree.insert(0, (1, 1, 3, 3))        # straddles both splitting lines
        >>> tree.insert(1, (0, 0, 1, 1))
        >>> tree.root.bodies, tree.root.children[0].bodies
        ([0], [1])
        """
        raise NotImplementedError("write Quadtree.insert(), then run `grader check quadtree`")

    def split(self, leaf: QuadtreeNode) -> None:
        """Give ``leaf`` four children and move down every body a child holds.

        A child that then holds too many bodies is split too, unless a stopping rule
        applies.

        Examples
        --------
        >>> tree = Quadtree((0, 0, 2, 2))
        >>> tree.boxes = {0: (0.2, 0.2, 0.4, 0.4), 1: (0.5, 0.5, 1.5, 1.5)}
        >>> tree.root.bodies = [0, 1]
        >>> tree.split(tree.root)
        >>> tree.root.bodies, [child.bodies for child in tree.root.children]
        ([1], [[0], [], [], []])
        """
        raise NotImplementedError("write Quadtree.split(), then run `grader check quadtree`")

    def pairs(self) -> set[tuple[int, int]]:
        """Overlapping-or-touching pairs ``(i, j)``, ``i < j``, among inserted bodies.

        Each body is tested against the later bodies of its own node and against the
        bodies of every descendant node whose region its box touches (a subtree the
        box does not touch cannot hold a partner).  A body also meets the bodies of
        its ancestor nodes: those pairs are found from the ancestor's side.  Each pair
        is tested once.

        Examples
        --------
        >>> tree = Quadtree((0, 0, 4, 4), max_bodies_per_node=1)
        >>> for index, box in enumerate([(0, 0, 2, 2), (1, 1, 1.5, 1.5), (3, 3, 4, 4)]):
        ...     tree.insert(index, box)
        >>> sorted(tree.pairs())
        [(0, 1)]
        """
        raise NotImplementedError("write Quadtree.pairs(), then run `grader check quadtree`")

    # ------------------------------------------------------- inspection
    def nodes(self) -> Iterator[QuadtreeNode]:
        """Every node, parents before children (depth-first, children in order 0..3)."""
        stack = [self.root]
        while stack:
            node = stack.pop()
            yield node
            stack.extend(reversed(node.children))

    def stored_bodies(self) -> Iterator[tuple[QuadtreeNode, int]]:
        """``(node, index)`` for every body stored in the tree."""
        for node in self.nodes():
            for index in node.bodies:
                yield node, index

    def check_invariants(self) -> None:
        """Raise AssertionError naming the first broken invariant, if any.

        Checked: every node has 0 or 4 children, which are its quarters one level
        deeper; no node is deeper than ``max_depth`` or (below the root) smaller than
        ``min_node_area``; every inserted body is stored exactly once; a body below the
        root lies inside its node and does not touch any ancestor's splitting lines; a
        body at an inner node could not go down (it touches a splitting line, or sticks
        out of the root); a leaf holds more than ``max_bodies_per_node`` bodies only if
        the depth or area rule forbids splitting it.

        Examples
        --------
        >>> Quadtree.from_aabbs([[0, 0, 1, 1], [2, 2, 3, 3]], max_bodies_per_node=1).check_invariants()
        """
        seen: dict[int, QuadtreeNode] = {}
        stack = [(self.root, [])]   # (node, its ancestors)
        while stack:
            node, ancestors = stack.pop()
            where = f"node at depth {node.depth} with bounds {node.bounds}"
            if len(node.children) not in (0, 4):
                fail(f"{where} has {len(node.children)} children; a quadtree node has 0 or 4")
            if [child.bounds for child in node.children] not in ([], node.quarter_bounds()):
                fail(f"{where}: its children are not its four quarters")
            if any(child.depth != node.depth + 1 for child in node.children):
                fail(f"{where}: a child's depth is not the parent's depth + 1")
            if node.depth > self.max_depth:
                fail(f"{where} is deeper than max_depth = {self.max_depth}")
            if ancestors and node.area < self.min_node_area:
                fail(f"{where} has area {node.area} < min_node_area = {self.min_node_area}")
            if node.is_leaf and len(node.bodies) > self.max_bodies_per_node \
                    and self.stopping_rule(node) not in (RULE_MAX_DEPTH, RULE_MIN_AREA):
                fail(f"leaf {where} holds {len(node.bodies)} > {self.max_bodies_per_node} bodies "
                     "but no stopping rule forbids splitting it")
            mid_x, mid_y = node.split_point()
            for index in node.bodies:
                if index in seen:
                    fail(f"body {index} is stored twice")
                seen[index] = node
                box = self.boxes.get(index)
                if box is None:
                    fail(f"body {index} is stored but was never inserted")
                if ancestors and not box_inside(box, node.bounds):
                    fail(f"body {index} {box} is not inside its {where}")
                for ancestor in ancestors:
                    line_x, line_y = ancestor.split_point()
                    if box[MIN_X] <= line_x <= box[MAX_X] or box[MIN_Y] <= line_y <= box[MAX_Y]:
                        fail(f"body {index} {box} touches a splitting line of an ancestor of its {where}")
                if not node.is_leaf:
                    touches_line = box[MIN_X] <= mid_x <= box[MAX_X] or box[MIN_Y] <= mid_y <= box[MAX_Y]
                    sticks_out = not ancestors and not box_inside(box, node.bounds)
                    if not (touches_line or sticks_out):
                        fail(f"body {index} {box} at inner {where} fits in a child but was not moved down")
            for child in node.children:
                stack.append((child, ancestors + [node]))
        missing = set(self.boxes) - set(seen)
        if missing:
            fail(f"inserted bodies {sorted(missing)[:10]} are not stored in any node")

    def check_new_body(self, index: int, box) -> tuple[float, float, float, float]:
        """Record ``box`` as body ``index``'s AABB and return it as a tuple of 4 floats.

        Raises ValueError for a bad box or an index already in the tree.

        Examples
        --------
        >>> Quadtree((0, 0, 1, 1)).check_new_body(3, [0, 0, 1, 1])
        (0.0, 0.0, 1.0, 1.0)
        """
        if index in self.boxes:
            raise ValueError(f"body {index} is already in the quadtree")
        checked = tuple(validate_aabbs([box])[0].tolist())
        self.boxes[index] = checked
        return checked


def fail(message: str) -> None:
    """Raise AssertionError (explicitly, so that ``python -O`` still checks)."""
    raise AssertionError(message)


def pairs_quadtree(aabbs, bounds=None, max_bodies_per_node: int = DEFAULT_MAX_BODIES_PER_NODE,
                   min_node_area: float = DEFAULT_MIN_NODE_AREA,
                   max_depth: int = DEFAULT_MAX_DEPTH) -> set[tuple[int, int]]:
    """Overlapping-or-touching pairs ``(i, j)``, ``i < j``, found with a quadtree.

    Parameters
    ----------
    aabbs : array_like, shape (N, 4)
        Boxes ``[min_x, min_y, max_x, max_y]`` (m).
    bounds : sequence of 4 floats, optional
        Root rectangle (m).  None: the data's :func:`scene_bounds`.  Bodies not
        inside given bounds are stored at the root and still tested against all.
    max_bodies_per_node : int, optional
        Split a leaf holding more bodies than this (>= 1).
    min_node_area : float, optional
        Do not create nodes with a smaller area (m^2, >= 0).
    max_depth : int, optional
        Do not create nodes deeper than this (root = 0).

    Returns
    -------
    set of tuple of int
        Exactly the pairs of the brute force.

    Examples
    --------
    >>> sorted(pairs_quadtree([[0, 0, 1, 1], [1, 0, 2, 1], [5, 5, 6, 6]], max_bodies_per_node=1))
    [(0, 1)]
    """
    tree = Quadtree.from_aabbs(aabbs, bounds=bounds, max_bodies_per_node=max_bodies_per_node,
                               min_node_area=min_node_area, max_depth=max_depth)
    return tree.pairs()


def tree_structure(aabbs, bounds=None, max_bodies_per_node: int = DEFAULT_MAX_BODIES_PER_NODE,
                   min_node_area: float = DEFAULT_MIN_NODE_AREA, max_depth: int = DEFAULT_MAX_DEPTH) -> dict:
    """The tree :func:`pairs_quadtree` builds, as plain data (for checks and pictures).

    Returns
    -------
    dict
        ``{"root_bounds": [4 floats], "nodes": [...]}``, nodes in depth-first order
        from the root, each ``{"depth": int, "bounds": [4 floats], "bodies": [ints],
        "children": [indices into nodes]}``.

    Examples
    --------
    >>> shape = tree_structure([[0, 0, 1, 1], [3, 3, 4, 4]], max_bodies_per_node=1)
    >>> [(node["depth"], node["bodies"], len(node["children"])) for node in shape["nodes"]]
    [(0, [], 4), (1, [0], 0), (1, [], 0), (1, [], 0), (1, [1], 0)]
    """
    tree = Quadtree.from_aabbs(aabbs, bounds=bounds, max_bodies_per_node=max_bodies_per_node,
                               min_node_area=min_node_area, max_depth=max_depth)
    nodes: list[dict] = []

    def visit(node: QuadtreeNode) -> int:
        number = len(nodes)
        entry = {"depth": int(node.depth), "bounds": [float(v) for v in node.bounds],
                 "bodies": [int(i) for i in node.bodies], "children": []}
        nodes.append(entry)
        entry["children"] = [visit(child) for child in node.children]
        return number

    visit(tree.root)
    return {"root_bounds": [float(v) for v in tree.root.bounds], "nodes": nodes}
