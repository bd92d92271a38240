"""Speculative box-box manifolds for many pairs at once (numpy).

The readable reference is
:func:`solutions.narrowphase.speculative.speculative_polygon_manifold`; this module
runs the same steps on arrays of ``m`` box pairs ``(A_k, B_k)`` and gives the same
answer for every pair, up to floating rounding:

1. *Corners and normals* of each box from its angle, as
   :func:`~solutions.shapes.box_vertices` and
   :func:`~solutions.narrowphase.polygon_polygon.polygon_faces` compute them (so a
   zero-size box still has four faces).  Numbering::

        3 ---------- 2        edge k runs from vertex k to vertex k+1
        |            |        edge 0 faces -y, 1 faces +x, 2 faces +y, 3 faces -x
        |            |        (in the box's own frame)
        0 ---------- 1

2. *Face separations* ``s_i = min_j Dot(n_i, w_j - v_i)`` of B against A's four faces
   and of A against B's; a pair is dropped when either maximum exceeds ``margin``.
3. *Reference face*: A's best face, unless B's is clearly better
   (:data:`~solutions.narrowphase.polygon_polygon.REFERENCE_FACE_RELATIVE_TOL` of A's
   separation plus
   :data:`~solutions.narrowphase.polygon_polygon.REFERENCE_FACE_ABSOLUTE_TOL` times
   the pair's :func:`~solutions.narrowphase.polygon_polygon.tolerance_scale`).
4. *Incident face*: the other box's face whose normal is most anti-parallel.
5. *Clipping* by the two side planes of the reference face (one Sutherland-Hodgman
   step each, with the roundoff tolerance
   :data:`~solutions.narrowphase.polygon_polygon.KEEP_POINT_TOL` times that scale: a
   cut point replaces the end point that was cut away and keeps its feature id), then
   *keeping* the points at most ``margin`` above the reference face that are not
   duplicates, each moved halfway to the face.

Ties (equal separations, equally anti-parallel faces) go to the first index, as
``numpy.argmax`` and ``numpy.argmin`` do in the scalar code.  The corners and the
incident-face dot products go through the same numpy products as the scalar code
(a batched ``matmul`` calls the same kernel per pair), so exact ties are broken the
same way.  Normal from A to B, SI units.
"""
from __future__ import annotations

### INSTRUCTOR ONLY: not in the student edition (the contacts exercise's clipping for boxes, in numpy form).

import math
from dataclasses import dataclass

import numpy as np

from ..contact import Contact
from ..shapes import AABB, OBB
from .batch_sat import checked_array
from .polygon_polygon import KEEP_POINT_TOL, REFERENCE_FACE_ABSOLUTE_TOL, REFERENCE_FACE_RELATIVE_TOL, tolerance_scale
from .speculative import SPECULATIVE_MARGIN


@dataclass(frozen=True, eq=False)
class BoxManifolds:
    """Speculative manifolds of ``m`` box pairs ``(A_k, B_k)``, as arrays.

    Pair ``k`` has a manifold when ``found[k]``; its points are
    ``points[k, :count[k]]``.  Slots that hold no point (all slots of a pair without
    a manifold) are NaN in the float arrays and -1 in the integer ones.

    Attributes
    ----------
    found : numpy.ndarray of bool, shape (m,)
        Whether the scalar function returns a manifold (not None).
    normal : numpy.ndarray, shape (m, 2)
        Unit normal from A to B (NaN when not found).
    count : numpy.ndarray of int, shape (m,)
        Number of points, 0, 1 or 2 (0 exactly when not found).
    points : numpy.ndarray, shape (m, 2, 2)
        Contact points (m): midpoints between the incident point and the reference face.
    separations : numpy.ndarray, shape (m, 2)
        Signed separation of each point (m; > 0 apart, <= 0 overlapping).
    reference_is_b : numpy.ndarray of bool, shape (m,)
        True when B holds the reference face (False when not found).
    reference_face, incident_face : numpy.ndarray of int, shape (m,)
        Reference face (of A, or of B if ``reference_is_b``) and incident face of the
        other box, 0..3 (-1 when not found).
    vertex : numpy.ndarray of int, shape (m, 2)
        End vertex of the incident face each point comes from, 0..3 (-1 in empty slots).

    The feature id of point ``s`` of pair ``k`` is ``("B" if reference_is_b[k] else "A",
    reference_face[k], incident_face[k], vertex[k, s])``.
    """

    found: np.ndarray
    normal: np.ndarray
    count: np.ndarray
    points: np.ndarray
    separations: np.ndarray
    reference_is_b: np.ndarray
    reference_face: np.ndarray
    incident_face: np.ndarray
    vertex: np.ndarray

    def __len__(self) -> int:
        return len(self.found)


