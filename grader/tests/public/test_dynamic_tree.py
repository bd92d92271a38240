"""Dynamic AABB tree (your ``best_sibling``, ``insert_leaf``, ``remove_leaf``, ``move`` and
``pairs``) against brute-force pairs and the tree's invariants.

The functions called are written for you: ``pairs_dynamic_tree`` (insert every box,
then your ``pairs``), ``moving_pairs`` (insert, then ``move`` every body frame by frame),
``tree_structure`` (the tree after inserts, removals and moves, as plain data),
``sibling_choice`` (the node your ``best_sibling`` picks), and in
``broadphase/dynamic_tree_reads.py`` ``pairs_reads`` and ``sibling_reads`` (how many node
boxes your ``pairs`` and ``best_sibling`` read: a search of the tree, not a scan).  Expected pairs come from
:mod:`grader.oracles.brute_force`; the tree is checked by
:mod:`grader.oracles.aabb_tree_shape`, which never runs your code or the reference's.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from grader.harness.compare import pairs as compare_pairs
from grader.harness.compare import show
from grader.harness.credit import fail
from grader.harness.outcome import StudentCallFailed
from grader.oracles.aabb_tree_shape import (COST_TOLERANCE, grown, median_split_cost, reinsertions, sibling_costs,
                                            structure_problem, well_formed)
from grader.oracles.brute_force import describe_boxes, overlapping_pairs, pairs_figure
from grader.oracles.random_cases import clustered_aabbs, random_aabbs, resting_piles
from grader.oracles.scaling import sparse_scene

MODULE = "broadphase.dynamic_tree"
READS_MODULE = "broadphase.dynamic_tree_reads"
WHO = "your dynamic tree"
MARGIN = 0.1
#: A tree may cost at most this many times a top-down median-split tree of the same boxes
#: (measured: the reference 0.88 to 1.1; pairing every leaf with the root 7 to 14, with the leftmost leaf 5.5 to 8).
MAX_COST_RATIO = 1.5
#: Boxes of the sparse scene on which the reads of a search are counted.  Counts, not
#: timings: they are exact and the same on a loaded machine.  Measured on 1000 boxes
#: (per body and level of the tree in ``pairs``; share of the nodes per ``best_sibling``
#: call): the reference 2.9 and 5.7 %, without rotations 2.5 and 3.9 %, best_sibling
#: returning the root 194 (its large boxes make each search enter most of the tree),
#: best_sibling scanning every node over 100 %; on 2000 boxes the reference 3.0 and 2 to
#: 3 %.  They replace a growth check that timed pairs_dynamic_tree on 8 scenes of 500
#: boxes against one of 4000 (8,000 to 24,000 leaves inserted a submission, 1.5 s): it
#: caught the scanning best_sibling (7.6 times more time per box), which the read count
#: catches on 1000 boxes, and missed the brute force, which only the count catches.
SEARCH_SCENE = 1000
#: Node boxes one body's search in ``pairs`` may read per level of the tree (log2 N) on that
#: scene (measured: the reference 2.9; a search entering every node about 200).
MAX_PAIR_READS_PER_LEVEL = 12
#: Share of the tree's nodes one ``best_sibling`` call may read on average there (measured:
#: the reference 5.7 %, small boxes anywhere in the world; a scan of every node over 100 %).
MAX_SIBLING_READ_SHARE = 0.25


def check_pair_search(student) -> None:
    """Fail when ``pairs`` finds the pairs of a sparse scene without searching the tree (it
    reads fewer node boxes than there are bodies) or reads far more than a search entering
    only the nodes a body's box meets.  Counted, not timed: on a few thousand boxes the
    library's numpy brute force takes no longer than the tree."""
    boxes = sparse_scene(SEARCH_SCENE, 3)
    answer = student.call_once(READS_MODULE, "pairs_reads", boxes, MARGIN)  # asked by three tests
    reads = answer.get("reads") if isinstance(answer, dict) else None
    if not isinstance(reads, int):
        fail(f"{WHO}: pairs_reads should return {{'pairs': [...], 'reads': int}}, got {show(answer)[:200]}")
    count, levels = len(boxes), math.log2(len(boxes))
    if reads < count:
        fail(f"{WHO}: on {count} sparse boxes your pairs read {reads} boxes of the tree's nodes, fewer than one per "
             "body: it finds the pairs without searching the tree. A brute force (or the library's "
             "pairs_brute_force_numpy) gives the right pairs but is not the exercise: each body's search starts at "
             "the root and enters only the nodes whose box its tight box meets.")
    if reads > MAX_PAIR_READS_PER_LEVEL * levels * count:
        fail(f"{WHO}: on {count} sparse boxes your pairs read {reads} boxes of the tree's nodes, {reads / count:.0f} "
             f"per body, more than {MAX_PAIR_READS_PER_LEVEL} per level of the tree "
             f"({MAX_PAIR_READS_PER_LEVEL * levels:.0f}): each body's search should enter only the nodes whose box "
             "its tight box meets and skip every subtree whose box it misses.")


