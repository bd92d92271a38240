# Exercise file of the collision course: write the functions that raise NotImplementedError, then
# check them with `grader check sat` (polygons_overlap, obbs_overlap) and `grader check contacts`
# (max_face_separation, reference_face_candidates, clip_segment_to_half_plane,
# reference_face_manifold, collide_polygon_polygon).
# Handed out with the course; generated from solutions/narrowphase/polygon_polygon.py on the
# instructor's side.
"""Convex polygon against convex polygon: SAT test, OBB-OBB test and contact manifold.

Works for every polygonal shape (AABB, OBB, ConvexPolygon) through
:func:`exercises.shapes.polygon_vertices`.  Box vertex and edge numbering::

        3 ---------- 2        edge k runs from vertex k to vertex k+1
        |            |        edge 0 faces -y, 1 faces +x, 2 faces +y, 3 faces -x
        |            |        (in the box's own frame)
        0 ---------- 1

Contact generation (the box2d-lite recipe):

1. *Face separation.*  For every face ``i`` of A (vertex ``v_i``, unit outward normal
   ``n_i``) the separation of B is ``s_i = min_j Dot(n_i, w_j - v_i)`` over B's
   vertices ``w_j``: > 0 means the face's line separates the shapes, <= 0 is minus the
   penetration along ``n_i``.  The same for B's faces against A.
2. *Reference face* = the face of largest separation (least penetration).  A keeps the
   role unless B's best face is clearly better (:data:`REFERENCE_FACE_RELATIVE_TOL`),
   so two nearly equal candidates do not swap from one step to the next, and unless
   A's manifold (steps 3-4) loses B's deepest vertex: then B's face is used
   (:func:`reference_face_candidates` lists the faces to try, in order).
3. *Incident face* = the face of the other polygon whose normal is most anti-parallel
   to the reference normal.
4. *Clipping* (Sutherland-Hodgman): cut the incident face by the two side planes of
   the reference face, then keep the points on or below the reference face.  Two
   parallel faces give a 2-point manifold, a vertex against a face gives one point.

Every contact point is the midpoint between the incident point and its projection on
the reference face; its depth is the distance between the two.  The normal points from
A to B: the reference normal if A holds the reference face, its opposite otherwise.

Scaffolding left readable for students (not exercises): :func:`polygon_faces`,
:func:`incident_face`.  Exercises: :func:`polygons_overlap`, :func:`obbs_overlap`,
:func:`max_face_separation`, :func:`reference_face_candidates`,
:func:`clip_segment_to_half_plane`, :func:`reference_face_manifold`,
:func:`collide_polygon_polygon`.  The soft step's speculative manifold
(:mod:`.speculative`) chooses its reference face with :func:`reference_face_candidates` too.
"""
from __future__ import annotations

import numpy as np

from ..contact import Contact
from ..shapes import AABB, OBB, ROUNDOFF_SIZE_RTOL, ConvexPolygon, polygon_vertices, rounding_tolerance
from .projection import (box_axes, edge_normals, intervals_overlap, nonzero_edges, project_vertices,
                         separating_axis_candidates)

#: B's reference face replaces A's only if its separation is larger by more than this
#: fraction of A's penetration depth (dimensionless).  box2d-lite uses 5 %; 2 % keeps
#: the reported depth within about 2 % of the least penetration, while still absorbing
#: the small tilts of a box resting on another one.
REFERENCE_FACE_RELATIVE_TOL = 0.02

#: ...plus this fraction of the pair's tolerance scale (m per m, :func:`tolerance_scale`):
#: the rounding of a separation, so that an exact tie (two identical boxes) is decided
#: the same way at the origin and at x = 1e6.
REFERENCE_FACE_ABSOLUTE_TOL = ROUNDOFF_SIZE_RTOL

#: A clipped point is kept if it lies at most this fraction of the pair's tolerance
#: scale (m per m, :func:`tolerance_scale`) above the reference face or beyond a side
#: plane, the rounding of a clipped point: two parallel faces that touch give both of
#: their points.  Its depth is 0.
KEEP_POINT_TOL = ROUNDOFF_SIZE_RTOL


