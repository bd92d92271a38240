# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/narrowphase/dispatch.py on the instructor's
# side.
"""One entry point for any pair of world shapes, in either order.

``shapes_overlap(a, b)`` answers yes/no with the cheapest SAT test for the pair;
``collide(a, b)`` returns the :class:`~exercises.contact.Contact` (normal from A to B)
or None.  Both accept Circle, AABB, OBB and ConvexPolygon.  A polygon-circle pair is
handled by the circle-polygon routine and the contact flipped, so the normal still
points from ``a`` to ``b``.

Touching counts as colliding, and the two functions agree on shapes that touch
exactly.  One SAT test cannot promise that by itself: a circle against a polygon is
projected on *unit* axes, whose components are rounded, so a circle that touches a
vertex or a slanted face exactly (a 3-4-5 triangle from centre to corner) can project
a hair beyond the polygon and be called apart.  ``collide`` decides from the distance
between the centre and the polygon's nearest point, which has no such rounding on
exact input; so for a pair that SAT calls apart, ``shapes_overlap`` asks
:func:`circle_reaches_polygon` (that distance) before it says no.

Invalid shapes never reach this module: the shape constructors raise ``ValueError``
for NaN or infinite coordinates, negative sizes and clockwise or non-convex polygons.
Anything that is not a shape raises ``TypeError``.
"""
from __future__ import annotations

import numpy as np

from ..contact import Contact
from ..shapes import AABB, OBB, Circle, ConvexPolygon, Shape, polygon_vertices, rounding_tolerance
from .aabb_aabb import aabbs_overlap, collide_aabb_aabb
from .circle_circle import circles_overlap, collide_circle_circle
from .circle_polygon import circle_polygon_overlap, collide_circle_polygon, collide_polygon_circle
from .polygon_polygon import collide_polygon_polygon, obbs_overlap, polygons_overlap

SHAPE_TYPES = (Circle, AABB, OBB, ConvexPolygon)


def _check(shape) -> None:
    if not isinstance(shape, SHAPE_TYPES):
        raise TypeError(f"expected a Circle, AABB, OBB or ConvexPolygon, got {type(shape).__name__}")


def circle_reaches_polygon(circle: Circle, polygon: AABB | OBB | ConvexPolygon) -> bool:
    """Whether :func:`collide` finds a contact between a circle and a polygonal shape.

    The bounding boxes come first, as a cheap no (apart by more than the rounding
    tolerance of the pair, :func:`~exercises.shapes.rounding_tolerance`); then
    :func:`~exercises.narrowphase.circle_polygon.collide_circle_polygon` decides.

    >>> circle_reaches_polygon(Circle((4.0, 5.0), 5.0), AABB((-1.0, -1.0), (1.0, 1.0)))   # on the corner
    True
    """
    vertices = polygon_vertices(polygon)
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    reach = rounding_tolerance(max(float(np.max(np.abs(vertices))), float(np.max(np.abs(circle.center)))),
                               max(float(np.max(high - low)), 2.0 * circle.radius)) + circle.radius
    if np.any(circle.center - reach > high) or np.any(circle.center + reach < low):
        return False
    return collide_circle_polygon(circle, polygon) is not None


def shapes_overlap(a: Shape, b: Shape) -> bool:
    """Whether two world shapes overlap or touch.

    Examples
    --------
    >>> shapes_overlap(AABB((8.0, -2.0), (12.0, 2.0)), Circle((-10.0, 0.0), 1.0))
    False
    >>> shapes_overlap(OBB((0.0, 0.0), (1.0, 1.0), 0.5), Circle((1.5, 0.0), 0.6))
    True
    """
    _check(a)
    _check(b)
    a_round, b_round = isinstance(a, Circle), isinstance(b, Circle)
    if a_round and b_round:
        return circles_overlap(a, b)
    # SAT first; a "no" is checked against the distance (see the module docstring).
    if a_round:
        return circle_polygon_overlap(a, b) or circle_reaches_polygon(a, b)
    if b_round:
        return circle_polygon_overlap(b, a) or circle_reaches_polygon(b, a)
    if isinstance(a, AABB) and isinstance(b, AABB):
        return aabbs_overlap(a, b)
    if isinstance(a, (AABB, OBB)) and isinstance(b, (AABB, OBB)):
        return obbs_overlap(a, b)
    return polygons_overlap(a, b)


def collide(a: Shape, b: Shape) -> Contact | None:
    """Contact between two world shapes (normal from ``a`` to ``b``), or None if apart.

    Examples
    --------
    >>> contact = collide(Circle((0.0, 1.5), 1.0), AABB((-2.0, -1.0), (2.0, 1.0)))
    >>> contact.normal.tolist(), contact.depth
    ([0.0, -1.0], 0.5)
    >>> (collide(AABB((-2.0, -1.0), (2.0, 1.0)), Circle((0.0, 1.5), 1.0)).normal + 0.0).tolist()
    [0.0, 1.0]
    """
    _check(a)
    _check(b)
    a_round, b_round = isinstance(a, Circle), isinstance(b, Circle)
    if a_round and b_round:
        return collide_circle_circle(a, b)
    if a_round:
        return collide_circle_polygon(a, b)
    if b_round:
        return collide_polygon_circle(a, b)
    if isinstance(a, AABB) and isinstance(b, AABB):
        return collide_aabb_aabb(a, b)
    return collide_polygon_polygon(a, b)