def check_sibling_search(student) -> None:
    """Fail when ``best_sibling`` reads a large share of the tree's nodes per call on a sparse
    scene (a scan of every node gives a least-cost node too, in N steps instead of about log N)."""
    boxes = sparse_scene(SEARCH_SCENE, 4)
    rng = np.random.default_rng(306)
    world = 2.0 * math.sqrt(SEARCH_SCENE)
    centres, halves = rng.uniform(0, world, (20, 2)), rng.uniform(0.05, 1.0, (20, 2))
    queries = np.hstack([centres - halves, centres + halves])
    try:
        reads = student.call_once(READS_MODULE, "sibling_reads", boxes, queries, MARGIN)  # by five tests
    except StudentCallFailed as exc:
        if exc.outcome.status != "timeout":
            raise
        fail(f"{WHO}: building a tree of {SEARCH_SCENE} sparse boxes (insert_leaf, best_sibling) and asking "
             f"best_sibling for {len(queries)} small boxes took too long: best_sibling should visit only the subtrees "
             "that could still hold a cheaper node, about log N steps, not every node.")
    if not (isinstance(reads, list) and len(reads) == len(queries) and all(isinstance(r, int) for r in reads)):
        fail(f"{WHO}: sibling_reads should return one int per query box, got {show(reads)[:200]}")
    nodes, mean = 2 * SEARCH_SCENE - 1, sum(reads) / len(reads)
    if mean > MAX_SIBLING_READ_SHARE * nodes:
        fail(f"{WHO}: in a tree of {SEARCH_SCENE} sparse boxes ({nodes} nodes) your best_sibling read on average "
             f"{mean:.0f} boxes of the tree's nodes per call for small new boxes, more than "
             f"{MAX_SIBLING_READ_SHARE:.0%} of the nodes: it should visit only the subtrees that could still hold a "
             "cheaper node (a subtree costs at least the new box's perimeter plus what its ancestors grow by), "
             "about log N steps, not all N.")


def pairs_text(pairs, limit: int = 10) -> str:
    pairs = sorted(tuple(p) for p in pairs)
    text = ", ".join(f"({i}, {j})" for i, j in pairs[:limit])
    return "{" + text + (", ..." if len(pairs) > limit else "") + "}"


def check_pair_scenes(student, scenes: list[tuple[np.ndarray, float]], label: str) -> None:
    """``pairs_dynamic_tree(boxes, margin)`` equals brute force on every scene (share right on failure),
    and the tree is searched, not scanned (the read counts, asked once a submission)."""
    answers = student.call_many(MODULE, "pairs_dynamic_tree", scenes)
    wrong = []
    for (boxes, margin), answer in zip(scenes, answers):
        want = overlapping_pairs(boxes)
        problem, missed, extra = compare_pairs(answer, want)
        if problem is not None:
            wrong.append((boxes, margin, want, answer, problem, missed, extra))
    if wrong:
        boxes, margin, want, answer, problem, missed, extra = wrong[0]
        fail(f"{WHO}, {label}: {len(wrong)} of {len(scenes)} scenes wrong. The first: pairs_dynamic_tree("
             f"aabbs={describe_boxes(boxes)}, margin={margin:g}) should return {pairs_text(want)}, got "
             f"{show(answer)}: {problem}", fraction=1 - len(wrong) / len(scenes),
             figure=pairs_figure(boxes, missed, extra, f"pairs_dynamic_tree: {label}"))
    check_pair_search(student)
    check_sibling_search(student)


def moving_scene(rng: np.random.Generator, count: int, frames: int, world: float, step: float) -> np.ndarray:
    """(frames, count, 4) boxes drifting by up to ``step`` m a frame, some far jumps."""
    boxes = random_aabbs(rng, count, world=world)
    velocity = rng.uniform(-step, step, (count, 2))
    out = [boxes]
    for _ in range(frames - 1):
        boxes = boxes + np.tile(velocity, 2)
        jump = rng.random(count) < 0.05                               # a few teleports
        boxes[jump] += np.tile(rng.uniform(-world / 2, world / 2, (int(jump.sum()), 2)), 2)
        out.append(boxes)
    return np.array(out)


