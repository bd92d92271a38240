"""Named cases of the narrow phase: projections, the classic bugs of the course notes,
degenerate and hard cases, invalid input, and consistency between the routines.

Expected values are geometry worked out by hand (a box's interval on an axis, the
distance from a centre to a face) or come from pymunk / brute force; none is a number
copied from the code under test.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from solutions.narrowphase.aabb_aabb import aabbs_overlap, collide_aabb_aabb
from solutions.narrowphase.circle_circle import COINCIDENT_CENTRES_NORMAL, circles_overlap, collide_circle_circle
from solutions.narrowphase.circle_polygon import circle_polygon_overlap, collide_circle_polygon, collide_polygon_circle
from solutions.narrowphase.dispatch import collide, shapes_overlap
from solutions.narrowphase.polygon_polygon import collide_polygon_polygon, obbs_overlap, polygons_overlap
from solutions.narrowphase.projection import (edge_normals, interval_overlap_depth, intervals_overlap,
                                              project_circle, project_vertices)
from solutions.shapes import AABB, OBB, Circle, ConvexPolygon, polygon_vertices
from test_narrowphase_oracles import pymunk_contact, random_shape, rotate, signed_gap, translate

FLT_MIN = 1.1754943508222875e-38   # C's FLT_MIN: the smallest *positive* normal float
#: m: hand-computed geometry on shapes of about 1 m is exact to ~1e-15.
ATOL = 1e-12


def box(x0, y0, x1, y1):
    return AABB((x0, y0), (x1, y1))


def assert_same_contact(ours, theirs, atol):
    """``ours`` (Contact) against pymunk's (normal, [(point, depth)]) within ``atol`` m."""
    assert ours is not None and theirs is not None
    normal, points = theirs
    np.testing.assert_allclose(ours.normal, normal, atol=atol)
    assert ours.depth == pytest.approx(max(d for _, d in points), abs=atol)
    assert len(ours.points) == len({tuple(np.round(p, 9)) for p, _ in points})
    for p in ours.points:
        assert min(float(np.hypot(*(p - q))) for q, _ in points) <= atol


# ------------------------------------------------------------------ projections
def test_project_vertices_of_a_box_left_of_the_origin():
    square = polygon_vertices(box(-6.0, -1.0, -4.0, 1.0))
    assert project_vertices(square, (1.0, 0.0)) == (-6.0, -4.0)
    assert project_vertices(square, (0.0, 1.0)) == (-1.0, 1.0)
    # Every call starts afresh: a second axis does not inherit the first one's interval.
    assert project_vertices(square, (1.0, 0.0)) == (-6.0, -4.0)


def test_project_vertices_on_a_diagonal_matches_numpy():
    rng = np.random.default_rng(3)
    for _ in range(50):
        vertices = rng.uniform(-10, 10, (int(rng.integers(1, 9)), 2))
        axis = rng.normal(size=2)
        along = vertices @ axis
        assert project_vertices(vertices, axis) == pytest.approx((along.min(), along.max()), abs=1e-12)


def test_project_circle_uses_the_signed_centre_and_the_radius():
    assert project_circle((-10.0, 0.0), 1.0, (1.0, 0.0)) == (-11.0, -9.0)
    axis = np.array([3.0, 4.0]) / 5.0
    low, high = project_circle((3.0, 4.0), 0.5, axis)
    assert (low, high) == pytest.approx((4.5, 5.5), abs=ATOL)


def test_intervals_are_closed():
    assert intervals_overlap((0.0, 1.0), (1.0, 2.0))            # touching
    assert intervals_overlap((0.0, 5.0), (1.0, 2.0))            # containment
    assert not intervals_overlap((0.0, 1.0), (1.0 + 1e-12, 2.0))
    assert not intervals_overlap((3.0, 4.0), (0.0, 2.0))