def tolerance_scale(vertices_a, vertices_b) -> float | np.ndarray:
    """Length (m) whose :data:`KEEP_POINT_TOL` part is the pair's rounding tolerance.

    ``KEEP_POINT_TOL * tolerance_scale(a, b)`` is
    :func:`~exercises.shapes.rounding_tolerance` of the pair: a few ulps of its largest
    coordinate plus 1e-12 of its size (the larger extent of the two polygons).  So the
    tolerances follow the shapes: centimetre boxes get 1e-14 m at the origin and 1.8e-6 m
    at x = 1e9 m (where a coordinate is only known to 1.2e-7 m), never millimetres.

    Parameters
    ----------
    vertices_a, vertices_b : array_like, shape (..., n, 2)
        Vertices of the two polygons (m); leading axes hold many pairs (one scale each).

    Examples
    --------
    >>> square = np.array([[0.0, 0.0], [0.01, 0.0], [0.01, 0.01], [0.0, 0.01]])
    >>> [f"{KEEP_POINT_TOL * tolerance_scale(square + x, square + x):.1e}" for x in (0.0, 1e9)]
    ['1.0e-14', '1.8e-06']
    """
    a, b = np.asarray(vertices_a, dtype=float), np.asarray(vertices_b, dtype=float)
    size = np.maximum(np.ptp(a, axis=-2).max(axis=-1), np.ptp(b, axis=-2).max(axis=-1))
    coordinates = np.maximum(np.abs(a).max(axis=(-2, -1)), np.abs(b).max(axis=(-2, -1)))
    return rounding_tolerance(coordinates, size) / KEEP_POINT_TOL


