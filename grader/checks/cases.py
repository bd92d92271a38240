"""Seeded random inputs shared by the checks: boxes, shapes, bodies.

Everything is built with the reference engine's classes and a numpy Generator, so a
seed names a case exactly.  Units: m, kg, s.
"""
from __future__ import annotations

import math

import numpy as np
from hypothesis import strategies as st

from solutions.body import Body
from solutions.shapes import OBB, Circle, ConvexPolygon


def random_aabbs(rng: np.random.Generator, count: int, world: float = 50.0, size: float = 2.0,
                 origin=(0.0, 0.0)) -> np.ndarray:
    """``count`` boxes [min_x, min_y, max_x, max_y] spread over a square of side ``world``."""
    centres = rng.uniform(-world / 2, world / 2, size=(count, 2)) + np.asarray(origin)
    halves = rng.uniform(0.05, size / 2, size=(count, 2))
    return np.hstack([centres - halves, centres + halves])


def clustered_aabbs(rng: np.random.Generator, count: int, clusters: int = 4) -> np.ndarray:
    centres = rng.uniform(-30, 30, size=(clusters, 2))[rng.integers(0, clusters, count)]
    centres = centres + rng.normal(0, 2.0, size=(count, 2))
    halves = rng.uniform(0.05, 0.6, size=(count, 2))
    return np.hstack([centres - halves, centres + halves])


def random_polygon(rng: np.random.Generator, center, radius: float) -> ConvexPolygon:
    """A convex CCW polygon of 3 to 7 vertices on a circle (sorted random angles)."""
    while True:
        count = int(rng.integers(3, 8))
        angles = np.sort(rng.uniform(0, 2 * math.pi, count))
        if np.min(np.diff(np.append(angles, angles[0] + 2 * math.pi))) > 0.2:
            break
    vertices = np.column_stack([np.cos(angles), np.sin(angles)]) * radius + np.asarray(center)
    return ConvexPolygon(vertices)


def random_obb(rng: np.random.Generator, spread: float = 2.0) -> OBB:
    return OBB(rng.uniform(-spread, spread, 2), rng.uniform(0.2, 1.5, 2), float(rng.uniform(-math.pi, math.pi)))


def random_circle(rng: np.random.Generator, spread: float = 2.0) -> Circle:
    return Circle(rng.uniform(-spread, spread, 2), float(rng.uniform(0.2, 1.5)))


def random_body(rng: np.random.Generator, static: bool = False) -> Body:
    """A box or a disc with random mass, pose and velocities."""
    kwargs = dict(position=rng.uniform(-2, 2, 2), angle=float(rng.uniform(-3, 3)), velocity=rng.normal(0, 3, 2),
                  angular_velocity=float(rng.normal(0, 2)), restitution=float(rng.uniform(0, 1)),
                  friction=float(rng.uniform(0, 1)))
    if static:
        kwargs.update(is_static=True, velocity=(0, 0), angular_velocity=0.0)
    else:
        kwargs["mass"] = float(rng.uniform(0.2, 5))
    if rng.random() < 0.5:
        return Body.circle(float(rng.uniform(0.2, 1.0)), **kwargs)
    return Body.box(float(rng.uniform(0.3, 2)), float(rng.uniform(0.3, 2)), **kwargs)


def unit_vector(rng: np.random.Generator) -> np.ndarray:
    a = rng.uniform(-math.pi, math.pi)
    return np.array([math.cos(a), math.sin(a)])


# Hypothesis strategies, for shrinking a failing random case to a small one.
coordinates = st.floats(-4, 4, allow_nan=False).map(lambda v: round(v, 2))
half_sizes = st.floats(0.1, 2, allow_nan=False).map(lambda v: round(v, 2))
angles = st.floats(-math.pi, math.pi, allow_nan=False).map(lambda v: round(v, 2))
obbs = st.builds(lambda x, y, hx, hy, a: OBB((x, y), (hx, hy), a), coordinates, coordinates, half_sizes, half_sizes, angles)
circles = st.builds(lambda x, y, r: Circle((x, y), r), coordinates, coordinates, half_sizes)
