"""Dynamic AABB tree broad phase: a binary tree of boxes that follows moving bodies.

Box2D, Bullet (``btDbvt``) and Chipmunk (pymunk's default index, ``cpBBTree``) keep
their bodies in such a tree.  Every leaf holds one body; every inner node has exactly
two children and a box holding both of theirs, so a query that misses a node's box
skips its whole subtree.  Unlike a grid or a quadtree, nothing depends on a cell size
or on the world's bounds: the tree adapts to wherever the bodies are.

Fat boxes (``margin``, m)
    A leaf stores its body's tight box grown by ``margin`` on every side.  While the
    body's tight box stays inside that fat box, :meth:`DynamicTree.move` changes
    nothing in the tree; only a body that leaves its fat box is removed and inserted
    again, with a new fat box around its new tight box.  Box2D v3 uses
    ``b2_aabbMargin`` = 0.1 m: a body moving 1 m/s at 60 Hz
    reinserts about every sixth step instead of every step.  Pairs are still exact:
    they are found between *tight* boxes; the fat boxes only steer the search.

Insertion by the surface-area heuristic (SAH)
    In 2D the "surface area" of a box is its perimeter.  The cost of a tree is the
    total perimeter of its inner nodes (:meth:`DynamicTree.cost`): a box query enters a
    node about as often as the node's box is hit, which grows with its size.  A new
    leaf becomes the sibling of the node that adds the least to that total
    (:meth:`DynamicTree.best_sibling`): the perimeter of the new parent, plus what
    every ancestor grows by to hold the new box.  The branch-and-bound search of
    Box2D v3 (``b2FindBestSibling`` in ``dynamic_tree.c``) finds that node exactly.

Rotations
    Insertions in an unlucky order can still make a lopsided tree.  Walking up after
    an insertion or a removal, :meth:`DynamicTree.balance` rotates a node whose
    children's heights differ by more than one, as Box2D v2.4 does (``Balance``):
    the taller child takes the node's place.  The heights stay within a factor of
    about 1.44 of log2(N), so a query never walks a list.

Units: m.  Boxes are ``(min_x, min_y, max_x, max_y)``; touching boxes are a pair.
"""
from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

from .aabb_array import MAX_X, MAX_Y, MIN_X, MIN_Y, validate_aabbs
from .brute_force import aabbs_overlap

#: Box2D's margin (m): each side of a leaf's fat box lies this far out from the tight box.
AABB_MARGIN = 0.1


def union(a, b) -> tuple[float, float, float, float]:
    """Smallest box holding boxes ``a`` and ``b`` (m).

    Examples
    --------
    >>> union((0, 0, 1, 1), (2, -1, 3, 0.5))
    (0, -1, 3, 1)
    """
    return (min(a[MIN_X], b[MIN_X]), min(a[MIN_Y], b[MIN_Y]), max(a[MAX_X], b[MAX_X]), max(a[MAX_Y], b[MAX_Y]))


def perimeter(box) -> float:
    """Perimeter of ``box`` (m): the 2D "surface area" of the SAH.

    Examples
    --------
    >>> perimeter((0, 0, 2, 1))
    6.0
    """
    return 2.0 * ((box[MAX_X] - box[MIN_X]) + (box[MAX_Y] - box[MIN_Y]))


def contains(outer, inner) -> bool:
    """True when closed box ``inner`` lies inside closed box ``outer`` (sharing an edge is inside).

    Examples
    --------
    >>> contains((0, 0, 2, 2), (0, 1, 2, 2)), contains((0, 0, 2, 2), (1, 1, 3, 2))
    (True, False)
    """
    return (outer[MIN_X] <= inner[MIN_X] and inner[MAX_X] <= outer[MAX_X]
            and outer[MIN_Y] <= inner[MIN_Y] and inner[MAX_Y] <= outer[MAX_Y])


def fattened(box, margin: float) -> tuple[float, float, float, float]:
    """``box`` grown by ``margin`` (m) on every side.

    Examples
    --------
    >>> fattened((1.0, 1.0, 2.0, 3.0), 0.5)
    (0.5, 0.5, 2.5, 3.5)
    """
    return (box[MIN_X] - margin, box[MIN_Y] - margin, box[MAX_X] + margin, box[MAX_Y] + margin)


