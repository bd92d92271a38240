"""Independent oracles for the narrow-phase tests, and checks of the oracles themselves.

Nothing here imports ``solutions.narrowphase``: the brute-force geometry uses only the
shapes' vertices, and pymunk (Chipmunk2D 7) is driven through a small adapter that
irons out its quirks (measured on pymunk 7.3.1):

- a shape must hang on a ``pymunk.Body`` (a body-less shape crashes in ``cache_bb``);
- ``cache_bb()`` must be called on shapes that were never stepped in a space, or
  ``shapes_collide`` uses stale positions;
- for shapes that do not touch, ``shapes_collide`` either raises AssertionError or
  returns a ContactPointSet without points;
- for the poly-vs-circle order the reported ``distance`` has the wrong sign, so the
  depth is recomputed as ``-Dot(point_b - point_a, normal)``;
- ``point_a`` lies on A's surface and ``point_b`` on B's; our contact point is their
  midpoint.  pymunk's normal points from A to B, as ours does.
"""
from __future__ import annotations

import math

import numpy as np
import pymunk
import pytest

from solutions.shapes import AABB, OBB, Circle, ConvexPolygon, polygon_vertices

KINDS = ("circle", "aabb", "obb", "poly")


# --------------------------------------------------------------------------- shapes
def random_shape(rng: np.random.Generator, kind: str, spread: float = 2.0, offset=(0.0, 0.0)):
    """A random world shape of ``kind`` near ``offset`` (sizes 0.1..1.5 m)."""
    c = np.asarray(offset, dtype=float) + rng.uniform(-spread, spread, 2)
    if kind == "circle":
        return Circle(c, rng.uniform(0.1, 1.5))
    if kind == "aabb":
        h = rng.uniform(0.1, 1.5, 2)
        return AABB(c - h, c + h)
    if kind == "obb":
        return OBB(c, rng.uniform(0.1, 1.5, 2), rng.uniform(-math.pi, math.pi))
    if kind == "poly":
        # Points on an ellipse in angular order are convex and CCW; then rotate.
        while True:
            k = int(rng.integers(3, 9))
            angles = np.sort(rng.uniform(0.0, 2 * math.pi, k))
            local = np.c_[np.cos(angles), np.sin(angles)] * rng.uniform(0.2, 1.5, 2)
            turn = rng.uniform(-math.pi, math.pi)
            rot = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]])
            try:
                return ConvexPolygon(local @ rot.T + c)
            except ValueError:  # three nearly equal angles: draw again
                continue
    raise ValueError(kind)


def translate(shape, offset):
    d = np.asarray(offset, dtype=float)
    if isinstance(shape, Circle):
        return Circle(shape.center + d, shape.radius)
    if isinstance(shape, AABB):
        return AABB(shape.min_corner + d, shape.max_corner + d)
    if isinstance(shape, OBB):
        return OBB(shape.center + d, shape.half_extents, shape.angle)
    return ConvexPolygon(shape.vertices + d)


def rotation(angle: float) -> np.ndarray:
    return np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])


def rotate(shape, angle: float):
    """The shape turned by ``angle`` about the world origin (an AABB becomes an OBB)."""
    rot = rotation(angle)
    if isinstance(shape, Circle):
        return Circle(rot @ shape.center, shape.radius)
    if isinstance(shape, AABB):
        return OBB(rot @ shape.center, shape.half_extents, angle)
    if isinstance(shape, OBB):
        return OBB(rot @ shape.center, shape.half_extents, shape.angle + angle)
    return ConvexPolygon(shape.vertices @ rot.T)


# ------------------------------------------------------------ brute-force geometry
def interval(shape, axis) -> tuple[float, float]:
    """Projection of a shape on a unit axis, with numpy (no loop, no running values)."""
    axis = np.asarray(axis, dtype=float)
    if isinstance(shape, Circle):
        c = float(shape.center @ axis)
        return c - shape.radius, c + shape.radius
    along = polygon_vertices(shape) @ axis
    return float(along.min()), float(along.max())


def overlap_along(a, b, normal) -> float:
    """How far B must move along ``normal`` to only touch A: ``max_A - min_B`` (m)."""
    return interval(a, normal)[1] - interval(b, normal)[0]


def _unit_normals(shape) -> np.ndarray:
    v = polygon_vertices(shape)
    edges = np.roll(v, -1, axis=0) - v
    lengths = np.hypot(edges[:, 0], edges[:, 1])
    keep = lengths > 1e-12 * max(1.0, float(np.abs(v).max()))
    normals = np.c_[edges[keep, 1], -edges[keep, 0]] / lengths[keep, None]
    if isinstance(shape, OBB):        # a zero-width box still has its two axes
        normals = np.r_[normals, rotation(shape.angle).T]
    elif isinstance(shape, AABB):
        normals = np.r_[normals, np.eye(2)]
    return normals


def _segment_distance(p, a, b) -> float:
    e = b - a
    length2 = float(e @ e)
    t = 0.0 if length2 == 0 else min(max(float((p - a) @ e) / length2, 0.0), 1.0)
    return float(np.hypot(*(p - a - t * e)))


