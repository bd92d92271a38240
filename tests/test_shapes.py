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
