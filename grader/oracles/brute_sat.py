"""Brute-force SAT quantities of plain shapes, with numpy and nothing else.

Used by the graded tests to sort random pairs into categories (which shape's axes
separate them, is the reference face clear) and to leave out the pairs whose answer
is a free choice of the method.  Nothing here is a model answer: the expected
contacts come from pymunk (:mod:`.pymunk_geometry`) or from literals.  Units: m.
"""
from __future__ import annotations

import numpy as np

from . import plain
from ..sandbox.codec import SHAPE_TAG


def interval(shape: dict, axis) -> tuple[float, float]:
    """``(min, max)`` of ``Dot(point, axis)`` over a plain shape (min/max of all vertex
    dot products; centre +- radius for a circle, ``axis`` a unit vector)."""
    axis = np.asarray(axis, dtype=float)
    if shape[SHAPE_TAG] == "Circle":
        along = float(np.asarray(shape["center"], dtype=float) @ axis)
        return along - shape["radius"], along + shape["radius"]
    along = plain.vertices(shape) @ axis
    return float(along.min()), float(along.max())


def face_normals(shape: dict) -> np.ndarray:
    """Unit outward normals (k, 2) of a plain polygonal shape's edges, edge k from
    vertex k to k+1 (CCW vertices: ``(e.y, -e.x) / |e|``)."""
    v = plain.vertices(shape)
    edges = np.roll(v, -1, axis=0) - v
    lengths = np.hypot(edges[:, 0], edges[:, 1])
    return np.column_stack([edges[:, 1], -edges[:, 0]]) / lengths[:, None]


def axis_gaps(a: dict, b: dict, axes) -> np.ndarray:
    """Gap between the intervals of A and B on each axis (m; > 0 apart, < 0 overlap)."""
    axes = np.asarray(axes, dtype=float).reshape(-1, 2)
    (lo_a, hi_a), (lo_b, hi_b) = intervals(a, axes), intervals(b, axes)
    return np.maximum(lo_b - hi_a, lo_a - hi_b)


def intervals(shape: dict, axes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`interval` on many unit axes (k, 2) at once: arrays of mins and maxes."""
    if shape[SHAPE_TAG] == "Circle":
        along = axes @ np.asarray(shape["center"], dtype=float)
        return along - shape["radius"], along + shape["radius"]
    along = plain.vertices(shape) @ axes.T
    return along.min(axis=0), along.max(axis=0)


def separating_owners(a: dict, b: dict, margin: float = 0.0) -> set[str]:
    """Which polygons' face normals separate A and B by more than ``margin``:
    a subset of ``{"A", "B"}`` (empty: SAT says they overlap)."""
    owners = set()
    if np.max(axis_gaps(a, b, face_normals(a))) > margin:
        owners.add("A")
    if np.max(axis_gaps(a, b, face_normals(b))) > margin:
        owners.add("B")
    return owners


def face_separations(a: dict, b: dict) -> list[tuple[np.ndarray, float]]:
    """Every face of A and of B as ``(normal from A to B, separation)``.

    For a face of A with outward normal ``n``: ``min_j Dot(n, w_j - v)`` over B's
    vertices ``w_j`` (``v`` on the face); for a face of B the same with the roles
    swapped and the normal turned to point from A to B.  The contact's normal is the
    face of largest separation (least penetration); its depth is minus that.
    """
    out = []
    va, vb = plain.vertices(a), plain.vertices(b)
    for ref, other, sign, normals in ((va, vb, 1.0, face_normals(a)), (vb, va, -1.0, face_normals(b))):
        for k, n in enumerate(normals):
            out.append((sign * n, float(np.min((other - ref[k]) @ n))))
    return out


def clear_reference_face(a: dict, b: dict, relative: float = 0.05, absolute: float = 1e-6) -> bool:
    """Whether the least-penetration face of a polygon pair is clear.

    True when every face direction other than the best one (faces of A and B whose
    normals are the same line, as two parallel faces in contact, count as one) is
    penetrated deeper by more than ``relative`` of the depth plus ``absolute`` (m).
    Then every method that takes the face of least penetration, with or without a
    small preference for A's faces, picks the same normal.
    """
    faces = sorted(face_separations(a, b), key=lambda f: -f[1])
    best_normal, best = faces[0]
    for normal, separation in faces[1:]:
        if float(normal @ best_normal) > 1 - 1e-9:
            continue  # the same direction: a parallel face, same normal and depth
        return separation < best - relative * abs(best) - absolute
    return True


def nearest_face_margin(circle: dict, shape: dict) -> float:
    """For a circle's centre inside a polygon: how much nearer (m) the nearest face is
    than the second nearest (the deep-penetration normal is a free choice at 0);
    ``inf`` when the centre is outside."""
    c = np.asarray(circle["center"], dtype=float)
    v = plain.vertices(shape)
    separations = np.einsum("kd,kd->k", c - v, face_normals(shape))
    if np.max(separations) > 0:
        return float("inf")
    distances = np.sort(-separations)
    return float(distances[1] - distances[0])


def contact_is_defined(a: dict, b: dict, margin: float = 1e-6) -> bool:
    """Whether the contact of A and B is the same for every method that follows the
    course's rules, i.e. no free choice (m).

    Free choices left out: two faces of a polygon pair penetrated almost equally (see
    :func:`clear_reference_face`), a circle's centre inside a polygon almost as near to
    two faces, and two circles with (almost) the same centre.
    """
    kinds = a[SHAPE_TAG], b[SHAPE_TAG]
    if kinds == ("Circle", "Circle"):
        return float(np.hypot(*(np.asarray(b["center"], float) - np.asarray(a["center"], float)))) > margin
    if kinds[0] == "Circle":
        return nearest_face_margin(a, b) > margin
    if kinds[1] == "Circle":
        return nearest_face_margin(b, a) > margin
    return clear_reference_face(a, b)
