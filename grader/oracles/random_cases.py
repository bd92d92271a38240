"""Seeded random inputs for the graded tests, as plain data (:mod:`.plain`).

A numpy Generator seeded by the test names each case exactly; the Hypothesis
strategies give small round-numbered cases that shrink well.  Units: m, kg, s.
"""
from __future__ import annotations

import math

import numpy as np
from hypothesis import strategies as st

from . import plain


def random_aabbs(rng: np.random.Generator, count: int, world: float = 50.0, size: float = 2.0,
                 origin=(0.0, 0.0)) -> np.ndarray:
    """``count`` boxes [min_x, min_y, max_x, max_y] spread over a square of side ``world``."""
    centres = rng.uniform(-world / 2, world / 2, size=(count, 2)) + np.asarray(origin)
    halves = rng.uniform(0.05, size / 2, size=(count, 2))
    return np.hstack([centres - halves, centres + halves])


def resting_piles(rng: np.random.Generator, count: int, origin=(0.0, 0.0)) -> np.ndarray:
    """``count`` boxes [min_x, min_y, max_x, max_y] as crates rest in a world: side-by-side
    columns of 1 to 5 stacked boxes, 0.5, 1 or 2 m wide and 0.5 or 1 m tall, from ``origin``
    (their bottom left) rightwards.  Every box touches its neighbours exactly, along an edge
    or at a corner, and every coordinate is a multiple of 0.5 m."""
    boxes: list[list[float]] = []
    x, y = (float(v) for v in origin)
    while len(boxes) < count:
        width, height = float(rng.choice([0.5, 1.0, 2.0])), float(rng.choice([0.5, 1.0]))
        boxes += [[x, y + k * height, x + width, y + (k + 1) * height] for k in range(int(rng.integers(1, 6)))]
        x += width
    return np.array(boxes[:count], dtype=float)


def clustered_aabbs(rng: np.random.Generator, count: int, clusters: int = 4) -> np.ndarray:
    centres = rng.uniform(-30, 30, size=(clusters, 2))[rng.integers(0, clusters, count)]
    centres = centres + rng.normal(0, 2.0, size=(count, 2))
    halves = rng.uniform(0.05, 0.6, size=(count, 2))
    return np.hstack([centres - halves, centres + halves])


def random_polygon(rng: np.random.Generator, center, radius: float) -> dict:
    """A convex CCW polygon of 3 to 7 vertices on a circle (sorted random angles)."""
    while True:
        count = int(rng.integers(3, 8))
        angles = np.sort(rng.uniform(0, 2 * math.pi, count))
        if np.min(np.diff(np.append(angles, angles[0] + 2 * math.pi))) > 0.2:
            break
    return plain.polygon(np.column_stack([np.cos(angles), np.sin(angles)]) * radius + np.asarray(center))


def random_obb(rng: np.random.Generator, spread: float = 2.0) -> dict:
    return plain.obb(rng.uniform(-spread, spread, 2), rng.uniform(0.2, 1.5, 2), float(rng.uniform(-math.pi, math.pi)))


def random_circle(rng: np.random.Generator, spread: float = 2.0) -> dict:
    return plain.circle(rng.uniform(-spread, spread, 2), float(rng.uniform(0.2, 1.5)))


def random_body(rng: np.random.Generator, static: bool = False) -> dict:
    """A box or a disc with random mass, pose and velocities."""
    kwargs = dict(position=rng.uniform(-2, 2, 2), angle=float(rng.uniform(-3, 3)), velocity=rng.normal(0, 3, 2),
                  angular_velocity=float(rng.normal(0, 2)), restitution=float(rng.uniform(0, 1)),
                  friction=float(rng.uniform(0, 1)))
    if static:
        kwargs.update(is_static=True, velocity=(0, 0), angular_velocity=0.0)
    else:
        kwargs["mass"] = float(rng.uniform(0.2, 5))
    if rng.random() < 0.5:
        return plain.body(plain.circle((0, 0), float(rng.uniform(0.2, 1.0))), **kwargs)
    return plain.body(plain.obb((0, 0), (float(rng.uniform(0.15, 1)), float(rng.uniform(0.15, 1))), 0.0), **kwargs)


def unit_vector(rng: np.random.Generator) -> np.ndarray:
    a = rng.uniform(-math.pi, math.pi)
    return np.array([math.cos(a), math.sin(a)])


# Hypothesis strategies: small, round-numbered cases that shrink well.
coordinates = st.floats(-4, 4, allow_nan=False).map(lambda v: round(v, 2))
half_sizes = st.floats(0.1, 2, allow_nan=False).map(lambda v: round(v, 2))
angles = st.floats(-math.pi, math.pi, allow_nan=False).map(lambda v: round(v, 2))
obbs = st.builds(lambda x, y, hx, hy, a: plain.obb((x, y), (hx, hy), a), coordinates, coordinates, half_sizes,
                 half_sizes, angles)
circles = st.builds(lambda x, y, r: plain.circle((x, y), r), coordinates, coordinates, half_sizes)
