"""Contacts: normal from A to B, depth and contact point(s) for every shape pair.

Expected contacts come from pymunk (:mod:`grader.oracles.pymunk_geometry`), whose
normal, depth (``-distance``) and points (the midpoint of its two surface points) are
the course's; and, for shapes built to touch exactly or small cases worked out by hand,
from literals (touching counts as colliding, with depth 0).  Every returned field is
compared: the normal (unit, finite, A to B), the depth, the number of points and each
point (:func:`grader.oracles.narrowphase_answers.contact_problem`), and each point's
feature id where the docstrings say what it is: pymunk gives none, so the feature ids
are tested on pairs worked out by hand (``test_feature_ids``).

Left out of the random batches, because pymunk does not follow the course's rule there
or the answer is free: pairs within 1e-7 m of touching by rounding only, polygon pairs
whose two best faces are penetrated almost equally (the course keeps A's face within
2 %), circles whose centre is inside a box almost as near to two faces.  The course's
rules for the reference face (the first face of A wins an exact tie, A keeps the role
within 2 % unless its side planes cut off the deepest point) are tested on pairs worked
out by hand, and so are the two clipping steps, called directly
(``clip_segment_to_half_plane``, ``reference_face_manifold``, feature ids included), and
boxes of zero width (segments and points).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from grader.harness.compare import as_number, as_vector, show
from grader.harness.credit import check_cases, fail
from grader.harness.shrink import smallest_failure
from grader.oracles import narrowphase_cases as cases
from grader.oracles import plain
from grader.oracles import random_cases as rc
from grader.oracles.brute_sat import contact_is_defined
from grader.harness.compare import call_text
from grader.oracles.narrowphase_answers import (contact_problem, contact_text, pair_figure, repeated_point_text,
                                                with_feature_ids)
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


#: Circles against boxes of zero width, worked out by hand: (circle, box, normal, depth, point).  Such a
#: box is a segment (or a point) with all four faces: two long ones on the same line with
#: opposite normals and two of zero length at its ends.  Only the faces the centre is
#: outside of (s_i >= 0) hold the closest point.
SEGMENT = plain.obb((0, 0), (1, 0), 0.0)   # from (-1, 0) to (1, 0)
ZERO_SIZE_BOXES = [
    # Off the end (1, 0): 0.5 m from it along (0.3, 0.4) / 0.5; depth 0.6 - 0.5; the point
    # halfway between (1, 0) and the circle's deepest point (1.3, 0.4) - 0.6 (0.6, 0.8).
    (plain.circle((1.3, 0.4), 0.6), SEGMENT, (-0.6, -0.8), 0.1, (0.97, -0.04)),
    (plain.circle((-1.3, -0.4), 0.6), plain.aabb((-1, 0), (1, 0)), (0.6, 0.8), 0.1, (-0.97, 0.04)),
    # On the segment's line, 0.5 m beyond its end: normal (-1, 0), depth 1 - 0.5, the point
    # halfway between (1, 0) and (0.5, 0).
    (plain.circle((1.5, 0), 1.0), SEGMENT, (-1, 0), 0.5, (0.75, 0)),
    # Above the middle: only the upper face (normal +y) faces the centre; the lower one
    # is the same segment seen from below.  Depth 0.5 - 0.3; point between (0.5, 0) and (0.5, -0.2).
    (plain.circle((0.5, 0.3), 0.5), SEGMENT, (0, -1), 0.2, (0.5, -0.1)),
    (plain.circle((0, 1.5), 0.6), plain.obb((0, 0), (0, 1), 0.0), (0, -1), 0.1, (0, 0.95)),
    # A box of zero size at (1, 1): the centre is 0.5 m away along (0.6, 0.8).
    (plain.circle((1.3, 1.4), 0.6), plain.obb((1, 1), (0, 0), 0.0), (-0.6, -0.8), 0.1, (0.97, 0.96)),
]


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
    batch += with_pymunk([cases.random_outside_polygon_circle(rng) for _ in range(30)],
                         "just outside a polygon: the nearest of the faces in front of the centre")
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
    batch += [(circle, box, plain.contact(n, d, [p]), "a box of zero height (a segment) or of zero size (a point)")
              for circle, box, n, d, p in ZERO_SIZE_BOXES]
    check_contacts(student, CIRCLE_POLYGON, "collide_circle_polygon", batch, "circles against boxes and polygons",
                   st.tuples(rc.circles, rc.obbs))


#: Boxes of zero width or zero size, worked out by hand: (A, B, normal, depth, point).  B's
#: incident face has length zero, so its two clipped ends are one point: one contact point.
ZERO_SIZE_PAIRS = [
    # B the segment x = 0.5, y in [0.7, 1.1], into A's top face y = 1: A's face and B's bottom
    # face tie at -0.3 (A keeps the role); B's face 0 runs from (0.5, 0.7) to (0.5, 0.7): the
    # point halfway between (0.5, 0.7) and y = 1.
    (plain.obb((0, 0), (1, 1), 0.0), plain.obb((0.5, 0.9), (0.0, 0.2), 0.0), (0, 1), 0.3, (0.5, 0.85)),
    # B the point (1.5, 0.75) inside A = [0, 2] x [0, 1]: A's top face (-0.25) ties with B's
    # face 0; the point halfway between (1.5, 0.75) and y = 1.
    (plain.aabb((0, 0), (2, 1)), plain.obb((1.5, 0.75), (0.0, 0.0), 0.0), (0, 1), 0.25, (1.5, 0.875)),
    # Two points at (2, 1), one turned: every separation is 0, A's face 0 (-y) wins the tie.
    (plain.obb((2, 1), (0.0, 0.0), 0.0), plain.obb((2, 1), (0.0, 0.0), 0.7), (0, -1), 0.0, (2, 1)),
]


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
    batch += [(a, b, plain.contact(n, d, [p]), "a box of zero width or zero size: one contact point, not the same "
               "point twice") for a, b, n, d, p in ZERO_SIZE_PAIRS]
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
    batch += [(a, b, plain.contact(n, 0.0, [p]), "corner to corner: one point, the first tied face of A")
              for a, b, n, p in corners_touching(("aabb", "aabb"))]
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


def corners_touching(kinds=("obb", "polygon")) -> list[tuple]:
    """Boxes touching corner to corner exactly (multiples of 1/8 m): (A, B, normal, point).

    Two faces of A have separation 0 there; the first of them in A's numbering (0 faces
    -y, 1 +x, 2 +y, 3 -x) is the reference face (max_face_separation: the first one on an
    exact tie; and B's faces, tied as well, are not clearly better): B up and to the right
    of A gives face 1, up and left face 2, down and left or right face 0.
    """
    a = cases.box((0.5, -0.25), (1.0, 0.5), 0.0, kinds[0])       # corners x = -0.5, 1.5; y = -0.75, 0.25
    out = []
    for center_b, normal, corner in (((2.0, 0.75), (1, 0), (1.5, 0.25)), ((-1.0, 0.75), (0, 1), (-0.5, 0.25)),
                                     ((-1.0, -1.25), (0, -1), (-0.5, -0.75)), ((2.0, -1.25), (0, -1), (1.5, -0.75))):
        out.append((a, cases.box(center_b, (0.5, 0.5), 0.0, kinds[1]), normal, corner))
    return out


def reference_face_cases() -> list[tuple]:
    """(A, B, expected contact, note) for the choice of the reference face, worked out by hand."""
    out = [(a, b, plain.contact(n, 0.0, [p]), "corner to corner: one point, the first tied face of A")
           for kinds in (("obb", "obb"), ("polygon", "obb"), ("obb", "polygon")) for a, b, n, p in corners_touching(kinds)]
    ground = plain.aabb((-1, -2), (1, 0))                         # top face y = 0 (face 2)
    # B: a 2 x 2 square turned so that its bottom face runs along (4, 3) / 5 from its lowest
    # vertex p = (-0.84, -0.5).  Face separations: A's top face -0.5 (p is 0.5 m deep); B's
    # bottom face (normal (0.6, -0.8)) -0.496, at A's corner (-1, 0): 0.6 (-0.16) - 0.8 (0.5).
    # B's face is better by 0.8 % only: within REFERENCE_FACE_RELATIVE_TOL (2 %) A keeps the
    # reference role, since its manifold holds p: normal (0, 1), depth 0.5, one point (B's
    # vertex (0.76, 0.7) is above y = 0) halfway between p and (-0.84, 0).
    tilted = plain.polygon([(-0.84, -0.5), (0.76, 0.7), (-0.44, 2.3), (-2.04, 1.1)])
    within = "B's face better by less than 2 %: A keeps the reference role"
    out.append((ground, tilted, plain.contact((0, 1), 0.5, [(-0.84, -0.25)]), within))
    # The same pair seen from B: B's bottom face is the least penetrated (-0.496), normal
    # (0.6, -0.8); the incident face is A's top face, whose vertex (-1, 0) is 0.496 deep and
    # (1, 0) above it; the point is (-1, 0) + 0.248 (0.6, -0.8).
    out.append((tilted, ground, plain.contact((0.6, -0.8), 0.496, [(-0.8512, -0.1984)]), "the least penetrated face"))
    # B a 3 x 2 rectangle whose bottom face runs along (399, 40) / 401 from p = (-1.04, -0.5),
    # just left of A's top face: A's face -0.5, B's bottom face -(0.5 - 0.04 tan) cos =
    # -197.9 / 401 (1.3 % better).  A's side plane x = -1 cuts p away, so A's manifold misses
    # the deepest point: B's face is the reference, normal -(40, -399) / 401 from A to B, depth
    # 197.9 / 401; both of A's top corners are below it, each moved halfway to it.
    c, s = 399 / 401, 40 / 401
    p = np.array([-1.04, -0.5])
    along, up = np.array([c, s]), np.array([-s, c])
    steep = plain.polygon([p, p + 3 * along, p + 3 * along + 2 * up, p + 2 * up])
    n_b = np.array([s, -c])
    points = [w - 0.5 * float(n_b @ (w - p)) * n_b for w in (np.array([-1.0, 0.0]), np.array([1.0, 0.0]))]
    out.append((ground, steep, plain.contact(-n_b, 197.9 / 401, points),
                "B's face better by less than 2 %, but A's side plane cuts off B's deepest vertex: B's face"))
    out.append((steep, ground, plain.contact(n_b, 197.9 / 401, points), "the least penetrated face"))
    return out


@pytest.mark.points(1)
def test_reference_face_rules(student):
    """Polygons: which face is the reference (ties, the 2 % preference for A)"""
    check_contacts(student, POLYGONS, "collide_polygon_polygon", reference_face_cases(), "reference face choices")


# The clipping steps, called directly ---------------------------------------------------------------
def plain_id(value):
    """A feature id as plain data: tuples become lists (as they cross the sandbox)."""
    return [plain_id(v) for v in value] if isinstance(value, (list, tuple)) else value


#: (segment [(point, id)], plane normal n, offset, tolerance, expected [(point, id)]), by hand:
#: keep Dot(n, x) <= offset + tolerance; a crossing is added only when exactly one end is
#: kept and the ends lie strictly on opposite sides; it comes last and keeps the id of the
#: end it replaces.
CLIP_CASES = [
    # Docstring example: x <= 3 cuts (4, 0) at (3, 0).
    ([((0, 0), "v0"), ((4, 0), "v1")], (1, 0), 3.0, 0.0, [((0, 0), "v0"), ((3, 0), "v1")]),
    # The first end is cut: the kept end first, then the crossing with the first end's id.
    ([((4, 0), "v0"), ((0, 0), "v1")], (1, 0), 3.0, 0.0, [((0, 0), "v1"), ((3, 0), "v0")]),
    ([((4, 0), "a"), ((2.5, 0), "b")], (1, 0), 3.0, 0.0, [((2.5, 0), "b"), ((3, 0), "a")]),
    # Left of the origin, normal (-1, 0): keep x >= -3; tuple ids as the clipping uses them.
    ([((-5, -1), ("A", 1, 2, 3)), ((-1, -1), ("A", 1, 2, 0))], (-1, 0), 3.0, 0.0,
     [((-1, -1), ("A", 1, 2, 0)), ((-3, -1), ("A", 1, 2, 3))]),
    # A normal of length 2 (the line 2 y = 2) and a slanted one (0.6 x + 0.8 y = 1).
    ([((0, 0), "a"), ((0, 4), "b")], (0, 2), 2.0, 0.0, [((0, 0), "a"), ((0, 1), "b")]),
    ([((0, 0), "a"), ((2, 1), "b")], (0.6, 0.8), 1.0, 0.0, [((0, 0), "a"), ((1, 0.5), "b")]),
    # Both kept, both cut.
    ([((0, 1), "a"), ((2, 1), "b")], (0, 1), 2.0, 0.0, [((0, 1), "a"), ((2, 1), "b")]),
    ([((0, 1), "a"), ((2, 1), "b")], (0, 1), 0.5, 0.0, []),
    # An end exactly on the line is kept as it is (<=), and adds no crossing.
    ([((3, 0), "a"), ((5, 0), "b")], (1, 0), 3.0, 0.0, [((3, 0), "a")]),
    ([((5, 0), "a"), ((3, 0), "b")], (1, 0), 3.0, 0.0, [((3, 0), "b")]),
    ([((1, 0), "a"), ((3, 0), "b")], (1, 0), 3.0, 0.0, [((1, 0), "a"), ((3, 0), "b")]),
    # A single point: kept on or below the line, else nothing.
    ([((1, 2), "p")], (0, 1), 2.0, 0.0, [((1, 2), "p")]),
    ([((1, 1), "p")], (0, 1), 2.0, 0.0, [((1, 1), "p")]),
    ([((1, 2.5), "p")], (0, 1), 2.0, 0.0, []),
    # Tolerance 0.001: an end 0.0005 beyond the line counts as on it (kept, no crossing).
    ([((0, 0), "a"), ((3.0005, 0), "b")], (1, 0), 3.0, 0.001, [((0, 0), "a"), ((3.0005, 0), "b")]),
    ([((3.0005, 0), "a"), ((5, 0), "b")], (1, 0), 3.0, 0.001, [((3.0005, 0), "a")]),
]


def pairs_problem(got, want: list) -> str | None:
    """A returned list of (point, id) against the expected one, in order."""
    if not isinstance(got, list) or not all(isinstance(item, list) and len(item) == 2 for item in got):
        return f"must return a list of (point, feature_id) pairs, got {show(got)}"
    if len(got) != len(want):
        return f"expected {len(want)} pair(s) {show(want)}, got {len(got)}: {show(got)}"
    for k, ((point, feature), (want_point, want_id)) in enumerate(zip(got, want)):
        vector = as_vector(point, 2)
        if vector is None or not np.all(np.abs(vector - np.asarray(want_point, dtype=float)) <= 1e-9):
            return f"pair {k}: expected the point {show(list(want_point))}, got {show(point)} (all pairs: {show(got)})"
        if feature != plain_id(want_id):
            return (f"pair {k} at {show(list(want_point))}: expected the feature id {show(plain_id(want_id))}, got "
                    f"{show(feature)} (a crossing keeps the id of the end it replaces)")
    return None


@pytest.mark.points(1)
def test_clip_segment(student):
    """One clipping step: the part of a segment on the kept side of a line"""
    calls = [([(np.array(pt, dtype=float), feature) for pt, feature in segment], np.array(normal, dtype=float), offset,
              tolerance) for segment, normal, offset, tolerance, _ in CLIP_CASES]
    answers = student.call_many(POLYGONS, "clip_segment_to_half_plane", calls)
    check_cases(zip(CLIP_CASES, answers), lambda case: pairs_problem(case[1], case[0][4]), "segments and lines",
                describe=lambda case: (f"clip_segment_to_half_plane({show([(list(pt), f) for pt, f in case[0][0]])}, "
                                       f"{show(list(case[0][1]))}, {show(case[0][2])}, tolerance={show(case[0][3])})"))


#: The outward normals of an axis-aligned box's faces 0 to 3 (-y, +x, +y, -x).
BOX_NORMALS = np.array([[0.0, -1.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0]])


def box_faces(vertices) -> tuple:
    """(vertices, unit outward normals, face indices) of a convex CCW polygon, every edge kept.

    An edge of length zero (a box of zero width or size) gets the normal of that face of an
    axis-aligned box, as polygon_faces gives a box of angle 0."""
    v = np.asarray(vertices, dtype=float)
    edges = np.roll(v, -1, axis=0) - v
    lengths = np.hypot(edges[:, 0], edges[:, 1])
    normals = np.column_stack([edges[:, 1], -edges[:, 0]]) / np.where(lengths > 0.0, lengths, 1.0)[:, None]
    if not np.all(lengths > 0.0):
        normals[lengths == 0.0] = BOX_NORMALS[lengths == 0.0]
    return v, normals, np.arange(len(v))


FLOOR = [(-1, -1), (1, -1), (1, 0), (-1, 0)]      # reference face 2: from (1, 0) to (-1, 0), normal (0, 1)


def far_floor(x: float) -> list:
    return [(x - 1, -1), (x + 1, -1), (x + 1, 0), (x - 1, 0)]


#: (reference vertices, reference normal, face, incident vertices, ref_name, scale,
#:  expected [(point, depth, feature id)]), worked out by hand: the incident face is the
#: one most anti-parallel to the normal; it is clipped to the reference face's side planes
#: (a crossing keeps the id of the vertex it replaces); points at most KEEP_POINT_TOL * scale
#: above the face are kept, each moved halfway to the face, its depth how far below it is.
MANIFOLD_CASES = [
    # Docstring example: a crate 0.1 m into a floor, its bottom face (face 0) inside the floor's top.
    ([(-5, -1), (5, -1), (5, 0), (-5, 0)], (0, 1), 2, [(-0.5, -0.1), (0.5, -0.1), (0.5, 0.9), (-0.5, 0.9)], "A", 5.0,
     [((-0.5, -0.05), 0.1, ("A", 2, 0, 0)), ((0.5, -0.05), 0.1, ("A", 2, 0, 1))]),
    # The crate reaches past the floor's left end x = -1: vertex 0 is cut there.
    (FLOOR, (0, 1), 2, [(-2, -0.1), (0.5, -0.1), (0.5, 0.9), (-2, 0.9)], "A", 2.0,
     [((-1, -0.05), 0.1, ("A", 2, 0, 0)), ((0.5, -0.05), 0.1, ("A", 2, 0, 1))]),
    # Past both ends: both vertices are cut, each crossing keeping its vertex's id.
    (FLOOR, (0, 1), 2, [(-2, -0.1), (3, -0.1), (3, 0.9), (-2, 0.9)], "A", 3.0,
     [((-1, -0.05), 0.1, ("A", 2, 0, 0)), ((1, -0.05), 0.1, ("A", 2, 0, 1))]),
    # A tilted bottom face: (-0.5, -0.2) is 0.2 deep, (0.5, 0.2) above the floor (dropped).
    (FLOOR, (0, 1), 2, [(-0.5, -0.2), (0.5, 0.2), (0.5, 1.2), (-0.5, 1.2)], "A", 1.2,
     [((-0.5, -0.1), 0.2, ("A", 2, 0, 0))]),
    # B holds the reference face, its face 1 (x = 1, normal (1, 0)); the incident face is
    # the other box's face 3, from its vertex 3 (0.9, 0.5) to vertex 0 (0.9, -0.5).
    ([(-1, -1), (1, -1), (1, 1), (-1, 1)], (1, 0), 1, [(0.9, -0.5), (2, -0.5), (2, 0.5), (0.9, 0.5)], "B", 2.0,
     [((0.95, 0.5), 0.1, ("B", 1, 3, 3)), ((0.95, -0.5), 0.1, ("B", 1, 3, 0))]),
    # Resting exactly on the floor, scale 0 (no roundoff allowance): points on the face are kept, depth 0.
    (FLOOR, (0, 1), 2, [(-0.5, 0), (0.5, 0), (0.5, 1), (-0.5, 1)], "A", 0.0,
     [((-0.5, 0), 0.0, ("A", 2, 0, 0)), ((0.5, 0), 0.0, ("A", 2, 0, 1))]),
    # 4e-7 m above the floor: kept when the coordinates are about 1e6 m (allowance 1e-12 *
    # 1e6 = 1e-6 m), each point 2e-7 above the face with depth -4e-7; dropped near the origin.
    (far_floor(1e6), (0, 1), 2, [(1e6 - 0.5, 4e-7), (1e6 + 0.5, 4e-7), (1e6 + 0.5, 1), (1e6 - 0.5, 1)], "A", 1e6 + 1,
     [((1e6 - 0.5, 2e-7), -4e-7, ("A", 2, 0, 0)), ((1e6 + 0.5, 2e-7), -4e-7, ("A", 2, 0, 1))]),
    (FLOOR, (0, 1), 2, [(-0.5, 4e-7), (0.5, 4e-7), (0.5, 1), (-0.5, 1)], "A", 1.0, []),
    # A box of zero size at (0.2, -0.1): its incident face 0 runs from (0.2, -0.1) to itself, so
    # its two clipped ends are one point, kept once with the first end's id.
    (FLOOR, (0, 1), 2, [(0.2, -0.1)] * 4, "A", 1.0, [((0.2, -0.05), 0.1, ("A", 2, 0, 0))]),
    # A box of zero width (the segment x = 0.3, y in [-0.2, 0.4]): its bottom face 0 has length 0.
    (FLOOR, (0, 1), 2, [(0.3, -0.2), (0.3, -0.2), (0.3, 0.4), (0.3, 0.4)], "A", 1.0,
     [((0.3, -0.1), 0.2, ("A", 2, 0, 0))]),
]
#: With a margin (the last entry, m): points up to that far above the reference face are
#: kept, each with a negative depth (the soft step's speculative contacts).
MARGIN_CASES = [
    # A crate hovering 1 cm above the floor: both corners within a 2 cm margin ...
    (FLOOR, (0, 1), 2, [(-0.5, 0.01), (0.5, 0.01), (0.5, 1), (-0.5, 1)], "A", 1.0,
     [((-0.5, 0.005), -0.01, ("A", 2, 0, 0)), ((0.5, 0.005), -0.01, ("A", 2, 0, 1))], 0.02),
    # ... and none within 5 mm.
    (FLOOR, (0, 1), 2, [(-0.5, 0.01), (0.5, 0.01), (0.5, 1), (-0.5, 1)], "A", 1.0, [], 0.005),
    # A tilted face: one corner 0.2 m deep, the other 1 cm above; both kept.
    (FLOOR, (0, 1), 2, [(-0.5, -0.2), (0.5, 0.01), (0.5, 1.2), (-0.5, 1.2)], "A", 1.2,
     [((-0.5, -0.1), 0.2, ("A", 2, 0, 0)), ((0.5, 0.005), -0.01, ("A", 2, 0, 1))], 0.02),
    # Exactly the margin above, scale 0 (no roundoff allowance): kept.
    (FLOOR, (0, 1), 2, [(-0.5, 0.02), (0.5, 0.02), (0.5, 1), (-0.5, 1)], "A", 0.0,
     [((-0.5, 0.01), -0.02, ("A", 2, 0, 0)), ((0.5, 0.01), -0.02, ("A", 2, 0, 1))], 0.02),
]


def manifold_problem(got, want: list) -> str | None:
    """Returned (points, depths, feature_ids) against the expected [(point, depth, id)], as a set."""
    if not (isinstance(got, list) and len(got) == 3 and all(isinstance(part, list) for part in got)
            and len(got[0]) == len(got[1]) == len(got[2])):
        return f"must return (points, depths, feature_ids), three lists of the same length, got {show(got)}"
    found = list(zip(*got))
    if len(found) != len(want):
        vectors = [as_vector(point, 2) for point in got[0]]
        repeated = repeated_point_text(vectors) if all(v is not None for v in vectors) else ""
        return (f"expected {len(want)} contact point(s) {show([list(w[0]) for w in want])}, got {len(found)}: "
                f"{show(got[0])}{repeated}")
    remaining = list(found)
    for point, depth, feature in want:
        match = [item for item in remaining if as_vector(item[0], 2) is not None
                 and np.all(np.abs(as_vector(item[0], 2) - np.asarray(point, dtype=float)) <= 1e-9)]
        if not match:
            return (f"expected a contact point at {show(list(point))} (halfway between the incident point and the "
                    f"reference face), got the points {show(got[0])}")
        item = match[0]
        remaining.remove(item)
        value = as_number(item[1])
        if value is None or not abs(value - depth) <= 1e-9:
            return f"the depth of the point {show(list(point))}: expected {show(depth)}, got {show(item[1])}"
        if item[2] != plain_id(feature):
            return (f"the feature id of the point {show(list(point))}: expected {show(plain_id(feature))}, got "
                    f"{show(item[2])} ((ref_name, reference face, incident face, the vertex it comes from))")
    return None


@pytest.mark.points(2)
def test_reference_face_manifold(student):
    """Clipping the incident face against a reference face"""
    cases = MANIFOLD_CASES + MARGIN_CASES
    calls = []
    for ref, normal, face, incident, name, scale, _, *margin in cases:
        calls.append((np.asarray(ref, dtype=float), np.array(normal, dtype=float), face, *box_faces(incident), name, scale,
                      *margin))
    answers = student.call_many(POLYGONS, "reference_face_manifold", calls)
    check_cases(zip(cases, answers), lambda case: manifold_problem(case[1], case[0][6]), "reference faces",
                describe=lambda case: (f"reference_face_manifold(ref_vertices={show([list(v) for v in case[0][0]])}, "
                                       f"ref_normal={show(list(case[0][1]))}, ref_face={case[0][2]}, "
                                       f"inc_vertices={show([list(v) for v in case[0][3]])}, (its normals and faces), "
                                       f"ref_name={case[0][4]!r}, scale={show(case[0][5])}"
                                       + "".join(f", margin={show(m)}" for m in case[0][7:]) + ")"))


#: The margin at every scale: (reference vertices, reference normal, face, incident vertices,
#: ref_name, expected [(point, depth, feature id)], margin), by hand at 1 m; the floor's face 2
#: (y = 0, normal (0, 1)) or a square's face 1 (x = 1).  Points up to ``margin`` above the
#: face are kept with their negative depth; points beyond it are dropped.
MARGIN_SHAPES = [
    # A crate hovering 1 cm above the floor, margin 2 cm: both corners, depth -0.01.
    (FLOOR, (0, 1), 2, [(-0.5, 0.01), (0.5, 0.01), (0.5, 1), (-0.5, 1)], "A",
     [((-0.5, 0.005), -0.01, ("A", 2, 0, 0)), ((0.5, 0.005), -0.01, ("A", 2, 0, 1))], 0.02),
    # The same crate, margin 5 mm: nothing.
    (FLOOR, (0, 1), 2, [(-0.5, 0.01), (0.5, 0.01), (0.5, 1), (-0.5, 1)], "A", [], 0.005),
    # Tilted: one corner 0.2 m deep, the other 1 cm above (kept), then 5 cm above (dropped).
    (FLOOR, (0, 1), 2, [(-0.5, -0.2), (0.5, 0.01), (0.5, 1.2), (-0.5, 1.2)], "A",
     [((-0.5, -0.1), 0.2, ("A", 2, 0, 0)), ((0.5, 0.005), -0.01, ("A", 2, 0, 1))], 0.02),
    (FLOOR, (0, 1), 2, [(-0.5, -0.2), (0.5, 0.05), (0.5, 1.2), (-0.5, 1.2)], "A",
     [((-0.5, -0.1), 0.2, ("A", 2, 0, 0))], 0.02),
    # Tilted and apart: one corner 5 mm above (kept, depth -0.005), the other 3 cm (dropped).
    (FLOOR, (0, 1), 2, [(-0.5, 0.005), (0.5, 0.03), (0.5, 1.03), (-0.5, 1.005)], "A",
     [((-0.5, 0.0025), -0.005, ("A", 2, 0, 0))], 0.02),
    # Wider than the floor, 1 cm above: both ends cut by the side planes x = -1 and x = 1.
    (FLOOR, (0, 1), 2, [(-2, 0.01), (3, 0.01), (3, 1), (-2, 1)], "A",
     [((-1, 0.005), -0.01, ("A", 2, 0, 0)), ((1, 0.005), -0.01, ("A", 2, 0, 1))], 0.02),
    # B holds the reference face (x = 1), the other box 1.5 cm to its right: its face 3.
    ([(-1, -1), (1, -1), (1, 1), (-1, 1)], (1, 0), 1, [(1.015, -0.5), (2, -0.5), (2, 0.5), (1.015, 0.5)], "B",
     [((1.0075, 0.5), -0.015, ("B", 1, 3, 3)), ((1.0075, -0.5), -0.015, ("B", 1, 3, 0))], 0.02),
]
#: Sizes (m per m of the cases above), each with a turn (rad) and a shift (m): a margin
#: proportional to the shapes must keep the same points wherever they are.
MARGIN_SCALES = [(0.01, 0.0, (0.0, 0.0)), (1.0, 0.4, (-3.0, 2.0)), (100.0, -1.1, (250.0, -40.0))]


def moved_margin_cases() -> list[tuple]:
    """MARGIN_SHAPES at each of MARGIN_SCALES: every length times the size, then turned and
    shifted (the points with the shapes; depths, margin and the roundoff scale only scaled)."""
    out = []
    for size, angle, shift in MARGIN_SCALES:
        turn = np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])
        place = [turn * size, np.asarray(shift, dtype=float)]      # x -> size R x + shift
        for ref, normal, face, incident, name, want, margin in MARGIN_SHAPES:
            out.append((placed(ref, *place), turn @ np.asarray(normal, dtype=float), face, placed(incident, *place),
                        name, size * 5.0 + float(np.abs(shift).max()),
                        [(tuple(placed([point], *place)[0]), size * depth, feature) for point, depth, feature in want],
                        size * margin, size))
    return out


def placed(points, linear: np.ndarray, shift: np.ndarray) -> list[np.ndarray]:
    return [linear @ np.asarray(p, dtype=float) + shift for p in points]


@pytest.mark.points(3)
def test_reference_face_manifold_margin(student):
    """Clipping with a margin: points up to the margin above the reference face, shapes from 1 cm to 100 m"""
    cases = moved_margin_cases()
    calls = [(np.asarray(ref, dtype=float), normal, face, *box_faces(incident), name, scale, margin)
             for ref, normal, face, incident, name, scale, _, margin, _ in cases]
    answers = student.call_many(POLYGONS, "reference_face_manifold", calls)

    def problem_of(case):
        (_, _, _, _, _, _, want, margin, size), got = case
        problem = manifold_problem(got, want)
        if problem is None:
            return None
        return (f"{problem} [shapes {size:g} times those of the worked cases, margin {margin:g} m: a point up to "
                f"the margin above the reference face is kept, with a negative depth]")

    check_cases(zip(cases, answers), problem_of, "reference faces with a margin",
                category=lambda case: f"{case[0][8]:g} m shapes",
                describe=lambda case: (f"reference_face_manifold(ref_vertices={show([list(v) for v in case[0][0]])}, "
                                       f"ref_normal={show(list(case[0][1]))}, ref_face={case[0][2]}, "
                                       f"inc_vertices={show([list(v) for v in case[0][3]])}, (its normals and faces), "
                                       f"ref_name={case[0][4]!r}, scale={show(case[0][5])}, "
                                       f"margin={show(case[0][7])})"))


# Feature ids, worked out by hand ------------------------------------------------------------------
#: A 2 x 1 box; its vertices (solutions.shapes numbering, CCW) 0 = (0, 0), 1 = (2, 0), 2 = (2, 1),
#: 3 = (0, 1); face k runs from vertex k to k + 1: 0 faces -y, 1 +x, 2 +y, 3 -x.
BOX = plain.aabb((0, 0), (2, 1))


def feature_contact(normal, depth: float, points, ids) -> dict:
    """An expected contact whose points come with their feature ids, in the same order."""
    return with_feature_ids(plain.contact(normal, depth, points), ids)


def any_of(*wants: dict):
    """Checker for a contact the docstring leaves to one of a few choices: any of
    ``wants`` (feature ids included) is right."""
    def problem(got):
        problems = [contact_problem(got, want) for want in wants]
        if any(p is None for p in problems):
            return None
        return (f"{problems[0]} (the docstring allows any of these contacts: "
                f"{'; '.join(contact_text(want) for want in wants)})")

    return problem


#: collide_aabb_aabb(A, B) with A = BOX, one case per reference face of A: the ids are
#: collide_polygon_polygon's ("A", reference face, incident face, k): B's incident face is
#: the one opposite the reference face (face + 2), from B's vertex j to j + 1, and k is the
#: vertex of that face the point comes from, either the vertex itself or the cut of A's side
#: plane that replaced it.  (Corners touching are left out: there collide_aabb_aabb keeps
#: the id of the first end, which is not what collide_polygon_polygon gives.)
AABB_IDS = [
    # Docstring example, B = [1, 3] x [0.5, 2]: face 2 (penetration 1 - 0.5); incident face
    # 0 of B, from its vertex 0 (1, 0.5), kept, to vertex 1 (3, 0.5), cut at x = 2.
    (plain.aabb((1, 0.5), (3, 2)),
     feature_contact((0, 1), 0.5, [(1, 0.75), (2, 0.75)], [("A", 2, 0, 0), ("A", 2, 0, 1)])),
    # B = [-1, 1] x [-1, 0.25] below: face 0 (penetration 0.25 - 0), incident face 2 of B from
    # its vertex 2 (1, 0.25), kept, to vertex 3 (-1, 0.25), cut at x = 0; y = 0.125.
    (plain.aabb((-1, -1), (1, 0.25)),
     feature_contact((0, -1), 0.25, [(1, 0.125), (0, 0.125)], [("A", 0, 2, 2), ("A", 0, 2, 3)])),
    # B = [1.75, 3] x [0.5, 2] on the right: face 1 (2 - 1.75), incident face 3 of B from its
    # vertex 3 (1.75, 2), cut at y = 1, to vertex 0 (1.75, 0.5), kept; x = 1.875.
    (plain.aabb((1.75, 0.5), (3, 2)),
     feature_contact((1, 0), 0.25, [(1.875, 1), (1.875, 0.5)], [("A", 1, 3, 3), ("A", 1, 3, 0)])),
    # B = [-1, 0.25] x [-0.5, 0.5] on the left: face 3 (0.25 - 0), incident face 1 of B from
    # its vertex 1 (0.25, -0.5), cut at y = 0, to vertex 2 (0.25, 0.5), kept; x = 0.125.
    (plain.aabb((-1, -0.5), (0.25, 0.5)),
     feature_contact((-1, 0), 0.25, [(0.125, 0), (0.125, 0.5)], [("A", 3, 1, 1), ("A", 3, 1, 2)])),
    # B = [-1, 3] x [0.75, 2], wider than A: face 2 (1 - 0.75), both ends of B's face 0 cut,
    # at x = 0 (vertex 0's) and x = 2 (vertex 1's); y = 0.875.
    (plain.aabb((-1, 0.75), (3, 2)),
     feature_contact((0, 1), 0.25, [(0, 0.875), (2, 0.875)], [("A", 2, 0, 0), ("A", 2, 0, 1)])),
]

#: collide_circle_polygon(circle, polygon): ("face", i) when the closest point q lies inside
#: face i or the centre is inside (the face it leaves through), ("vertex", k) when q is
#: vertex k.  The normal points from the circle to the polygon.
CIRCLE_POLYGON_IDS = [
    # Above the top face: s_2 = 0.4, q = (1.5, 1) inside face 2: depth 0.5 - 0.4, the point
    # halfway between q and (1.5, 1.4 - 0.5).
    (plain.circle((1.5, 1.4), 0.5), BOX, feature_contact((0, -1), 0.1, [(1.5, 0.95)], [("face", 2)])),
    # Left of face 3 (from (0, 1) down to (0, 0)): q = (0, 0.25), depth 0.5 - 0.3, the point
    # halfway between q and (-0.3 + 0.5, 0.25).
    (plain.circle((-0.3, 0.25), 0.5), BOX, feature_contact((1, 0), 0.2, [(0.1, 0.25)], [("face", 3)])),
    # Off vertex 2 = (2, 1), 0.5 m away along (0.6, 0.8): face 1 ends there, face 2 starts
    # there; depth 0.6 - 0.5, the point halfway between (2, 1) and (2.3, 1.4) - 0.6 (0.6, 0.8).
    (plain.circle((2.3, 1.4), 0.6), BOX, feature_contact((-0.6, -0.8), 0.1, [(1.97, 0.96)], [("vertex", 2)])),
    # Off vertex 0 = (0, 0), 0.5 m away along (-0.6, -0.8): face 0 starts there, face 3 ends
    # there; the point halfway between (0, 0) and (-0.3, -0.4) + 0.6 (0.6, 0.8).
    (plain.circle((-0.3, -0.4), 0.6), BOX, feature_contact((0.6, 0.8), 0.1, [(0.03, 0.04)], [("vertex", 0)])),
    # Centre inside, 0.8 below the top face (s = -0.8, the largest): it leaves through face 2.
    (plain.circle((0.1, 0.2), 0.3), plain.obb((0, 0), (1, 1), 0.0),
     feature_contact((0, -1), 1.1, [(0.1, 0.45)], [("face", 2)])),
    # Centre on the top face's line (s_2 = 0, the others < 0): the deep case, face 2, depth
    # 0.25; the point halfway between the centre (0.5, 1) and (0.5, 1 - 0.25).
    (plain.circle((0.5, 1), 0.25), BOX, feature_contact((0, -1), 0.25, [(0.5, 0.875)], [("face", 2)])),
    # Centre exactly on the corner (2, 1): s_1 = s_2 = 0, the deep case; it leaves through
    # face 1 or face 2 (a tie the docstring does not settle), never "vertex": depth 0.25, the
    # point halfway between (2, 1) and (2, 1) - 0.25 n.
    (plain.circle((2, 1), 0.25), BOX,
     any_of(feature_contact((-1, 0), 0.25, [(1.875, 1)], [("face", 1)]),
            feature_contact((0, -1), 0.25, [(2, 0.875)], [("face", 2)]))),
    # A box of zero width, the segment from (0, -1) to (0, 1): vertices 0 and 1 are both at
    # (0, -1), the closest point to the centre (0, -1.5); depth 0.6 - 0.5, the point halfway
    # between (0, -1) and (0, -0.9).  Either vertex's id is right.
    (plain.circle((0, -1.5), 0.6), plain.obb((0, 0), (0, 1), 0.0),
     any_of(feature_contact((0, 1), 0.1, [(0, -0.95)], [("vertex", 0)]),
            feature_contact((0, 1), 0.1, [(0, -0.95)], [("vertex", 1)]))),
]


def polygon_ids_cases() -> list[tuple]:
    """(A, B, expected contact) for collide_polygon_polygon: ids (ref, face, incident face, k)."""
    out = [
        # FACE_FACE's first pair: A's top face (2) and B's bottom face (0) are tied (-0.05):
        # A keeps the reference role; B's face 0 runs from its vertex 0 (-0.2, 0.45) to 1
        # (0.8, 0.45), both inside A's side planes x = -1, 1.
        (plain.obb((0, 0), (1, 0.5), 0.0), plain.obb((0.3, 0.95), (0.5, 0.5), 0.0),
         feature_contact((0, 1), 0.05, [(-0.2, 0.475), (0.8, 0.475)], [("A", 2, 0, 0), ("A", 2, 0, 1)])),
        # FACE_FACE's last pair: A's bottom face (0) and B's top face (2) tied (-0.1), A keeps
        # it; B's face 2 from its vertex 2 (4, -0.2) to 3 (-2, -0.2), both cut by A's side
        # planes x = 0.5 and x = -0.5.
        (plain.polygon([(-0.5, -0.3), (0.5, -0.3), (0.5, 0.7), (-0.5, 0.7)]), plain.obb((1, -1), (3, 0.8), 0.0),
         feature_contact((0, -1), 0.1, [(0.5, -0.25), (-0.5, -0.25)], [("A", 0, 2, 2), ("A", 0, 2, 3)])),
    ]
    # reference_face_cases' steep pair: B's bottom face (0) is the reference ("B"); A's
    # incident face is its top face 2, from its vertex 2 (1, 0) to 3 (-1, 0), both kept.
    # Seen from the steep box (A), the same faces with "A".
    c, s = 399 / 401, 40 / 401
    p = np.array([-1.04, -0.5])
    along, up = np.array([c, s]), np.array([-s, c])
    steep = plain.polygon([p, p + 3 * along, p + 3 * along + 2 * up, p + 2 * up])
    ground = plain.aabb((-1, -2), (1, 0))
    n_b = np.array([s, -c])
    corners = (np.array([1.0, 0.0]), np.array([-1.0, 0.0]))
    points = [w - 0.5 * float(n_b @ (w - p)) * n_b for w in corners]
    out.append((ground, steep, feature_contact(-n_b, 197.9 / 401, points, [("B", 0, 2, 2), ("B", 0, 2, 3)])))
    out.append((steep, ground, feature_contact(n_b, 197.9 / 401, points, [("A", 0, 2, 2), ("A", 0, 2, 3)])))
    return out


@pytest.mark.points(1)
def test_feature_ids(student):
    """Feature ids: which features touch at each contact point (AABBs, circle and box, polygons)"""
    check_contacts(student, AABBS, "collide_aabb_aabb", [(BOX, b, want, 'feature ids ("A", reference face, '
                   "incident face, the incident vertex each point comes from)") for b, want in AABB_IDS],
                   "feature ids of axis-aligned boxes")
    check_contacts(student, CIRCLE_POLYGON, "collide_circle_polygon",
                   [(circle, box, want, 'feature ids ("face", i) or ("vertex", k) of the polygon')
                    for circle, box, want in CIRCLE_POLYGON_IDS], "feature ids of a circle against a box")
    check_contacts(student, POLYGONS, "collide_polygon_polygon",
                   [(a, b, want, "feature ids (ref, reference face, incident face, the incident vertex each point "
                     "comes from)") for a, b, want in polygon_ids_cases()], "feature ids of polygons")


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
