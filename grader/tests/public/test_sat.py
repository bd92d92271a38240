"""SAT: projections, interval overlap and the yes/no overlap tests of every shape pair.

Expected values come from oracles a student may hold: the projections from brute force
(min and max of the dot products, computed here), the yes/no answers from pymunk
(:mod:`grader.oracles.pymunk_geometry`), and the answers for exact touching from the
construction (touching counts as colliding: shapes built on multiples of 1/8 m or on
Pythagorean triples touch with no rounding at all).  Pairs within 1e-7 m of touching
by rounding only are left out of the random batches.

Every batch holds pairs on both sides of the answer in named categories, so a constant
True or False earns nothing, and each classic bug breaks a category of at least 10 % of
the cases of the test aimed at it, so that it loses at least half of that test's points
(partial credit starts at 90 % right): forgetting B's axes, edge directions taken for
normals, a strict ``<``, FLT_MIN as the start of a maximum, a minimum started at 0 (the
polygon and box tests), no centre-to-vertex axis (the circle test).  The category tests
(Hypothesis) shrink a failure to a small case of round numbers in the same category.
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from grader.harness.compare import number, show
from grader.harness.credit import check_cases, fail
from grader.harness.shrink import smallest_failure
from grader.oracles import narrowphase_cases as cases
from grader.oracles import plain
from grader.oracles import random_cases as rc
from grader.harness.compare import call_text
from grader.oracles.narrowphase_answers import boolean_problem, pair_figure
from grader.oracles.pymunk_geometry import definite_overlap

PROJECTION = "narrowphase.projection"
POLYGONS = "narrowphase.polygon_polygon"
CIRCLE_POLYGON = "narrowphase.circle_polygon"
CIRCLES = "narrowphase.circle_circle"
AABBS = "narrowphase.aabb_aabb"
TOUCHING = "touching exactly (touching counts as colliding)"
#: Examples per category test (Hypothesis): each costs a round trip or two (2 to 20 ms).
CATEGORY_EXAMPLES = 20


# Helpers -----------------------------------------------------------------------------------
def with_pymunk(pairs, note: str) -> list[tuple]:
    """(A, B, expected, note) for the pairs pymunk answers for sure (not within 1e-7 m of touching)."""
    out = []
    for a, b in pairs:
        want = definite_overlap(a, b)
        if want is not None:
            out.append((a, b, want, note))
    return out


def touching(triples) -> list[tuple]:
    """(A, B, True, note) for pairs built to touch exactly (the contact is not used here)."""
    return [(a, b, True, TOUCHING) for a, b, _ in triples]


def check_yes_no(student, module: str, function: str, batch: list[tuple], label: str, strategy=None) -> None:
    """Ask ``function`` about every (A, B, expected, note) in one round trip; fail with
    the share of right answers (and a small wrong pair from ``strategy``, shrunk)."""
    answers = student.call_many(module, function, [(a, b) for a, b, _, _ in batch])

    def smaller():
        def wrong_case(pair):
            found = with_pymunk([pair], "a small case found by Hypothesis")
            if not found:
                return None
            got = student.call(module, function, *pair)
            return (found[0], got) if boolean_problem(got, found[0][2]) is not None else None

        pair = smallest_failure(strategy, lambda pair: wrong_case(pair) is not None)
        return wrong_case(pair) if pair is not None else None

    def problem_of(case):
        (a, b, want, note), got = case
        problem = boolean_problem(got, want)
        return None if problem is None else f"{problem} [{note}]"

    check_cases(zip(batch, answers), problem_of, label, smaller=smaller if strategy is not None else None,
                category=lambda case: case[0][3],
                describe=lambda case: call_text(function, case[0][0], case[0][1]),
                figure_of=lambda case: pair_figure(case[0][0], case[0][1], f"{function}: {case[0][3]}"))


def with_kinds(a: dict, b: dict, rng: np.random.Generator) -> tuple:
    """The same OBB pair, each box turned into a ConvexPolygon of its corners half the time."""
    return tuple(plain.polygon(plain.vertices(s)) if rng.random() < 0.5 else s for s in (a, b))


def both_ways(pairs) -> list[tuple]:
    """Each (A, B) and the same pair swapped: if only B's axes separate A and B, only
    A's separate B and A."""
    return [(a, b) for a, b in pairs] + [(b, a) for a, b in pairs]