def check_margin(margin) -> float:
    """``margin`` as a float; ValueError unless it is finite and >= 0 (m).

    Examples
    --------
    >>> check_margin(0.1)
    0.1
    """
    value = float(margin)
    if not math.isfinite(value) or value < 0:
        raise ValueError(f"margin must be a finite length >= 0 (m), got {margin!r}")
    return value


@dataclass(eq=False)
class TreeNode:
    """A node of the tree.  A leaf has no children and holds ``body``, with its fat box
    as ``box``; an inner node has two children and ``box`` = the union of theirs.
    ``height`` is 0 for a leaf, else 1 + the larger of the children's heights."""

    box: tuple[float, float, float, float]
    parent: "TreeNode | None" = None
    child1: "TreeNode | None" = None
    child2: "TreeNode | None" = None
    height: int = 0
    body: int | None = None

    @property
    def is_leaf(self) -> bool:
        return self.child1 is None

    def sibling(self) -> "TreeNode":
        """The other child of this node's parent."""
        parent = self.parent
        return parent.child2 if parent.child1 is self else parent.child1

    def replace_child(self, old: "TreeNode", new: "TreeNode") -> None:
        """Put ``new`` where child ``old`` was (and make this node its parent)."""
        if self.child1 is old:
            self.child1 = new
        else:
            self.child2 = new
        new.parent = self


