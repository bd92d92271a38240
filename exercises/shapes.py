# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/shapes.py on the instructor's side.
"""Collision shapes: circle, AABB, OBB and convex polygon.

Every shape is an immutable value in one frame: a body holds its shape in the body's
local frame (``_local``) and :meth:`solutions.body.Body.world_shape` gives the same
shape in world coordinates (``_world``), which is what the narrow phase tests.

Conventions (see :mod:`solutions`): SI units, y up, angles in radians counter-clockwise,
polygon vertices counter-clockwise so that ``perp(edge) = (y, -x)`` points outwards.

Invalid input raises ``ValueError`` with a message naming the problem: NaN or infinite
coordinates, a negative radius or half-extent, fewer than three polygon vertices, a
clockwise or non-convex polygon.  Zero-size shapes (radius 0, half-extents 0) are
allowed: they are points or segments, and every test gives them a defined answer.

ASCII picture of box vertex numbering (AABB and OBB, local frame)::

        3 ---------- 2        y
        |            |        ^
        |     c      |        |
        |            |        +--> x
        0 ---------- 1

Edge ``k`` runs from vertex ``k`` to vertex ``k+1``; its outward normal is
``perp(v[k+1] - v[k])``: edge 0 faces -y, edge 1 faces +x, edge 2 faces +y, edge 3 -x.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .vector import cross, rotation_matrix

#: Relative tolerance of the convexity and orientation checks of a polygon.
CONVEXITY_RTOL = 1e-12


def as_point(name: str, value) -> np.ndarray:
    """``value`` as a read-only float array of shape (2,); ValueError if not finite."""
    point = np.array(value, dtype=float)
    if point.shape != (2,):
        raise ValueError(f"{name} must be a 2D point (x, y), got shape {point.shape}")
    if not np.all(np.isfinite(point)):
        raise ValueError(f"{name} must be finite, got {point.tolist()}")
    point.setflags(write=False)
    return point


def as_length(name: str, value) -> float:
    """``value`` as a float >= 0; ValueError for negative, NaN or infinite values."""
    length = float(value)
    if not math.isfinite(length):
        raise ValueError(f"{name} must be finite, got {length}")
    if length < 0:
        raise ValueError(f"{name} must be >= 0, got {length}")
    return length


def box_vertices(center, half_extents, angle: float) -> np.ndarray:
    """The four CCW corners (4, 2) of a box, numbered as in the module docstring."""
    hx, hy = half_extents
    corners_local = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])
    return corners_local @ rotation_matrix(angle).T + np.asarray(center, dtype=float)


@dataclass(frozen=True, eq=False)
class Circle:
    """A disc of ``radius`` (m) around ``center`` (m)."""

    center: np.ndarray
    radius: float

    def __post_init__(self):
        object.__setattr__(self, "center", as_point("circle center", self.center))
        object.__setattr__(self, "radius", as_length("circle radius", self.radius))

    def __repr__(self):
        return f"Circle(center={self.center.tolist()}, radius={self.radius})"


@dataclass(frozen=True, eq=False)
class AABB:
    """Axis-aligned box in min/max form: ``min_corner <= max_corner`` per axis (m).

    The centre/half-extents form is :meth:`from_center` and the properties
    ``center`` and ``half_extents``.
    """

    min_corner: np.ndarray
    max_corner: np.ndarray

    def __post_init__(self):
        lo = as_point("AABB min_corner", self.min_corner)
        hi = as_point("AABB max_corner", self.max_corner)
        if np.any(lo > hi):
            raise ValueError(f"AABB min_corner {lo.tolist()} exceeds max_corner {hi.tolist()}")
        object.__setattr__(self, "min_corner", lo)
        object.__setattr__(self, "max_corner", hi)

    @classmethod
    def from_center(cls, center, half_extents) -> "AABB":
        """AABB from its centre and half-extents (both in m)."""
        c = as_point("AABB center", center)
        h = np.array([as_length("AABB half-extent", e) for e in np.asarray(half_extents, dtype=float)])
        return cls(c - h, c + h)

    @property
    def center(self) -> np.ndarray:
        return (self.min_corner + self.max_corner) / 2

    @property
    def half_extents(self) -> np.ndarray:
        return (self.max_corner - self.min_corner) / 2

    def vertices(self) -> np.ndarray:
        """CCW corners (4, 2)."""
        return box_vertices(self.center, self.half_extents, 0.0)

    def __repr__(self):
        return f"AABB(min_corner={self.min_corner.tolist()}, max_corner={self.max_corner.tolist()})"


@dataclass(frozen=True, eq=False)
class OBB:
    """Oriented box: ``center`` (m), ``half_extents`` (m) along its own axes, ``angle`` (rad)."""

    center: np.ndarray
    half_extents: np.ndarray
    angle: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "center", as_point("OBB center", self.center))
        h = np.array([as_length("OBB half-extent", e) for e in np.asarray(self.half_extents, dtype=float).reshape(-1)])
        if h.shape != (2,):
            raise ValueError(f"OBB half_extents must be (hx, hy), got {h.tolist()}")
        h.setflags(write=False)
        object.__setattr__(self, "half_extents", h)
        angle = float(self.angle)
        if not math.isfinite(angle):
            raise ValueError(f"OBB angle must be finite, got {angle}")
        object.__setattr__(self, "angle", angle)

    def axes(self) -> np.ndarray:
        """Rows are the box's unit x and y axes in world coordinates (2, 2)."""
        return rotation_matrix(self.angle).T.copy()

    def vertices(self) -> np.ndarray:
        """CCW corners (4, 2), numbered as in the module docstring."""
        return box_vertices(self.center, self.half_extents, self.angle)

    def __repr__(self):
        return f"OBB(center={self.center.tolist()}, half_extents={self.half_extents.tolist()}, angle={self.angle})"


