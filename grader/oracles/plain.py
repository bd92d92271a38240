"""Shapes, bodies and contacts as the plain tagged dicts of :mod:`grader.sandbox.codec`.

The public graded tests build their inputs with these (never with the reference
engine's classes); the worker rebuilds them with the student's own classes.  Units:
m, kg, s, rad; polygon vertices counter-clockwise.
"""
from __future__ import annotations

import math

import numpy as np

from ..sandbox.codec import BODY_TAG, CONTACT_TAG, SHAPE_TAG


def _xy(value) -> list[float]:
    x, y = (float(v) for v in np.asarray(value, dtype=float).reshape(2))
    return [x, y]


def circle(center, radius: float) -> dict:
    return {SHAPE_TAG: "Circle", "center": _xy(center), "radius": float(radius)}


def aabb(min_corner, max_corner) -> dict:
    return {SHAPE_TAG: "AABB", "min_corner": _xy(min_corner), "max_corner": _xy(max_corner)}


def aabb_from_center(center, half_extents) -> dict:
    c, h = np.asarray(center, dtype=float), np.asarray(half_extents, dtype=float)
    return aabb(c - h, c + h)


def obb(center, half_extents, angle: float) -> dict:
    return {SHAPE_TAG: "OBB", "center": _xy(center), "half_extents": _xy(half_extents), "angle": float(angle)}


def polygon(vertices) -> dict:
    return {SHAPE_TAG: "ConvexPolygon", "vertices": [_xy(v) for v in np.asarray(vertices, dtype=float)]}


def vertices(shape: dict) -> np.ndarray:
    """The counter-clockwise corners of a box or polygon (world frame), shape (n, 2)."""
    kind = shape[SHAPE_TAG]
    if kind == "ConvexPolygon":
        return np.asarray(shape["vertices"], dtype=float)
    if kind == "AABB":
        (x0, y0), (x1, y1) = shape["min_corner"], shape["max_corner"]
        return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=float)
    if kind == "OBB":
        hx, hy = shape["half_extents"]
        c, s = math.cos(shape["angle"]), math.sin(shape["angle"])
        local = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]], dtype=float)
        return local @ np.array([[c, s], [-s, c]]) + np.asarray(shape["center"], dtype=float)
    raise ValueError(f"a {kind} has no vertices")


def moment_of_inertia(shape: dict, mass: float) -> float:
    """Inertia (kg m^2) about the local origin of a uniform shape centred on it."""
    kind = shape[SHAPE_TAG]
    if kind == "Circle":
        c = np.asarray(shape["center"], dtype=float)
        return mass * (0.5 * shape["radius"] ** 2 + float(c @ c))
    if kind in ("OBB", "AABB"):
        v = vertices(shape)
        if kind == "AABB":
            w, h = (float(x) for x in v.max(axis=0) - v.min(axis=0))
        else:
            w, h = 2 * shape["half_extents"][0], 2 * shape["half_extents"][1]
        c = v.mean(axis=0)
        return float(mass * ((w * w + h * h) / 12.0 + float(c @ c)))
    v = vertices(shape)
    nxt = np.roll(v, -1, axis=0)
    cross = v[:, 0] * nxt[:, 1] - v[:, 1] * nxt[:, 0]
    terms = (v * v).sum(1) + (v * nxt).sum(1) + (nxt * nxt).sum(1)
    return mass * float(np.sum(cross * terms)) / (6.0 * float(np.sum(cross)))


def body(shape: dict, mass: float = 1.0, position=(0.0, 0.0), angle: float = 0.0, velocity=(0.0, 0.0),
         angular_velocity: float = 0.0, restitution: float = 0.0, friction: float = 0.0, is_static: bool = False,
         fixed_rotation: bool = False, is_bullet: bool = False) -> dict:
    """A body whose ``shape`` is given in its local frame, centred on the centre of mass."""
    return {BODY_TAG: True, "shape": shape, "position": _xy(position), "velocity": _xy(velocity),
            "mass": float(mass), "angle": float(angle), "angular_velocity": float(angular_velocity),
            "restitution": float(restitution), "friction": float(friction), "is_static": bool(is_static),
            "fixed_rotation": bool(fixed_rotation or shape[SHAPE_TAG] == "AABB"), "is_bullet": bool(is_bullet)}


def inverse_mass(data: dict) -> float:
    return 0.0 if data["is_static"] else 1.0 / data["mass"]


def inverse_inertia(data: dict) -> float:
    """1/I (1/(kg m^2)); 0 for a static body or a fixed rotation."""
    if data["is_static"] or data["fixed_rotation"]:
        return 0.0
    return 1.0 / moment_of_inertia(data["shape"], data["mass"])


def contact(normal, depth: float, points) -> dict:
    return {CONTACT_TAG: True, "normal": _xy(normal), "depth": float(depth), "points": [_xy(p) for p in points]}