class DynamicTree:
    """Bodies (any int ids) in a dynamic AABB tree with fat leaves.

    ``insert(body, box)``, ``remove(body)`` and ``move(body, box)`` keep the tree;
    ``pairs()`` lists the pairs of bodies whose tight boxes overlap or touch.

    Examples
    --------
    >>> tree = DynamicTree(margin=0.1)
    >>> tree.insert(0, (0, 0, 1, 1)); tree.insert(1, (1, 0, 2, 1)); tree.insert(2, (5, 5, 6, 6))
    >>> sorted(tree.pairs()), tree.root.height
    ([(0, 1)], 2)
    """

    def __init__(self, margin: float = AABB_MARGIN):
        self.margin = check_margin(margin)
        self.root: TreeNode | None = None
        #: The leaf of every body, and its tight box (m).
        self.leaves: dict[int, TreeNode] = {}
        self.tight: dict[int, tuple[float, float, float, float]] = {}

    @classmethod
    def from_aabbs(cls, aabbs, margin: float = AABB_MARGIN) -> "DynamicTree":
        """A tree holding body ``i`` = row ``i`` of ``aabbs``, inserted in order."""
        tree = cls(margin)
        for body, box in enumerate(validate_aabbs(aabbs).tolist()):
            tree.insert(body, box)
        return tree

    # ------------------------------------------------------------- the interface
    def insert(self, body: int, box) -> None:
        """Add ``body`` with tight box ``box`` (m): a new leaf with the fat box.

        Raises ValueError for a body already in the tree or a bad box.
        """
        if body in self.leaves:
            raise ValueError(f"body {body} is already in the tree")
        tight = tuple(validate_aabbs([box])[0].tolist())
        leaf = TreeNode(fattened(tight, self.margin), body=body)
        self.tight[body] = tight
        self.leaves[body] = leaf
        self.insert_leaf(leaf)

    def remove(self, body: int) -> None:
        """Take ``body`` out of the tree (KeyError if it is not in it)."""
        leaf = self.leaves.pop(body)
        del self.tight[body]
        self.remove_leaf(leaf)

    def refit(self, node: TreeNode) -> None:
        """Set inner ``node``'s box and height from its two children."""
        node.box = union(node.child1.box, node.child2.box)
        node.height = 1 + max(node.child1.height, node.child2.height)

    def balance(self, node: TreeNode) -> TreeNode:
        """Rotate the taller child up if ``node``'s children's heights differ by more than 1.

        Returns the node now at ``node``'s place (``node`` itself when nothing turned),
        with its box and height refitted; the boxes and heights above it are the caller's
        to fix.  Box2D v2.4's ``b2DynamicTree::Balance``: of the tall child's two children,
        the taller stays with it and the shorter goes down to ``node``::

                node                 tall
               /    \\               /    \\
            short   tall    ->    node   keep
                   /    \\        /    \\
                keep   give   short   give
        """
        if node.is_leaf or node.height < 2:
            return node
        if abs(node.child1.height - node.child2.height) <= 1:
            return node
        short, tall = ((node.child1, node.child2) if node.child2.height > node.child1.height
                       else (node.child2, node.child1))
        keep, give = ((tall.child1, tall.child2) if tall.child1.height >= tall.child2.height
                      else (tall.child2, tall.child1))
        parent = node.parent
        if parent is None:
            self.root = tall
            tall.parent = None
        else:
            parent.replace_child(node, tall)
        node.child1, node.child2 = short, give
        short.parent = give.parent = node
        tall.child1, tall.child2 = node, keep
        node.parent = keep.parent = tall
        self.refit(node)
        self.refit(tall)
        return tall

    # -------------------------------------------------------------- the exercises
    def best_sibling(self, box) -> TreeNode:
        """The node that a new leaf with fat box ``box`` (m) should be paired with.

        Pairing the leaf with node ``X`` puts a new parent (box: ``X``'s box joined with
        ``box``) where ``X`` was, and makes every ancestor of ``X`` grow to hold ``box``.
        The cost of the choice is what the tree's :meth:`cost` (total perimeter of the
        inner nodes) grows by: the new parent's perimeter plus every ancestor's growth
        in perimeter.  Return a node of least cost (any of them on a tie).  The root is
        always a candidate: pairing with it adds only a new root.

        Visit only the subtrees that could still hold a cheaper node: on a tree of N
        leaves the search should take about log N steps, not N.

        Requires a non-empty tree.

        Examples
        --------
        >>> tree = DynamicTree(margin=0.0)
        >>> for body, box in enumerate([(0, 0, 1, 1), (1, 0, 2, 1), (10, 0, 11, 1)]):
        ...     tree.insert(body, box)
        >>> tree.best_sibling((10.5, 0.5, 11.5, 1.0)).body      # beside body 2
        2
        >>> tree.best_sibling((-50, -50, 50, 50)) is tree.root     # holds everything
        True
        """
        ### BEGIN SOLUTION
        box_perimeter = perimeter(box)
        best, best_cost = self.root, perimeter(union(self.root.box, box))
        # (node, the growth in perimeter of its ancestors if the leaf goes below them)
        stack = [(self.root, 0.0)]
        while stack:
            node, inherited = stack.pop()
            joined = perimeter(union(node.box, box))
            if joined + inherited < best_cost:
                best, best_cost = node, joined + inherited
            if node.is_leaf:
                continue
            inherited += joined - perimeter(node.box)
            # Any node below costs at least its new parent (>= the box's perimeter) plus inherited.
            if box_perimeter + inherited < best_cost:
                stack.append((node.child1, inherited))
                stack.append((node.child2, inherited))
        return best
        ### END SOLUTION

    def insert_leaf(self, leaf: TreeNode) -> None:
        """Link ``leaf`` (a new node with its fat box set) into the tree.

        The leaf and the node :meth:`best_sibling` chooses become the two children of a
        new inner node, which takes the sibling's place (it may become the root).  Then
        every ancestor of the leaf, from its parent up to the root, gets the box and
        height that hold its children; :meth:`balance` each on the way up, as a
        rotation changes the nodes above.  The first leaf simply becomes the root.

        Examples
        --------
        >>> tree = DynamicTree(margin=0.0)
        >>> tree.insert_leaf(TreeNode((0, 0, 1, 1), body=0))
        >>> tree.insert_leaf(TreeNode((3, 0, 4, 2), body=1))
        >>> tree.root.box, tree.root.height, tree.root.child1.body, tree.root.child2.body
        ((0, 0, 4, 2), 1, 0, 1)
        """
        ### BEGIN SOLUTION
        if self.root is None:
            self.root = leaf
            leaf.parent = None
            return
        sibling = self.best_sibling(leaf.box)
        old_parent = sibling.parent
        parent = TreeNode(union(sibling.box, leaf.box), child1=sibling, child2=leaf, height=sibling.height + 1)
        if old_parent is None:
            self.root = parent
        else:
            old_parent.replace_child(sibling, parent)
        sibling.parent = leaf.parent = parent
        node = parent
        while node is not None:
            node = self.balance(node)
            self.refit(node)
            node = node.parent
        ### END SOLUTION

    def remove_leaf(self, leaf: TreeNode) -> None:
        """Unlink ``leaf`` from the tree.

        Its parent disappears and the leaf's sibling takes the parent's place (it
        becomes the root if the parent was).  Every node above, up to the root, then
        gets the box and height that hold its children, :meth:`balance` d on the way
        up.  Removing the only leaf leaves an empty tree (``root`` None).

        Examples
        --------
        >>> tree = DynamicTree(margin=0.0)
        >>> for body, box in enumerate([(0, 0, 1, 1), (1, 0, 2, 1), (10, 0, 11, 1)]):
        ...     tree.insert(body, box)
        >>> tree.remove_leaf(tree.leaves[2])
        >>> tree.root.box, tree.root.height
        ((0.0, 0.0, 2.0, 1.0), 1)
        """
        ### BEGIN SOLUTION
        if leaf is self.root:
            self.root = None
            return
        parent = leaf.parent
        sibling = leaf.sibling()
        grandparent = parent.parent
        leaf.parent = None
        if grandparent is None:
            self.root = sibling
            sibling.parent = None
            return
        grandparent.replace_child(parent, sibling)
        node = grandparent
        while node is not None:
            node = self.balance(node)
            self.refit(node)
            node = node.parent
        ### END SOLUTION

    def move(self, body: int, box) -> bool:
        """Give ``body`` its new tight box ``box`` (m); True if its leaf was reinserted.

        While the new tight box lies inside the leaf's fat box (touching its edge is
        inside), only the tight box is recorded: the tree does not change and the
        answer is False.  Otherwise the leaf leaves the tree, gets a new fat box
        around the new tight box (``self.margin`` on every side) and is inserted
        again: True.

        Examples
        --------
        >>> tree = DynamicTree(margin=0.1)
        >>> tree.insert(0, (0.0, 0.0, 1.0, 1.0))
        >>> tree.move(0, (0.05, 0.0, 1.05, 1.0)), tree.leaves[0].box
        (False, (-0.1, -0.1, 1.1, 1.1))
        >>> tree.move(0, (0.5, 0.0, 1.5, 1.0)), tree.leaves[0].box
        (True, (0.4, -0.1, 1.6, 1.1))
        """
        ### BEGIN SOLUTION
        tight = tuple(float(v) for v in box)
        leaf = self.leaves[body]
        self.tight[body] = tight
        if contains(leaf.box, tight):
            return False
        self.remove_leaf(leaf)
        leaf.box = fattened(tight, self.margin)
        self.insert_leaf(leaf)
        return True
        ### END SOLUTION

    def pairs(self) -> set[tuple[int, int]]:
        """Pairs ``(i, j)``, ``i < j``, of bodies whose *tight* boxes overlap or touch.

        Each pair once.  Search the tree for each body's partners, entering only the
        nodes whose box its tight box meets: a subtree the box misses holds no partner.

        Examples
        --------
        >>> tree = DynamicTree(margin=0.5)
        >>> for body, box in enumerate([(0, 0, 1, 1), (1.2, 0, 2, 1), (1, 1, 3, 3)]):
        ...     tree.insert(body, box)
        >>> sorted(tree.pairs())       # 0 and 1 are 0.2 m apart: their fat boxes overlap, they do not
        [(0, 2), (1, 2)]
        """
        ### BEGIN SOLUTION
        pairs = set()
        if self.root is None:
            return pairs
        for i, box in self.tight.items():
            stack = [self.root]
            while stack:
                node = stack.pop()
                if not aabbs_overlap(box, node.box):
                    continue
                if node.is_leaf:
                    j = node.body
                    if i < j and aabbs_overlap(box, self.tight[j]):
                        pairs.add((i, j))
                else:
                    stack.append(node.child1)
                    stack.append(node.child2)
        return pairs
        ### END SOLUTION

    # ------------------------------------------------------------- inspection
    def nodes(self) -> Iterator[TreeNode]:
        """Every node, parents before children (depth-first, child1 first)."""
        stack = [self.root] if self.root is not None else []
        while stack:
            node = stack.pop()
            yield node
            if not node.is_leaf:
                stack.extend((node.child2, node.child1))

    def cost(self) -> float:
        """Total perimeter of the inner nodes (m): the SAH cost of the tree."""
        return sum(perimeter(node.box) for node in self.nodes() if not node.is_leaf)

    def structure(self) -> dict:
        """The tree as plain data (for checks and pictures).

        ``{"margin": float, "nodes": [...]}``; nodes in :meth:`nodes` order (the root
        first), each ``{"box": [4 floats], "height": int, "body": int or None, "parent":
        index or None, "children": [indices]}``.
        """
        order = list(self.nodes())
        number = {id(node): k for k, node in enumerate(order)}
        nodes = [{"box": [float(v) for v in node.box], "height": int(node.height),
                  "body": None if node.body is None else int(node.body),
                  "parent": None if node.parent is None else number.get(id(node.parent), -1),
                  "children": [] if node.is_leaf else [number[id(node.child1)], number[id(node.child2)]]}
                 for node in order]
        return {"margin": self.margin, "nodes": nodes}


