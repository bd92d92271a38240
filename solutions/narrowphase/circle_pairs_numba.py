"""Disc contacts of the compiled soft step: the twin of :func:`solutions.narrowphase.circle_circle.collide_circle_circle`.

Every candidate pair of discs at once, written as the box manifolds of
:mod:`solutions.narrowphase.box_pairs_numba` are (``MANIFOLD_*`` rows, one point per
pair that touches), for the compiled soft step (:mod:`solutions.response.soft_step_numba`).

Conventions: SI units; normal from disc ``i`` to disc ``j``; separation < 0 overlapping.
"""
from __future__ import annotations

### INSTRUCTOR ONLY: not in the student edition (a twin of the disc contacts).

import math

from numba import njit

from .box_pairs_numba import (MANIFOLD_COUNT, MANIFOLD_FOUND, MANIFOLD_NX, MANIFOLD_NY, MANIFOLD_POINT,
                              MANIFOLD_SEPARATION)
from .circle_circle import COINCIDENT_CENTRES_ATOL, COINCIDENT_CENTRES_NORMAL
from ..compiled_cache import forget_stale_machine_code


#: The feature id of a disc-disc contact point (``("circle", "circle")``); box ids are 0..127.
CIRCLE_FEATURE = 1 << 10


@njit(cache=True)
def circle_manifolds(first, second, position, half, ints, floats):
    """:func:`~solutions.narrowphase.circle_circle.collide_circle_circle` for every pair
    of discs of radius ``half[:, 0]``, into ``ints`` and ``floats`` as the box manifolds
    are (``MANIFOLD_*`` rows; one point per pair found)."""
    ints[MANIFOLD_FOUND], ints[MANIFOLD_COUNT] = 0, 0
    for k in range(first.shape[0]):
        i, j = first[k], second[k]
        dx, dy = position[j, 0] - position[i, 0], position[j, 1] - position[i, 1]
        distance = math.hypot(dx, dy)
        reach = half[i, 0] + half[j, 0]
        if distance > reach:
            continue
        if distance <= COINCIDENT_CENTRES_ATOL:
            ux, uy = COINCIDENT_CENTRES_NORMAL
        else:
            ux, uy = dx / distance, dy / distance
        ints[MANIFOLD_FOUND, k], ints[MANIFOLD_COUNT, k] = 1, 1
        floats[MANIFOLD_NX, k], floats[MANIFOLD_NY, k] = ux, uy
        ax, ay = position[i, 0] + half[i, 0] * ux, position[i, 1] + half[i, 0] * uy
        bx, by = position[j, 0] - half[j, 0] * ux, position[j, 1] - half[j, 0] * uy
        floats[MANIFOLD_POINT, k], floats[MANIFOLD_POINT + 1, k] = (ax + bx) / 2, (ay + by) / 2
        floats[MANIFOLD_SEPARATION, k] = -(reach - distance)


# Cached machine code compiled from older sources is forgotten (solutions.compiled_cache).
forget_stale_machine_code(globals())
