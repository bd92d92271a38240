"""Speculative box-box manifolds for many pairs at once, compiled with numba.

:func:`speculative_box_manifolds_numba` is the compiled twin of
:func:`solutions.narrowphase.speculative_batch.speculative_box_manifolds` (numpy):
same inputs, same :class:`~solutions.narrowphase.speculative_batch.BoxManifolds`
output, same steps (corners and normals, face separations, reference face, incident
face, two clipping steps, keep and deduplicate), written as one loop over the pairs
instead of whole-array steps, so it allocates only its outputs.  Read the numpy module
(and the readable :func:`~solutions.narrowphase.speculative.speculative_polygon_manifold`
behind it) for what each step means; this file follows it line by line.

Equal to the numpy version, and how exactly
    Every step does the same floating-point operations in the same order, so the
    results are the numpy version's bit for bit on this machine (the tests ask for
    1e-12 and the same counts, flags and feature ids).  Two of numpy's steps are
    ``matmul`` calls (the corners, and the incident-face dot products), which numpy
    hands to its BLAS; a BLAS may fuse a product and a sum into one FMA (one
    rounding), and which of the two products it fuses depends on the BLAS kernel
    chosen for the CPU.  :func:`matmul_rounding` finds out once per process, by
    comparing numpy's ``matmul`` on a fixed probe with the three candidates (plain,
    or one of the two fused forms), and the kernel then rounds the same way.  If no
    candidate matches (an unknown BLAS), the kernel uses plain arithmetic: every
    result still agrees to about 1e-15 m per m of coordinates, but exact ties (two
    faces equally good to the last bit, as between two equal boxes) may be broken
    differently, giving another face, normal and feature ids.  (Measured here with
    plain arithmetic forced: 33 of 250 equal-box pairs and 105 of 250 equal squares
    turned by quarter turns came out different.)

Conventions (as the numpy version): SI units, angles in radians counter-clockwise,
normal from A to B, separations > 0 apart and <= 0 overlapping, ties to the first
index, empty slots NaN (floats) or -1 (ints).  Compiled with ``@njit(cache=True)``:
the first call in a fresh checkout compiles (a few seconds) and stores the machine
code in ``__pycache__``; later processes load it.
"""
from __future__ import annotations

### INSTRUCTOR ONLY: not in the student edition (the contacts exercise's clipping for boxes, compiled).

import math

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

from ..shapes import EPS, ROUNDOFF_SIZE_RTOL, ROUNDOFF_ULPS
from .batch_sat import checked_array
from .polygon_polygon import KEEP_POINT_TOL, REFERENCE_FACE_ABSOLUTE_TOL, REFERENCE_FACE_RELATIVE_TOL
from .speculative import SPECULATIVE_MARGIN
from .speculative_batch import BoxManifolds
from ..compiled_cache import forget_stale_machine_code
from ..compiled_views import contiguous_view

#: ``ROUNDOFF_ULPS * EPS``, the first factor of ``rounding_tolerance`` (evaluated as there).
_ULPS_EPS = ROUNDOFF_ULPS * EPS

#: Rows of the manifolds' integer block (one column per pair): found (0 or 1), point
#: count, whether B holds the reference face (0 or 1), the reference and incident faces,
#: and the two points' vertex ids (-1 where no point).
(MANIFOLD_FOUND, MANIFOLD_COUNT, MANIFOLD_REFERENCE_IS_B, MANIFOLD_REFERENCE_FACE, MANIFOLD_INCIDENT_FACE,
 MANIFOLD_VERTEX) = range(6)
MANIFOLD_INTS = 7
#: Rows of their float block: the normal (from A to B), the two points' separations (m),
#: and the two points (m) as x0, y0, x1, y1 (NaN where no point).
MANIFOLD_NX, MANIFOLD_NY, MANIFOLD_SEPARATION, MANIFOLD_POINT = 0, 1, 2, 4
MANIFOLD_FLOATS = 8
#: Size of the clipping work space of :func:`indexed_manifolds`: floats, then integers.
CLIPPING_FLOATS, CLIPPING_INTS = 10, 2