def _box_faces(centre: np.ndarray, half: np.ndarray, angle: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Corners (m, 4, 2) and unit outward face normals (m, 4, 2) of ``m`` boxes.

    The same arithmetic as ``box_vertices`` and ``polygon_faces``: ``math.cos`` and
    ``math.sin`` (as ``rotation_matrix``) and the local corners times ``R^T`` through
    ``matmul``, so the corners are those of the scalar code bit for bit.
    """
    cos = np.array([math.cos(t) for t in angle.tolist()])
    sin = np.array([math.sin(t) for t in angle.tolist()])
    rotation = np.empty((len(angle), 2, 2))
    rotation[:, 0, 0], rotation[:, 0, 1], rotation[:, 1, 0], rotation[:, 1, 1] = cos, -sin, sin, cos
    hx, hy = half[:, 0], half[:, 1]
    corners_local = np.stack([np.stack([-hx, -hy], axis=1), np.stack([hx, -hy], axis=1),
                              np.stack([hx, hy], axis=1), np.stack([-hx, hy], axis=1)], axis=1)
    vertices = corners_local @ rotation.transpose(0, 2, 1) + centre[:, None, :]
    x_axis = np.stack([cos, sin], axis=1) + 0.0            # rows of R^T, as box_axes
    y_axis = np.stack([-sin, cos], axis=1) + 0.0
    normals = np.stack([-y_axis, x_axis, y_axis, -x_axis], axis=1) + 0.0
    return vertices, normals


def _max_face_separation(ref_vertices: np.ndarray, ref_normals: np.ndarray,
                         other_vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``max_i min_j Dot(n_i, w_j - v_i)`` (m,) and the first face ``i`` reaching it (m,)."""
    offsets = other_vertices[:, None, :, :] - ref_vertices[:, :, None, :]     # w_j - v_i, (m, 4, 4, 2)
    separations = (offsets[..., 0] * ref_normals[:, :, None, 0]
                   + offsets[..., 1] * ref_normals[:, :, None, 1]).min(axis=2)
    face = np.argmax(separations, axis=1)
    return separations[np.arange(len(face)), face], face


def _clip(points, ids, count, plane_normal, plane_offset, tolerance):
    """One Sutherland-Hodgman step on every pair, as ``clip_segment_to_half_plane``.

    ``points`` (m, 2, 2) and ``ids`` (m, 2) hold ``count`` (m,) end points in their
    first slots.  The kept end points come first, in input order, then the crossing
    point, which takes the id of the end point that was cut away.
    """
    distances = points[..., 0] * plane_normal[:, None, 0] + points[..., 1] * plane_normal[:, None, 1]
    distances = distances - plane_offset[:, None]
    d0, d1 = distances[:, 0], distances[:, 1]
    keep0 = (count >= 1) & (d0 <= tolerance)
    keep1 = (count >= 2) & (d1 <= tolerance)
    cross = (count == 2) & (keep0 != keep1) & (d0 * d1 < 0.0)
    p0, p1 = points[:, 0], points[:, 1]
    with np.errstate(divide="ignore", invalid="ignore"):   # only used where d0 * d1 < 0
        fraction = d0 / (d0 - d1)
        crossing = p0 + fraction[:, None] * (p1 - p0)
    crossing_id = np.where(d1 > 0.0, ids[:, 1], ids[:, 0])
    first = np.where(keep0[:, None], p0, p1)
    first_id = np.where(keep0, ids[:, 0], ids[:, 1])
    second = np.where(cross[:, None], crossing, p1)
    second_id = np.where(cross, crossing_id, ids[:, 1])
    return (np.stack([first, second], axis=1), np.stack([first_id, second_id], axis=1),
            keep0.astype(int) + keep1 + cross)


def speculative_box_manifolds(centre_a, half_a, angle_a, centre_b, half_b, angle_b,
                              margin: float = SPECULATIVE_MARGIN) -> BoxManifolds:
    """Speculative manifolds of ``m`` box pairs, as the scalar function finds them.

    Pair ``k`` is ``OBB(centre_a[k], half_a[k], angle_a[k])`` against
    ``OBB(centre_b[k], half_b[k], angle_b[k])``; the result for it is that of
    :func:`~solutions.narrowphase.speculative.speculative_polygon_manifold` on the two
    boxes (up to floating rounding), see :func:`manifolds_as_contacts`.  An AABB is
    the OBB of its centre and half-extents at angle 0.

    Parameters
    ----------
    centre_a, centre_b : array_like, shape (m, 2)
        Box centres (m).
    half_a, half_b : array_like, shape (m, 2)
        Half-extents (m) along each box's own x and y axes, >= 0 (0 allowed).
    angle_a, angle_b : array_like, shape (m,)
        Box angles (rad, counter-clockwise).
    margin : float
        Largest separation (m) of a point that is kept, >= 0.

    Returns
    -------
    BoxManifolds
        Arrays of the normals, points, signed separations and feature ids; empty
        slots are NaN (floats) or -1 (ints).

    Raises
    ------
    ValueError
        For ``margin < 0``, mismatched shapes, NaN or infinite values, or a negative
        half-extent.

    Examples
    --------
    A crate hovering 1 cm above the floor, and the same crate 1 m above it:

    >>> result = speculative_box_manifolds([[0.0, -0.5], [0.0, -0.5]], [[5.0, 0.5], [5.0, 0.5]], [0.0, 0.0],
    ...                                    [[0.0, 0.51], [0.0, 1.5]], [[0.5, 0.5], [0.5, 0.5]], [0.0, 0.0])
    >>> result.found.tolist(), result.count.tolist(), result.normal[0].tolist()
    ([True, False], [2, 0], [0.0, 1.0])
    >>> result.points[0].round(12).tolist(), result.separations[0].round(12).tolist()
    ([[-0.5, 0.005], [0.5, 0.005]], [0.01, 0.01])
    >>> result.reference_face.tolist(), result.incident_face.tolist(), result.vertex.tolist()
    ([2, -1], [0, -1], [[0, 1], [-1, -1]])
    """
    if not margin >= 0.0:
        raise ValueError(f"margin must be >= 0 m, got {margin}")
    centre_a = checked_array("centre_a", centre_a, (0, 2), None)
    m = len(centre_a)
    half_a = checked_array("half_a", half_a, (0, 2), m)
    angle_a = checked_array("angle_a", angle_a, (0,), m)
    centre_b = checked_array("centre_b", centre_b, (0, 2), m)
    half_b = checked_array("half_b", half_b, (0, 2), m)
    angle_b = checked_array("angle_b", angle_b, (0,), m)
    if np.any(half_a < 0) or np.any(half_b < 0):
        raise ValueError("half-extents must be >= 0")
    rows = np.arange(m)

    vertices_a, normals_a = _box_faces(centre_a, half_a, angle_a)
    vertices_b, normals_b = _box_faces(centre_b, half_b, angle_b)
    separation_a, face_a = _max_face_separation(vertices_a, normals_a, vertices_b)
    separation_b, face_b = _max_face_separation(vertices_b, normals_b, vertices_a)
    close = (separation_a <= margin) & (separation_b <= margin)
    scale = tolerance_scale(vertices_a, vertices_b)          # (m,), for the rounding tolerances
    b_ref = separation_b > (separation_a + REFERENCE_FACE_RELATIVE_TOL * np.abs(separation_a)
                            + REFERENCE_FACE_ABSOLUTE_TOL * scale)

    # Reference box (its face, unit normal n, side vertices v1 -> v2) and incident box.
    pick = b_ref[:, None, None]
    ref_vertices, ref_normals = np.where(pick, vertices_b, vertices_a), np.where(pick, normals_b, normals_a)
    inc_vertices, inc_normals = np.where(pick, vertices_a, vertices_b), np.where(pick, normals_a, normals_b)
    face = np.where(b_ref, face_b, face_a)
    n = ref_normals[rows, face]
    tangent = np.stack([-n[:, 1], n[:, 0]], axis=1)
    v1, v2 = ref_vertices[rows, face], ref_vertices[rows, (face + 1) % 4]

    j = np.argmin(np.matmul(inc_normals, n[:, :, None])[:, :, 0], axis=1)   # as normals @ n
    j2 = (j + 1) % 4
    segment = np.stack([inc_vertices[rows, j], inc_vertices[rows, j2]], axis=1)
    ids = np.stack([j, j2], axis=1)
    count = np.full(m, 2)

    roundoff = KEEP_POINT_TOL * scale
    offset_2 = tangent[:, 0] * v2[:, 0] + tangent[:, 1] * v2[:, 1]
    segment, ids, count = _clip(segment, ids, count, tangent, offset_2, roundoff)
    minus_tangent = -tangent
    offset_1 = minus_tangent[:, 0] * v1[:, 0] + minus_tangent[:, 1] * v1[:, 1]
    segment, ids, count = _clip(segment, ids, count, minus_tangent, offset_1, roundoff)

    relative = segment - v1[:, None, :]
    separations = relative[..., 0] * n[:, None, 0] + relative[..., 1] * n[:, None, 1]
    midpoints = segment - (0.5 * separations)[:, :, None] * n[:, None, :]
    low = separations <= (margin + roundoff)[:, None]
    keep0 = close & (count >= 1) & low[:, 0]
    duplicate = keep0 & (np.abs(midpoints[:, 1] - midpoints[:, 0]).max(axis=1) <= roundoff)
    keep1 = close & (count >= 2) & low[:, 1] & ~duplicate

    # Kept points first, in clipping order; empty slots NaN / -1.
    count = keep0.astype(int) + keep1
    found = count > 0
    first = np.where(keep0, 0, 1)
    points = np.full((m, 2, 2), np.nan)
    kept_separations = np.full((m, 2), np.nan)
    vertex = np.full((m, 2), -1)
    points[found, 0] = midpoints[rows, first][found]
    kept_separations[found, 0] = separations[rows, first][found]
    vertex[found, 0] = ids[rows, first][found]
    both = count == 2
    points[both, 1] = midpoints[both, 1]
    kept_separations[both, 1] = separations[both, 1]
    vertex[both, 1] = ids[both, 1]

    normal = np.where(b_ref[:, None], 0.0 - n, n)
    normal[~found] = np.nan
    return BoxManifolds(found=found, normal=normal, count=count, points=points, separations=kept_separations,
                        reference_is_b=b_ref & found, reference_face=np.where(found, face, -1),
                        incident_face=np.where(found, j, -1), vertex=vertex)


def manifolds_as_contacts(result: BoxManifolds) -> list[Contact | None]:
    """What the scalar function returns for each pair: a Contact or None.

    The contact's ``separations`` are the pair's (m), its ``depths`` ``max(-separations,
    0)``, its ``depth`` their maximum and its ``feature_ids`` the tuples ``(ref, face,
    incident_face, vertex)`` described in :class:`BoxManifolds`.

    Examples
    --------
    >>> result = speculative_box_manifolds([[0.0, -0.5]], [[5.0, 0.5]], [0.0],
    ...                                    [[0.0, 0.45]], [[0.5, 0.5]], [0.0])
    >>> contact, = manifolds_as_contacts(result)
    >>> round(contact.depth, 12), contact.separations.round(12).tolist(), contact.feature_ids
    (0.05, [-0.05, -0.05], (('A', 2, 0, 0), ('A', 2, 0, 1)))
    """
    # Everything but the Contact objects is computed on the arrays at once.
    all_depths = np.maximum(-result.separations, 0.0)                  # NaN in empty slots
    depth = np.where(result.count == 2, np.fmax(all_depths[:, 0], all_depths[:, 1]), all_depths[:, 0]).tolist()
    names = np.where(result.reference_is_b, "B", "A").tolist()
    faces, incident = result.reference_face.tolist(), result.incident_face.tolist()
    vertices, counts = result.vertex.tolist(), result.count.tolist()
    out: list[Contact | None] = []
    for k, count in enumerate(counts):
        if count == 0:
            out.append(None)
            continue
        ids = tuple((names[k], faces[k], incident[k], vertex) for vertex in vertices[k][:count])
        out.append(Contact(result.normal[k], depth[k], result.points[k, :count], all_depths[k, :count], ids,
                           result.separations[k, :count]))
    return out


def box_pose(shape: AABB | OBB) -> tuple[np.ndarray, np.ndarray, float]:
    """``(centre, half_extents, angle)`` of a box (m, m, rad), the form
    :func:`speculative_box_manifolds` takes; an AABB has angle 0.

    >>> [x.tolist() if hasattr(x, "tolist") else x for x in box_pose(AABB((0.0, 0.0), (2.0, 1.0)))]
    [[1.0, 0.5], [1.0, 0.5], 0.0]
    """
    if isinstance(shape, AABB):
        return shape.center, shape.half_extents, 0.0
    return shape.center, shape.half_extents, float(shape.angle)