def polygon_faces(shape: AABB | OBB | ConvexPolygon) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices, unit outward face normals and face indices of a polygonal shape.

    Face ``k`` runs from vertex ``k`` to vertex ``k+1``.  A box has four faces whose
    normals come from its angle, so even a zero-width box (a segment or a point) has
    all of them; a ConvexPolygon has one face per edge (it drops repeated and collinear
    vertices when it is built, so no two faces share a direction).

    Returns
    -------
    vertices : numpy.ndarray, shape (n, 2)
        CCW vertices (m).
    normals : numpy.ndarray, shape (k, 2)
        Unit outward normal of each kept face.
    faces : numpy.ndarray of int, shape (k,)
        Index of each kept face (its first vertex).

    Examples
    --------
    >>> vertices, normals, faces = polygon_faces(AABB((0.0, 0.0), (2.0, 1.0)))
    >>> normals.tolist(), faces.tolist()
    ([[0.0, -1.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0]], [0, 1, 2, 3])
    """
    vertices = np.asarray(polygon_vertices(shape), dtype=float)
    if isinstance(shape, (AABB, OBB)):
        x_axis, y_axis = box_axes(shape)
        normals = np.array([-y_axis, x_axis, y_axis, -x_axis]) + 0.0  # + 0.0 turns -0.0 into 0.0
        return vertices, normals, np.arange(4)
    return vertices, edge_normals(vertices), nonzero_edges(vertices)  # same edges, same order


def incident_face(normals: np.ndarray, faces: np.ndarray, reference_normal: np.ndarray) -> int:
    """Index of the face whose normal is most anti-parallel to ``reference_normal``.

    Examples
    --------
    >>> normals = np.array([[0.0, -1.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0]])
    >>> incident_face(normals, np.arange(4), np.array([0.0, 1.0]))
    0
    """
    return int(faces[int(np.argmin(normals @ reference_normal))])


def polygons_overlap(a: AABB | OBB | ConvexPolygon, b: AABB | OBB | ConvexPolygon) -> bool:
    """SAT yes/no test for two convex polygonal shapes; touching counts as overlapping.

    The candidate axes are the edge normals of both shapes (two per box).  The test
    stops at the first axis whose intervals do not overlap (early out): in a typical
    scene most pairs are apart and are rejected after one or two axes.

    Parameters
    ----------
    a, b : AABB, OBB or ConvexPolygon
        Shapes in world coordinates (m).

    Returns
    -------
    bool
        True if the shapes overlap or touch.

    Examples
    --------
    >>> polygons_overlap(OBB((-5.0, 0.0), (1.0, 1.0)), OBB((-2.0, 0.0), (1.0, 1.0)))
    False
    >>> triangle = ConvexPolygon([[0.0, 0.0], [2.0, 0.0], [0.0, 2.0]])
    >>> polygons_overlap(triangle, OBB((1.0, 1.0), (0.5, 0.5), 0.3))
    True
    """
    raise NotImplementedError("write polygons_overlap(), then run `grader check sat`")


def obbs_overlap(a: OBB | AABB, b: OBB | AABB) -> bool:
    """SAT yes/no test for two oriented boxes, with two normals per box.

    A box's four edge normals are ``perp(v1 - v0)``, ``perp(v2 - v1)`` and their
    opposites; an axis and its opposite give the same test, so the box's unit x and y
    axes (:func:`exercises.narrowphase.projection.box_axes`) are enough.  They are taken
    from the angle so that a zero-width box still has two axes.  Min and max start at
    ``+inf`` and ``-inf`` for each axis (see :func:`project_vertices`).

    Parameters
    ----------
    a, b : OBB or AABB
        Boxes in world coordinates (m).

    Returns
    -------
    bool
        True if the boxes overlap or touch.

    Examples
    --------
    >>> obbs_overlap(OBB((0.0, 0.0), (1.0, 1.0), 0.0), OBB((2.3, 0.0), (1.0, 1.0), 0.785398))
    True
    >>> obbs_overlap(OBB((0.0, 0.0), (1.0, 1.0), 0.0), OBB((2.5, 0.0), (1.0, 1.0), 0.0))
    False
    """
    raise NotImplementedError("write obbs_overlap(), then run `grader check sat`")


def max_face_separation(ref_vertices: np.ndarray, ref_normals: np.ndarray, ref_faces: np.ndarray,
                        other_vertices: np.ndarray) -> tuple[float, int]:
    """Largest face separation of ``other`` against the faces of the reference polygon.

    ``s_i = min_j Dot(n_i, w_j - v_i)``: how far the other polygon's deepest vertex
    ``w_j`` lies outside face ``i`` (m; negative = inside, i.e. penetrating).

    Returns
    -------
    separation : float
        ``max_i s_i`` (m).  > 0 means face ``i`` separates the polygons.
    face : int
        Index of that face (the first one on an exact tie).

    Examples
    --------
    >>> square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    >>> normals = np.array([[0.0, -1.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0]])
    >>> max_face_separation(square, normals, np.arange(4), square + [0.75, 0.5])
    (-0.25, 1)
    """
    raise NotImplementedError("write max_face_separation(), then run `grader check contacts`")


def reference_face_candidates(polygon_a: tuple, polygon_b: tuple, margin: float = 0.0) -> list[tuple]:
    """Steps 1 and 2 of the module docstring: the faces to try as the reference face, in order.

    The best face of A (separation ``s_a``, :func:`max_face_separation` of B's vertices)
    and the best face of B (``s_b``, of A's vertices).  If either separates the shapes by
    more than ``margin`` there is no contact: ``[]``.  Otherwise A keeps the reference
    role unless B's face is *clearly better*, ``s_b > s_a + REFERENCE_FACE_RELATIVE_TOL *
    |s_a| + REFERENCE_FACE_ABSOLUTE_TOL * tolerance_scale(vertices_a, vertices_b)``:

    - B clearly better: ``[B's]``;
    - B better, but not clearly (``s_b > s_a``): ``[A's, B's]``; :func:`collide_polygon_polygon`
      falls back to B's face when A's manifold misses B's deepest vertex;
    - otherwise (an exact tie included): ``[A's]``.

    :func:`collide_polygon_polygon` (``margin`` 0) and the soft step's speculative manifold
    (:func:`~exercises.narrowphase.speculative.speculative_polygon_manifold`, which takes
    the first candidate) both choose their reference face here.

    Parameters
    ----------
    polygon_a, polygon_b : tuple
        ``(vertices, normals, faces)`` of A and B, as returned by :func:`polygon_faces`.
    margin : float, optional
        Largest separation (m, >= 0) of shapes that still get candidates.

    Returns
    -------
    list of tuple
        Each candidate ``(ref_name, separation, face, reference_polygon, incident_polygon)``:
        ``"A"`` or ``"B"``, its separation (m), the face's index, then the
        ``(vertices, normals, faces)`` of the polygon holding the face and of the other one.

    Examples
    --------
    >>> ground, crate = polygon_faces(AABB((-5.0, -1.0), (5.0, 0.0))), polygon_faces(AABB((-0.5, -0.1), (0.5, 0.9)))
    >>> [(name, round(separation, 12), face) for name, separation, face, _, _ in reference_face_candidates(ground, crate)]
    [('A', -0.1, 2)]
    >>> reference_face_candidates(ground, polygon_faces(AABB((-0.5, 0.01), (0.5, 1.0))))
    []
    >>> [name for name, *_ in reference_face_candidates(ground, polygon_faces(AABB((-0.5, 0.01), (0.5, 1.0))),
    ...                                                 margin=0.02)]
    ['A']
    """
    raise NotImplementedError("write reference_face_candidates(), then run `grader check contacts`")


def clip_segment_to_half_plane(points: list, plane_normal: np.ndarray, plane_offset: float,
                               tolerance: float = 0.0) -> list:
    """One Sutherland-Hodgman step: the part of a segment where ``Dot(n, x) <= offset``.

    Parameters
    ----------
    points : list of (numpy.ndarray, hashable)
        One or two ``(point, feature_id)`` pairs: the end points of the segment (m).
    plane_normal : numpy.ndarray, shape (2,)
        Normal ``n`` of the clipping line, pointing to the side that is cut away.
    plane_offset : float
        The line is ``Dot(n, x) = offset`` (m if ``n`` is a unit vector).
    tolerance : float, optional
        End points at most this far beyond the line (m) count as on it and are kept.
        A crossing point computed by one step is on the line only up to roundoff,
        and the next step must not drop it (a zero-length reference face has both
        side planes on the same line).

    Returns
    -------
    list of (numpy.ndarray, hashable)
        The kept end points, in input order, then the crossing point if any.  The
        crossing point replaces the end point that was cut away and keeps its feature
        id, so the id of a contact point does not change when a side plane starts or
        stops cutting (as in Box2D v3).

    Examples
    --------
    >>> segment = [(np.array([0.0, 0.0]), "v0"), (np.array([4.0, 0.0]), "v1")]
    >>> [(p.tolist(), i) for p, i in clip_segment_to_half_plane(segment, np.array([1.0, 0.0]), 3.0)]
    [([0.0, 0.0], 'v0'), ([3.0, 0.0], 'v1')]
    """
    raise NotImplementedError("write clip_segment_to_half_plane(), then run `grader check contacts`")


def reference_face_manifold(ref_vertices: np.ndarray, ref_normal: np.ndarray, ref_face: int,
                            inc_vertices: np.ndarray, inc_normals: np.ndarray, inc_faces: np.ndarray,
                            ref_name: str, scale: float, margin: float = 0.0) -> tuple[list, list, list]:
    """Contact points of the incident face clipped against reference face ``ref_face``.

    Steps 3 and 4 of the module docstring: pick the incident face, clip it by the two
    side planes of the reference face, keep the points on or below the reference face
    (up to :data:`KEEP_POINT_TOL` times ``scale``, m) or at most ``margin`` above it,
    and move each one halfway to the reference face.  ``margin`` is 0 for a contact;
    the soft step's speculative contacts (:mod:`.speculative`) keep points that are
    still apart but nearly touching, as Box2D v3 does, with a negative depth.

    Parameters
    ----------
    ref_vertices : numpy.ndarray, shape (n, 2)
        Vertices of the polygon holding the reference face (m).
    ref_normal : numpy.ndarray, shape (2,)
        Unit outward normal of the reference face.
    ref_face : int
        Index of the reference face (from vertex ``ref_face`` to ``ref_face + 1``).
    inc_vertices, inc_normals, inc_faces
        The other polygon, as returned by :func:`polygon_faces`.
    ref_name : str
        ``"A"`` or ``"B"``, the first entry of every feature id.
    scale : float
        The pair's tolerance scale (m, :func:`tolerance_scale`): points up to
        ``KEEP_POINT_TOL * scale`` beyond a side plane or above the face are on it.
    margin : float, optional
        Largest distance (m, >= 0) above the reference face of a point that is kept.

    Returns
    -------
    points : list of numpy.ndarray
        0, 1 or 2 contact points (m), never the same point twice: when the two clipped
        points coincide (up to the rounding tolerance), as a zero-size incident face's
        do, the first is kept.
    depths : list of float
        Depth of each point below the reference face (m, may be -0 when touching;
        down to ``-margin`` for a point above it).
    feature_ids : list of tuple
        One id per point, ``(ref_name, ref_face, incident_face, k)``, see
        :func:`collide_polygon_polygon`.

    Examples
    --------
    >>> floor = np.array([[-5.0, -1.0], [5.0, -1.0], [5.0, 0.0], [-5.0, 0.0]])
    >>> crate_vertices, crate_normals, crate_faces = polygon_faces(AABB((-0.5, -0.1), (0.5, 0.9)))
    >>> points, depths, ids = reference_face_manifold(floor, np.array([0.0, 1.0]), 2, crate_vertices,
    ...                                               crate_normals, crate_faces, "A", 5.0)
    >>> [p.round(12).tolist() for p in points], [round(d, 12) for d in depths], ids
    ([[-0.5, -0.05], [0.5, -0.05]], [0.1, 0.1], [('A', 2, 0, 0), ('A', 2, 0, 1)])

    The crate lifted to hover 1 cm above the floor: no point, unless the margin
    reaches it.

    >>> hovering = crate_vertices + [0.0, 0.11]
    >>> reference_face_manifold(floor, np.array([0.0, 1.0]), 2, hovering, crate_normals, crate_faces, "A", 5.0)
    ([], [], [])
    >>> points, depths, ids = reference_face_manifold(floor, np.array([0.0, 1.0]), 2, hovering, crate_normals,
    ...                                               crate_faces, "A", 5.0, margin=0.02)
    >>> [p.round(12).tolist() for p in points], [round(d, 12) for d in depths]
    ([[-0.5, 0.005], [0.5, 0.005]], [-0.01, -0.01])
    """
    raise NotImplementedError("write reference_face_manifold(), then run `grader check contacts`")


def collide_polygon_polygon(a: AABB | OBB | ConvexPolygon, b: AABB | OBB | ConvexPolygon) -> Contact | None:
    """Contact manifold between two convex polygonal shapes, or None if they are apart.

    See the module docstring for the algorithm.  ``normal`` is the reference face's
    normal, turned to point from A to B, and ``depth`` the overlap along it: the least
    penetration over all faces, or within :data:`REFERENCE_FACE_RELATIVE_TOL` of it when
    A keeps the reference role.  A keeps it only if its manifold still holds the
    incident polygon's deepest vertex; otherwise the least-penetration face is used.
    Moving B by ``depth * normal`` separates the shapes.  ``points`` holds 1 or 2
    points, each the midpoint between the incident point and the reference face, with
    its own ``depths`` entry.  ``feature_ids`` are ``(ref, face, incident_face, k)``:
    ``ref`` is ``"A"`` or ``"B"`` (who holds the reference face), ``face`` the reference
    face, ``incident_face`` the other polygon's clipped face and ``k`` the end vertex of
    that face the point comes from, either the vertex itself or, when a side plane cut
    it away, the cut.  They stay the same while those two faces touch.

    Parameters
    ----------
    a, b : AABB, OBB or ConvexPolygon
        Shapes in world coordinates (m).

    Returns
    -------
    Contact or None
        None when a face separates the shapes (separation > 0); touching (depth 0)
        gives a contact.

    Examples
    --------
    >>> ground = AABB((-5.0, -1.0), (5.0, 0.0))
    >>> crate = OBB((0.0, 0.4), (0.5, 0.5), 0.0)
    >>> contact = collide_polygon_polygon(ground, crate)
    >>> contact.normal.tolist(), round(contact.depth, 12), sorted(contact.points.round(12).tolist())
    ([0.0, 1.0], 0.1, [[-0.5, -0.05], [0.5, -0.05]])
    """
    raise NotImplementedError("write collide_polygon_polygon(), then run `grader check contacts`")
