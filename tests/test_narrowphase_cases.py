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
from solutions.narrowphase.speculative import speculative_polygon_manifold
from solutions.shapes import AABB, OBB, Circle, ConvexPolygon, polygon_vertices
from solutions.vector import rotation_matrix
from test_narrowphase_oracles import contains, pymunk_contact, random_shape, rotate, signed_gap, translate

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


# ------------------------------------------------------------- robustness (issue #12)
def test_polygon_with_collinear_vertices_gives_the_manifold_of_its_corners():
    # (1, 0) lies on the bottom edge: the polygon is the 2 m square.  A 0.6 m wide box
    # sunk 5 cm into that edge between x = 1.2 and 1.8 touches it there: depth 0.05,
    # points halfway down the overlap, (1.2, 0.025) and (1.8, 0.025), normal -y.
    with_middle = ConvexPolygon([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])
    crate = OBB((1.5, -0.45), (0.3, 0.5), 0.0)
    expected_points = np.array([[1.2, 0.025], [1.8, 0.025]])
    for turn, shift in ((0.0, (0.0, 0.0)), (0.7, (-3.0, 2.0))):
        polygon, box_ = translate(rotate(with_middle, turn), shift), translate(rotate(crate, turn), shift)
        down = rotation_matrix(turn) @ (0.0, -1.0)                          # the normal, turned
        points = expected_points @ rotation_matrix(turn).T + shift
        results = [collide(polygon, box_), collide(box_, polygon).flipped(),
                   speculative_polygon_manifold(polygon, box_),
                   speculative_polygon_manifold(box_, polygon).flipped()]
        for contact in results:
            np.testing.assert_allclose(contact.normal, down, atol=ATOL)
            assert contact.depth == pytest.approx(0.05, abs=ATOL)
            np.testing.assert_allclose(contact.depths, [0.05, 0.05], atol=ATOL)
            np.testing.assert_allclose(contact.points[np.lexsort(contact.points.T[::-1])],
                                       points[np.lexsort(points.T[::-1])], atol=ATOL)


def exactly_touching_pairs(rng, count):
    """(name, A, B) built to touch exactly: coordinates are multiples of 1/64 m and
    distances Pythagorean, so the shapes touch with no rounding in the construction."""
    triples = ((3, 4, 5), (5, 12, 13), (8, 15, 17), (7, 24, 25), (20, 21, 29), (0, 1, 1), (1, 0, 1))
    corner_signs = np.array([(-1, -1), (1, -1), (1, 1), (-1, 1)], dtype=float)
    face_normals = np.array([(0, -1), (1, 0), (0, 1), (-1, 0)], dtype=float)

    def a_box(center, half):
        kind = rng.integers(3)
        shape = AABB(center - half, center + half)
        return shape if kind == 0 else OBB(center, half, 0.0) if kind == 1 else ConvexPolygon(shape.vertices())

    for _ in range(count):
        center, half = rng.integers(-40, 41, 2) / 8, rng.integers(1, 17, 2) / 8
        a, b, hypotenuse = triples[rng.integers(len(triples))]
        scale = 2.0 ** -int(rng.integers(0, 4))
        k = rng.integers(4)
        corner = center + corner_signs[k] * half
        away = corner_signs[k] * np.array([a, b]) * scale        # out of the box's corner
        yield "circle on a box corner", Circle(corner + away, hypotenuse * scale), a_box(center, half)
        n = face_normals[rng.integers(4)]
        along = np.abs(n[::-1])
        radius, slide = rng.integers(1, 17) / 8, rng.integers(-8, 9) / 8
        yield "circle on a box face", Circle(center + n * (half + radius) + along * slide * (along @ half), radius), \
            a_box(center, half)
        other_half = rng.integers(1, 17, 2) / 8
        slide = float(rng.choice([-1, 1])) if rng.integers(3) == 0 else rng.integers(-7, 8) / 8
        yield "boxes sharing an edge or a corner", a_box(center, half), \
            a_box(center + n * (half + other_half) + along * slide * (along @ (half + other_half)), other_half)
        share = rng.integers(1, 8) / 8
        offset = rng.choice([-1, 1], 2) * np.array([a, b]) * scale
        yield "circles", Circle(center, share * hypotenuse * scale), Circle(center + offset, (1 - share) * hypotenuse * scale)
        if a and b:     # right triangles with a slanted edge (a, -b) * size
            size = scale * float(rng.choice([1, 2, 4]))
            p = center + rng.integers(-8, 9, 2) / 8
            triangle = ConvexPolygon([p, p + (a * size, 0), p + (0, b * size)])
            yield "triangles sharing the slanted edge", triangle, \
                ConvexPolygon([p + (a * size, 0), p + (a * size, b * size), p + (0, b * size)])
            yield "triangles touching at a vertex", triangle, ConvexPolygon([2 * p - v for v in triangle.vertices])
            # The slanted edge's outward normal is (b, a) / hypotenuse; j/8 of the way along it.
            on_edge = p + (a * size, 0) + rng.integers(0, 9) / 8 * np.array([-a * size, b * size])
            k = rng.integers(1, 5) / 4
            yield "circle on a slanted face", Circle(on_edge + k * np.array([b, a]), k * hypotenuse), triangle
            yield "circle on a triangle's vertex", Circle(p - np.array([a, b]) * size, hypotenuse * size), triangle


