# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/continuous.py on the instructor's side.
"""Continuous (a priori) collision detection for fast bodies ("bullets").

Discrete detection looks only at the end of each step, so a body that moves farther
than its own size in one step can pass through a thin wall (tunnelling).  For a body
flagged ``is_bullet`` the world sweeps its shape along the step's translation before
moving it, and stops it at the time of first contact: the solver then meets the
contact on the next step.  Rotation during the sweep is ignored (bullets are small).

The sweep samples the translation every ``inner_radius / 2`` (so no sample can skip a
wall) and refines the first overlapping interval by bisection to ``TOI_TOLERANCE``.
"""
from __future__ import annotations

import math

import numpy as np

from .narrowphase.dispatch import shapes_overlap
from .shapes import AABB, Shape, bounding_aabb, inner_radius, translated

#: Fraction of the step (dimensionless) to which the time of impact is refined.
TOI_TOLERANCE = 1e-6
#: Sampling step as a fraction of the moving shape's inner radius.
SAMPLE_FRACTION = 0.5
#: Smallest sampling step (m), for zero-size shapes.
MIN_SAMPLE_STEP = 1e-4


def swept_aabb(shape: Shape, displacement) -> AABB:
    """AABB (m) covering ``shape`` at every point of a straight move by ``displacement``."""
    start = bounding_aabb(shape)
    d = np.asarray(displacement, dtype=float)
    return AABB(start.min_corner + np.minimum(d, 0), start.max_corner + np.maximum(d, 0))


def time_of_impact(moving: Shape, displacement, obstacle: Shape) -> float | None:
    """First fraction t in [0, 1] of the move at which ``moving`` touches ``obstacle``.

    Parameters
    ----------
    moving : Shape
        The moving shape at the start of the step (world frame, m).
    displacement : array_like (2,)
        Its translation over the step (m).
    obstacle : Shape
        A shape that does not move during the step.

    Returns
    -------
    float or None
        ``t`` such that ``moving`` moved by ``t * displacement`` touches the obstacle
        (within ``TOI_TOLERANCE``), 0 if they overlap already, None if never.

    >>> from exercises.shapes import Circle, AABB
    >>> t = time_of_impact(Circle((0, 0), 0.05), (1.6, 0), AABB((1.0, -1), (1.1, 1)))
    >>> round(t, 4)  # centre stops 0.05 m before x = 1.0
    0.5938
    """
    d = np.asarray(displacement, dtype=float)
    if shapes_overlap(moving, obstacle):
        return 0.0
    distance = math.hypot(d[0], d[1])
    if distance == 0.0:
        return None
    step = max(SAMPLE_FRACTION * inner_radius(moving), MIN_SAMPLE_STEP)
    samples = max(1, math.ceil(distance / step))
    previous = 0.0
    for k in range(1, samples + 1):
        t = k / samples
        if shapes_overlap(translated(moving, t * d), obstacle):
            lo, hi = previous, t
            while hi - lo > TOI_TOLERANCE:
                mid = 0.5 * (lo + hi)
                if shapes_overlap(translated(moving, mid * d), obstacle):
                    hi = mid
                else:
                    lo = mid
            return hi
        previous = t
    return None