def test_interval_overlap_depth_is_the_push_out_distance():
    assert interval_overlap_depth((0.0, 4.0), (3.0, 5.0)) == 1.0     # push b up by 1
    assert interval_overlap_depth((0.0, 10.0), (4.0, 5.0)) == 5.0    # contained: min(10 - 4, 5 - 0)
    assert interval_overlap_depth((0.0, 1.0), (1.0, 2.0)) == 0.0
    assert interval_overlap_depth((0.0, 1.0), (3.0, 5.0)) == -2.0


def test_edge_normals_are_unit_outward_and_skip_zero_length_edges():
    triangle = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 0.0], [0.0, 3.0]])
    normals = edge_normals(triangle)
    assert normals.shape == (3, 2)
    np.testing.assert_allclose(np.hypot(normals[:, 0], normals[:, 1]), 1.0, atol=1e-15)
    np.testing.assert_allclose(normals, [[0.0, -1.0], [0.6, 0.8], [-1.0, 0.0]], atol=1e-15)


# ---------------------------------------------------- the classic bugs, as regressions
def project_flt_min(vertices, axis):
    """The notes' OBB loop: max starts at FLT_MIN (wrong), min at FLT_MAX."""
    lowest, highest = 3.4e38, FLT_MIN
    for v in vertices:
        lowest, highest = min(lowest, float(v @ axis)), max(highest, float(v @ axis))
    return lowest, highest


def test_flt_min_bug_boxes_left_of_the_origin_are_apart():
    a, b = box(-6.0, -1.0, -4.0, 1.0), box(-3.0, -1.0, -1.0, 1.0)   # x = -5 and x = -2
    # The bug: with max starting at FLT_MIN > 0 both x intervals end at FLT_MIN.
    assert intervals_overlap(project_flt_min(polygon_vertices(a), np.array([1.0, 0.0])),
                             project_flt_min(polygon_vertices(b), np.array([1.0, 0.0])))
    assert pymunk_contact(a, b) is None
    oa, ob = OBB((-5.0, 0.0), (1.0, 1.0)), OBB((-2.0, 0.0), (1.0, 1.0))
    assert not aabbs_overlap(a, b) and not polygons_overlap(a, b) and not obbs_overlap(oa, ob)
    assert not shapes_overlap(oa, ob) and collide(a, b) is None and collide(oa, ob) is None


def circle_obb_notes(circle, polygon, *, use_abs, use_diameter, normalise):
    """The notes' circle-OBB test with its switches: abs(), diameter, raw vertex axes,
    and limits never reset for the circle-to-vertex axes."""
    vertices = polygon_vertices(polygon)
    normals = edge_normals(vertices)
    reach = 2 * circle.radius if use_diameter else circle.radius
    fold = abs if use_abs else (lambda x: x)
    for n in normals:
        along = [fold(float(v @ n)) for v in vertices]
        c = fold(float(circle.center @ n))
        if c - reach > max(along) or c + reach < min(along):
            return False
    for v in vertices:
        axis = circle.center - v
        if normalise:
            axis = axis / np.hypot(*axis)
        along = [fold(float(w @ axis)) for w in vertices]
        c = fold(float(circle.center @ axis))
        if c - reach > max(along) or c + reach < min(along):
            return False
    return True


def test_abs_bug_box_right_and_circle_left_of_the_origin_are_apart():
    square, ball = box(8.0, -0.5, 12.0, 0.5), Circle((-10.0, 0.0), 1.0)
    assert circle_obb_notes(ball, square, use_abs=True, use_diameter=False, normalise=True)  # the bug
    assert pymunk_contact(square, ball) is None
    assert not circle_polygon_overlap(ball, square) and not shapes_overlap(square, ball)
    assert collide(ball, square) is None and collide(square, ball) is None


def test_diameter_bug_circle_half_a_radius_from_a_face_is_apart():
    square, ball = box(0.0, 0.0, 2.0, 2.0), Circle((3.5, 1.0), 1.0)   # gap 0.5 < radius
    assert circle_obb_notes(ball, square, use_abs=False, use_diameter=True, normalise=True)
    assert pymunk_contact(ball, square) is None
    assert not circle_polygon_overlap(ball, square) and collide(ball, square) is None