def check_moving(student, scenes: list[tuple[np.ndarray, float]], label: str) -> None:
    """``moving_pairs(frames, margin)``: every frame's pairs are brute force's and exactly the
    bodies whose tight box left their fat box are reinserted."""
    answers = student.call_many(MODULE, "moving_pairs", scenes)
    for (frames, margin), answer in zip(scenes, answers):
        call = f"moving_pairs({len(frames)} frames of {frames.shape[1]} boxes, margin={margin:g})"
        if not (isinstance(answer, dict) and isinstance(answer.get("pairs"), list)
                and isinstance(answer.get("reinserted"), list) and len(answer["pairs"]) == len(frames)
                and len(answer["reinserted"]) == len(frames)):
            fail(f"{WHO}, {label}: {call} should return {{'pairs': [...], 'reinserted': [...]}} with one list per "
                 f"frame, got {show(answer)}")
        want_moved, _ = reinsertions(frames.tolist(), margin)
        for frame, boxes in enumerate(frames):
            want = overlapping_pairs(boxes)
            problem, missed, extra = compare_pairs(answer["pairs"][frame], want)
            if problem is not None:
                fail(f"{WHO}, {label}: {call}, frame {frame}: the pairs should be {pairs_text(want)}, got "
                     f"{pairs_text(answer['pairs'][frame])}: {problem}",
                     figure=pairs_figure(boxes, missed, extra, f"moving_pairs: {label}, frame {frame}"))
            got = answer["reinserted"][frame]
            if got != want_moved[frame]:
                fail(f"{WHO}, {label}: {call}, frame {frame}: move should reinsert exactly the bodies whose tight "
                     f"box left their fat box ({margin:g} m around the tight box when last inserted), "
                     f"{want_moved[frame][:12]}, but reinserted {show(got)}. A body that stays inside its fat "
                     "box keeps its leaf (the point of the margin); one that leaves it must be reinserted.")


def check_structures(student, cases: list[tuple], label: str) -> None:
    """``tree_structure(boxes, margin, removed, moves)`` keeps every invariant."""
    calls = [(boxes, margin, removed, moves) for boxes, margin, removed, moves in cases]
    answers = student.call_many(MODULE, "tree_structure", calls)
    for (boxes, margin, removed, moves), answer in zip(cases, answers):
        tight = {body: box for body, box in enumerate(boxes.tolist()) if body not in set(removed)}
        fat = {body: grown(box, margin) for body, box in tight.items()}
        if moves is not None:
            for body, box in enumerate(moves.tolist()):
                if body in tight:
                    _, after = reinsertions([[tight[body]], [box]], margin)   # inserted, then moved once
                    tight[body], fat[body] = box, after[0]
        problem = structure_problem(answer, tight, fat)
        if problem is not None:
            steps = f"{len(boxes)} boxes inserted" + (f", {len(removed)} removed" if len(removed) else "") + (
                ", every body moved" if moves is not None else "")
            fail(f"{WHO}, {label}: tree_structure(aabbs={describe_boxes(boxes)}, margin={margin:g}) [{steps}]: "
                 f"{problem}")


#: Bodies 0 and 1 side by side, body 2 far to the right, body 3 far to the left: inserted in
#: this order, body 3's least-cost sibling is the root (adds 64.8 m of perimeter; the pair of
#: bodies 0 and 1 adds 86.8 m, body 2 104.8 m), of height 2 with children of heights 1
#: (bodies 0 and 1) and 0 (body 2).  Derived by hand from the docstrings.
ROTATION_BOXES = [[0, 0, 1, 1], [1, 0, 2, 1], [10, 0, 11, 1], [-20, 0, -19, 1]]


def check_rotation(student) -> None:
    """The new parent is balanced too: pairing body 3 with the root of height 2 makes a new
    root whose children's heights are 2 and 0, which :meth:`balance` rotates (the old root
    comes up, body 2 goes down beside body 3): the tree's height stays 2."""
    answer = student.call(MODULE, "tree_structure", np.array(ROTATION_BOXES, dtype=float), MARGIN)
    problem = well_formed(answer) or (None if answer["nodes"] else "the tree is empty")
    if problem is not None:
        fail(f"{WHO}: tree_structure(aabbs={describe_boxes(np.array(ROTATION_BOXES))}) returned "
             f"{show(answer)[:300]}: {problem}")
    height = answer["nodes"][0].get("height")
    if height != 2:
        fail(f"{WHO}: after inserting {describe_boxes(np.array(ROTATION_BOXES))} in this order (margin {MARGIN:g}) "
             f"the root has height {show(height)}, should be 2.  Body 3's least-cost sibling is the root (height 2, "
             "its children of heights 1 and 0), so the new parent of the root and body 3 has children of heights "
             "2 and 0, and balance, called on every node from the new parent up, rotates there: the old root "
             "comes up and body 2 goes down beside body 3.  Give the new parent its height (1 + its children's "
             "larger) before balance reads it, and start the walk up at the new parent itself.")


