# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/broadphase/dynamic_tree_reads.py on the
# instructor's side.
"""How much of a dynamic tree a search reads: the node boxes read by ``pairs`` and ``best_sibling``.

A search that enters only the nodes its box meets (``pairs``) or only the subtrees that
could hold a cheaper sibling (``best_sibling``) reads a few boxes per level of the tree;
one that visits every node reads about 2 N per body, and a brute force over the tight
boxes reads none at all.  The graded tests count the reads to tell a tree search from a
scan that returns the same answers: on a few thousand boxes a fast brute force takes no
longer than the tree, so its time does not tell them apart.

Each node of the tree built by :meth:`DynamicTree.from_aabbs
<exercises.broadphase.dynamic_tree.DynamicTree.from_aabbs>` is turned into a
:class:`CountedNode`, the same node whose ``box`` attribute counts its reads.
"""
from __future__ import annotations

from .dynamic_tree import AABB_MARGIN, DynamicTree, TreeNode


class CountedNode(TreeNode):
    """A :class:`TreeNode` that adds 1 to :attr:`reads` each time its ``box`` is read."""

    reads = 0

    @property
    def box(self):
        CountedNode.reads += 1
        return self.__dict__["box"]

    @box.setter
    def box(self, value):
        self.__dict__["box"] = value


def counted_tree(aabbs, margin: float) -> DynamicTree:
    """The tree of ``aabbs`` (inserted in order) with every node counting its box reads."""
    tree = DynamicTree.from_aabbs(aabbs, margin)
    for node in list(tree.nodes()):
        node.__class__ = CountedNode
    CountedNode.reads = 0
    return tree


def pairs_reads(aabbs, margin: float = AABB_MARGIN) -> dict:
    """``{"pairs": sorted [i, j] lists, "reads": node boxes read by one pairs() call}``
    for the tree of ``aabbs`` (m).

    Examples
    --------
    >>> answer = pairs_reads([[0, 0, 1, 1], [1, 0, 2, 1], [5, 5, 6, 6]])
    >>> answer["pairs"], answer["reads"] >= 3
    ([[0, 1]], True)
    """
    tree = counted_tree(aabbs, margin)
    found = tree.pairs()
    return {"pairs": sorted([int(i), int(j)] for i, j in found), "reads": CountedNode.reads}


def sibling_reads(aabbs, boxes, margin: float = AABB_MARGIN) -> list[int]:
    """For each box of ``boxes`` (m), the node boxes read by one best_sibling(box) call in
    the tree of ``aabbs`` (built once; best_sibling changes nothing).

    Examples
    --------
    >>> reads = sibling_reads([[0, 0, 1, 1], [5, 0, 6, 1]], [[-50, -50, 50, 50], [5, 0, 6, 1]])
    >>> len(reads), all(r >= 1 for r in reads)
    (2, True)
    """
    tree = counted_tree(aabbs, margin)
    reads = []
    for box in boxes:
        CountedNode.reads = 0
        tree.best_sibling(tuple(float(v) for v in box))
        reads.append(CountedNode.reads)
    return reads