def test_unnormalised_vertex_axis_bug_circle_over_a_corner_collides():
    # Centre 0.2*sqrt(2) = 0.28 m from the corner (1, 1), radius 0.3: they overlap.  On
    # the raw axis from the far corner (0, 0), (1.2, 1.2), the centre is scaled by 1.7
    # but the radius is not, and a false gap opens: the notes' test says "apart".
    square, ball = box(0.0, 0.0, 1.0, 1.0), Circle((1.2, 1.2), 0.3)
    assert not circle_obb_notes(ball, square, use_abs=False, use_diameter=False, normalise=False)
    assert pymunk_contact(ball, square) is not None
    assert circle_polygon_overlap(ball, square) and collide(ball, square) is not None


def obb_notes_no_reset(a, b):
    """The notes' OBB test with min/max set once before the axis loop (FLT_MAX, -FLT_MAX)."""
    va, vb = a.vertices(), b.vertices()
    normals = [np.array([e[1], -e[0]]) for e in (va[1] - va[0], va[2] - va[1], vb[1] - vb[0], vb[2] - vb[1])]
    a_min = b_min = math.inf
    a_max = b_max = -math.inf
    for n in normals:
        for v in va:
            a_min, a_max = min(a_min, float(v @ n)), max(a_max, float(v @ n))
        for v in vb:
            b_min, b_max = min(b_min, float(v @ n)), max(b_max, float(v @ n))
        if a_min > b_max or a_max < b_min:
            return False
    return True


def test_no_reset_bug_random_obb_pairs_agree_with_pymunk():
    rng = np.random.default_rng(2024)
    wrong_ours = wrong_notes = checked = 0
    for _ in range(5000):
        a, b = random_shape(rng, "obb"), random_shape(rng, "obb")
        if abs(signed_gap(a, b)) < 1e-9:
            continue
        checked += 1
        truth = pymunk_contact(a, b) is not None
        wrong_ours += (obbs_overlap(a, b) != truth) + (polygons_overlap(a, b) != truth)
        wrong_notes += obb_notes_no_reset(a, b) != truth
    assert checked > 4900
    assert wrong_notes > checked // 20       # the draw does catch the bug ...
    assert wrong_ours == 0                    # ... and ours does not have it


# ------------------------------------------------------------ degenerate cases
def test_coincident_centres_give_the_documented_normal_never_nan():
    contact = collide_circle_circle(Circle((1.0, 2.0), 1.0), Circle((1.0, 2.0), 0.5))
    np.testing.assert_array_equal(contact.normal, COINCIDENT_CENTRES_NORMAL)
    assert contact.depth == 1.5
    assert np.all(np.isfinite(contact.points))
    # Moving B by depth along the documented normal separates them (touching then).
    moved = Circle(np.array([1.0, 2.0]) + (contact.depth + 1e-12) * contact.normal, 0.5)
    assert not circles_overlap(Circle((1.0, 2.0), 1.0), moved)


def test_zero_radius_circles_are_points():
    point = Circle((0.0, 0.0), 0.0)
    same = collide(point, Circle((0.0, 0.0), 0.0))
    assert same is not None and same.depth == 0.0 and np.all(np.isfinite(same.normal))
    assert collide(point, Circle((1e-9, 0.0), 0.0)) is None
    inside = collide(Circle((0.5, 0.7), 0.0), box(-2.0, -1.0, 2.0, 1.0))      # deepest: 0.3 below the top
    np.testing.assert_allclose(inside.normal, (0.0, -1.0), atol=ATOL)
    assert inside.depth == pytest.approx(0.3, abs=ATOL)
    on_face = collide(box(-2.0, -1.0, 2.0, 1.0), Circle((0.5, 1.0), 0.0))
    assert on_face is not None and on_face.depth == 0.0
    assert collide(box(-2.0, -1.0, 2.0, 1.0), Circle((0.5, 1.0 + 1e-9), 0.0)) is None


