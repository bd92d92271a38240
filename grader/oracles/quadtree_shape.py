"""The quadtree's invariants, checked here on the plain data of the student's own tree.

``tree_structure`` (a library function of ``exercises/broadphase/quadtree.py``)
returns the tree the student's ``insert`` and ``split`` built, as nodes in depth-first
order.  Returned pairs alone do not reveal a tree that never splits (right pairs, all
N (N - 1) / 2 tests), splits too early or too deep, or keeps a body at a node it does
not belong to; :func:`structure_problem` checks, independently of the student's code:

- every node has 0 or 4 children, which are its quarters (SW, SE, NW, NE) one level
  deeper; no node is deeper than ``max_depth`` or, below the root, smaller than
  ``min_node_area``;
- every body is stored exactly once; a body below the root lies inside its node and
  does not touch any ancestor's splitting lines; a body at an inner node touches one of
  that node's splitting lines (or, at the root, sticks out of it);
- a leaf holds more than ``max_bodies_per_node`` bodies only when the depth or area
  rule forbids splitting it; an inner node's subtree holds more than
  ``max_bodies_per_node`` bodies (it was split because it had to be).

Units: m.  Boxes are ``[min_x, min_y, max_x, max_y]``; touching counts as touching.
"""
from __future__ import annotations

import math

#: Most nodes a tree may have before the check stops reading it (the parent's work is capped).
MAX_NODES = 200_000


def _inside(box, bounds) -> bool:
    return bounds[0] <= box[0] and box[2] <= bounds[2] and bounds[1] <= box[1] and box[3] <= bounds[3]


def _touches_lines(box, bounds) -> bool:
    mid_x, mid_y = (bounds[0] + bounds[2]) / 2, (bounds[1] + bounds[3]) / 2
    return box[0] <= mid_x <= box[2] or box[1] <= mid_y <= box[3]


def _quarters(bounds) -> list[list[float]]:
    lo_x, lo_y, hi_x, hi_y = bounds
    mid_x, mid_y = (lo_x + hi_x) / 2, (lo_y + hi_y) / 2
    return [[lo_x, lo_y, mid_x, mid_y], [mid_x, lo_y, hi_x, mid_y], [lo_x, mid_y, mid_x, hi_y],
            [mid_x, mid_y, hi_x, hi_y]]


def _well_formed(structure) -> str | None:
    if not isinstance(structure, dict) or not isinstance(structure.get("nodes"), list):
        return "tree_structure must return {'root_bounds': [...], 'nodes': [...]}"
    nodes = structure["nodes"]
    if not nodes:
        return "the tree has no root node"
    if len(nodes) > MAX_NODES:
        return f"the tree has {len(nodes)} nodes (more than {MAX_NODES}): it splits far too much"
    for number, node in enumerate(nodes):
        if not isinstance(node, dict):
            return f"node {number} is not a dict"
        bounds, bodies, children = node.get("bounds"), node.get("bodies"), node.get("children")
        if not (isinstance(bounds, list) and len(bounds) == 4
                and all(isinstance(v, (int, float)) and math.isfinite(v) for v in bounds)):
            return f"node {number} has bounds {bounds!r}, not 4 finite numbers"
        if not (isinstance(bodies, list) and all(isinstance(i, int) and not isinstance(i, bool) for i in bodies)):
            return f"node {number} has bodies {bodies!r}, not a list of body indices"
        if not (isinstance(children, list)
                and all(isinstance(c, int) and not isinstance(c, bool) and 0 < c < len(nodes) for c in children)):
            return f"node {number} has children {children!r}, not indices of other nodes"
        if not isinstance(node.get("depth"), int):
            return f"node {number} has no integer depth"
    return None


