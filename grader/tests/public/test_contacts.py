"""Contacts: normal from A to B, depth and contact point(s) for every shape pair.

Expected contacts come from pymunk (:mod:`grader.oracles.pymunk_geometry`), whose
normal, depth (``-distance``) and points (the midpoint of its two surface points) are
the course's; and, for shapes built to touch exactly or small cases worked out by hand,
from literals (touching counts as colliding, with depth 0).  Every returned field is
compared: the normal (unit, finite, A to B), the depth, the number of points and each
point (:func:`grader.oracles.narrowphase_answers.contact_problem`).

Left out, because the course leaves the answer free there: pairs within 1e-7 m of
touching by rounding only, polygon pairs whose two best faces are penetrated almost
equally (the course keeps A's face within 2 %), circles whose centre is inside a box
almost as near to two faces.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from grader.credit import check_cases, fail
from grader.shrink import smallest_failure
from grader.oracles import narrowphase_cases as cases
from grader.oracles import plain
from grader.oracles import random_cases as rc
from grader.oracles.brute_sat import contact_is_defined
from grader.oracles.narrowphase_answers import call_text, contact_problem, contact_text, pair_figure
from grader.oracles.pymunk_geometry import definite_overlap, pymunk_contact

AABBS = "narrowphase.aabb_aabb"
CIRCLES = "narrowphase.circle_circle"
CIRCLE_POLYGON = "narrowphase.circle_polygon"
POLYGONS = "narrowphase.polygon_polygon"
TOUCHING = "touching exactly: a contact of depth 0"
#: Examples per category test (Hypothesis): each costs a round trip (2 to 20 ms).
CATEGORY_EXAMPLES = 20
LEFT = (-9.0, -7.0)
RIGHT = (8.0, 6.0)


# Helpers ---------------------------------------------------------------------------------------
def with_pymunk(pairs, note: str) -> list[tuple]:
    """(A, B, expected contact or None, note) for the pairs whose contact is defined."""
    out = []
    for a, b in pairs:
        overlap = definite_overlap(a, b)
        if overlap is None or (overlap and not contact_is_defined(a, b)):
            continue
        out.append((a, b, pymunk_contact(a, b) if overlap else None, note))
    return out


def touching(triples, note: str = TOUCHING) -> list[tuple]:
    return [(a, b, contact, note) for a, b, contact in triples]


def check_contacts(student, module: str, function: str, batch: list[tuple], label: str, strategy=None) -> None:
    """Every case of ``batch`` against its expected contact; on a failure, a small
    wrong pair drawn from ``strategy`` (Hypothesis, shrunk) is shown instead."""
    answers = student.call_many(module, function, [(case[0], case[1]) for case in batch])

    def smaller():
        def wrong_case(pair):
            found = with_pymunk([pair], "a small case found by Hypothesis")
            if not found:
                return None
            a, b, want, note = found[0]
            got = student.call(module, function, a, b)
            return ((a, b, want, note), got) if contact_problem(got, want) is not None else None

        pair = smallest_failure(strategy, lambda pair: wrong_case(pair) is not None)
        return wrong_case(pair) if pair is not None else None

    def problem_of(case):
        (a, b, want, note), got = case
        problem = want(got) if callable(want) else contact_problem(got, want)
        return None if problem is None else f"{problem} [{note}]"

    check_cases(zip(batch, answers), problem_of, label, smaller=smaller if strategy is not None else None,
                category=lambda case: case[0][3],
                describe=lambda case: call_text(function, case[0][0], case[0][1]),
                figure_of=lambda case: pair_figure(case[0][0], case[0][1], f"{function}: {case[0][3]}",
                                                   None if callable(case[0][2]) else case[0][2], case[1]))


def as_polygons(a: dict, b: dict, rng: np.random.Generator) -> tuple:
    """Each box as a ConvexPolygon of its corners half the time."""
    return tuple(plain.polygon(plain.vertices(s)) if s["$shape"] != "Circle" and rng.random() < 0.5 else s
                 for s in (a, b))


def coincident_centres(a: dict, b: dict):
    """Checker for two circles with the same centre: the normal is a convention (any
    finite unit vector n will do), the depth is r_a + r_b and the point the midpoint
    of c + r_a n and c - r_b n."""
    def problem(got):
        if not isinstance(got, dict) or "normal" not in got:
            return f"expected a contact of depth {a['radius'] + b['radius']:g} (same centre), got {got!r}"
        normal = got.get("normal")
        try:
            n = np.array(normal, dtype=float).reshape(2)
        except (TypeError, ValueError):
            return f"the normal must be two numbers, got {normal!r}"
        if not np.all(np.isfinite(n)) or not abs(math.hypot(*n) - 1) <= 1e-9:
            return (f"with the same centre the direction is undefined: the normal must still be a finite unit "
                    f"vector (the docstring's COINCIDENT_CENTRES_NORMAL), got {normal!r}")
        c = np.asarray(a["center"], dtype=float)
        want = plain.contact(n, a["radius"] + b["radius"], [c + (a["radius"] - b["radius"]) / 2 * n])
        return contact_problem(got, want)

    return problem


# The ported tests ----------------------------------------------------------------------------------
@pytest.mark.points(2)
@pytest.mark.partial_credit
def test_circle_circle(student):
    """Contact between two circles"""
    rng = np.random.default_rng(401)
    batch = with_pymunk([(rc.random_circle(rng, 1.0), rc.random_circle(rng, 1.0)) for _ in range(60)], "random circles")
    batch += with_pymunk(cases.far_pairs(rng, 10, LEFT, lambda r: (rc.random_circle(r, 0.8), rc.random_circle(r, 0.8))),
                         "left of the origin")
    batch += with_pymunk(cases.far_pairs(rng, 10, RIGHT, lambda r: (rc.random_circle(r, 0.8), rc.random_circle(r, 0.8))),
                         "right of the origin")
    # Docstring example, by hand: normal (1, 0), depth 2 - 1.5, midpoint of x = 1 and x = 0.5.
    batch.append((plain.circle((0, 0), 1), plain.circle((1.5, 0), 1), plain.contact((1, 0), 0.5, [(0.75, 0)]),
                  "docstring example"))
    # By hand: B straight below A, 4 m apart, radii 2 + 3: depth 1, midpoint of A's lowest
    # point y = -4 and B's highest y = -3.
    batch.append((plain.circle((-2, -2), 2), plain.circle((-2, -6), 3), plain.contact((0, -1), 1.0, [(-2, -3.5)]),
                  "B below A"))
    for a, b in ((plain.circle((1.5, -0.5), 0.75), plain.circle((1.5, -0.5), 0.25)),
                 (plain.circle((-7, -3), 0.5), plain.circle((-7, -3), 1.25)),
                 (plain.circle((0, 0), 1.0), plain.circle((0, 0), 1.0))):
        batch.append((a, b, coincident_centres(a, b), "same centre: the direction is undefined, the normal is not"))
    batch += touching(cases.random_touching_circles(rng) for _ in range(8))
    check_contacts(student, CIRCLES, "collide_circle_circle", batch, "circle pairs", st.tuples(rc.circles, rc.circles))


@pytest.mark.points(3)
@pytest.mark.partial_credit
def test_circle_polygon(student):
    """Contact between a circle and a box"""
    rng = np.random.default_rng(402)
    batch = with_pymunk([as_polygons(rc.random_circle(rng, 1.2), rc.random_obb(rng, 1.2), rng) for _ in range(40)],
                        "random circles and boxes")
    batch += with_pymunk([(rc.random_circle(rng, 1.0), rc.random_polygon(rng, rng.uniform(-1, 1, 2), 1.2))
                          for _ in range(15)], "random circles and polygons")
    batch += with_pymunk([cases.random_corner_circle(rng, apart=False) for _ in range(15)],
                         "overlapping a corner: the normal is along the centre-to-corner line")
    batch += with_pymunk([cases.random_corner_circle(rng, apart=True) for _ in range(5)], "apart, off a corner")
    batch += with_pymunk([cases.random_face_circle(rng, apart=k % 4 == 0) for k in range(20)], "next to a face")
    batch += with_pymunk([cases.random_inside_circle(rng) for _ in range(15)],
                         "centre inside the box: it leaves through the nearest face")
    batch += with_pymunk(cases.far_pairs(rng, 10, LEFT, lambda r: (rc.random_circle(r, 0.8), rc.random_obb(r, 0.8))),
                         "left of the origin")
    batch += with_pymunk(cases.far_pairs(rng, 10, RIGHT, lambda r: (rc.random_circle(r, 0.8), rc.random_obb(r, 0.8))),
                         "right of the origin")
    # By hand (docstring example): the circle 0.5 into the top face, normal circle -> box
    # (0, -1), point halfway between y = 1 (box) and y = 0.5 (circle).
    batch.append((plain.circle((0, 1.5), 1), plain.aabb((-2, -1), (2, 1)), plain.contact((0, -1), 0.5, [(0, 0.75)]),
                  "docstring example"))
    # By hand: centre inside, 0.8 below the top face (the nearest): depth 0.3 + 0.8,
    # point halfway between (0.1, 1) and the circle's deepest point (0.1, -0.1).
    batch.append((plain.circle((0.1, 0.2), 0.3), plain.obb((0, 0), (1, 1), 0.0), plain.contact((0, -1), 1.1, [(0.1, 0.45)]),
                  "centre inside the box"))
    batch += touching(cases.random_touching_circle_box(rng) for _ in range(8))
    check_contacts(student, CIRCLE_POLYGON, "collide_circle_polygon", batch, "circles against boxes and polygons",
                   st.tuples(rc.circles, rc.obbs))


@pytest.mark.points(4)
@pytest.mark.partial_credit
def test_polygon_polygon(student):
    """Contact between two convex polygons (clipping)"""
    rng = np.random.default_rng(403)
    batch = with_pymunk([as_polygons(rc.random_obb(rng, 1.2), rc.random_obb(rng, 1.2), rng) for _ in range(70)],
                        "random boxes")
    batch += with_pymunk([(rc.random_polygon(rng, rng.uniform(-1, 1, 2), 1.0), rc.random_polygon(rng, rng.uniform(-1, 1, 2), 1.0))
                          for _ in range(40)], "random polygons")
    batch += with_pymunk([cases.random_face_face(rng, kinds=(("obb", "polygon")[k % 2], ("obb", "polygon")[k % 3 == 0]))
                          for k in range(20)], "face to face: two contact points")
    batch += with_pymunk(cases.far_pairs(rng, 10, LEFT, lambda r: (rc.random_obb(r, 0.8), rc.random_obb(r, 0.8))),
                         "left of the origin")
    batch += with_pymunk(cases.far_pairs(rng, 10, RIGHT, lambda r: (rc.random_obb(r, 0.8), rc.random_obb(r, 0.8))),
                         "right of the origin")
    batch += touching(cases.random_touching_boxes(rng, kinds=(("obb", "polygon")[k % 2], "obb")) for k in range(10))
    check_contacts(student, POLYGONS, "collide_polygon_polygon", batch, "boxes and polygons",
                   st.tuples(rc.obbs, rc.obbs))


@pytest.mark.points(1)
@pytest.mark.partial_credit
def test_aabb_contacts(student):
    """Contact between two AABBs (pymunk and touching boxes)"""
    rng = np.random.default_rng(404)

    def random_pair(r):
        return tuple(plain.aabb_from_center(r.uniform(-1, 1, 2), r.uniform(0.3, 1, 2)) for _ in range(2))

    batch = with_pymunk([random_pair(rng) for _ in range(50)], "random boxes")
    batch += with_pymunk(cases.far_pairs(rng, 10, LEFT, random_pair), "left of the origin")
    batch += with_pymunk(cases.far_pairs(rng, 10, RIGHT, random_pair), "right of the origin")
    # By hand (docstring example): A's top face y = 1 is the least penetrated (0.5);
    # the faces share x in [1, 2]; points halfway between y = 1 and y = 0.5.
    batch.append((plain.aabb((0, 0), (2, 1)), plain.aabb((1, 0.5), (3, 2)), plain.contact((0, 1), 0.5, [(1, 0.75), (2, 0.75)]),
                  "docstring example"))
    batch += touching(cases.random_touching_boxes(rng, kinds=("aabb", "aabb")) for k in range(8))
    check_contacts(student, AABBS, "collide_aabb_aabb", batch, "axis-aligned boxes")


#: Boxes face to face, worked out by hand: (A, B, normal, depth, points).
FACE_FACE = [
    # B's bottom y = 0.45 in A's top y = 0.5; faces share x in [-0.2, 0.8]; points at y = 0.475.
    (plain.obb((0, 0), (1, 0.5), 0.0), plain.obb((0.3, 0.95), (0.5, 0.5), 0.0), (0, 1), 0.05, [(-0.2, 0.475), (0.8, 0.475)]),
    # B's left x = 0.4 in A's right x = 0.5; faces share y in [-0.3, 0.5]; points at x = 0.45.
    (plain.obb((0, 0), (0.5, 0.5), 0.0), plain.obb((0.9, 0.2), (0.5, 0.5), 0.0), (1, 0), 0.1, [(0.45, -0.3), (0.45, 0.5)]),
    # Left of the origin: B's bottom y = -4.6 in A's top y = -4.5; x in [-7.25, -6].
    (plain.obb((-7, -5), (1, 0.5), 0.0), plain.obb((-6.5, -4.1), (0.75, 0.5), 0.0), (0, 1), 0.1,
     [(-7.25, -4.55), (-6, -4.55)]),
    # B below A: B's top y = 2.2 in A's bottom y = 2; normal (0, -1); x in [1.5, 3]; y = 2.1.
    (plain.obb((2, 3), (1, 1), 0.0), plain.aabb((1.5, 0.2), (3.5, 2.2)), (0, -1), 0.2, [(1.5, 2.1), (3, 2.1)]),
    # A narrow box on a wide one (A's face is clipped by nothing, B's by A's side planes):
    # A's bottom y = -0.3 in B's top y = -0.2; normal (0, -1); x in [-0.5, 0.5]; y = -0.25.
    (plain.polygon([(-0.5, -0.3), (0.5, -0.3), (0.5, 0.7), (-0.5, 0.7)]), plain.obb((1, -1), (3, 0.8), 0.0), (0, -1),
     0.1, [(-0.5, -0.25), (0.5, -0.25)]),
]


@pytest.mark.points(2)
def test_face_face(student):
    """Two-point manifold for boxes face to face"""
    batch = [(a, b, plain.contact(n, d, p), "face to face: two contact points") for a, b, n, d, p in FACE_FACE]
    # Turned by 0.3 rad, B 0.98 m from A's centre along A's y axis: 0.02 m deep; from pymunk.
    up = np.array([-math.sin(0.3), math.cos(0.3)])
    a, b = plain.obb((0, 0), (2, 0.5), 0.3), plain.obb(0.98 * up, (0.5, 0.5), 0.3)
    batch.append((a, b, pymunk_contact(a, b), "face to face, turned: two contact points"))
    a, b = plain.obb((-3, -3), (1, 0.5), -2.0), plain.obb(np.array([-3, -3]) + 0.9 * np.array([math.sin(-2.0), -math.cos(-2.0)]),
                                                         (0.6, 0.5), -2.0 + math.pi)
    batch.append((a, b, pymunk_contact(a, b), "face to face, left of the origin, B turned half a turn"))
    if not all(len(want["points"]) == 2 for _, _, want, _ in batch):
        raise RuntimeError("the face-to-face cases must all have two contact points (a problem of the test)")
    check_contacts(student, POLYGONS, "collide_polygon_polygon", batch, "boxes face to face")


# Categories (Hypothesis: a failing case shrinks to a small one of the same category) -------------
def assert_contacts(student, module: str, function: str, pairs, note: str) -> None:
    """``function`` gives pymunk's contact for each (A, B) whose contact is defined (one round trip)."""
    batch = with_pymunk(pairs, note)
    answers = student.call_many(module, function, [(a, b) for a, b, _, _ in batch])
    for (a, b, want, _), got in zip(batch, answers):
        problem = contact_problem(got, want)
        if problem is not None:
            fail(f"{call_text(function, a, b)}: {problem} [{note}; expected {contact_text(want)}]",
                 figure=pair_figure(a, b, f"{function}: {note}", want, got))


def few(strategy):
    """1 to 6 cases per example, asked in one round trip; a failure shrinks to one case."""
    return st.lists(strategy, min_size=1, max_size=6)


@pytest.mark.points(1)
@settings(max_examples=CATEGORY_EXAMPLES)
@given(few(cases.inside_circle_pairs()))
def test_centre_inside(student, pairs):
    """A circle whose centre is inside a box leaves through the nearest face"""
    assert_contacts(student, CIRCLE_POLYGON, "collide_circle_polygon", pairs,
                    "centre inside the box: normal = minus the nearest face's normal, depth = radius + the centre's "
                    "distance to that face")


@pytest.mark.points(1)
@settings(max_examples=CATEGORY_EXAMPLES)
@given(few(cases.face_face_pairs()))
def test_face_face_boxes(student, pairs):
    """Boxes face to face get two contact points"""
    assert_contacts(student, POLYGONS, "collide_polygon_polygon", pairs,
                    "boxes face to face: two contact points, the ends of the clipped incident face, each halfway "
                    "to the reference face")
