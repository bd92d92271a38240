"""The dynamic AABB tree's invariants and costs, checked on the plain data of the student's tree.

``tree_structure`` and ``sibling_choice`` (library functions of
``exercises/broadphase/dynamic_tree.py``) return the tree the student's ``insert_leaf``,
``remove_leaf`` and ``move`` built, as nodes (root first) ``{"box", "height", "body",
"parent", "children"}``.  Checked here, independently of the student's code:

- :func:`structure_problem`: one root; parent and child links agree; an inner node has
  two children and its box is exactly the union of theirs (min and max are exact), its
  height 1 + the larger of theirs; every body that should be in the tree is in exactly
  one leaf, whose box is the fat box it should have (its tight box grown by the
  margin, or the one it kept while it moved inside it), and holds its tight box.
- :func:`sibling_costs`: what pairing a new leaf with each node would add to the
  tree's total inner perimeter (the cost ``best_sibling`` minimises).
- :func:`reinsertions`: which bodies leave their fat box frame by frame.
- :func:`median_split_cost`: the cost of a tree built top-down by median splits along
  the longer axis: a yardstick of a good tree that no insertion order changes.

Units: m.  Boxes are ``[min_x, min_y, max_x, max_y]``.
"""
from __future__ import annotations

import math

#: Most nodes a tree may have before the check stops reading it.
MAX_NODES = 400_000
#: Relative tolerance of a cost compared with the least (sums of perimeters in floats).
COST_TOLERANCE = 1e-9


def perimeter(box) -> float:
    return 2.0 * ((box[2] - box[0]) + (box[3] - box[1]))


def union(a, b) -> list[float]:
    return [min(a[0], b[0]), min(a[1], b[1]), max(a[2], b[2]), max(a[3], b[3])]


def grown(box, margin: float) -> list[float]:
    return [box[0] - margin, box[1] - margin, box[2] + margin, box[3] + margin]


def _inside(outer, inner) -> bool:
    return outer[0] <= inner[0] and inner[2] <= outer[2] and outer[1] <= inner[1] and inner[3] <= outer[3]


def well_formed(structure) -> str | None:
    """None if ``structure`` has the shape of tree data (any tree), else what is wrong."""
    if not isinstance(structure, dict) or not isinstance(structure.get("nodes"), list):
        return "expected {'margin': ..., 'nodes': [...]} (the tree's structure())"
    nodes = structure["nodes"]
    if len(nodes) > MAX_NODES:
        return f"the tree has {len(nodes)} nodes, more than {MAX_NODES}"
    for number, node in enumerate(nodes):
        if not isinstance(node, dict):
            return f"node {number} is not a dict"
        box, children, parent = node.get("box"), node.get("children"), node.get("parent")
        if not (isinstance(box, list) and len(box) == 4
                and all(isinstance(v, (int, float)) and math.isfinite(v) for v in box)):
            return f"node {number} has box {box!r}, not 4 finite numbers"
        if not (isinstance(children, list) and all(isinstance(c, int) and 0 <= c < len(nodes) for c in children)):
            return f"node {number} has children {children!r}, not indices of nodes"
        if parent is not None and not (isinstance(parent, int) and 0 <= parent < len(nodes)):
            return f"node {number} has parent {parent!r}, not None or the index of a node"
    return None