#: How a two-term dot product ``a0 * b0 + a1 * b1`` is rounded (see the module docstring).
PLAIN, FUSE_SECOND, FUSE_FIRST = 0, 1, 2
ROUNDING_NAMES = {PLAIN: "a0*b0 + a1*b1 (two roundings of products, one of the sum)",
                  FUSE_SECOND: "fma(a1, b1, a0*b0)", FUSE_FIRST: "fma(a0, b0, a1*b1)"}


@intrinsic
def _fma(typingctx, a, b, c):
    """``a * b + c`` with one rounding (LLVM's ``llvm.fma``; exact in software if the CPU lacks FMA)."""
    signature = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, sig, args):
        double = ir.DoubleType()
        function = builder.module.declare_intrinsic("llvm.fma", [double], ir.FunctionType(double, [double] * 3))
        return builder.call(function, args)

    return signature, codegen


@njit(cache=True, inline="always")
def _dot2(a0, a1, b0, b1, rounding):
    """``a0 * b0 + a1 * b1`` rounded as ``rounding`` says."""
    if rounding == FUSE_SECOND:
        return _fma(a1, b1, a0 * b0)
    if rounding == FUSE_FIRST:
        return _fma(a0, b0, a1 * b1)
    return a0 * b0 + a1 * b1


@njit(cache=True)
def _dot2_all(a, b, rounding):
    """Row-wise ``_dot2`` of two (k, 2) arrays (used by :func:`matmul_rounding`)."""
    out = np.empty(a.shape[0])
    for k in range(a.shape[0]):
        out[k] = _dot2(a[k, 0], a[k, 1], b[k, 0], b[k, 1], rounding)
    return out


_ROUNDING: tuple[int, int, bool] | None = None


def matmul_rounding() -> tuple[int, int, bool]:
    """How numpy's batched ``matmul`` rounds the two products the numpy version uses.

    Returns ``(corners, incident, exact)``: the rounding (:data:`PLAIN`,
    :data:`FUSE_SECOND` or :data:`FUSE_FIRST`) of the corner product
    ``(m, 4, 2) @ (m, 2, 2)`` (the local corners times the transposed rotation) and of
    the incident-face product ``(m, 4, 2) @ (m, 2, 1)``, and whether both were
    identified (False: PLAIN is used where none matched).  Found once per process on a
    fixed probe laid out as in :mod:`~solutions.narrowphase.speculative_batch`.
    """
    global _ROUNDING
    if _ROUNDING is None:
        rng = np.random.default_rng(20240612)
        m = 64
        angle = rng.uniform(-4.0, 4.0, m)
        cos, sin = np.cos(angle), np.sin(angle)
        rotation = np.empty((m, 2, 2))
        rotation[:, 0, 0], rotation[:, 0, 1], rotation[:, 1, 0], rotation[:, 1, 1] = cos, -sin, sin, cos
        local = rng.normal(size=(m, 4, 2))
        corners = local @ rotation.transpose(0, 2, 1)          # as the numpy version's corners
        normals = rng.normal(size=(m, 4, 2))
        n = rng.normal(size=(m, 2))
        dots = np.matmul(normals, n[:, :, None])[:, :, 0]       # as its incident-face products

        def identify(got, rows_a, rows_b):
            for rounding in (PLAIN, FUSE_SECOND, FUSE_FIRST):
                if np.array_equal(_dot2_all(rows_a, rows_b, rounding), got.reshape(-1)):
                    return rounding
            return None

        # corners[k, i, c] = local[k, i] . rotation[k, c];  dots[k, q] = normals[k, q] . n[k]
        corner_rounding = identify(corners, np.repeat(local.reshape(-1, 2), 2, axis=0),
                                   np.broadcast_to(rotation[:, None], (m, 4, 2, 2)).reshape(-1, 2))
        incident_rounding = identify(dots, normals.reshape(-1, 2), np.repeat(n, 4, axis=0))
        _ROUNDING = (PLAIN if corner_rounding is None else corner_rounding,
                     PLAIN if incident_rounding is None else incident_rounding,
                     corner_rounding is not None and incident_rounding is not None)
    return _ROUNDING