# -------------------------------------------------- the functions the tests call
def pairs_dynamic_tree(aabbs, margin: float = AABB_MARGIN) -> set[tuple[int, int]]:
    """Overlapping-or-touching pairs ``(i, j)``, ``i < j``, found with a dynamic tree.

    Body ``i`` (tight box = row ``i`` of the ``(N, 4)`` array ``aabbs``, m) is inserted
    in order with fat boxes ``margin`` (m) wider on every side.

    Examples
    --------
    >>> sorted(pairs_dynamic_tree([[0, 0, 1, 1], [1, 0, 2, 1], [5, 5, 6, 6]]))
    [(0, 1)]
    """
    return DynamicTree.from_aabbs(aabbs, margin).pairs()


def moving_pairs(frames, margin: float = AABB_MARGIN) -> dict:
    """Insert the boxes of ``frames[0]``, then move every body to its box of each later frame.

    ``frames`` has shape ``(F, N, 4)`` (m): body ``i``'s tight box in frame ``f`` is
    ``frames[f][i]``.  Returns ``{"pairs": [F sorted lists of [i, j]], "reinserted":
    [F sorted lists of bodies whose move reinserted them]}`` (frame 0's list is empty:
    bodies are inserted, not moved).

    Examples
    --------
    >>> moving_pairs([[[0, 0, 1, 1], [3, 0, 4, 1]], [[0.05, 0, 1.05, 1], [1.05, 0, 2.05, 1]]])
    {'pairs': [[], [[0, 1]]], 'reinserted': [[], [1]]}
    """
    frames = [validate_aabbs(frame) for frame in frames]
    tree = DynamicTree.from_aabbs(frames[0], margin) if frames else DynamicTree(margin)
    pairs = [sorted([i, j] for i, j in tree.pairs())] if frames else []
    reinserted: list[list[int]] = [[]] if frames else []
    for frame in frames[1:]:
        if len(frame) != len(frames[0]):
            raise ValueError(f"every frame must hold {len(frames[0])} boxes, got {len(frame)}")
        moved = [body for body, box in enumerate(frame.tolist()) if tree.move(body, box)]
        reinserted.append(moved)
        pairs.append(sorted([i, j] for i, j in tree.pairs()))
    return {"pairs": pairs, "reinserted": reinserted}


