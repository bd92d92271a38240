"""Speculative manifolds: contact points of polygons that touch, overlap, or nearly touch.

The soft step (:mod:`solutions.response.soft_step`) finds contacts once per step and
moves the bodies several times before it looks again.  A box resting on a face then
needs both of its corners in the manifold even when one of them has lifted by a
hair: without that corner the box pivots on the other one and the stack rocks.  So,
as Box2D v3 does, the soft step keeps every clipped point within ``margin`` (m)
above the reference face, with its signed ``separation`` (m, > 0 apart, <= 0
overlapping); the solver lets a point with separation ``s > 0`` close at ``s / h``
and no faster, so a speculative point never pulls.

The reference face is chosen as
:func:`~solutions.narrowphase.polygon_polygon.collide_polygon_polygon` chooses it, by
:func:`~solutions.narrowphase.polygon_polygon.reference_face_candidates` (with
``margin``), and the clipping is its own,
:func:`~solutions.narrowphase.polygon_polygon.reference_face_manifold`, with points
kept up to ``margin`` above the reference face instead of 0.  One difference: the
first candidate is used, without ``collide_polygon_polygon``'s second look when A's
manifold misses B's deepest vertex (a deep-overlap case, about 2 % of random
overlapping pairs; moving B by ``depth * normal`` still separates them).  Circles are not handled here: the soft
step uses the exact contact for them.
Normal from A to B, SI units.
"""
from __future__ import annotations

import numpy as np

from ..contact import Contact
from ..shapes import AABB, OBB, ConvexPolygon
from .polygon_polygon import polygon_faces, reference_face_candidates, reference_face_manifold, tolerance_scale

#: Box2D's speculative distance, 4 times its linear slop of 5 mm (m).
SPECULATIVE_MARGIN = 0.02


def speculative_polygon_manifold(a: AABB | OBB | ConvexPolygon, b: AABB | OBB | ConvexPolygon,
                                 margin: float = SPECULATIVE_MARGIN) -> Contact | None:
    """Manifold of two polygonal shapes closer than ``margin``, with signed separations.

    Parameters
    ----------
    a, b : AABB, OBB or ConvexPolygon
        Shapes in world coordinates (m).
    margin : float
        Largest separation (m) of a point that is kept, >= 0.

    Returns
    -------
    Contact or None
        The contact: its ``separations`` are each point's signed separation (m, > 0
        apart) and its ``depths`` their overlaps, clamped at 0, as the
        :class:`~solutions.contact.Contact` conventions ask.  None when a face
        separates the shapes by more than ``margin`` or no point is that close.

    Examples
    --------
    A crate hovering 1 cm above the floor gives two speculative points:

    >>> floor = AABB((-5.0, -1.0), (5.0, 0.0))
    >>> crate = OBB((0.0, 0.51), (0.5, 0.5), 0.0)
    >>> contact = speculative_polygon_manifold(floor, crate)
    >>> contact.normal.tolist(), contact.depth, contact.separations.round(12).tolist()
    ([0.0, 1.0], 0.0, [0.01, 0.01])
    >>> speculative_polygon_manifold(floor, crate, margin=0.005) is None
    True
    """
    if not margin >= 0.0:
        raise ValueError(f"margin must be >= 0 m, got {margin}")
    polygon_a, polygon_b = polygon_faces(a), polygon_faces(b)
    candidates = reference_face_candidates(polygon_a, polygon_b, margin)
    if not candidates:
        return None  # a face separates the shapes by more than the margin
    ref_name, _, face, (ref_vertices, ref_normals, ref_faces), incident = candidates[0]
    scale = tolerance_scale(polygon_a[0], polygon_b[0])      # for the rounding tolerances
    n = ref_normals[int(np.flatnonzero(ref_faces == face)[0])]
    points, depths, ids = reference_face_manifold(ref_vertices, n, face, *incident, ref_name, scale, margin)
    if not points:
        return None
    depths = np.array(depths)                    # < 0 for points still apart: the Contact keeps them as separations
    normal = n if ref_name == "A" else 0.0 - n
    return Contact(normal, max(float(depths.max()), 0.0), np.array(points), depths, tuple(ids))
