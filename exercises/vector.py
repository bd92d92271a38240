# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/vector.py on the instructor's side.
"""Small 2D vector helpers shared by every module.

Vectors are numpy arrays of shape ``(2,)`` (or ``(..., 2)`` where stated).
"""
from __future__ import annotations

import math

import numpy as np


def perp(edge: np.ndarray) -> np.ndarray:
    """Outward normal direction of an edge of a counter-clockwise polygon.

    ``perp((x, y)) = (y, -x)``: the edge direction turned by -90 degrees.  Not
    normalised.

    >>> perp(np.array([1.0, 0.0]))
    array([ 0., -1.])
    """
    edge = np.asarray(edge, dtype=float)
    return np.stack([edge[..., 1], -edge[..., 0]], axis=-1)


def cross(a, b) -> float | np.ndarray:
    """2D cross product ``a.x * b.y - a.y * b.x`` (the z of the 3D cross product).

    >>> float(cross(np.array([1.0, 0.0]), np.array([0.0, 1.0])))
    1.0
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def cross_scalar_vector(w: float, r) -> np.ndarray:
    """``w x r`` for a scalar angular velocity ``w`` (rad/s) and a vector ``r``:
    the velocity ``(-w * r.y, w * r.x)`` of a point at ``r`` from the rotation centre.

    >>> cross_scalar_vector(2.0, np.array([1.0, 0.0])).tolist()
    [-0.0, 2.0]
    """
    r = np.asarray(r, dtype=float)
    return np.stack([-w * r[..., 1], w * r[..., 0]], axis=-1)


def rotation_matrix(angle: float) -> np.ndarray:
    """2x2 matrix turning a local vector by ``angle`` radians (counter-clockwise)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


def normalize(v, tiny: float = 1e-300) -> np.ndarray | None:
    """Unit vector along ``v``, or ``None`` when ``|v|`` is below ``tiny``."""
    v = np.asarray(v, dtype=float)
    length = math.hypot(v[0], v[1])
    if length <= tiny:
        return None
    return v / length