def check_siblings(student, cases: list[tuple], label: str) -> None:
    """``sibling_choice(boxes, box, margin)`` picks a node of least cost."""
    answers = student.call_many(MODULE, "sibling_choice", cases)
    for (boxes, box, margin), answer in zip(cases, answers):
        tree = answer.get("tree") if isinstance(answer, dict) else None
        problem = well_formed(tree) or (None if tree["nodes"] else "the tree is empty")
        chosen = answer.get("chosen") if isinstance(answer, dict) else None
        if problem is not None or not (isinstance(chosen, int) and 0 <= chosen < len(tree["nodes"])):
            fail(f"{WHO}, {label}: sibling_choice should return the tree and the index of the chosen node, got "
                 f"{show(answer)[:300]} ({problem or 'no such node'})")
        costs = sibling_costs(tree, box)
        best = min(range(len(costs)), key=costs.__getitem__)
        if costs[chosen] > costs[best] * (1 + COST_TOLERANCE):
            node, other = tree["nodes"][chosen], tree["nodes"][best]
            fail(f"{WHO}, {label}: in the tree of {describe_boxes(boxes)} (margin {margin:g}), best_sibling"
                 f"({show(list(box))}) chose the node with box {node['box']} (body {node['body']}), which would add "
                 f"{costs[chosen]:.6g} m of inner perimeter; the node with box {other['box']} (body {other['body']})"
                 f" adds only {costs[best]:.6g} m (its new parent's perimeter plus its ancestors' growth).")
    check_sibling_search(student)


def check_quality(student, scenes: list[tuple[np.ndarray, str]], label: str) -> None:
    """The tree's cost stays within MAX_COST_RATIO of a median-split tree's."""
    answers = student.call_many(MODULE, "tree_structure", [(boxes, MARGIN) for boxes, _ in scenes])
    for (boxes, note), answer in zip(scenes, answers):
        cost = answer.get("cost") if isinstance(answer, dict) else None
        yardstick = median_split_cost(boxes.tolist(), MARGIN)
        if not isinstance(cost, (int, float)) or not cost <= MAX_COST_RATIO * yardstick:
            fail(f"{WHO}, {label} ({note}, {len(boxes)} boxes): the tree's cost (total perimeter of the inner "
                 f"nodes) is {show(cost)} m, more than {MAX_COST_RATIO:g} times the {yardstick:.5g} m of a tree "
                 "split top-down at medians: each new leaf should go where it adds the least perimeter "
                 "(best_sibling), and rotations keep the tree from growing lopsided.")


# Special cases, with the pairs derived by hand (index pairs i < j).
SPECIAL_CASES = [
    ("no box", np.zeros((0, 4)), 0.1, []),
    ("one box", [[1, 1, 2, 3]], 0.1, []),
    ("two boxes touching along an edge", [[0, 0, 1, 1], [1, 0.5, 2, 2]], 0.1, [(0, 1)]),
    ("two boxes touching at a corner, margin 0", [[0, 0, 1, 1], [1, 1, 2, 2]], 0.0, [(0, 1)]),
    ("fat boxes overlap, tight boxes 0.15 m apart", [[0, 0, 1, 1], [1.15, 0, 2, 1]], 0.1, []),
    ("a zero-size box inside another and one on its edge", [[0, 0, 2, 2], [1, 1, 1, 1], [2, 0.5, 2, 0.5]], 0.1,
     [(0, 1), (0, 2)]),
    ("two zero-size boxes at one point", [[3, 3, 3, 3], [3, 3, 3, 3], [3.2, 3, 3.2, 3]], 0.1, [(0, 1)]),
    ("five equal boxes", [[0, 0, 1, 1]] * 5, 0.1, [(i, j) for i in range(5) for j in range(i + 1, 5)]),
    ("boxes at negative coordinates", [[-1, -1, 0, 0], [-0.5, -0.5, -0.25, -0.25], [0, 0, 1, 1]], 0.1,
     [(0, 1), (0, 2)]),
]