def signed_gap(a, b) -> float:
    """> 0: the shapes are apart by about this much (m); < 0: minus the least penetration.

    Circle-circle and circle-polygon are exact distances; polygon-polygon is the largest
    interval gap over every edge normal of both (the SAT value: exact when overlapping,
    a lower bound of the distance when apart, 0 exactly when touching).
    """
    if isinstance(a, Circle) and isinstance(b, Circle):
        return float(np.hypot(*(b.center - a.center))) - a.radius - b.radius
    if isinstance(b, Circle):
        a, b = b, a
    if isinstance(a, Circle):
        v = polygon_vertices(b)
        c = a.center
        edges = np.roll(v, -1, axis=0) - v
        area2 = float(np.sum(v[:, 0] * np.roll(v[:, 1], -1) - v[:, 1] * np.roll(v[:, 0], -1)))
        inside = area2 > 0 and np.all(edges[:, 0] * (c[1] - v[:, 1]) - edges[:, 1] * (c[0] - v[:, 0]) >= 0)
        if inside:
            normals = _unit_normals(b)
            starts = np.array([v[int(np.argmax(v @ n))] for n in normals])
            # distance to the nearest face line, from inside
            return -float(np.min(np.einsum("kd,kd->k", starts - c, normals))) - a.radius
        dist = min(_segment_distance(c, v[k], v[(k + 1) % len(v)]) for k in range(len(v)))
        return dist - a.radius
    normals = np.r_[_unit_normals(a), _unit_normals(b)]
    along_a = polygon_vertices(a) @ normals.T        # (vertices of A, axes)
    along_b = polygon_vertices(b) @ normals.T
    gaps = np.maximum(along_b.min(axis=0) - along_a.max(axis=0), along_a.min(axis=0) - along_b.max(axis=0))
    return float(gaps.max())


def contains(shape, point, tol: float) -> bool:
    """Whether ``point`` lies in the closed shape, up to ``tol`` (m)."""
    p = np.asarray(point, dtype=float)
    if isinstance(shape, Circle):
        return float(np.hypot(*(p - shape.center))) <= shape.radius + tol
    v = polygon_vertices(shape)
    edges = np.roll(v, -1, axis=0) - v
    lengths = np.maximum(np.hypot(edges[:, 0], edges[:, 1]), 1e-300)
    left = (edges[:, 0] * (p[1] - v[:, 1]) - edges[:, 1] * (p[0] - v[:, 0])) / lengths
    return bool(np.all(left >= -tol))


# ----------------------------------------------------------------- pymunk adapter
def to_pymunk(shape) -> pymunk.Shape:
    body = pymunk.Body(body_type=pymunk.Body.STATIC)
    if isinstance(shape, Circle):
        pm = pymunk.Circle(body, shape.radius, offset=tuple(map(float, shape.center)))
    else:
        pm = pymunk.Poly(body, [tuple(map(float, v)) for v in polygon_vertices(shape)], radius=0)
    pm.cache_bb()
    pm._keep_body = body  # the shape only holds a weak reference to its body
    return pm


def pymunk_contact(a, b):
    """pymunk's view of the pair: None, or (normal, [(midpoint, depth), ...])."""
    return pymunk_contact_of(to_pymunk(a), to_pymunk(b))


def pymunk_contact_of(pm_a: pymunk.Shape, pm_b: pymunk.Shape):
    try:
        result = pm_a.shapes_collide(pm_b)
    except AssertionError:
        return None
    if not result.points:
        return None
    normal = np.array(result.normal)
    points = []
    for p in result.points:
        point_a, point_b = np.array(p.point_a), np.array(p.point_b)
        points.append(((point_a + point_b) / 2, -float((point_b - point_a) @ normal)))
    return normal, points


# ------------------------------------------------------------ checks of the oracles
def test_pymunk_adapter_reports_depth_with_our_sign_in_both_orders():
    box = AABB((-2.0, -1.0), (2.0, 1.0))
    ball = Circle((0.0, 1.5), 1.0)
    for a, b, normal in ((box, ball, (0.0, 1.0)), (ball, box, (0.0, -1.0))):
        got_normal, points = pymunk_contact(a, b)
        np.testing.assert_allclose(got_normal, normal, atol=1e-12)
        assert len(points) == 1
        np.testing.assert_allclose(points[0][0], (0.0, 0.75), atol=1e-12)
        assert points[0][1] == pytest.approx(0.5, abs=1e-12)


def test_pymunk_adapter_returns_none_for_apart_shapes():
    assert pymunk_contact(Circle((0.0, 0.0), 1.0), Circle((5.0, 0.0), 1.0)) is None
    assert pymunk_contact(AABB((-6.0, -1.0), (-4.0, 1.0)), AABB((-3.0, -1.0), (-1.0, 1.0))) is None


@pytest.mark.parametrize("kind_a", KINDS)
@pytest.mark.parametrize("kind_b", KINDS)
def test_signed_gap_agrees_with_pymunk(kind_a, kind_b):
    """The brute-force gap used to skip near-touching pairs is right about the sign,
    and as a penetration depth it equals pymunk's deepest point (atol 1e-9 m: both are
    closed-form double-precision values for shapes of about 1 m)."""
    rng = np.random.default_rng(7)
    for _ in range(200):
        a, b = random_shape(rng, kind_a), random_shape(rng, kind_b)
        gap = signed_gap(a, b)
        theirs = pymunk_contact(a, b)
        if abs(gap) < 1e-9:
            continue
        assert (gap <= 0) == (theirs is not None), (a, b, gap)
        if theirs is not None:
            assert -gap == pytest.approx(max(d for _, d in theirs[1]), abs=1e-9)