@njit(cache=True, inline="always")
def _box_faces(cx, cy, hx, hy, cos, sin, corner_rounding, vertices, normals):
    """Corners and unit outward normals of one box into ``vertices``/``normals`` (4, 2),
    with the numpy version's arithmetic (``+ 0.0`` turns -0.0 into 0.0 as it does)."""
    local_x = (-hx, hx, hx, -hx)
    local_y = (-hy, -hy, hy, hy)
    for i in range(4):
        vertices[i, 0] = _dot2(local_x[i], local_y[i], cos, -sin, corner_rounding) + cx
        vertices[i, 1] = _dot2(local_x[i], local_y[i], sin, cos, corner_rounding) + cy
    x0, x1 = cos + 0.0, sin + 0.0
    y0, y1 = -sin + 0.0, cos + 0.0
    normals[0, 0], normals[0, 1] = -y0 + 0.0, -y1 + 0.0
    normals[1, 0], normals[1, 1] = x0 + 0.0, x1 + 0.0
    normals[2, 0], normals[2, 1] = y0 + 0.0, y1 + 0.0
    normals[3, 0], normals[3, 1] = -x0 + 0.0, -x1 + 0.0


@njit(cache=True)
def faces_of_boxes(centre, half, angle, corner_rounding, faces):
    """Each box's corners and outward normals into ``faces`` (n, 2, 4, 2): ``faces[i, 0]``
    the corners, ``faces[i, 1]`` the normals, as :func:`_box_faces` makes them."""
    for i in range(angle.shape[0]):
        _box_faces(centre[i, 0], centre[i, 1], half[i, 0], half[i, 1], math.cos(angle[i]), math.sin(angle[i]),
                   corner_rounding, faces[i, 0], faces[i, 1])


@njit(cache=True, inline="always")
def _tolerance_scale(faces, a, b):
    """:func:`~solutions.narrowphase.polygon_polygon.tolerance_scale` of boxes ``a`` and
    ``b`` of ``faces``, with its arithmetic: ``rounding_tolerance(largest absolute
    coordinate, larger extent) / KEEP_POINT_TOL``."""
    size, coordinates = 0.0, 0.0
    for box in (a, b):
        for c in range(2):
            low, high = faces[box, 0, 0, c], faces[box, 0, 0, c]
            for i in range(4):
                low, high = min(low, faces[box, 0, i, c]), max(high, faces[box, 0, i, c])
                coordinates = max(coordinates, abs(faces[box, 0, i, c]))
            size = max(size, high - low)
    return (_ULPS_EPS * coordinates + ROUNDOFF_SIZE_RTOL * size) / KEEP_POINT_TOL


@njit(cache=True)
def _tolerance_scales(vertices_a, vertices_b):
    """``_tolerance_scale`` of every pair of (m, 4, 2) corner arrays (for the tests)."""
    m = vertices_a.shape[0]
    faces = np.zeros((2 * m, 2, 4, 2))
    faces[0::2, 0], faces[1::2, 0] = vertices_a, vertices_b
    out = np.empty(m)
    for k in range(m):
        out[k] = _tolerance_scale(faces, 2 * k, 2 * k + 1)
    return out


@njit(cache=True, inline="always")
def _max_face_separation(faces, reference, other):
    """``max_i min_j Dot(n_i, w_j - v_i)`` over the faces ``i`` of box ``reference`` and
    the corners ``w_j`` of box ``other``, and the first face ``i`` reaching it."""
    best, best_face = -np.inf, 0
    for i in range(4):
        lowest = np.inf
        for j in range(4):
            separation = ((faces[other, 0, j, 0] - faces[reference, 0, i, 0]) * faces[reference, 1, i, 0]
                          + (faces[other, 0, j, 1] - faces[reference, 0, i, 1]) * faces[reference, 1, i, 1])
            if separation < lowest:
                lowest = separation
        if lowest > best or i == 0:
            best, best_face = lowest, i
    return best, best_face


