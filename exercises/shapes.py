# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/shapes.py on the instructor's side.
"""Collision shapes: circle, AABB, OBB and convex polygon.

Every shape is an immutable value in one frame: a body holds its shape in the body's
local frame (``_local``) and :meth:`exercises.body.Body.world_shape` gives the same
shape in world coordinates (``_world``), which is what the narrow phase tests.

Conventions (see :mod:`exercises`): SI units, y up, angles in radians counter-clockwise,
polygon vertices counter-clockwise so that ``perp(edge) = (y, -x)`` points outwards.

Invalid input raises ``ValueError`` with a message naming the problem: NaN or infinite
coordinates, coordinates or sizes beyond :data:`MAX_COORDINATE` (their squares would
overflow), a negative radius or half-extent, fewer than three polygon vertices, a
clockwise or non-convex polygon.  Zero-size shapes (radius 0, half-extents 0) are
allowed: they are points or segments, and every test gives them a defined answer.

Rounding.  A coordinate ``x`` is only known to about ``eps * |x|`` (``eps = 2**-52``):
1.2e-7 m at x = 1e9 m.  :func:`rounding_tolerance` turns that, plus a small part of the
shapes' own size, into the distance (m) below which the narrow phase treats two computed
positions as equal; it follows the shapes, not the origin, so a centimetre box at
x = 1e9 m gets a tolerance of micrometres, not millimetres.

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

#: Relative tolerance of the zero-area check of a polygon (m^2 per m^2 of its size squared).
CONVEXITY_RTOL = 1e-12

#: Largest absolute coordinate, radius or half-extent (m) a shape accepts.  Distances
#: are compared squared (``dx * dx + dy * dy <= r * r``); differences of coordinates up
#: to this size have squares below 1e302, far from the largest double (1.8e308), while
#: radii of 1e154 m and more would overflow to inf and make apart shapes "touch".
MAX_COORDINATE = 1e150

#: Relative spacing of doubles, 2**-52.
EPS = float(np.finfo(float).eps)

#: A coordinate ``x`` computed by a few floating operations is off by a few ``eps * |x|``
#: (``eps = 2**-52``, so 1 eps * |x| is at most one ulp): :func:`rounding_tolerance`
#: allows this many of them for the largest coordinate involved ...
ROUNDOFF_ULPS = 8

#: ... plus this fraction of the shapes' own size (m per m), for what is computed from
#: the shapes (rotated corners, unit normals, clipped points): a few thousand times the
#: relative rounding of a double, still far below any length that matters (1e-12 m for
#: 1 m shapes).
ROUNDOFF_SIZE_RTOL = 1e-12


def rounding_tolerance(coordinate_scale, size) -> float | np.ndarray:
    """Distance (m) below which two computed positions are equal up to rounding.

    ``ROUNDOFF_ULPS * eps * coordinate_scale + ROUNDOFF_SIZE_RTOL * size``.

    Parameters
    ----------
    coordinate_scale : float or numpy.ndarray
        Largest absolute coordinate involved (m): its rounding is what cannot be avoided.
    size : float or numpy.ndarray
        Size of the shapes involved (m), for the rounding of what is computed from them.
        Arrays give one tolerance per element (broadcast).

    Examples
    --------
    A 1 cm box near the origin and at x = 1e9 m (where a double resolves 1.2e-7 m):

    >>> f"{rounding_tolerance(0.01, 0.01):.1e} m, {rounding_tolerance(1e9, 0.01):.1e} m"
    '1.0e-14 m, 1.8e-06 m'
    """
    tolerance = (ROUNDOFF_ULPS * EPS * np.asarray(coordinate_scale, dtype=float)
                 + ROUNDOFF_SIZE_RTOL * np.asarray(size, dtype=float))
    return float(tolerance) if tolerance.ndim == 0 else tolerance


def check_coordinate_range(name: str, values) -> None:
    """ValueError unless every value is finite and at most :data:`MAX_COORDINATE` in size."""
    values = np.asarray(values, dtype=float)
    if not np.all(np.abs(values) <= MAX_COORDINATE):     # also False for NaN
        if not np.all(np.isfinite(values)):
            raise ValueError(f"{name} must be finite, got {values.tolist()}")
        raise ValueError(f"{name} must be at most {MAX_COORDINATE:g} m in absolute value (squared distances of "
                         f"larger numbers overflow), got {float(np.max(np.abs(values))):g}")


def as_point(name: str, value) -> np.ndarray:
    """``value`` as a read-only float array of shape (2,); ValueError if not finite or
    beyond :data:`MAX_COORDINATE`."""
    point = np.array(value, dtype=float)
    if point.shape != (2,):
        raise ValueError(f"{name} must be a 2D point (x, y), got shape {point.shape}")
    check_coordinate_range(name, point)
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


def as_size(name: str, value) -> float:
    """A radius or half-extent (m): :func:`as_length`, and at most :data:`MAX_COORDINATE`."""
    length = as_length(name, value)
    if length > MAX_COORDINATE:
        check_coordinate_range(name, length)
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
        object.__setattr__(self, "radius", as_size("circle radius", self.radius))

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
        h = np.array([as_size("AABB half-extent", e) for e in np.asarray(half_extents, dtype=float)])
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
        h = np.array([as_size("OBB half-extent", e) for e in np.asarray(self.half_extents, dtype=float).reshape(-1)])
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

    Repeated and collinear consecutive vertices are allowed and dropped: ``vertices``
    keeps the corners only (:func:`polygon_corners`), so that every edge has its own
    direction and no two edges face the same way (the contact routines pick one face per
    direction).  A clockwise, self-intersecting or non-convex polygon, or one of zero
    area, raises ``ValueError``.

    >>> ConvexPolygon([(0, 0), (1, 0), (2, 0), (2, 2), (2, 2), (0, 2)]).vertices.tolist()
    [[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]]
    """

    vertices: np.ndarray

    def __post_init__(self):
        v = np.array(self.vertices, dtype=float)
        if v.ndim != 2 or v.shape[1] != 2 or v.shape[0] < 3:
            raise ValueError(f"a polygon needs an (n, 2) array of n >= 3 vertices, got shape {v.shape}")
        if not np.all(np.isfinite(v)):
            raise ValueError("polygon vertices must be finite (no NaN or inf)")
        check_coordinate_range("polygon vertices", v)
        v = polygon_corners(v)
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


