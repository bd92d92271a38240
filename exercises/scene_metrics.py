# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/scene_metrics.py on the instructor's side.
"""Measurements of a simulated scene, the same for the reference engine and pymunk.

Each takes plain bodies (pymunk states are copied into them first), so one yardstick
measures both engines: penetration by the reference narrow phase, drift as distance
from the start, energy and momentum as sums.  Units: m, J, kg m/s.
"""
from __future__ import annotations

import numpy as np

from .body import Body
from .broadphase.aabb_array import aabb_array
from .broadphase.sorted_grid_numpy import pairs_grid_numpy
from .narrowphase.dispatch import collide


def max_penetration(bodies: list[Body]) -> float:
    """Deepest overlap (m) between any two bodies, static-static pairs excluded."""
    shapes = [b.world_shape() for b in bodies]
    deepest = 0.0
    for i, j in pairs_grid_numpy(aabb_array(shapes)).tolist():
        if bodies[i].is_static and bodies[j].is_static:
            continue
        contact = collide(shapes[i], shapes[j])
        if contact is not None:
            deepest = max(deepest, contact.depth)
    return deepest


def max_drift(bodies: list[Body], start_positions: np.ndarray) -> float:
    """Largest distance (m) of a dynamic body from where it started."""
    moved = [np.linalg.norm(b.position - p) for b, p in zip(bodies, start_positions) if not b.is_static]
    return float(max(moved, default=0.0))


def total_energy(bodies: list[Body], gravity=(0.0, -9.81)) -> float:
    """Kinetic plus gravitational potential energy (J), potential zero at y = 0."""
    g = np.asarray(gravity, dtype=float)
    return sum(b.kinetic_energy() - (0.0 if b.is_static else b.mass * float(g @ b.position)) for b in bodies)


def linear_momentum(bodies: list[Body]) -> np.ndarray:
    """Total linear momentum (kg m/s) of the dynamic bodies."""
    return sum((b.mass * b.velocity for b in bodies if not b.is_static), np.zeros(2))


def start_positions(bodies: list[Body]) -> np.ndarray:
    """Positions (N, 2) to measure drift against later."""
    return np.array([b.position.copy() for b in bodies])