#: Far from the origin: every projection on an axis near x or y is negative (FLT_MIN as
#: the start of a maximum) or positive (a minimum started at 0).
LEFT = (-9.0, -7.0)
RIGHT = (8.0, 6.0)


# Projections ------------------------------------------------------------------------------------
def interval_problem(got, lo: float, hi: float) -> str | None:
    if not isinstance(got, list) or len(got) != 2:
        return f"must return (min, max), got {show(got)}"
    return number("min", got[0], lo) or number("max", got[1], hi)


@pytest.mark.points(1)
def test_project_vertices(student):
    """Projection of a polygon on an axis"""
    rng = np.random.default_rng(301)
    batch = []
    for k in range(45):
        # A third each: every projection negative (FLT_MIN trap), every one positive (a
        # minimum started at 0), and around the origin.
        center = (rng.uniform(-20, -8, 2), rng.uniform(8, 20, 2), rng.uniform(-3, 3, 2))[k % 3]
        vertices = np.asarray(rc.random_polygon(rng, center, float(rng.uniform(0.5, 2)))["vertices"])
        batch.append((vertices, rc.unit_vector(rng)))
    batch += [(np.array([[-6.0, -1.0], [-4.0, -1.0], [-4.0, 1.0], [-6.0, 1.0]]), np.array([1.0, 0.0])),  # docstring
              (np.array([[4.0, 1.0], [6.0, 1.0], [6.0, 3.0], [4.0, 3.0]]), np.array([0.0, 1.0])),
              (np.array([[-2.0, 3.0]]), np.array([0.6, 0.8])),                    # one vertex: min = max
              (np.array([[1.0, 2.0], [3.0, 2.0], [2.0, 5.0]]), np.array([2.0, 0.0]))]  # axis not unit: allowed
    answers = student.call_many(PROJECTION, "project_vertices", batch)

    def problem_of(case):
        (vertices, axis), got = case
        along = vertices @ axis  # brute force: every dot product
        return interval_problem(got, float(along.min()), float(along.max()))

    check_cases(zip(batch, answers), problem_of, "projections of polygons",
                describe=lambda case: f"project_vertices({show(case[0][0].tolist())}, {show(case[0][1].tolist())})")


@pytest.mark.points(1)
def test_project_circle(student):
    """Projection of a circle on an axis"""
    rng = np.random.default_rng(302)
    batch = [(rng.uniform(-10, 10, 2), float(rng.uniform(0.1, 3)), rc.unit_vector(rng)) for _ in range(30)]
    batch += [(np.array([-10.0, 0.0]), 1.0, np.array([1.0, 0.0])),   # docstring: (-11, -9), no abs()
              (np.array([-3.0, -4.0]), 0.5, np.array([0.6, 0.8])),   # centre projects to -5
              (np.array([2.0, 7.0]), 0.0, np.array([0.0, -1.0]))]    # a point
    answers = student.call_many(PROJECTION, "project_circle", batch)

    def problem_of(case):
        (center, radius, axis), got = case
        along = float(center @ axis)
        problem = interval_problem(got, along - radius, along + radius)
        return None if problem is None else problem + " (the interval is Dot(centre, axis) +- radius)"

    check_cases(zip(batch, answers), problem_of, "projections of circles",
                describe=lambda case: f"project_circle({show(case[0][0].tolist())}, {show(case[0][1])}, "
                                      f"{show(case[0][2].tolist())})")


#: (a, b, overlap?) written out by hand: closed intervals, a shared end point overlaps.
INTERVAL_CASES = [
    ((0.0, 1.0), (1.0, 2.0), True),       # b starts where a ends
    ((1.0, 2.0), (0.0, 1.0), True),       # a starts where b ends
    ((0.0, 1.0), (1.5, 2.0), False),
    ((1.5, 2.0), (0.0, 1.0), False),
    ((-6.0, -4.0), (-3.0, -1.0), False),  # left of the origin
    ((-3.0, -1.0), (-6.0, -4.0), False),
    ((-6.0, -2.0), (-3.0, -1.0), True),
    ((2.0, 3.0), (0.0, 5.0), True),       # a inside b
    ((0.0, 5.0), (2.0, 3.0), True),       # b inside a
    ((-1.0, 1.0), (-1.0, 1.0), True),     # equal
    ((3.0, 4.0), (0.0, 2.999), False),
    ((0.0, 2.999), (3.0, 4.0), False),
    ((-2.0, -1.0), (-1.0, 0.0), True),
    ((5.0, 5.0), (5.0, 5.0), True),       # two equal points
    ((5.0, 5.0), (5.0, 6.0), True),       # a point at b's start
    ((6.0, 6.0), (5.0, 6.0), True),       # a point at b's end
    ((4.0, 4.0), (5.0, 6.0), False),
    ((0.0, 10.0), (-3.0, 0.0), True),
    ((1e-9, 1.0), (-1.0, 0.0), False),    # apart by 1e-9
]


