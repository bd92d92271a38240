"""Shapes: validation, CCW vertices, bounding boxes."""
import math

import numpy as np
import pytest
from hypothesis import given, strategies as st

from solutions.shapes import (AABB, OBB, Circle, ConvexPolygon, bounding_aabb, polygon_centroid,
                              polygon_vertices, signed_area)

finite = st.floats(-1e3, 1e3, allow_nan=False)
positive = st.floats(1e-3, 1e2)


@pytest.mark.parametrize("make, message", [
    (lambda: Circle((0, 0), -1), "radius must be >= 0"),
    (lambda: Circle((math.nan, 0), 1), "finite"),
    (lambda: Circle((0, 0), math.inf), "finite"),
    (lambda: AABB((1, 0), (0, 1)), "exceeds"),
    (lambda: OBB((0, 0), (-1, 1)), "half-extent must be >= 0"),
    (lambda: OBB((0, 0), (1, 1), math.nan), "angle must be finite"),
    (lambda: ConvexPolygon([[0, 0], [0, 1], [1, 0]]), "clockwise"),
    (lambda: ConvexPolygon([[0, 0], [2, 0], [1, 0.2], [2, 2], [0, 2]]), "not convex"),
    (lambda: ConvexPolygon([[0, 0], [1, 0], [2, 0]]), "zero area"),
    (lambda: ConvexPolygon([[0, 0], [1, 0]]), "n >= 3"),
    (lambda: ConvexPolygon([[0, 0], [1, 0], [math.nan, 1]]), "finite"),
    (lambda: ConvexPolygon([[np.cos(a), np.sin(a)] for a in np.arange(5) * 4 * np.pi / 5]), "self-intersecting"),
])
def test_invalid_shapes_raise_value_error(make, message):
    with pytest.raises(ValueError, match=message):
        make()


@given(finite, finite, positive, positive, st.floats(-10, 10))
def test_box_vertices_are_ccw_with_the_right_area(x, y, hx, hy, angle):
    v = OBB((x, y), (hx, hy), angle).vertices()
    assert signed_area(v) == pytest.approx(4 * hx * hy, rel=1e-9)
    np.testing.assert_allclose(polygon_centroid(v), (x, y), atol=1e-9 * (1 + abs(x) + abs(y)))
    ConvexPolygon(v)  # passes validation: convex and counter-clockwise


def test_aabb_forms_agree():
    box = AABB.from_center((1, -2), (3, 0.5))
    np.testing.assert_array_equal(box.min_corner, (-2, -2.5))
    np.testing.assert_array_equal(box.max_corner, (4, -1.5))
    np.testing.assert_array_equal(box.center, (1, -2))
    np.testing.assert_array_equal(box.half_extents, (3, 0.5))


@given(finite, finite, positive, positive, st.floats(-10, 10))
def test_bounding_aabb_touches_the_extreme_vertices(x, y, hx, hy, angle):
    obb = OBB((x, y), (hx, hy), angle)
    box = bounding_aabb(obb)
    v = polygon_vertices(obb)
    np.testing.assert_array_equal(box.min_corner, v.min(axis=0))
    np.testing.assert_array_equal(box.max_corner, v.max(axis=0))


def test_zero_size_shapes_are_allowed():
    assert bounding_aabb(Circle((1, 1), 0)).half_extents.tolist() == [0, 0]
    assert np.all(OBB((0, 0), (0, 0)).vertices() == 0)


def test_shapes_are_immutable():
    c = Circle((0, 0), 1)
    with pytest.raises(ValueError):
        c.center[0] = 5.0


def test_repeated_and_collinear_vertices_are_dropped():
    square = [[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]]
    # Midpoints of edges, a repeated corner, three vertices along the top edge.
    padded = ConvexPolygon([[0, 0], [1, 0], [2, 0], [2, 2], [2, 2], [1.5, 2], [0.5, 2], [0, 2], [0, 1]])
    assert padded.vertices.tolist() == square
    # The same far from the origin and turned: the middle vertex is on the edge only up
    # to the rounding of coordinates of 1e9 m (1.2e-7 m), and is still dropped.
    turn = np.array([[math.cos(0.3), -math.sin(0.3)], [math.sin(0.3), math.cos(0.3)]])
    corners = np.array([[0.0, 0.0], [0.02, 0.0], [0.02, 0.01], [0.0, 0.01]]) @ turn.T + [1e9, -2e9]
    with_middle = np.insert(corners, 1, (corners[0] + corners[1]) / 2, axis=0)
    assert len(ConvexPolygon(with_middle).vertices) == 4
    # A corner that is a real corner is kept, however blunt: 1e-6 m off a 2 m chord.
    blunt = ConvexPolygon([[0, 0], [1, -1e-6], [2, 0], [2, 2], [0, 2]])
    assert len(blunt.vertices) == 5
    # Area and centroid do not change.
    assert signed_area(padded.vertices) == 4.0
    np.testing.assert_allclose(polygon_centroid(padded.vertices), (1.0, 1.0), atol=1e-15)
    # A spike (an edge that turns back on itself) is not convex.
    with pytest.raises(ValueError, match="not convex"):
        ConvexPolygon([[0, 0], [2, 0], [1, 0], [1, 1]])


@pytest.mark.parametrize("make, name", [
    (lambda big: Circle((0, 0), big), "circle radius"),
    (lambda big: Circle((big, 0), 1), "circle center"),
    (lambda big: AABB((0, -big), (1, 1)), "AABB min_corner"),
    (lambda big: AABB.from_center((0, 0), (big, 1)), "AABB half-extent"),
    (lambda big: OBB((0, 0), (1, big), 0.3), "OBB half-extent"),
    (lambda big: OBB((0, big), (1, 1), 0.3), "OBB center"),
    (lambda big: ConvexPolygon([[0, 0], [big, 0], [0, big]]), "polygon vertices"),
])
def test_sizes_whose_squares_overflow_are_refused(make, name):
    # Two circles of radius 1e154 reach 2e154, whose square is inf: they would "touch"
    # circles far outside them.
    assert 2e154 * 2e154 == math.inf
    with pytest.raises(ValueError, match=f"{name} must be at most 1e\\+150 m"):
        make(1e154)
    with pytest.raises(ValueError, match=name):
        make(2e150)
    make(1e150)     # the largest size allowed builds