def test_zero_size_boxes_are_points_and_segments():
    dot = OBB((0.5, 0.5), (0.0, 0.0), 0.3)
    assert shapes_overlap(dot, box(0.0, 0.0, 1.0, 1.0))
    contact = collide(box(0.0, 0.0, 1.0, 1.0), dot)
    assert contact.depth == pytest.approx(0.5, abs=ATOL) and len(contact.points) == 1
    assert not shapes_overlap(dot, OBB((0.5, 0.5 + 1e-6), (0.0, 0.0), 0.0))     # two points apart
    assert shapes_overlap(dot, OBB((0.5, 0.5), (0.0, 0.0), 1.0))                 # the same point
    # Two collinear segments on the x axis, apart: needs the segments' own direction as axis.
    left, right = OBB((0.0, 0.0), (1.0, 0.0), 0.0), OBB((2.5, 0.0), (1.0, 0.0), 0.0)
    assert not shapes_overlap(left, right) and collide(left, right) is None
    assert not shapes_overlap(rotate(left, 0.7), rotate(right, 0.7))
    # A segment crossing a box, and a circle touching a segment from above.
    cross = collide(box(-1.0, -1.0, 1.0, 1.0), OBB((0.0, 1.5), (0.0, 1.0), 0.0))
    np.testing.assert_allclose(cross.normal, (0.0, 1.0), atol=ATOL)
    assert cross.depth == pytest.approx(0.5, abs=ATOL)
    ball = collide(Circle((0.0, 1.0), 1.0), AABB((-1.0, 0.0), (1.0, 0.0)))
    np.testing.assert_allclose(ball.normal, (0.0, -1.0), atol=ATOL)
    assert ball.depth == 0.0


def test_parallel_edges_give_a_two_point_manifold():
    ground = box(-5.0, -1.0, 5.0, 0.0)
    crate = OBB((1.0, 0.45), (0.5, 0.5), 0.0)              # 0.05 m into the ground
    for turn, shift in ((0.0, (0.0, 0.0)), (0.5, (3.0, -2.0)), (-2.0, (-7.0, 4.0))):
        a, b = translate(rotate(ground, turn), shift), translate(rotate(crate, turn), shift)
        contact = collide(a, b)
        assert len(contact.points) == 2
        np.testing.assert_allclose(contact.depths, [0.05, 0.05], atol=ATOL)
        assert_same_contact(contact, pymunk_contact(a, b), atol=1e-9)
        swapped = collide(b, a)
        np.testing.assert_allclose(swapped.normal, -contact.normal, atol=ATOL)
        assert len(swapped.points) == 2


def test_exact_touching_counts_as_colliding_with_depth_zero():
    pairs = [
        (box(0.0, 0.0, 1.0, 1.0), box(1.0, 0.0, 2.0, 1.0), 2),            # face to face
        (box(0.0, 0.0, 1.0, 1.0), box(1.0, 1.0, 2.0, 2.0), 1),            # corner to corner
        (Circle((0.0, 0.0), 1.0), Circle((2.0, 0.0), 1.0), 1),
        (box(0.0, 0.0, 1.0, 1.0), Circle((2.0, 0.5), 1.0), 1),
        (Circle((1.0 + 0.5 * math.sqrt(2), 1.0 + 0.5 * math.sqrt(2)), 1.0), box(0.0, 0.0, 1.0, 1.0), 1),
        (OBB((0.0, 0.0), (1.0, 1.0), 0.0), OBB((2.0, 0.5), (1.0, 1.0), 0.0), 2),
    ]
    for a, b, count in pairs:
        assert shapes_overlap(a, b) and shapes_overlap(b, a)
        contact = collide(a, b)
        assert contact is not None and contact.depth == pytest.approx(0.0, abs=1e-12)
        assert len(contact.points) == count
        assert collide(b, a) is not None