def structure_problem(structure, aabbs, max_bodies_per_node: int, min_node_area: float = 0.0,
                      max_depth: int = 16, root_bounds=None) -> str | None:
    """None when the tree keeps every invariant of the module docstring, else the first
    broken one in words (naming the node by its depth and bounds, and the body)."""
    problem = _well_formed(structure)
    if problem:
        return problem
    nodes = structure["nodes"]
    boxes = [[float(v) for v in box] for box in aabbs]
    if nodes[0]["depth"] != 0:
        return f"the root has depth {nodes[0]['depth']}; the root's depth is 0"
    if root_bounds is not None and [float(v) for v in nodes[0]["bounds"]] != [float(v) for v in root_bounds]:
        return f"the root's bounds are {nodes[0]['bounds']}, expected the given bounds {list(root_bounds)}"
    stored: dict[int, int] = {}
    visited = set()
    stack = [(0, [])]  # (node number, numbers of its ancestors)
    subtree_bodies = [0] * len(nodes)
    order = []
    while stack:
        number, ancestors = stack.pop()
        if number in visited:
            return f"node {number} is reached twice: the tree is not a tree"
        visited.add(number)
        order.append((number, ancestors))
        node = nodes[number]
        where = f"the node at depth {node['depth']} with bounds {node['bounds']}"
        children = node["children"]
        if len(children) not in (0, 4):
            return f"{where} has {len(children)} children; a quadtree node has 0 or 4"
        if children and [nodes[c]["bounds"] for c in children] != _quarters(node["bounds"]):
            return f"{where}: its children are not its four quarters in the order SW, SE, NW, NE"
        if any(nodes[c]["depth"] != node["depth"] + 1 for c in children):
            return f"{where}: a child's depth is not the parent's depth + 1"
        if node["depth"] > max_depth:
            return f"{where} is deeper than max_depth = {max_depth}"
        bounds = node["bounds"]
        area = (bounds[2] - bounds[0]) * (bounds[3] - bounds[1])
        if ancestors and area < min_node_area:
            return f"{where} has area {area:g} m^2 < min_node_area = {min_node_area:g}"
        for index in node["bodies"]:
            if not 0 <= index < len(boxes):
                return f"{where} stores body {index}, but there are only {len(boxes)} bodies"
            if index in stored:
                return f"body {index} is stored twice"
            stored[index] = number
            box = boxes[index]
            if ancestors and not _inside(box, bounds):
                return f"body {index} {box} is stored in {where}, but it is not inside that node"
            for ancestor in ancestors:
                if _touches_lines(box, nodes[ancestor]["bounds"]):
                    return (f"body {index} {box} is stored in {where}, below a node whose splitting lines it "
                            "touches: a box touching or crossing a splitting line has no child, it must stay at "
                            "that node, or a partner touching it from across the line can end in another subtree "
                            "and be missed")
            if children and not _touches_lines(box, bounds) and (ancestors or _inside(box, bounds)):
                return (f"body {index} {box} is stored at the inner {where}, but one of its children holds it "
                        "whole: it must go down")
        for child in reversed(children):
            stack.append((child, ancestors + [number]))
    missing = [i for i in range(len(boxes)) if i not in stored]
    if missing:
        return f"bodies {missing[:10]} are not stored in any node"
    for number, ancestors in reversed(order):  # children before parents
        node = nodes[number]
        subtree_bodies[number] = len(node["bodies"]) + sum(subtree_bodies[c] for c in node["children"])
    for number, _ in order:
        node = nodes[number]
        bounds = node["bounds"]
        where = f"the node at depth {node['depth']} with bounds {bounds}"
        area = (bounds[2] - bounds[0]) * (bounds[3] - bounds[1])
        if not node["children"] and len(node["bodies"]) > max_bodies_per_node \
                and node["depth"] < max_depth and area / 4 >= min_node_area:
            return (f"the leaf at depth {node['depth']} with bounds {bounds} holds {len(node['bodies'])} bodies > "
                    f"max_bodies_per_node = "
                    f"{max_bodies_per_node}, and neither max_depth nor min_node_area forbids splitting it: "
                    "a full leaf must split")
        if node["children"] and subtree_bodies[number] <= max_bodies_per_node:
            return (f"{where} was split although it and everything below it hold only {subtree_bodies[number]} "
                    f"bodies <= max_bodies_per_node = {max_bodies_per_node}: split only a leaf holding more")
    return None
