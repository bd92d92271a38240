# Exercise file of the collision course: write the functions that raise NotImplementedError, then
# check them with `grader check sat`.
# Handed out with the course; generated from solutions/narrowphase/projection.py on the instructor's
# side.
"""Projecting shapes onto a candidate separating axis: the building blocks of SAT.

Separating axis theorem (2D, convex shapes): two convex shapes are disjoint if and only
if there is an axis on which their projections, the intervals ``[min, max]`` of
``Dot(point, axis)``, do not overlap.  For convex polygons the candidate axes are the
edge normals of both polygons: if they are separated, at least one edge normal
separates them (other axes may separate them too).

Conventions: intervals are closed, so intervals that share an end point overlap
(touching counts as colliding).  Vertices are counter-clockwise, so
``perp(edge) = (edge.y, -edge.x)`` points outwards.  Lengths in m.

The two classic bugs of the course notes live here: the running maximum must start at
``-inf`` (``FLT_MIN`` is the smallest *positive* float, so boxes on the negative side of
the origin look as if they overlap), and both running values must be reset for every
axis (otherwise the intervals of earlier axes leak into later ones).
"""
from __future__ import annotations

import math

import numpy as np

from ..shapes import AABB, OBB, ConvexPolygon
from ..vector import perp

#: An edge shorter than this fraction of the polygon's size (m per m) has no direction
#: that can be trusted, so :func:`edge_normals` skips it.  Such edges come from repeated
#: vertices; dropping them loses no candidate axis because the neighbouring edges of a
#: polygon of positive area still span every direction SAT needs.
ZERO_EDGE_RTOL = 1e-12


def project_vertices(vertices, axis) -> tuple[float, float]:
    """Interval ``(min, max)`` of ``Dot(v, axis)`` over all vertices ``v``.

    Parameters
    ----------
    vertices : array_like, shape (n, 2)
        Polygon vertices (m), n >= 1.
    axis : array_like, shape (2,)
        Direction to project on.  It need not be a unit vector for a yes/no overlap
        test, but it must be one when the interval is compared with a circle's
        projection or turned into a depth (then the interval is in m).

    Returns
    -------
    tuple of float
        ``(lowest, highest)`` with ``lowest <= highest``.

    Examples
    --------
    >>> project_vertices([[-6.0, -1.0], [-4.0, -1.0], [-4.0, 1.0], [-6.0, 1.0]], [1.0, 0.0])
    (-6.0, -4.0)
    """
    raise NotImplementedError("write project_vertices(), then run `grader check sat`")


def project_circle(center, radius: float, axis) -> tuple[float, float]:
    """Interval ``(c - r, c + r)`` of a circle on a unit ``axis``, with ``c = Dot(center, axis)``.

    The circle's projection has half-width ``radius`` (not the diameter) and the centre
    is projected with its sign (no ``abs``: folding negative values onto positive ones
    makes a circle at x = -10 look as if it overlapped a box at x = +10).

    Parameters
    ----------
    center : array_like, shape (2,)
        Circle centre (m).
    radius : float
        Circle radius (m), >= 0.
    axis : array_like, shape (2,)
        Unit vector.  With a non-unit axis the centre is scaled but the radius is not,
        which is wrong.

    Returns
    -------
    tuple of float
        ``(lowest, highest)`` (m along ``axis``).

    Examples
    --------
    >>> project_circle([-10.0, 0.0], 1.0, [1.0, 0.0])
    (-11.0, -9.0)
    """
    raise NotImplementedError("write project_circle(), then run `grader check sat`")


def intervals_overlap(a, b) -> bool:
    """Whether the closed intervals ``a = (a_min, a_max)`` and ``b`` overlap.

    Sharing only an end point counts as overlapping (touching counts as colliding).
    The intervals are separated when one ends before the other starts.

    Examples
    --------
    >>> intervals_overlap((-6.0, -4.0), (-3.0, -1.0))
    False
    >>> intervals_overlap((0.0, 1.0), (1.0, 2.0))
    True
    """
    raise NotImplementedError("write intervals_overlap(), then run `grader check sat`")