def test_exactly_touching_pairs_touch_for_both_functions():
    # Touching counts as colliding: shapes_overlap and collide must both say so, in
    # either order, whatever rounding the unit axes of the yes/no test carry (with the
    # unit axis to the nearest vertex, a circle on a box's corner used to be "apart"
    # one time in four).
    assert shapes_overlap(Circle((4.0, 5.0), 5.0), OBB((0.0, 0.0), (1.0, 1.0), 0.0))
    seen = set()
    for name, a, b in exactly_touching_pairs(np.random.default_rng(12), 300):
        seen.add(name)
        for first, second in ((a, b), (b, a)):
            contact = collide(first, second)
            assert shapes_overlap(first, second), (name, first, second)
            assert contact is not None, (name, first, second)
            assert contact.depth <= 1e-12, (name, first, second, contact)
    assert len(seen) == 8


def far_centimetre_pairs(offset: float, turn: float):
    """Pairs of centimetre boxes overlapping by 1 mm near ``(offset, -offset / 2)``, built
    in the frame of box A (turned by ``turn``), with their contact worked out by hand in
    that frame: (A, B, unit normal from A to B, points), all in A's frame."""
    origin = np.array([offset, -offset / 2])
    frame = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]])
    h = 0.005
    a = OBB(origin, (h, h), turn)

    def b_box(centre, half, angle):
        return OBB(origin + frame @ np.asarray(centre), (half, half), turn + angle)

    up = np.array([0.0, 1.0])
    # Face to face, B's bottom 1 mm below A's top and hanging 0.5 mm over A's right side:
    # the side plane cuts B's face at x = h.  Points halfway between the faces.
    yield a, b_box((0.0005, 0.009), h, 0.0), up, [(-0.0045, 0.0045), (h, 0.0045)]
    # B turned 45 degrees, its lowest corner (0.001, 0.004) 1 mm deep: one point.
    yield a, b_box((0.001, 0.004 + h * math.sqrt(2.0)), h, math.pi / 4), up, [(0.001, 0.0045)]
    # B (half 4 mm) tilted so that its bottom corners are 1.1 mm apart in height: the
    # left one 1 mm deep, the right one 0.1 mm above A's top: one point only.
    tilt = math.asin(0.0011 / 0.008)
    left_corner = np.array([-0.004, 0.004])
    centre = left_corner + rotation_matrix(tilt) @ (0.004, 0.004)
    yield a, b_box(centre, 0.004, tilt), up, [(-0.004, 0.0045)]
    # B turned 40 degrees, its lowest corner q 1.1 mm deep under A's top face, and A's
    # top-right corner c 1 mm deep under B's face through q whose outward normal is
    # m = -(cos 40, sin 40): that face penetrates least, so it is the reference face,
    # depth 1 mm, normal -m.  A's most opposed face is its right face (x = h): its
    # points are c, and the cut of that face by the side plane through q (along m).
    beta = math.radians(40.0)
    m = -np.array([math.cos(beta), math.sin(beta)])
    c = np.array([h, h])
    q = np.array([h + (0.001 + m[1] * 0.0011) / m[0], h - 0.0011])       # -m . (c - q) = 1 mm
    lowest_corner_offset = rotation_matrix(beta) @ (-h, -h)             # B's vertex 0, the lowest
    cut = q + (h - q[0]) / m[0] * m                                     # on x = h, on the line q + s m
    depth_at_cut = -float(m @ (cut - q))
    yield a, b_box(q - lowest_corner_offset, h, beta), -m, [c + 0.0005 * m, cut + 0.5 * depth_at_cut * m]