@pytest.mark.points(1)
def test_intervals_overlap(student):
    """Overlap of two intervals"""
    batch = [(a, b) for a, b, _ in INTERVAL_CASES]
    answers = student.call_many(PROJECTION, "intervals_overlap", batch)
    check_cases(zip(INTERVAL_CASES, answers),
                lambda case: boolean_problem(case[1], case[0][2]) and
                boolean_problem(case[1], case[0][2]) + " (closed intervals: sharing an end point counts as overlapping)",
                "interval pairs", describe=lambda case: f"intervals_overlap({case[0][0]}, {case[0][1]})")


# The yes/no tests ---------------------------------------------------------------------------------
@pytest.mark.points(1)
@pytest.mark.partial_credit
def test_aabbs_overlap(student):
    """AABB against AABB"""
    rng = np.random.default_rng(303)

    def random_pair(rng):
        return tuple(plain.aabb_from_center(rng.uniform(-3, 3, 2), rng.uniform(0.2, 1.5, 2)) for _ in range(2))

    batch = with_pymunk([random_pair(rng) for _ in range(50)], "random boxes")
    batch += with_pymunk(cases.far_pairs(rng, 10, LEFT, random_pair), "boxes left of the origin")
    batch += with_pymunk(cases.far_pairs(rng, 10, RIGHT, random_pair), "boxes right of the origin")
    batch += [(plain.aabb((-6, -1), (-4, 1)), plain.aabb((-3, -1), (-1, 1)), False, "docstring example")]
    batch += touching(cases.random_touching_boxes(rng, corner=k % 3 == 0, kinds=("aabb", "aabb")) for k in range(10))
    check_yes_no(student, AABBS, "aabbs_overlap", batch, "axis-aligned boxes")


@pytest.mark.points(3)
@pytest.mark.partial_credit
def test_polygons_overlap_random(student):
    """SAT for boxes and convex polygons"""
    rng = np.random.default_rng(304)
    batch = with_pymunk([with_kinds(rc.random_obb(rng), rc.random_obb(rng), rng) for _ in range(60)],
                        "random boxes")
    batch += with_pymunk([(rc.random_polygon(rng, rng.uniform(-2, 2, 2), 1.2),
                           rc.random_polygon(rng, rng.uniform(-2, 2, 2), 1.2)) for _ in range(40)], "random polygons")
    one_side = [cases.random_one_side(rng, kinds=(("obb", "polygon")[k % 2], ("polygon", "obb")[k % 3 == 0]))
                for k in range(25)]
    batch += with_pymunk(one_side, "apart: only B's edge normals separate them")
    batch += with_pymunk([(b, a) for a, b in one_side], "apart: only A's edge normals separate them")
    batch += with_pymunk(cases.far_pairs(rng, 12, LEFT, lambda r: with_kinds(rc.random_obb(r, 1.2), rc.random_obb(r, 1.2), r)),
                         "shapes left of the origin")
    batch += with_pymunk(cases.far_pairs(rng, 12, RIGHT, lambda r: with_kinds(rc.random_obb(r, 1.2), rc.random_obb(r, 1.2), r)),
                         "shapes right of the origin")
    aligned = lambda r: cases.random_aligned_boxes(r, spread=2.0)  # noqa: E731
    batch += with_pymunk(cases.far_pairs(rng, 20, LEFT, aligned),
                         "boxes left of the origin, every projection on x and y negative")
    batch += with_pymunk(cases.far_pairs(rng, 20, RIGHT, aligned),
                         "boxes right of the origin, every projection on x and y positive")
    close = [cases.random_close_apart(rng) for _ in range(35)]
    batch += with_pymunk(close, "polygons just apart: only a face normal separates them (an edge direction does not)")
    batch += with_pymunk([cases.close_apart_pair(*cases.random_close_apart(rng), gap=float(rng.uniform(-0.05, -0.01)))
                          for _ in range(10)], "polygons just overlapping")
    batch += touching(cases.random_touching_boxes(rng, corner=k % 3 == 0) for k in range(34))
    check_yes_no(student, POLYGONS, "polygons_overlap", batch, "boxes and polygons", st.tuples(rc.obbs, rc.obbs))


