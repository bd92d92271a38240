# Exercise file of the collision course: write the functions that raise NotImplementedError, then
# check them with `grader check sat` (circle_polygon_overlap) and `grader check contacts`
# (collide_circle_polygon).
# Handed out with the course; generated from solutions/narrowphase/circle_polygon.py on the
# instructor's side.
"""Circle against a convex polygonal shape (AABB, OBB or ConvexPolygon).

SAT test.  A circle has infinitely many normals, yet only one extra candidate axis is
needed besides the polygon's edge normals: the axis from the circle's centre to the
polygon vertex *nearest* to it (Arvo, "A Simple Method for Box-Sphere Intersection
Testing").  If the shapes are apart, the polygon point closest to the centre is either
inside an edge (that edge's normal separates) or a vertex, and then it is the nearest
vertex.  On every axis the circle projects to ``Dot(c, axis) +- r`` (radius, not
diameter; no ``abs``) with the axis normalised, and each axis gets fresh intervals.

Contact.  Let ``s_i`` be the signed distance of the centre ``c`` from the line of face
``i`` (> 0 outside).

- Centre outside (``max s_i > 0``): ``q`` = the polygon point closest to ``c``, found
  on the faces with ``s_i >= 0``; the shapes touch when ``|c - q| <= r``.  The normal (polygon to circle) is the face
  normal if ``q`` lies inside a face, else ``(c - q) / |c - q|`` (vertex region).
- Centre inside or on the boundary (``max s_i <= 0``, deep penetration): the circle
  leaves through the face of least penetration, ``i* = argmax s_i``; the normal is its
  outward normal and the depth ``r - s_i*``.

Either way the single contact point is the midpoint between ``q`` (on the polygon) and
the circle's deepest point ``c - r n``.  Feature ids: ``("face", i)`` or
``("vertex", k)`` of the polygon.
"""
from __future__ import annotations

import numpy as np

from ..contact import Contact
from ..shapes import AABB, OBB, Circle, ConvexPolygon, polygon_vertices
from ..vector import normalize
from .polygon_polygon import polygon_faces
from .projection import intervals_overlap, project_circle, project_vertices, separating_axis_candidates

Polygonal = AABB | OBB | ConvexPolygon


def circle_polygon_overlap(circle: Circle, polygon: Polygonal) -> bool:
    """SAT yes/no test between a circle and a convex polygonal shape; touching counts.

    Candidate axes: the polygon's edge normals (two for a box) and the unit axis from
    the circle centre to the nearest polygon vertex.  If the centre sits on that
    vertex the axis is undefined and skipped: the shapes touch, and the edge normals
    alone report it.

    Parameters
    ----------
    circle : Circle
        World circle (m).
    polygon : AABB, OBB or ConvexPolygon
        World shape (m).

    Examples
    --------
    >>> circle_polygon_overlap(Circle((-10.0, 0.0), 1.0), AABB((8.0, -2.0), (12.0, 2.0)))
    False
    >>> circle_polygon_overlap(Circle((2.7, 2.7), 1.0), OBB((0.0, 0.0), (2.0, 2.0), 0.0))
    True
    """
    raise NotImplementedError("write circle_polygon_overlap(), then run `grader check sat`")


def collide_circle_polygon(circle: Circle, polygon: Polygonal) -> Contact | None:
    """Contact between a circle (A) and a convex polygonal shape (B), or None.

    The normal points from the circle to the polygon; see the module docstring for
    the outside and deep (centre inside) cases.

    Parameters
    ----------
    circle : Circle
        World circle (m), shape A.
    polygon : AABB, OBB or ConvexPolygon
        World shape (m), shape B.

    Returns
    -------
    Contact or None
        One point; ``depth = r - |c - q|`` outside, ``r + |s_i*|`` inside.

    Examples
    --------
    >>> contact = collide_circle_polygon(Circle((0.0, 1.5), 1.0), AABB((-2.0, -1.0), (2.0, 1.0)))
    >>> contact.normal.tolist(), contact.depth, contact.points.tolist()
    ([0.0, -1.0], 0.5, [[0.0, 0.75]])
    """
    raise NotImplementedError("write collide_circle_polygon(), then run `grader check contacts`")


def collide_polygon_circle(polygon: Polygonal, circle: Circle) -> Contact | None:
    """Contact between a convex polygonal shape (A) and a circle (B), or None.

    :func:`collide_circle_polygon` seen from the other side: the normal points from the
    polygon to the circle; depth and point are the same.

    Examples
    --------
    >>> contact = collide_polygon_circle(AABB((-2.0, -1.0), (2.0, 1.0)), Circle((0.0, 1.5), 1.0))
    >>> (contact.normal + 0.0).tolist(), contact.depth
    ([0.0, 1.0], 0.5)
    """
    contact = collide_circle_polygon(circle, polygon)
    return None if contact is None else contact.flipped()