def structure_problem(structure, tight: dict[int, list[float]], fat: dict[int, list[float]]) -> str | None:
    """None if ``structure`` is a correct tree of the bodies of ``tight`` (body -> tight
    box) with leaf boxes ``fat`` (body -> the fat box it should have), else the first
    broken invariant, in words."""
    problem = well_formed(structure)
    if problem is not None:
        return problem
    nodes = structure["nodes"]
    if not tight:
        return None if not nodes else f"the tree of no bodies has {len(nodes)} nodes (root should be None)"
    if not nodes:
        return f"the tree holds no node but {len(tight)} bodies were inserted"
    roots = [k for k, node in enumerate(nodes) if node["parent"] is None]
    if roots != [0]:
        return f"the nodes without parent are {roots[:5]}: a tree has one, its root"
    seen: dict[int, int] = {}
    reached, stack = 0, [0]
    while stack:
        number = stack.pop()
        reached += 1
        if reached > len(nodes):
            return "the child links make a cycle"
        node = nodes[number]
        children = node["children"]
        where = f"node {number} (box {node['box']})"
        if not children:
            body = node.get("body")
            if not isinstance(body, int) or body not in tight:
                return f"leaf {where} holds body {body!r}, which is not one of the bodies in the tree"
            if body in seen:
                return f"body {body} is in two leaves ({seen[body]} and {number})"
            seen[body] = number
            if node.get("height") != 0:
                return f"leaf {where} has height {node.get('height')!r}, should be 0"
            if not _inside(node["box"], tight[body]):
                return (f"the fat box {node['box']} of body {body} does not hold its tight box {tight[body]}: "
                        "a pair of its tight box could be missed")
            want = fat[body]
            if any(abs(a - b) > 1e-9 * (1 + abs(b)) for a, b in zip(node["box"], want)):
                return f"the fat box of body {body} is {node['box']}, should be {want}"
            continue
        if len(children) != 2:
            return f"inner {where} has {len(children)} children; every inner node has 2"
        for child in children:
            if nodes[child]["parent"] != number:
                return f"node {child} is a child of node {number} but names node {nodes[child]['parent']} as parent"
        a, b = (nodes[c] for c in children)
        if node["box"] != union(a["box"], b["box"]):
            return (f"{where}: an inner node's box should be the smallest box holding its children's, "
                    f"{union(a['box'], b['box'])}")
        heights = [a.get("height"), b.get("height")]
        if not all(isinstance(h, int) for h in heights) or node.get("height") != 1 + max(heights):
            return f"{where} has height {node.get('height')!r}, its children {heights}: should be 1 + the larger"
        stack.extend(children)
    if reached != len(nodes):
        return f"{len(nodes) - reached} nodes cannot be reached from the root"
    missing = sorted(set(tight) - set(seen))
    if missing:
        return f"bodies {missing[:10]} are in no leaf"
    return None


def sibling_costs(structure, box) -> list[float]:
    """For each node (in the structure's order): the perimeter of its box joined with
    ``box``, plus what each of its ancestors' perimeters grows by to hold ``box``."""
    nodes = structure["nodes"]
    costs = [0.0] * len(nodes)
    stack = [(0, 0.0)]
    while stack:
        number, inherited = stack.pop()
        joined = perimeter(union(nodes[number]["box"], box))
        costs[number] = joined + inherited
        for child in nodes[number]["children"]:
            stack.append((child, inherited + joined - perimeter(nodes[number]["box"])))
    return costs


def reinsertions(frames, margin: float) -> tuple[list[list[int]], dict[int, list[float]]]:
    """(bodies reinserted at each frame, every body's fat box after the last frame): a
    body is reinserted when its tight box leaves its fat box, which is then its tight box
    grown by ``margin``."""
    fat = {body: grown(box, margin) for body, box in enumerate(frames[0])} if frames else {}
    moved: list[list[int]] = [[]] if frames else []
    for frame in frames[1:]:
        now = []
        for body, box in enumerate(frame):
            if not _inside(fat[body], box):
                fat[body] = grown(box, margin)
                now.append(body)
        moved.append(now)
    return moved, fat


def median_split_cost(boxes, margin: float) -> float:
    """Total inner perimeter of the tree built top-down: each node's boxes split at the
    median centre along the longer side of the node's box."""
    items = [grown(box, margin) for box in boxes]
    total, stack = 0.0, [items]
    while stack:
        group = stack.pop()
        if len(group) < 2:
            continue
        whole = group[0]
        for box in group[1:]:
            whole = union(whole, box)
        total += perimeter(whole)
        axis = 0 if whole[2] - whole[0] >= whole[3] - whole[1] else 1
        group = sorted(group, key=lambda b: b[axis] + b[axis + 2])
        half = len(group) // 2
        stack += [group[:half], group[half:]]
    return total