@pytest.mark.parametrize("offset", [0.0, 1e3, 1e6, 1e9])
def test_centimetre_boxes_far_from_the_origin_give_the_depth_at_the_origin(offset):
    # A coordinate of 1e9 m is known to 1.2e-7 m (one ulp): that rounding, a few times
    # over, is all the error allowed.  The tolerances follow the boxes' size and the
    # rounding of their coordinates, not 1e-12 of the coordinate (1 mm at 1e9 m, which
    # kept points up to 1 mm outside the faces and preferred a face 10 % deeper).
    rounding = 8 * np.spacing(max(offset, 1.0))
    for turn in (0.0, 0.3, -2.0):
        frame = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]])
        for a, b, normal, local_points in far_centimetre_pairs(offset, turn):
            # The least penetration, by brute force on the same pair at the origin.
            assert -signed_gap(translate(a, -a.center), translate(b, -a.center)) == pytest.approx(0.001, abs=rounding)
            expected = a.center + np.array(local_points) @ frame.T
            for contact in (collide(a, b), speculative_polygon_manifold(a, b, margin=0.0),
                            collide(b, a).flipped()):
                np.testing.assert_allclose(contact.normal, frame @ normal, atol=1e-6)
                assert contact.depth == pytest.approx(0.001, abs=rounding)
                assert len(contact.points) == len(expected)
                along = frame @ (-normal[1], normal[0])                   # sort along the reference face
                got = contact.points[np.argsort((contact.points - a.center) @ along)]
                want = expected[np.argsort((expected - a.center) @ along)]
                np.testing.assert_allclose(got, want, rtol=0, atol=rounding)
                for point in contact.points:
                    assert contains(a, point, rounding) and contains(b, point, rounding)


def test_largest_shapes_allowed_compare_squared_distances_without_overflow():
    # Radii and coordinates up to MAX_COORDINATE = 1e150 m: squared distances stay finite.
    big = 1e150
    assert circles_overlap(Circle((-big, 0.0), 0.5 * big), Circle((big, 0.0), 0.5 * big)) is False
    assert collide(Circle((-big, 0.0), 0.5 * big), Circle((big, 0.0), 0.5 * big)) is None
    # Centres 0.5 * big apart (3-4-5), radii 0.6 + 0.4 times big: 0.5 * big deep.
    overlapping = (Circle((0.0, 0.0), 0.6 * big), Circle((0.3 * big, 0.4 * big), 0.4 * big))
    assert circles_overlap(*overlapping) and collide(*overlapping).depth == pytest.approx(0.5 * big, rel=1e-12)
    corner = OBB((0.0, 0.0), (0.5 * big, 0.5 * big), 0.0)
    ball = Circle((0.5 * big + 0.3 * big, 0.5 * big + 0.4 * big), 0.5 * big)     # exactly on the corner
    assert shapes_overlap(ball, corner) and collide(ball, corner).depth == pytest.approx(0.0, abs=1e-12 * big)
    assert not shapes_overlap(translate(ball, (0.01 * big, 0.0)), corner)
    with pytest.raises(ValueError, match="at most 1e\\+150 m"):
        Circle((0.0, 0.0), 1e154)