def test_coordinates_near_a_million_give_the_result_at_the_origin():
    # At 1e6 m a double resolves 1.2e-10 m: inputs themselves are rounded that much,
    # so results may differ by a few 1e-10 m; 1e-8 m is far below any feature size.
    rng = np.random.default_rng(99)
    shift = np.array([1e6, -1e6])
    for kind_a, kind_b in (("obb", "obb"), ("poly", "obb"), ("circle", "poly"), ("obb", "circle"),
                           ("circle", "circle"), ("aabb", "aabb")):
        for _ in range(100):
            a, b = random_shape(rng, kind_a), random_shape(rng, kind_b)
            if abs(signed_gap(a, b)) < 1e-6:
                continue
            here, there = collide(a, b), collide(translate(a, shift), translate(b, shift))
            assert (here is None) == (there is None)
            if here is None:
                continue
            np.testing.assert_allclose(there.normal, here.normal, atol=1e-8)
            assert there.depth == pytest.approx(here.depth, abs=1e-8)
            np.testing.assert_allclose(np.sort(there.points - shift, axis=0), np.sort(here.points, axis=0), atol=1e-8)


def test_deep_penetration_circle_centre_inside_a_box():
    slab = box(-2.0, -1.0, 2.0, 1.0)
    ball = Circle((0.5, 0.7), 0.25)                  # 0.3 below the top face, 1.5 from the right
    contact = collide(slab, ball)
    np.testing.assert_allclose(contact.normal, (0.0, 1.0), atol=ATOL)
    assert contact.depth == pytest.approx(0.55, abs=ATOL)
    assert_same_contact(contact, pymunk_contact(slab, ball), atol=1e-9)
    tilted = OBB((0.3, -0.2), (2.0, 1.0), 0.4)
    for centre in ((0.0, 0.0), (0.4, -0.1), (1.0, 0.5), (-1.2, -0.4)):
        ball = Circle(centre, 0.3)
        assert_same_contact(collide(ball, tilted), pymunk_contact(ball, tilted), atol=1e-9)
        assert_same_contact(collide(tilted, ball), pymunk_contact(tilted, ball), atol=1e-9)


def test_circle_centred_on_the_box_centre_leaves_through_the_first_nearest_face():
    # Faces 0 (-y) and 2 (+y) of the box are equally near: the tie goes to the first
    # face in box numbering, so B is pushed along the box's -y axis, by r + h_y.
    tilted = OBB((0.3, -0.2), (2.0, 1.0), 0.4)
    contact = collide(tilted, Circle((0.3, -0.2), 0.3))
    np.testing.assert_allclose(contact.normal, -tilted.axes()[1], atol=ATOL)
    assert contact.depth == pytest.approx(1.3, abs=ATOL)


def test_deep_penetration_box_inside_a_box():
    big, small = OBB((0.0, 0.0), (3.0, 2.0), 0.2), OBB((0.5, 0.8), (0.4, 0.3), -0.3)
    assert_same_contact(collide(big, small), pymunk_contact(big, small), atol=1e-9)
    assert_same_contact(collide(small, big), pymunk_contact(small, big), atol=1e-9)


# ----------------------------------------------------------------- invalid input
@pytest.mark.parametrize("make_bad", [
    lambda: Circle((0.0, 0.0), -1.0),
    lambda: Circle((math.nan, 0.0), 1.0),
    lambda: OBB((0.0, 0.0), (1.0, -0.5), 0.0),
    lambda: OBB((0.0, 0.0), (1.0, 1.0), math.nan),
    lambda: AABB((0.0, 0.0), (math.inf, 1.0)),
    lambda: ConvexPolygon([[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]]),                      # clockwise
    lambda: ConvexPolygon([[0.0, 0.0], [2.0, 0.0], [1.0, 0.2], [2.0, 2.0], [0.0, 2.0]]),  # non-convex
])
@pytest.mark.parametrize("function", [collide, shapes_overlap])
def test_invalid_shapes_raise_value_error(make_bad, function):
    good = box(0.0, 0.0, 1.0, 1.0)
    with pytest.raises(ValueError):
        function(make_bad(), good)
    with pytest.raises(ValueError):
        function(good, make_bad())