def polygon_corners(vertices: np.ndarray) -> np.ndarray:
    """The corners of a convex CCW polygon: ``vertices`` without the repeated and collinear ones.

    A vertex is dropped when it lies within :func:`rounding_tolerance` (m) of the segment
    joining its two neighbours: one vertex at a time, the one nearest to its segment
    first, and its neighbours then become neighbours.  Raises ValueError unless the
    vertices form a convex CCW polygon of positive area: every corner left must turn
    left (a vertex where an edge turns back on itself is not convex).

    Examples
    --------
    >>> polygon_corners(np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [1.0, 1.0]])).tolist()
    [[0.0, 0.0], [2.0, 0.0], [1.0, 1.0]]
    """
    v = np.asarray(vertices, dtype=float)
    size = float(np.max(np.ptp(v, axis=0)))
    area = signed_area(v)
    if area < 0:
        raise ValueError("polygon vertices are clockwise; list them counter-clockwise")
    if area <= CONVEXITY_RTOL * size * size:
        raise ValueError("polygon has zero area (all vertices on one line)")
    tolerance = rounding_tolerance(float(np.max(np.abs(v))), size)
    kept = list(range(len(v)))
    near = _distances_to_neighbour_chords(v) <= tolerance
    while np.any(near) and len(kept) > 2:
        # Drop the vertex closest to its chord, then look at its neighbours again.
        del kept[int(np.argmin(np.where(near, _distances_to_neighbour_chords(v[kept]), np.inf)))]
        near = _distances_to_neighbour_chords(v[kept]) <= tolerance
    corners = v[kept]
    if len(corners) < 3:
        raise ValueError("polygon has zero area (all vertices on one line)")
    edges = np.roll(corners, -1, axis=0) - corners
    turns = cross(np.roll(edges, 1, axis=0), edges)          # the turn at each corner
    if np.any(turns <= 0.0):
        raise ValueError("polygon is not convex: SAT needs convex shapes; split it into convex parts")
    # A star polygon turns left at every corner but winds twice.
    angles = np.arctan2(edges[:, 1], edges[:, 0])
    winding = np.sum(np.mod(np.diff(np.append(angles, angles[0])) + np.pi, 2 * np.pi) - np.pi)
    if winding > 2 * np.pi + 1e-6:
        raise ValueError("polygon is self-intersecting (winds more than once)")
    return corners


def _distances_to_neighbour_chords(v: np.ndarray) -> np.ndarray:
    """Distance (m) of each vertex from the segment joining its two neighbours."""
    before, after = np.roll(v, 1, axis=0), np.roll(v, -1, axis=0)
    chord, offset = after - before, v - before
    length2 = np.einsum("kd,kd->k", chord, chord)
    with np.errstate(divide="ignore", invalid="ignore"):
        along = np.clip(np.einsum("kd,kd->k", offset, chord) / length2, 0.0, 1.0)
    along = np.where(length2 > 0.0, along, 0.0)
    rest = offset - along[:, None] * chord
    return np.hypot(rest[:, 0], rest[:, 1])


def check_convex_ccw(vertices: np.ndarray) -> None:
    """Raise ValueError unless ``vertices`` form a convex CCW polygon of positive area
    (collinear and repeated vertices allowed, see :func:`polygon_corners`)."""
    polygon_corners(vertices)


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
