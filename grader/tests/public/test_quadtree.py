"""Quadtree (``pairs_quadtree`` over your ``Quadtree``) against brute-force pairs of boxes.

``pairs_quadtree(aabbs, bounds, max_bodies_per_node)`` is written for you; it builds a
``Quadtree`` with your ``insert`` (which uses ``child_holding`` and ``split``) and
returns your ``pairs()``.  Every expected set of pairs comes from
:mod:`grader.oracles.brute_force` or is written here as a literal derived by hand.
The cases the notes worry about each have a test: bodies on and across splitting
lines, many bodies at one point, bodies outside the root, negative coordinates.
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from grader.harness.compare import pairs as compare_pairs
from grader.harness.compare import show
from grader.harness.credit import fail
from grader.oracles.brute_force import describe_boxes, overlapping_pairs, pairs_figure, smallest_wrong_scene
from grader.oracles.random_cases import clustered_aabbs, random_aabbs, resting_piles
from grader.oracles.scaling import growth_problem
from grader.harness.outcome import StudentCallFailed, StudentCallStopped

MODULE = "broadphase.quadtree"
FUNCTION = "pairs_quadtree"
WHO = "pairs_quadtree (your Quadtree.insert, child_holding, split and pairs)"
ALGORITHM = ("a quadtree (each body tested against its own node and the nodes below it that its box touches, "
             "not against every body)")


def check_algorithm(student) -> None:
    """Fail every pairs test when pairs_quadtree does the work of a brute force (measured
    once a session, bounds None): right pairs from testing every pair are not the exercise."""
    problem = growth_problem(student, MODULE, FUNCTION, lambda boxes: (boxes,), ALGORITHM)
    if problem is not None:
        fail(f"{problem} (pairs_quadtree runs your Quadtree.insert, split and pairs)")


# Comparing and reporting -----------------------------------------------------------------
def pairs_text(pairs, limit: int = 10) -> str:
    pairs = sorted(pairs)
    text = ", ".join(f"({i}, {j})" for i, j in pairs[:limit])
    return "{" + text + (", ..." if len(pairs) > limit else "") + "}"


def call_text(boxes, bounds, max_bodies: int) -> str:
    where = "None (the boxes' own bounds)" if bounds is None else show([float(b) for b in bounds])
    return f"{FUNCTION}(aabbs={describe_boxes(boxes)}, bounds={where}, max_bodies_per_node={max_bodies})"


def figure_bounds(boxes, bounds):
    """The root to draw: ``bounds``, or for None the boxes' bounds as the module's
    docstring defines them (a zero span widened on the positive side)."""
    if bounds is not None:
        return bounds
    boxes = np.asarray(boxes, dtype=float).reshape(-1, 4)
    lo_x, lo_y, hi_x, hi_y = boxes[:, 0].min(), boxes[:, 1].min(), boxes[:, 2].max(), boxes[:, 3].max()
    span = max(hi_x - lo_x, hi_y - lo_y) or 1.0
    return [lo_x, lo_y, hi_x if hi_x > lo_x else lo_x + span, hi_y if hi_y > lo_y else lo_y + span]


def wrong_answer(boxes, bounds, max_bodies: int, answer, want=None) -> tuple[str, dict] | None:
    """None if ``answer`` is the right set of pairs (brute force unless ``want``), else
    (message, figure)."""
    want = overlapping_pairs(boxes) if want is None else set(want)
    problem, missed, extra = compare_pairs(answer, want)
    if problem is None:
        return None
    message = (f"{call_text(boxes, bounds, max_bodies)} should return the pairs {pairs_text(want)} (boxes "
               f"overlapping or touching, i < j), got {show(answer)}: {problem}")
    return message, pairs_figure(boxes, missed, extra, f"{FUNCTION}, max_bodies_per_node = {max_bodies}",
                                 bounds=figure_bounds(boxes, bounds))


def call_or_timeout(student, boxes, bounds, max_bodies: int, label: str, timeout: float = 5.0):
    """The answer of one call; a call that does not finish in ``timeout`` s fails the
    test naming the scene (outside Hypothesis only: it would retry a hanging call)."""
    result = student.raw(MODULE, FUNCTION, boxes, bounds, max_bodies, timeout=timeout)
    if result.status == "timeout":
        fail(f"{WHO}, {label}: {call_text(boxes, bounds, max_bodies)} did not finish within {timeout:g} s (the "
             "reference takes milliseconds). Splitting must stop: no split can separate copies of one point, so "
             "the depth rule (max_depth) has to end it.",
             figure=pairs_figure(boxes, [], [], f"{FUNCTION}: {label}", bounds=figure_bounds(boxes, bounds)))
    return student.value_of(result, f"{MODULE}.{FUNCTION}")


def check_scene(student, boxes, bounds, max_bodies: int, label: str) -> None:
    """One scene, all or nothing (the category and @given tests)."""
    check_algorithm(student)
    boxes = np.asarray(boxes, dtype=float).reshape(-1, 4)
    found = wrong_answer(boxes, bounds, max_bodies, student.call(MODULE, FUNCTION, boxes, bounds, max_bodies))
    if found is not None:
        fail(f"{WHO}, {label}: {found[0]}", figure=found[1])


def check_scenes(student, scenes: list[tuple], label: str) -> None:
    """Seeded scenes ``(boxes, bounds, max_bodies)`` in one round trip; fail with the
    share of right scenes and a failing scene cut down to a few boxes."""
    check_algorithm(student)
    answers = student.call_many(MODULE, FUNCTION, scenes)
    wrong = [(scene, found) for scene, answer in zip(scenes, answers)
             if (found := wrong_answer(*scene, answer)) is not None]
    if not wrong:
        return
    (boxes, bounds, max_bodies), first = wrong[0]

    def wrong_many(subscenes):
        got = student.call_many(MODULE, FUNCTION, [(sub, bounds, max_bodies) for sub in subscenes])
        return [wrong_answer(sub, bounds, max_bodies, answer) is not None for sub, answer in zip(subscenes, got)]

    try:
        small = smallest_wrong_scene(boxes, wrong_many)
        found = wrong_answer(small, bounds, max_bodies, student.call(MODULE, FUNCTION, small, bounds, max_bodies))
    except (StudentCallFailed, StudentCallStopped):
        found = None
    found = found or first
    kept = len(found[1]["aabbs"])
    shown = f"Cut down to {kept} boxes: {found[0]}" if kept < len(boxes) else f"The first: {found[0]}"
    fail(f"{WHO}, {label}: {len(wrong)} of {len(scenes)} scenes wrong ({len(boxes)} boxes in the first). {shown}",
         fraction=1 - len(wrong) / len(scenes), figure=found[1])


def arranged(draw, boxes: list) -> list:
    """The boxes rotated and maybe reversed: any box can be first or last (cheaper to
    draw than a permutation, and it shrinks to the order the scene was built in)."""
    k = draw(st.integers(0, len(boxes) - 1))
    boxes = boxes[k:] + boxes[:k]
    return boxes[::-1] if draw(st.booleans()) else boxes


# Hypothesis strategies: each generates one category only, so a shrunk example stays in it.
ROOT = (0.0, 0.0, 16.0, 16.0)
#: Splitting lines of ROOT at depths 0, 1 and 2, in half metres (the strategies' unit).
LINES = (16, 8, 24, 4, 12, 20, 28)
HALF = 0.5


def scaled(box, unit: float) -> list[float]:
    return [v * unit for v in box]


@st.composite
def on_split_lines(draw, offset: float = 0.0):
    """(boxes, bounds, max_bodies): boxes in ROOT (moved by ``offset``) with half-metre
    coordinates, and a pair meeting on a splitting line: either A ends on the line and
    B starts there (touching across it, an edge or a corner), or A crosses the line
    and B, beside it, overlaps A.  Filler boxes make the tree split."""
    line = draw(st.sampled_from(LINES))
    kind = draw(st.sampled_from(("touching", "crossing")))
    w, bw = draw(st.integers(1, min(6, line))), draw(st.integers(1, min(6, 32 - line)))
    h, bh = draw(st.integers(0, 6)), draw(st.integers(0, 6))
    y = draw(st.integers(0, 32 - h))
    by = draw(st.integers(max(0, y - bh), min(32 - bh, y + h)))        # the y ranges meet
    if kind == "touching":
        a, b = [line - w, y, line, y + h], [line, by, line + bw, by + bh]
    else:
        a = [line - w, y, line + draw(st.integers(1, min(6, 32 - line))), y + h]
        start = draw(st.integers(max(0, a[0] - 1), min(31, a[2])))     # the x ranges meet
        b = [start, by, start + 1, by + bh]                            # beside the line or across it
        if draw(st.booleans()):
            a, b = b, a
    pair = [a, b]
    if draw(st.booleans()):                                           # the same along y
        pair = [[p[1], p[0], p[3], p[2]] for p in pair]
    fillers = [divmod(v, 32) for v in draw(st.lists(st.integers(0, 32 * 32 - 1), max_size=8))]
    boxes = pair + [[x, y2, x + 1, y2 + 1] for x, y2 in fillers]
    boxes = [[v * HALF + offset for v in box] for box in arranged(draw, boxes)]
    bounds = [v + offset for v in ROOT]
    return boxes, bounds, draw(st.sampled_from((1, 2)))


@st.composite
def coincident_boxes(draw):
    """(boxes, bounds, max_bodies): two to twelve copies of one box (often a point),
    coordinates in tenths of a metre, and a few other boxes; no split can separate
    the copies, so they end in one node however deep the tree goes."""
    x, y = draw(st.integers(0, 90)), draw(st.integers(0, 90))
    w, h = draw(st.sampled_from((0, 0, 1, 3))), draw(st.sampled_from((0, 0, 1, 3)))
    copies = [[x, y, x + w, y + h]] * draw(st.integers(2, 12))
    others = [[ox, oy, ox + draw(st.integers(0, 10)), oy + draw(st.integers(0, 10))]
              for ox, oy in draw(st.lists(st.tuples(st.integers(0, 90), st.integers(0, 90)), max_size=4))]
    boxes = [scaled(b, 0.1) for b in arranged(draw, copies + others)]
    bounds = draw(st.sampled_from((None, (0.0, 0.0, 10.0, 10.0))))
    return boxes, bounds, draw(st.sampled_from((1, 2, 3)))


def mirrored(box, size: float = 8.0) -> list[float]:
    return [size - box[2], box[1], size - box[0], box[3]]


def swapped(box) -> list[float]:
    return [box[1], box[0], box[3], box[2]]


@st.composite
def outside_bounds(draw):
    """(boxes, bounds=(0, 0, 8, 8), max_bodies): a pair with a box not inside the root:
    it touches an inside box on the root's edge from outside, or sticks into the root
    over an inside box, or both boxes lie outside.  Built on the left side, then
    mirrored or turned to any side; filler boxes inside make the tree split."""
    kind = draw(st.sampled_from(("touching_edge", "sticking_in", "both_outside")))
    h, bh = draw(st.integers(0, 4)), draw(st.integers(0, 4))
    y = draw(st.integers(0, 16 - h))
    by = draw(st.integers(y - bh, y + h))                             # the y ranges meet
    if kind == "touching_edge":                                       # both edges on x = 0
        a, b = [-draw(st.integers(1, 4)), by, 0, by + bh], [0, y, draw(st.integers(0, 4)), y + h]
    elif kind == "sticking_in":
        reach = draw(st.integers(0, 12))
        a = [-draw(st.integers(1, 6)), by, reach, by + bh]
        start = draw(st.integers(0, reach))
        b = [start, y, start + draw(st.integers(0, 4)), y + h]
    else:                                                             # x ranges meet left of x = 0
        ax0 = draw(st.integers(-8, -1))
        ax1 = draw(st.integers(ax0, -1))
        bx0 = draw(st.integers(ax0 - 3, ax1))
        a, b = [ax0, by, ax1, by + bh], [bx0, y, draw(st.integers(max(bx0, ax0), 0)), y + h]
    fillers = [[x, y2, x + 1, y2 + 1] for x, y2 in map(lambda v: divmod(v, 16),
                                                        draw(st.lists(st.integers(0, 255), max_size=6)))]
    boxes = [scaled(box, HALF) for box in [a, b] + fillers]
    if draw(st.booleans()):
        boxes = [mirrored(box) for box in boxes]
    if draw(st.booleans()):
        boxes = [swapped(box) for box in boxes]
    return arranged(draw, boxes), (0.0, 0.0, 8.0, 8.0), draw(st.sampled_from((1, 2)))


# Special cases, with the pairs derived by hand (index pairs i < j).
NEXT_AFTER_TWO = float(np.nextafter(2.0, 3.0))
SPECIAL_CASES = [
    ("one box", [[1, 1, 2, 3]], (0, 0, 4, 4), []),
    ("one point", [[1.5, 1.5, 1.5, 1.5]], None, []),
    ("two boxes apart", [[0.5, 0.5, 1, 1], [3, 3, 3.5, 3.5]], (0, 0, 4, 4), []),
    ("16 boxes, one per quarter of a quarter, no pairs",
     [[i + 0.25, j + 0.25, i + 0.75, j + 0.75] for i in range(4) for j in range(4)], (0, 0, 4, 4), []),
    # x = 2 is the root's splitting line; B starts one float after A ends there.
    ("two boxes apart by the smallest gap across the splitting line",
     [[1, 1, 2, 1.5], [NEXT_AFTER_TWO, 1, 3, 1.5], [0.2, 3, 0.4, 3.2], [3, 3, 3.5, 3.5]], (0, 0, 4, 4), []),
    ("two boxes touching along the root's splitting line",
     [[1, 1, 2, 1.5], [2, 1, 3, 1.5], [0.2, 3, 0.4, 3.2], [3, 3, 3.5, 3.5]], (0, 0, 4, 4), [(0, 1)]),
    ("two boxes touching at the root's centre",
     [[1, 1, 2, 2], [2, 2, 3, 3], [0.2, 3, 0.4, 3.2], [3, 0.2, 3.5, 0.5]], (0, 0, 4, 4), [(0, 1)]),
    ("three coincident boxes", [[1.3, 1.3, 1.7, 1.7]] * 3 + [[3, 3, 3.5, 3.5]], (0, 0, 4, 4),
     [(0, 1), (0, 2), (1, 2)]),
    # Box 0 straddles both splitting lines and overlaps one small box in each quarter.
    ("a box across both splitting lines over four small ones",
     [[1, 1, 3, 3], [0.5, 0.5, 1.2, 1.2], [2.8, 0.5, 3.5, 1.2], [0.5, 2.8, 1.2, 3.5], [2.8, 2.8, 3.5, 3.5]],
     (0, 0, 4, 4), [(0, 1), (0, 2), (0, 3), (0, 4)]),
    ("a small box inside a large one", [[0, 0, 10, 10], [4, 4, 5, 5], [6, 6, 6.5, 6.5]], None,
     [(0, 1), (0, 2)]),
    # Box 1 lies inside box 0; box 2 touches box 0 at the corner (0, 0) only.
    ("boxes at negative coordinates", [[-1, -1, 0, 0], [-0.5, -0.5, -0.25, -0.25], [0, 0, 1, 1]], None,
     [(0, 1), (0, 2)]),
    # Box 0 lies left of the root (0, 0, 4, 4) and touches box 1 on the root's edge x = 0.
    ("a box outside the root touching one inside on the root's edge",
     [[-1, 1, 0, 2], [0, 1.5, 0.5, 1.8], [3, 3, 3.5, 3.5], [2.5, 0.5, 3, 1]], (0, 0, 4, 4), [(0, 1)]),
]


@pytest.mark.points(3)
@pytest.mark.partial_credit
@pytest.mark.title("Quadtree: random and clustered boxes, resting crates")
def test_random(student):
    rng = np.random.default_rng(201)
    scenes = []
    for k in range(20):
        boxes = random_aabbs(rng, 80, world=30.0) if k % 4 else clustered_aabbs(rng, 80)
        bounds = None if k % 3 else [-32.0, -32.0, 32.0, 32.0]
        scenes.append((boxes, bounds, (1, 2, 4, 8)[k % 4]))
    # Crates resting on each other touch exactly, on the splitting lines of the root [-32, 32]^2.
    piles = np.random.default_rng(202)
    scenes += [(resting_piles(piles, 80, origin=piles.integers(-25, 5, 2)), [-32.0, -32.0, 32.0, 32.0], (1, 2, 4, 8)[k])
               for k in range(4)]
    check_scenes(student, scenes, "random boxes and resting crates")


@pytest.mark.points(2)
@pytest.mark.title("Quadtree: bodies across splitting lines")
def test_straddling(student):
    # Bodies lying across the root's and the quarters' splitting lines stay at inner
    # nodes and must still meet the bodies below them (erratum 5); also mirrored.
    bounds = [0.0, 0.0, 16.0, 16.0]
    boxes = np.array([[7.5, 2, 8.5, 3], [7.0, 2.2, 7.6, 2.8], [8.4, 2.4, 9.0, 2.6], [2, 7.5, 3, 8.5],
                      [2.2, 8.4, 2.8, 9.5], [7.6, 7.6, 8.4, 8.4], [7.0, 7.0, 7.7, 7.7], [8.3, 8.3, 9.0, 9.0],
                      [3.5, 3.5, 4.5, 4.5], [4.4, 3.0, 5.0, 3.8], [11.5, 11.5, 12.5, 12.5], [12.4, 12.4, 13.0, 13.0],
                      [1, 1, 1.5, 1.5], [14, 14, 14.5, 14.5]])
    mirror = np.column_stack([16 - boxes[:, 2], 16 - boxes[:, 3], 16 - boxes[:, 0], 16 - boxes[:, 1]])
    for scene in (boxes, mirror):
        for max_bodies in (1, 2):
            check_scene(student, scene, bounds, max_bodies, "bodies across splitting lines")


@pytest.mark.points(1)
@pytest.mark.title("Quadtree: special cases (one box, no pairs, coincident boxes, the smallest gap)")
def test_special_cases(student):
    # Five copies of one point, bounds None: the point is the root's corner and halving
    # reaches nodes one float wide that still hold it; only max_depth ends the splitting.
    check_algorithm(student)
    points = np.tile([[0.3, 0.3, 0.3, 0.3]], (5, 1))
    answer = call_or_timeout(student, points, None, 1, "five copies of one point")
    found = wrong_answer(points, None, 1, answer, [(i, j) for i in range(5) for j in range(i + 1, 5)])
    if found is not None:
        fail(f"{WHO}, five copies of one point: {found[0]}", figure=found[1])
    cases = [(name, np.array(boxes, dtype=float), None if bounds is None else [float(b) for b in bounds], want, m)
             for name, boxes, bounds, want in SPECIAL_CASES for m in (1, 2)]
    answers = student.call_many(MODULE, FUNCTION, [(boxes, bounds, m) for _, boxes, bounds, _, m in cases])
    wrong = [(name, found) for (name, boxes, bounds, want, m), answer in zip(cases, answers)
             if (found := wrong_answer(boxes, bounds, m, answer, want)) is not None]
    if wrong:
        name, (message, figure) = wrong[0]
        fail(f"{WHO}: {len(wrong)} of {len(cases)} special cases wrong, e.g. {name}: {message}", figure=figure)


@pytest.mark.points(1)
@pytest.mark.title("Quadtree: boxes on and across splitting lines")
@given(scene=on_split_lines())
def test_on_split_lines(student, scene):
    check_scene(student, *scene, "boxes meeting on a splitting line of the root (0, 0, 16, 16)")


@pytest.mark.points(1)
@pytest.mark.title("Quadtree: coincident boxes and points")
@given(scene=coincident_boxes())
def test_coincident(student, scene):
    check_scene(student, *scene, "copies of one box that no split can separate")


@pytest.mark.points(1)
@pytest.mark.title("Quadtree: boxes outside the root")
@given(scene=outside_bounds())
def test_outside_bounds(student, scene):
    check_scene(student, *scene, "boxes not inside the root (0, 0, 8, 8)")


@pytest.mark.points(1)
@pytest.mark.title("Quadtree: negative coordinates")
@given(scene=on_split_lines(offset=-16.0))
def test_negative_coordinates(student, scene):
    check_scene(student, *scene, "boxes at negative coordinates meeting on a splitting line of (-16, -16, 0, 0)")


# The tree itself -----------------------------------------------------------------------------
STRUCTURE = "tree_structure"


def structure_cases(seed: int) -> list[tuple]:
    """(boxes, bounds, max_bodies_per_node, min_node_area, max_depth, note) scenes."""
    rng = np.random.default_rng(seed)
    # Small scenes first: the first broken one is the one shown.
    # Boxes 0-3 each touch one splitting line from one side and lie strictly on one side
    # of the other line: child_holding gives them no child, so they stay where the line is.
    one_line = np.array([[1, 0.5, 2, 1.5], [2, 2.5, 3, 3.5], [0.5, 1, 1.5, 2], [2.5, 2, 3.5, 3],
                         [0.2, 0.2, 0.4, 0.4], [3.6, 3.6, 3.8, 3.8]], dtype=float)
    out = [(np.array([[0, 0, 1, 1], [1, 0, 2, 1], [0, 1, 1, 2], [1, 1, 2, 2], [0.2, 0.2, 0.4, 0.4]], dtype=float),
            [0.0, 0.0, 2.0, 2.0], 1, 0.0, 16, "boxes on the root's splitting lines stay at the root"),
           (one_line, [0.0, 0.0, 4.0, 4.0], 1, 0.0, 16,
            "boxes ending or starting on one splitting line of the root (x = 2 or y = 2) stay at the root"),
           (np.vstack([one_line, [[6, 6, 7, 7]]]), [0.0, 0.0, 8.0, 8.0], 1, 0.0, 16,
            "boxes ending or starting on a splitting line of the quarter (0, 0, 4, 4) stay in that quarter"),
           (np.array([[0.3, 0.3, 0.3, 0.3]] * 6 + [[0.0, 0.0, 4.0, 4.0]]), None, 2, 0.0, 5,
            "many bodies at one point: the depth rule stops splitting"),
           (random_aabbs(rng, 12, world=8.0, size=0.5), [-4.0, -4.0, 4.0, 4.0], 2, 0.0, 16,
            "given bounds, small boxes"),
           (random_aabbs(rng, 30, world=16.0), [-4.0, -4.0, 4.0, 4.0], 2, 0.0, 16,
            "given bounds, some boxes outside the root"),
           (random_aabbs(rng, 50, world=4.0, size=0.3), None, 1, 0.05, 16,
            "one body per leaf, the area rule stops splitting"),
           (random_aabbs(rng, 60, world=20.0), None, 4, 0.0, 16, "random boxes"),
           (clustered_aabbs(rng, 80), None, 3, 0.0, 16, "clustered boxes")]
    return out


def structure_call(boxes, bounds, max_bodies, min_area, max_depth) -> str:
    where = "None" if bounds is None else show([float(b) for b in bounds])
    return (f"{STRUCTURE}(aabbs={describe_boxes(boxes)}, bounds={where}, max_bodies_per_node={max_bodies}, "
            f"min_node_area={min_area:g}, max_depth={max_depth})")


@pytest.mark.points(2)
def test_structure(student):
    """Quadtree: the tree your insert and split build keeps every invariant"""
    from grader.oracles.quadtree_shape import structure_problem

    cases = structure_cases(221)
    answers = student.call_many(MODULE, STRUCTURE, [(boxes, bounds, m, a, d) for boxes, bounds, m, a, d, _ in cases])
    for (boxes, bounds, max_bodies, min_area, max_depth, note), answer in zip(cases, answers):
        problem = structure_problem(answer, boxes, max_bodies, min_area, max_depth, bounds)
        if problem is not None:
            fail(f"{structure_call(boxes, bounds, max_bodies, min_area, max_depth)} [{note}]: {problem}. "
                 f"(tree_structure reads the tree built by your Quadtree.insert, child_holding and split.)",
                 figure=pairs_figure(boxes, set(), set(), f"{STRUCTURE}: {note}",
                                     bounds=figure_bounds(boxes, bounds)))