@njit(cache=True, inline="always")
def _clip(p, ids, count, normal_x, normal_y, offset, tolerance):
    """One Sutherland-Hodgman step on ``p`` (2, 2) and ``ids`` (2,) in place; new count."""
    d0 = (p[0, 0] * normal_x + p[0, 1] * normal_y) - offset
    d1 = (p[1, 0] * normal_x + p[1, 1] * normal_y) - offset
    keep0 = count >= 1 and d0 <= tolerance
    keep1 = count >= 2 and d1 <= tolerance
    cross = count == 2 and keep0 != keep1 and d0 * d1 < 0.0
    second_x, second_y, second_id = p[1, 0], p[1, 1], ids[1]
    if cross:
        fraction = d0 / (d0 - d1)
        second_x = p[0, 0] + fraction * (p[1, 0] - p[0, 0])
        second_y = p[0, 1] + fraction * (p[1, 1] - p[0, 1])
        second_id = ids[1] if d1 > 0.0 else ids[0]
    if not keep0:
        p[0, 0], p[0, 1], ids[0] = p[1, 0], p[1, 1], ids[1]
    p[1, 0], p[1, 1], ids[1] = second_x, second_y, second_id
    return int(keep0) + int(keep1) + int(cross)


@njit(cache=True)
def _manifolds_kernel(centre_a, half_a, angle_a, centre_b, half_b, angle_b, margin,
                      corner_rounding, incident_rounding):
    """The manifolds of pairs given box by box: pair ``k``'s boxes are faces ``2k`` and ``2k + 1``."""
    m = centre_a.shape[0]
    faces = np.empty((2 * m, 2, 4, 2))
    faces_of_boxes(centre_a, half_a, angle_a, corner_rounding, faces[0::2])
    faces_of_boxes(centre_b, half_b, angle_b, corner_rounding, faces[1::2])
    index = np.arange(2 * m)
    ints, floats = np.empty((MANIFOLD_INTS, m), dtype=np.int64), np.empty((MANIFOLD_FLOATS, m))
    indexed_manifolds(faces, index[0::2], index[1::2], margin, incident_rounding, ints, floats,
                       np.empty(CLIPPING_FLOATS), np.empty(CLIPPING_INTS, dtype=np.int64))
    return ints, floats


