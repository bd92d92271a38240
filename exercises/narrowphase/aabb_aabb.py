# Exercise file of the collision course: write the functions that raise NotImplementedError, then
# check them with `grader check sat` (aabbs_overlap) and `grader check contacts`
# (collide_aabb_aabb).
# Handed out with the course; generated from solutions/narrowphase/aabb_aabb.py on the instructor's
# side.
"""AABB against AABB: SAT with the x and y axes only.

Both boxes share their face normals (the world axes), and on those axes the projection
of a box is simply its ``[min, max]`` coordinates, so no dot product is needed.  The
boxes are apart if their intervals are apart on x or on y.

Contact: the face of A with the least penetration is the reference face (faces
numbered as in :mod:`exercises.shapes`: 0 faces -y, 1 +x, 2 +y, 3 -x; the first one wins
a tie).  Faces of two AABBs are always parallel, so the manifold is the overlap of the
two faces: 2 points (1 if the overlap is a single point, as when corners touch), on
the line halfway between A's face and B's opposite face.  Feature ids use the same
scheme as :func:`exercises.narrowphase.polygon_polygon.collide_polygon_polygon`
(``("A", reference face, incident face, B's vertex)``), which gives the same contact
for two AABBs, except where the faces share a single point: that point keeps the id of
the incident face's first vertex, ``(face + 2) % 4``.
"""
from __future__ import annotations

from ..contact import Contact
from ..shapes import AABB

#: Outward normal of A's faces 0..3.
FACE_NORMALS = ((0.0, -1.0), (1.0, 0.0), (0.0, 1.0), (-1.0, 0.0))


def aabbs_overlap(a: AABB, b: AABB) -> bool:
    """Whether two AABBs overlap or touch (closed boxes).

    Examples
    --------
    >>> aabbs_overlap(AABB((-6.0, -1.0), (-4.0, 1.0)), AABB((-3.0, -1.0), (-1.0, 1.0)))
    False
    >>> aabbs_overlap(AABB((0.0, 0.0), (1.0, 1.0)), AABB((1.0, 1.0), (2.0, 2.0)))
    True
    """
    raise NotImplementedError("write aabbs_overlap(), then run `grader check sat`")


def collide_aabb_aabb(a: AABB, b: AABB) -> Contact | None:
    """Contact manifold between two AABBs, or None if they are apart.

    ``normal`` is the outward normal of A's least-penetrated face (from A to B), and
    ``depth`` the penetration along it: ``min(a.max - b.min, b.max - a.min)`` on that
    axis (m, >= 0).  Both points share that depth.

    Examples
    --------
    >>> contact = collide_aabb_aabb(AABB((0.0, 0.0), (2.0, 1.0)), AABB((1.0, 0.5), (3.0, 2.0)))
    >>> contact.normal.tolist(), contact.depth, sorted(contact.points.tolist())
    ([0.0, 1.0], 0.5, [[1.0, 0.75], [2.0, 0.75]])
    """
    raise NotImplementedError("write collide_aabb_aabb(), then run `grader check contacts`")