@dataclass(frozen=True, eq=False)
class ConvexPolygon:
    """Convex polygon with counter-clockwise ``vertices`` (n, 2), n >= 3, in m.

    Collinear consecutive vertices are allowed; a clockwise, self-intersecting or
    non-convex polygon, or one of zero area, raises ``ValueError``.
    """

    vertices: np.ndarray

    def __post_init__(self):
        v = np.array(self.vertices, dtype=float)
        if v.ndim != 2 or v.shape[1] != 2 or v.shape[0] < 3:
            raise ValueError(f"a polygon needs an (n, 2) array of n >= 3 vertices, got shape {v.shape}")
        if not np.all(np.isfinite(v)):
            raise ValueError("polygon vertices must be finite (no NaN or inf)")
        check_convex_ccw(v)
        v.setflags(write=False)
        object.__setattr__(self, "vertices", v)

    @property
    def center(self) -> np.ndarray:
        """Area centroid (m)."""
        return polygon_centroid(self.vertices)

    def __repr__(self):
        return f"ConvexPolygon(vertices={self.vertices.tolist()})"


def signed_area(vertices: np.ndarray) -> float:
    """Signed area (m^2): positive for counter-clockwise vertices (shoelace formula).

    Computed relative to the first vertex, so that far from the origin the products
    stay small and the result keeps its precision.
    """
    v = np.asarray(vertices, dtype=float)
    v = v - v[0]
    return 0.5 * float(np.sum(cross(v, np.roll(v, -1, axis=0))))


def polygon_centroid(vertices: np.ndarray) -> np.ndarray:
    """Area centroid of a simple polygon (m); the vertex mean if the area is zero."""
    v = np.asarray(vertices, dtype=float)
    origin = v[0]
    rel = v - origin
    w = cross(rel, np.roll(rel, -1, axis=0))
    area2 = float(np.sum(w))
    if area2 == 0.0:
        return v.mean(axis=0)
    c = ((rel + np.roll(rel, -1, axis=0)) * w[:, None]).sum(axis=0) / (3.0 * area2)
    return origin + c


def check_convex_ccw(vertices: np.ndarray) -> None:
    """Raise ValueError unless ``vertices`` form a convex CCW polygon of positive area."""
    v = np.asarray(vertices, dtype=float)
    scale = max(float(np.max(np.abs(v - v.mean(axis=0)))), 1e-300)
    area = signed_area(v)
    if area < 0:
        raise ValueError("polygon vertices are clockwise; list them counter-clockwise")
    if area <= CONVEXITY_RTOL * scale * scale:
        raise ValueError("polygon has zero area (all vertices on one line)")
    edges = np.roll(v, -1, axis=0) - v
    turns = cross(edges, np.roll(edges, -1, axis=0))
    if np.any(turns < -CONVEXITY_RTOL * scale * scale):
        raise ValueError("polygon is not convex: SAT needs convex shapes; split it into convex parts")
    # A star polygon turns left at every corner but winds twice.
    angles = np.arctan2(edges[:, 1], edges[:, 0])
    winding = np.sum(np.mod(np.diff(np.append(angles, angles[0])) + np.pi, 2 * np.pi) - np.pi)
    if winding > 2 * np.pi + 1e-6:
        raise ValueError("polygon is self-intersecting (winds more than once)")


Shape = Circle | AABB | OBB | ConvexPolygon


def polygon_vertices(shape: AABB | OBB | ConvexPolygon) -> np.ndarray:
    """CCW vertices (n, 2) of any polygonal shape."""
    if isinstance(shape, ConvexPolygon):
        return shape.vertices
    if isinstance(shape, (AABB, OBB)):
        return shape.vertices()
    raise TypeError(f"{type(shape).__name__} has no vertices")


def bounding_aabb(shape: Shape) -> AABB:
    """Smallest AABB enclosing ``shape`` (touching its extreme points)."""
    if isinstance(shape, Circle):
        return AABB(shape.center - shape.radius, shape.center + shape.radius)
    if isinstance(shape, AABB):
        return shape
    v = polygon_vertices(shape)
    return AABB(v.min(axis=0), v.max(axis=0))


def translated(shape: Shape, offset) -> Shape:
    """The same shape moved by ``offset`` (m)."""
    d = np.asarray(offset, dtype=float)
    if isinstance(shape, Circle):
        return Circle(shape.center + d, shape.radius)
    if isinstance(shape, AABB):
        return AABB(shape.min_corner + d, shape.max_corner + d)
    if isinstance(shape, OBB):
        return OBB(shape.center + d, shape.half_extents, shape.angle)
    return ConvexPolygon(shape.vertices + d)


def inner_radius(shape: Shape) -> float:
    """Radius (m) of a disc around the shape's centre that the shape contains.

    A translation shorter than this cannot carry the shape across a wall of zero
    thickness without some sampled position overlapping it; continuous detection uses
    it to choose its step.  0 for zero-size shapes.
    """
    if isinstance(shape, Circle):
        return shape.radius
    if isinstance(shape, (AABB, OBB)):
        return float(np.min(shape.half_extents))
    v = shape.vertices
    c = polygon_centroid(v)
    edges = np.roll(v, -1, axis=0) - v
    lengths = np.hypot(edges[:, 0], edges[:, 1])
    keep = lengths > 0
    distances = np.abs(cross(edges[keep], (c - v)[keep])) / lengths[keep]
    return float(distances.min())