@njit(cache=True)
def indexed_manifolds(faces, box_a, box_b, margin, incident_rounding, ints, floats, clipping_floats,
                       clipping_ints):
    """The manifolds of the pairs ``faces[box_a[k]]`` against ``faces[box_b[k]]``
    (:func:`faces_of_boxes`) into ``ints`` and ``floats`` (``MANIFOLD_*`` rows, one
    column per pair); ``clipping_*`` are work space (``CLIPPING_*`` values)."""
    m = box_a.shape[0]
    found, count, reference_is_b = ints[MANIFOLD_FOUND], ints[MANIFOLD_COUNT], ints[MANIFOLD_REFERENCE_IS_B]
    reference_face, incident_face = ints[MANIFOLD_REFERENCE_FACE], ints[MANIFOLD_INCIDENT_FACE]
    # Empty slots: 0 and -1, NaN.
    found[:m], count[:m], reference_is_b[:m] = 0, 0, 0
    ints[MANIFOLD_REFERENCE_FACE:, :m] = -1
    floats[:, :m] = np.nan
    segment, midpoints = contiguous_view(clipping_floats[0:4], (2, 2)), contiguous_view(clipping_floats[4:8], (2, 2))
    point_separations, ids = clipping_floats[8:10], clipping_ints
    for k in range(m):
        a, b = box_a[k], box_b[k]
        separation_a, face_a = _max_face_separation(faces, a, b)
        separation_b, face_b = _max_face_separation(faces, b, a)
        if not (separation_a <= margin and separation_b <= margin):
            continue
        scale = _tolerance_scale(faces, a, b)      # for the rounding tolerances
        b_ref = separation_b > (separation_a + REFERENCE_FACE_RELATIVE_TOL * abs(separation_a)
                                + REFERENCE_FACE_ABSOLUTE_TOL * scale)
        reference, incident, face = (b, a, face_b) if b_ref else (a, b, face_a)
        n_x, n_y = faces[reference, 1, face, 0], faces[reference, 1, face, 1]
        tangent_x, tangent_y = -n_y, n_x
        face_2 = (face + 1) % 4
        v1_x, v1_y = faces[reference, 0, face, 0], faces[reference, 0, face, 1]
        v2_x, v2_y = faces[reference, 0, face_2, 0], faces[reference, 0, face_2, 1]

        j, lowest = 0, np.inf
        for q in range(4):
            alignment = _dot2(faces[incident, 1, q, 0], faces[incident, 1, q, 1], n_x, n_y, incident_rounding)
            if alignment < lowest or q == 0:
                j, lowest = q, alignment
        j2 = (j + 1) % 4
        segment[0, 0], segment[0, 1], ids[0] = faces[incident, 0, j, 0], faces[incident, 0, j, 1], j
        segment[1, 0], segment[1, 1], ids[1] = faces[incident, 0, j2, 0], faces[incident, 0, j2, 1], j2

        roundoff = KEEP_POINT_TOL * scale
        offset_2 = tangent_x * v2_x + tangent_y * v2_y
        clipped = _clip(segment, ids, 2, tangent_x, tangent_y, offset_2, roundoff)
        minus_x, minus_y = -tangent_x, -tangent_y
        offset_1 = minus_x * v1_x + minus_y * v1_y
        clipped = _clip(segment, ids, clipped, minus_x, minus_y, offset_1, roundoff)

        for s in range(2):
            point_separations[s] = (segment[s, 0] - v1_x) * n_x + (segment[s, 1] - v1_y) * n_y
            half_separation = 0.5 * point_separations[s]
            midpoints[s, 0] = segment[s, 0] - half_separation * n_x
            midpoints[s, 1] = segment[s, 1] - half_separation * n_y
        limit = margin + roundoff
        keep0 = clipped >= 1 and point_separations[0] <= limit
        duplicate = keep0 and max(abs(midpoints[1, 0] - midpoints[0, 0]),
                                  abs(midpoints[1, 1] - midpoints[0, 1])) <= roundoff
        keep1 = clipped >= 2 and point_separations[1] <= limit and not duplicate
        kept = int(keep0) + int(keep1)
        if kept == 0:
            continue
        first = 0 if keep0 else 1
        found[k] = 1
        count[k] = kept
        floats[MANIFOLD_POINT, k], floats[MANIFOLD_POINT + 1, k] = midpoints[first, 0], midpoints[first, 1]
        floats[MANIFOLD_SEPARATION, k] = point_separations[first]
        ints[MANIFOLD_VERTEX, k] = ids[first]
        if kept == 2:
            floats[MANIFOLD_POINT + 2, k], floats[MANIFOLD_POINT + 3, k] = midpoints[1, 0], midpoints[1, 1]
            floats[MANIFOLD_SEPARATION + 1, k] = point_separations[1]
            ints[MANIFOLD_VERTEX + 1, k] = ids[1]
        if b_ref:
            floats[MANIFOLD_NX, k], floats[MANIFOLD_NY, k] = 0.0 - n_x, 0.0 - n_y
        else:
            floats[MANIFOLD_NX, k], floats[MANIFOLD_NY, k] = n_x, n_y
        reference_is_b[k] = b_ref
        reference_face[k] = face
        incident_face[k] = j