def interval_overlap_depth(a, b) -> float:
    """Shortest distance to slide ``b`` along the axis so that it only touches ``a``.

    ``min(a_max - b_min, b_max - a_min)``: positive when the intervals overlap, 0 when
    they touch, minus the gap when they are apart.  When one interval contains the
    other this is more than the length of their intersection, because ``b`` has to
    leave ``a`` entirely.  Same units as the intervals (m on a unit axis).

    Examples
    --------
    >>> interval_overlap_depth((0.0, 4.0), (3.0, 5.0))
    1.0
    >>> interval_overlap_depth((0.0, 1.0), (3.0, 5.0))
    -2.0
    """
    a_min, a_max = a
    b_min, b_max = b
    return float(min(a_max - b_min, b_max - a_min))


def edge_normals(vertices) -> np.ndarray:
    """Unit outward normals ``perp(v[k+1] - v[k]) / |...|`` of a CCW polygon's edges.

    Edges of (near) zero length, shorter than :data:`ZERO_EDGE_RTOL` times the
    polygon's size, are skipped; the others keep their order (edge 0 first).

    Parameters
    ----------
    vertices : array_like, shape (n, 2)
        Counter-clockwise vertices (m).

    Returns
    -------
    numpy.ndarray, shape (k, 2)
        One unit normal per edge of non-zero length, k <= n.

    Examples
    --------
    >>> edge_normals([[0.0, 0.0], [2.0, 0.0], [2.0, 0.0], [0.0, 1.0]]).round(3).tolist()
    [[0.0, -1.0], [0.447, 0.894], [-1.0, -0.0]]
    """
    v = np.asarray(vertices, dtype=float).reshape(-1, 2)
    edges = np.roll(v, -1, axis=0) - v
    kept = nonzero_edges(v)
    return perp(edges[kept]) / np.hypot(edges[kept, 0], edges[kept, 1])[:, None]


def nonzero_edges(vertices) -> np.ndarray:
    """Indices of the edges longer than :data:`ZERO_EDGE_RTOL` times the polygon's size.

    Edge ``k`` runs from vertex ``k`` to vertex ``k+1``.

    Examples
    --------
    >>> nonzero_edges([[0.0, 0.0], [2.0, 0.0], [2.0, 0.0], [0.0, 1.0]]).tolist()
    [0, 2, 3]
    """
    v = np.asarray(vertices, dtype=float).reshape(-1, 2)
    edges = np.roll(v, -1, axis=0) - v
    lengths = np.hypot(edges[:, 0], edges[:, 1])
    size = float(np.max(np.abs(v - v.mean(axis=0)))) if len(v) else 0.0
    return np.flatnonzero(lengths > ZERO_EDGE_RTOL * size)


def box_axes(box: AABB | OBB) -> np.ndarray:
    """Rows are the box's unit x and y axes (2, 2): the normals of its edges 1 and 2.

    A box needs only two candidate axes because opposite faces have opposite normals
    and an axis's sign does not change an overlap test.  The axes come from the angle,
    not from the edges, so a box of zero width (a segment or a point) still has both.

    Examples
    --------
    >>> box_axes(AABB((0.0, 0.0), (1.0, 1.0))).tolist()
    [[1.0, 0.0], [0.0, 1.0]]
    """
    if isinstance(box, AABB):
        return np.eye(2)
    return box.axes() + 0.0  # + 0.0 turns -0.0 into 0.0 (printing only)


def separating_axis_candidates(shape: AABB | OBB | ConvexPolygon) -> np.ndarray:
    """Candidate separating axes (k, 2), unit length, of one polygonal shape.

    Two per box (:func:`box_axes`), one per non-degenerate edge of a convex polygon
    (:func:`edge_normals`).  SAT for a pair tests the candidates of both shapes.

    Examples
    --------
    >>> separating_axis_candidates(OBB((0.0, 0.0), (2.0, 1.0), 0.0)).tolist()
    [[1.0, 0.0], [0.0, 1.0]]
    """
    if isinstance(shape, (AABB, OBB)):
        return box_axes(shape)
    if isinstance(shape, ConvexPolygon):
        return edge_normals(shape.vertices)
    raise TypeError(f"{type(shape).__name__} is not a polygonal shape")