@pytest.mark.points(2)
@pytest.mark.title("Dynamic tree: touching, zero-size and equal boxes")
def test_special_cases(student):
    cases = [(np.asarray(boxes, dtype=float).reshape(-1, 4), margin) for _, boxes, margin, _ in SPECIAL_CASES]
    answers = student.call_many(MODULE, "pairs_dynamic_tree", cases)
    for (name, _, margin, want), (boxes, _), answer in zip(SPECIAL_CASES, cases, answers):
        problem, missed, extra = compare_pairs(answer, set(want))
        if problem is not None:
            fail(f"{WHO}, {name}: pairs_dynamic_tree(aabbs={describe_boxes(boxes)}, margin={margin:g}) should "
                 f"return {pairs_text(want)} (tight boxes overlapping or touching), got {show(answer)}: {problem}",
                 figure=pairs_figure(boxes, missed, extra, f"pairs_dynamic_tree: {name}"))


@pytest.mark.points(2)
@pytest.mark.title("Dynamic tree: moving boxes, pairs and reinsertions frame by frame")
def test_moving(student):
    rng = np.random.default_rng(302)
    scenes = [(moving_scene(rng, 40, 8, 12.0, step), margin) for step, margin in
              ((0.03, 0.1), (0.08, 0.1), (0.2, 0.1), (0.05, 0.0), (0.05, 0.3))]
    check_moving(student, scenes, "boxes drifting, a few jumping")


@pytest.mark.points(2)
@pytest.mark.title("Dynamic tree: the tree after inserts, removals and moves keeps every invariant")
def test_structure(student):
    rng = np.random.default_rng(303)
    cases = [(np.array([[0, 0, 1, 1]], dtype=float), 0.1, [], None),
             (np.array([[0, 0, 1, 1], [3, 0, 4, 1], [0, 3, 1, 4]], dtype=float), 0.1, [1], None),
             (np.array([[0, 0, 1, 1], [3, 0, 4, 1]], dtype=float), 0.1, [0, 1], None)]
    for k in range(5):
        boxes = random_aabbs(rng, 40, world=15.0)
        removed = rng.choice(40, 10, replace=False).tolist() if k % 2 else []
        moves = boxes + np.tile(rng.uniform(-0.15, 0.15, (40, 2)), 2) if k >= 2 else None
        cases.append((boxes, MARGIN, removed, moves))
    check_structures(student, cases, "small trees")
    check_rotation(student)


@pytest.mark.points(2)
@pytest.mark.title("Dynamic tree: best_sibling picks a node of least cost")
def test_best_sibling(student):
    rng = np.random.default_rng(304)
    three = np.array([[0, 0, 1, 1], [1, 0, 2, 1], [10, 0, 11, 1]], dtype=float)   # root: (bodies 0, 1), body 2
    cases = [(three, [10.5, 0.5, 11.5, 1.0], 0.0), (three, [-50, -50, 50, 50], 0.0),
             # Near ties with the root (24 m): body 2 adds 23.4 m, less than the root by 0.6 m; then the
             # root adds 24.4 m, less by 0.4 m than the pair of bodies 0 and 1 (24.4 m + the root's 0.4 m).
             (three, [0.3, 0.0, 11.0, 1.0], 0.0), (three, [-0.2, 0.0, 11.0, 1.0], 0.0)]
    for _ in range(12):
        boxes = random_aabbs(rng, int(rng.integers(5, 60)), world=20.0)
        centre = rng.uniform(-12, 12, 2)
        half = rng.uniform(0.05, 3.0, 2)
        cases.append((boxes, [*(centre - half), *(centre + half)], MARGIN))
    check_siblings(student, cases, "random trees")


@pytest.mark.points(1)
@pytest.mark.title("Dynamic tree: the tree's cost stays near a well-built tree's")
def test_quality(student):
    rng = np.random.default_rng(305)
    boxes = random_aabbs(rng, 400, world=2 * math.sqrt(400))
    check_quality(student, [(boxes, "random order"), (clustered_aabbs(rng, 400), "clustered")], "tree quality")


@pytest.mark.points(3)
@pytest.mark.partial_credit
@pytest.mark.title("Dynamic tree: pairs of random and clustered boxes")
def test_random(student):
    rng = np.random.default_rng(301)
    scenes = [(random_aabbs(rng, 80, world=25.0) if k % 3 else clustered_aabbs(rng, 80), (0.1, 0.0, 0.5)[k % 3])
              for k in range(18)]
    # Resting crates: every box touches its neighbours exactly, along an edge or at a corner.
    piles = np.random.default_rng(307)
    scenes += [(resting_piles(piles, 80, origin=piles.integers(-25, 5, 2)), (0.1, 0.0)[k % 2]) for k in range(4)]
    check_pair_scenes(student, scenes, "random boxes and resting crates")