def tree_structure(aabbs, margin: float = AABB_MARGIN, removed=(), moves=None) -> dict:
    """The tree after inserting the boxes of ``aabbs``, removing the bodies ``removed``
    and moving body ``i`` to ``moves[i]`` for each row (``moves``: ``(N, 4)`` or None),
    as :meth:`DynamicTree.structure` data plus its ``"cost"`` (m).

    Examples
    --------
    >>> shape = tree_structure([[0, 0, 1, 1], [3, 0, 4, 1]], margin=0.0)
    >>> shape["cost"], [node["body"] for node in shape["nodes"]]
    (10.0, [None, 0, 1])
    """
    tree = DynamicTree.from_aabbs(aabbs, margin)
    for body in removed:
        tree.remove(int(body))
    if moves is not None:
        for body, box in enumerate(validate_aabbs(moves).tolist()):
            if body in tree.leaves:
                tree.move(body, box)
    shape = tree.structure()
    shape["cost"] = tree.cost()
    return shape


def sibling_choice(aabbs, box, margin: float = AABB_MARGIN) -> dict:
    """The node :meth:`DynamicTree.best_sibling` chooses for a new leaf with fat box
    ``box`` (m) in the tree of ``aabbs``: ``{"tree": the tree's structure, "chosen":
    the chosen node's index in tree["nodes"]}``.

    Examples
    --------
    >>> sibling_choice([[0, 0, 1, 1], [5, 0, 6, 1]], [5.5, 0, 6.5, 1], margin=0.0)["chosen"]
    2
    """
    tree = DynamicTree.from_aabbs(aabbs, margin)
    chosen = tree.best_sibling(tuple(float(v) for v in box))
    number = next(k for k, node in enumerate(tree.nodes()) if node is chosen)
    return {"tree": tree.structure(), "chosen": number}