@pytest.mark.points(2)
@pytest.mark.partial_credit
def test_obbs_overlap_random(student):
    """SAT for two oriented boxes (two axes each)"""
    rng = np.random.default_rng(305)
    batch = with_pymunk([(rc.random_obb(rng), rc.random_obb(rng)) for _ in range(60)], "random boxes")
    one_side = [cases.random_one_side(rng) for _ in range(20)]
    batch += with_pymunk(one_side, "apart: only B's axes separate them")
    batch += with_pymunk([(b, a) for a, b in one_side], "apart: only A's axes separate them")
    batch += with_pymunk(cases.far_pairs(rng, 10, LEFT, lambda r: (rc.random_obb(r, 1.2), rc.random_obb(r, 1.2))),
                         "boxes left of the origin")
    batch += with_pymunk(cases.far_pairs(rng, 10, RIGHT, lambda r: (rc.random_obb(r, 1.2), rc.random_obb(r, 1.2))),
                         "boxes right of the origin")
    aligned = lambda r: cases.random_aligned_boxes(r, kinds=("obb", "aabb"))  # noqa: E731
    batch += with_pymunk(cases.far_pairs(rng, 14, LEFT, aligned), "boxes left of the origin, every projection negative")
    batch += with_pymunk(cases.far_pairs(rng, 14, RIGHT, aligned), "boxes right of the origin, every projection positive")
    batch += [(plain.obb((-9, -7), (1, 0.5), 0.3), plain.obb((-5, -7), (1, 0.5), -0.2), False, "boxes left of the origin"),
              (plain.obb((-5, 0), (0.5, 0.5), 0.0), plain.obb((-2, 0), (0.5, 0.5), 0.0), False, "boxes left of the origin")]
    batch += touching(cases.random_touching_boxes(rng, corner=k % 3 == 0, kinds=(("obb", "aabb")[k % 2], "obb"))
                      for k in range(20))
    check_yes_no(student, POLYGONS, "obbs_overlap", batch, "oriented boxes", st.tuples(rc.obbs, rc.obbs))


@pytest.mark.points(3)
@pytest.mark.partial_credit
def test_circle_polygon_random(student):
    """SAT for a circle against a box"""
    rng = np.random.default_rng(306)
    batch = with_pymunk([(rc.random_circle(rng), rc.random_obb(rng)) for _ in range(50)], "random circles and boxes")
    batch += with_pymunk([(rc.random_circle(rng), rc.random_polygon(rng, rng.uniform(-2, 2, 2), 1.2)) for _ in range(20)],
                         "random circles and polygons")
    batch += with_pymunk([cases.random_corner_circle(rng, apart=True) for _ in range(30)],
                         "apart, off a corner: only the axis from the centre to the nearest vertex separates them")
    batch += with_pymunk([cases.random_corner_circle(rng, apart=False) for _ in range(15)], "overlapping a corner")
    batch += with_pymunk([cases.random_face_circle(rng, apart=k % 2 == 0) for k in range(20)], "next to a face")
    batch += with_pymunk([cases.random_inside_circle(rng) for _ in range(10)], "centre inside the box")
    batch += with_pymunk(cases.far_pairs(rng, 10, LEFT, lambda r: (rc.random_circle(r, 1.2), rc.random_obb(r, 1.2))),
                         "left of the origin")
    batch += with_pymunk(cases.far_pairs(rng, 10, RIGHT, lambda r: (rc.random_circle(r, 1.2), rc.random_obb(r, 1.2))),
                         "right of the origin")
    batch += touching(cases.random_touching_circle_box(rng) for _ in range(20))
    check_yes_no(student, CIRCLE_POLYGON, "circle_polygon_overlap", batch, "circles and boxes",
                 st.tuples(rc.circles, rc.obbs))