def speculative_box_manifolds_numba(centre_a, half_a, angle_a, centre_b, half_b, angle_b,
                                    margin: float = SPECULATIVE_MARGIN) -> BoxManifolds:
    """Speculative manifolds of ``m`` box pairs, compiled: the numpy version's result.

    Same contract as
    :func:`~solutions.narrowphase.speculative_batch.speculative_box_manifolds`: pair
    ``k`` is ``OBB(centre_a[k], half_a[k], angle_a[k])`` against
    ``OBB(centre_b[k], half_b[k], angle_b[k])`` (an AABB is the OBB of its centre and
    half-extents at angle 0), and every array of the result equals the numpy
    version's (see the module docstring for how exactly).

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
        Normals (from A to B), points (m), signed separations (m, > 0 apart) and
        feature ids; empty slots are NaN (floats) or -1 (ints).

    Raises
    ------
    ValueError
        For ``margin < 0``, mismatched shapes, NaN or infinite values, or a negative
        half-extent (the numpy version's checks and messages).

    Examples
    --------
    >>> result = speculative_box_manifolds_numba([[0.0, -0.5], [0.0, -0.5]], [[5.0, 0.5], [5.0, 0.5]], [0.0, 0.0],
    ...                                          [[0.0, 0.51], [0.0, 1.5]], [[0.5, 0.5], [0.5, 0.5]], [0.0, 0.0])
    >>> result.found.tolist(), result.count.tolist(), result.normal[0].tolist()
    ([True, False], [2, 0], [0.0, 1.0])
    >>> result.points[0].round(12).tolist(), result.separations[0].round(12).tolist()
    ([[-0.5, 0.005], [0.5, 0.005]], [0.01, 0.01])
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
    corner_rounding, incident_rounding, _ = matmul_rounding()
    ints, floats = _manifolds_kernel(*(np.ascontiguousarray(a) for a in (centre_a, half_a, angle_a,
                                                                         centre_b, half_b, angle_b)),
                                     float(margin), corner_rounding, incident_rounding)
    return BoxManifolds(found=ints[MANIFOLD_FOUND].astype(bool),
                        normal=floats[MANIFOLD_NX:MANIFOLD_NY + 1].T.copy(),
                        count=ints[MANIFOLD_COUNT].copy(),
                        points=floats[MANIFOLD_POINT:MANIFOLD_POINT + 4].T.reshape(m, 2, 2).copy(),
                        separations=floats[MANIFOLD_SEPARATION:MANIFOLD_SEPARATION + 2].T.copy(),
                        reference_is_b=ints[MANIFOLD_REFERENCE_IS_B].astype(bool),
                        reference_face=ints[MANIFOLD_REFERENCE_FACE].copy(),
                        incident_face=ints[MANIFOLD_INCIDENT_FACE].copy(),
                        vertex=ints[MANIFOLD_VERTEX:MANIFOLD_VERTEX + 2].T.copy())


@njit(cache=True, inline="always")
def packed_feature_ids(ints, features):
    """The feature id of each point of the manifolds ``ints`` (``MANIFOLD_*`` rows, one
    column per pair) as one integer, ``features[k, s]`` for point ``s`` of pair ``k``:
    ``((reference_is_b * 4 + reference_face) * 4 + incident_face) * 4 + vertex``, the
    numpy version's tuple ``(ref, face, incident_face, vertex)`` (:func:`feature_id`)."""
    for k in range(ints.shape[1]):
        for s in range(ints[MANIFOLD_COUNT, k]):
            features[k, s] = ((ints[MANIFOLD_REFERENCE_IS_B, k] * 4 + ints[MANIFOLD_REFERENCE_FACE, k]) * 4
                              + ints[MANIFOLD_INCIDENT_FACE, k]) * 4 + ints[MANIFOLD_VERTEX + s, k]


def feature_id(code: int) -> tuple:
    """The feature id ``("A" or "B", face, incident_face, vertex)`` packed as ``code`` by
    :func:`packed_feature_ids`.

    >>> feature_id(((1 * 4 + 2) * 4 + 3) * 4 + 1)
    ('B', 2, 3, 1)
    """
    rest, vertex = divmod(code, 4)
    rest, incident_face = divmod(rest, 4)
    reference_is_b, face = divmod(rest, 4)
    return ("B" if reference_is_b else "A", face, incident_face, vertex)


# Cached machine code compiled from older sources is forgotten (solutions.compiled_cache).
forget_stale_machine_code(globals())
