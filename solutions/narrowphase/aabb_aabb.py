"""AABB against AABB: SAT with the x and y axes only.

Both boxes share their face normals (the world axes), and on those axes the projection
of a box is simply its ``[min, max]`` coordinates, so no dot product is needed.  The
boxes are apart if their intervals are apart on x or on y.

Contact: the face of A with the least penetration is the reference face (faces
numbered as in :mod:`solutions.shapes`: 0 faces -y, 1 +x, 2 +y, 3 -x; the first one wins
a tie).  Faces of two AABBs are always parallel, so the manifold is the overlap of the
two faces: 2 points (1 if the overlap is a single point, as when corners touch), on
the line halfway between A's face and B's opposite face.  Feature ids use the same
scheme as :func:`solutions.narrowphase.polygon_polygon.collide_polygon_polygon`
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
    ### BEGIN SOLUTION
    if a.max_corner[0] < b.min_corner[0] or b.max_corner[0] < a.min_corner[0]:
        return False  # apart on the x axis
    if a.max_corner[1] < b.min_corner[1] or b.max_corner[1] < a.min_corner[1]:
        return False  # apart on the y axis
    return True
    ### END SOLUTION


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
    ### BEGIN SOLUTION
    (a_x0, a_y0), (a_x1, a_y1) = a.min_corner.tolist(), a.max_corner.tolist()
    (b_x0, b_y0), (b_x1, b_y1) = b.min_corner.tolist(), b.max_corner.tolist()
    # How far B must move along the outward normal of each face of A to leave A.
    penetrations = [b_y1 - a_y0, a_x1 - b_x0, a_y1 - b_y0, b_x1 - a_x0]
    face = min(range(4), key=penetrations.__getitem__)
    depth = penetrations[face]
    if depth < 0.0:
        return None  # a gap on this axis: separated

    normal_along_y = face in (0, 2)   # then the points spread along x, else along y
    if normal_along_y:
        level = (a_y0 + b_y1) / 2 if face == 0 else (a_y1 + b_y0) / 2
        a_lo, a_hi, b_lo, b_hi = a_x0, a_x1, b_x0, b_x1
    else:
        level = (a_x1 + b_x0) / 2 if face == 1 else (a_x0 + b_x1) / 2
        a_lo, a_hi, b_lo, b_hi = a_y0, a_y1, b_y0, b_y1

    # Ends of the overlap of the two faces.  Reference face `face` runs from A's vertex
    # `face` to `face + 1`; B's incident face is the opposite one, `face + 2`, whose first
    # vertex lies at the end of A's vertex `face + 1`.  Each end is B's vertex or, if that
    # lies beyond A's face, the cut by A's side plane; either way it keeps the id of B's
    # vertex, as in the polygon routine.
    incident = (face + 2) % 4
    next_is_high = face in (0, 1)   # does the face run towards increasing x or y?
    ends = []
    for b_vertex, at_high in ((incident, next_is_high), ((incident + 1) % 4, not next_is_high)):
        along = min(a_hi, b_hi) if at_high else max(a_lo, b_lo)
        ends.append((along, ("A", face, incident, b_vertex)))
    if ends[0][0] == ends[1][0]:
        ends = ends[:1]    # the faces share a single point (corners touching)
    points = [(along, level) if normal_along_y else (level, along) for along, _ in ends]
    return Contact(FACE_NORMALS[face], depth, points, [depth] * len(points), tuple(f for _, f in ends))
    ### END SOLUTION