@pytest.mark.points(1)
@pytest.mark.partial_credit
def test_circles_overlap(student):
    """Circle against circle"""
    rng = np.random.default_rng(307)
    batch = with_pymunk([(rc.random_circle(rng), rc.random_circle(rng)) for _ in range(60)], "random circles")
    batch += with_pymunk(cases.far_pairs(rng, 10, LEFT, lambda r: (rc.random_circle(r, 1.2), rc.random_circle(r, 1.2))),
                         "left of the origin")
    batch += with_pymunk(cases.far_pairs(rng, 10, RIGHT, lambda r: (rc.random_circle(r, 1.2), rc.random_circle(r, 1.2))),
                         "right of the origin")
    batch += [(plain.circle((0, 0), 1), plain.circle((2.5, 0), 1), False, "0.5 m apart (radius, not diameter)"),
              (plain.circle((-3, -3), 1), plain.circle((-3, -3), 0.5), True, "same centre"),
              (plain.circle((1, 2), 0), plain.circle((1, 2), 0), True, "two equal points (radius 0)"),
              (plain.circle((1, 2), 0), plain.circle((1, 2.5), 0.25), False, "a point 0.25 m outside a circle")]
    batch += touching(cases.random_touching_circles(rng) for _ in range(10))
    check_yes_no(student, CIRCLES, "circles_overlap", batch, "circles")


# Categories (Hypothesis: a failing case shrinks to a small one of the same category) -------------
def assert_yes_no(student, module: str, function: str, pairs, note: str) -> None:
    """``function`` gives pymunk's answer for each (A, B), asked in one round trip."""
    pairs = [(a, b) for a, b in pairs if definite_overlap(a, b) is not None]
    expected = [definite_overlap(a, b) for a, b in pairs]
    answers = student.call_many(module, function, pairs)
    for (a, b), want, got in zip(pairs, expected, answers):
        problem = boolean_problem(got, want)
        if problem is not None:
            fail(f"{call_text(function, a, b)}: {problem} [{note}]", figure=pair_figure(a, b, f"{function}: {note}"))


def few(strategy):
    """1 to 6 cases per example, asked in one round trip; a failure shrinks to one case."""
    return st.lists(strategy, min_size=1, max_size=6)


@pytest.mark.points(1)
@settings(max_examples=CATEGORY_EXAMPLES)
@given(few(st.one_of(cases.one_side_pairs(apart=True), cases.one_side_pairs(apart=False))))
def test_one_side_separates(student, pairs):
    """SAT tests the axes of both shapes: pairs that only one shape's normals separate

    Each pair comes both ways round, (A, B) and (B, A); about half of them are pushed
    into the corner instead, so that they overlap.
    """
    assert_yes_no(student, POLYGONS, "polygons_overlap", both_ways(pairs),
                  "a box off another one's corner: when apart, only the edge normals of one of the two shapes "
                  "separate them, so test the axes of both")
    boxes = [(a, b) for a, b in pairs if a["$shape"] == b["$shape"] == "OBB"]
    if boxes:
        assert_yes_no(student, POLYGONS, "obbs_overlap", both_ways(boxes),
                      "a box off another one's corner: when apart, only the axes of one of the two boxes separate "
                      "them, so test the axes of both")


@pytest.mark.points(1)
@settings(max_examples=CATEGORY_EXAMPLES)
@given(few(st.one_of(cases.corner_circle_pairs(apart=True), cases.corner_circle_pairs(apart=False))))
def test_circle_off_corner(student, pairs):
    """A circle off a box's corner: the axis from the centre to the nearest vertex"""
    assert_yes_no(student, CIRCLE_POLYGON, "circle_polygon_overlap", pairs,
                  "a circle off a corner: only the unit axis from the centre to the nearest vertex can separate them")


def far_pairs_strategy(coordinate):
    """(box, box, circle) with every coordinate drawn from ``coordinate``."""
    boxes = st.builds(lambda x, y, hx, hy, a: plain.obb((x, y), (hx, hy), a), coordinate, coordinate,
                      cases.halves, cases.halves, cases.angles)
    circles = st.builds(lambda x, y, r: plain.circle((x, y), r), coordinate, coordinate, cases.halves)
    return st.tuples(boxes, boxes, circles)


@pytest.mark.points(1)
@settings(max_examples=CATEGORY_EXAMPLES)
@given(st.one_of(few(far_pairs_strategy(cases.rounded(-9, -6))), few(far_pairs_strategy(cases.rounded(6, 9)))))
def test_far_from_origin(student, triples):
    """Boxes and circles left (all coordinates < 0) or right (all > 0) of the origin"""
    note = "shapes far from the origin (every coordinate of the same sign)"
    assert_yes_no(student, POLYGONS, "polygons_overlap", [(a, b) for a, b, _ in triples], note)
    assert_yes_no(student, CIRCLE_POLYGON, "circle_polygon_overlap", [(c, a) for a, _, c in triples], note)