@pytest.mark.parametrize("function", [collide, shapes_overlap])
def test_non_shapes_raise_type_error(function):
    with pytest.raises(TypeError):
        function((0.0, 0.0), box(0.0, 0.0, 1.0, 1.0))


# --------------------------------------------------------- consistency between routines
def test_aabb_contact_equals_the_polygon_contact_for_two_aabbs():
    rng = np.random.default_rng(5)
    for _ in range(500):
        a, b = random_shape(rng, "aabb"), random_shape(rng, "aabb")
        fast, general = collide_aabb_aabb(a, b), collide_polygon_polygon(a, b)
        assert aabbs_overlap(a, b) == polygons_overlap(a, b) == (fast is not None) == (general is not None)
        if fast is None:
            continue
        np.testing.assert_allclose(fast.normal, general.normal, atol=ATOL)
        assert fast.depth == pytest.approx(general.depth, abs=ATOL)
        order_fast, order_general = np.lexsort(fast.points.T), np.lexsort(general.points.T)
        np.testing.assert_allclose(fast.points[order_fast], general.points[order_general], atol=ATOL)
        assert set(fast.feature_ids) == set(general.feature_ids)


def test_polygon_circle_is_the_flipped_circle_polygon():
    rng = np.random.default_rng(6)
    for _ in range(300):
        ball, shape = random_shape(rng, "circle"), random_shape(rng, "poly")
        forward, backward = collide_circle_polygon(ball, shape), collide_polygon_circle(shape, ball)
        assert (forward is None) == (backward is None) == (not circle_polygon_overlap(ball, shape))
        if forward is not None:
            np.testing.assert_array_equal(forward.normal, -backward.normal)
            np.testing.assert_array_equal(forward.points, backward.points)


def test_feature_ids_are_stable_while_the_same_features_touch():
    ground = box(-5.0, -1.0, 5.0, 0.0)
    ids = set()
    # Slide and rock the crate, and let it hang over the ground's edge: the same two
    # faces touch, so the ids stay (a side-plane cut keeps the id of the vertex it
    # replaces, as in Box2D v3).
    for x in [*np.linspace(-1.0, 1.0, 21), 4.8]:
        crate = OBB((x, 0.45), (0.5, 0.5), 1e-3 * x)
        contact = collide(ground, crate)
        assert len(contact.points) == 2
        ids.add(frozenset(contact.feature_ids))
    assert len(ids) == 1
    hash(next(iter(ids)))
    # Tipped by 0.7 rad onto a corner of the same face: that corner keeps its id.
    tipped = collide(ground, OBB((0.0, 0.6), (0.5, 0.5), 0.7))
    assert len(tipped.points) == 1 and set(tipped.feature_ids) < next(iter(ids))
    # Tipped past 45 degrees: the crate's face 3 is the incident face now, new ids.
    rolled = collide(ground, OBB((0.0, 0.6), (0.5, 0.5), 1.0))
    assert len(rolled.points) == 1 and not set(rolled.feature_ids) & next(iter(ids))


def test_feature_ids_of_equal_width_stacked_boxes_do_not_flicker():
    # The upper box's corners sit exactly on the lower box's side planes; roundoff
    # from a tiny sideways jitter must not change the ids (that would lose warm starts).
    lower = OBB((0.0, 0.5), (0.5, 0.5), 0.0)
    seen = set()
    for jitter in (-1e-12, 0.0, 1e-12, 3e-13):
        upper = OBB((jitter, 1.49), (0.5, 0.5), jitter)
        contact = collide(lower, upper)
        assert len(contact.points) == 2
        seen.add(frozenset(contact.feature_ids))
    assert len(seen) == 1
