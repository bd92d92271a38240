"""The compiled soft step's contact preparation: twins of :mod:`solutions.response.contact_preparation`.

:func:`recall_impulses` is ``ContactPreparation._recall_impulses`` on arrays (the warm
start's matching of last step's points), and :func:`separations` is
``SoftStepSolver.separations`` (each point's separation at the current poses), for the
compiled soft step (:mod:`solutions.response.soft_step_numba`).

Conventions: SI units; normal from body ``a`` to body ``b``; points in manifold order.
"""
from __future__ import annotations

### INSTRUCTOR ONLY: not in the student edition (the compiled soft step's prestep).

import math

from numba import njit

from ..compiled_cache import forget_stale_machine_code


@njit(cache=True, _nrt=False)     # (without reference counts: see soft_step_numba._step_on_pairs)
def recall_impulses(pair_key, feature, px, py, old_key, old_feature, old_x, old_y, old_normal, old_tangent,
            first_of, count_of, match_distance, normal_total, tangent_total, work):
    """``ContactPreparation._recall_impulses`` on arrays: per point, the old point of the
    same pair with the same feature id, else the nearest untaken one within
    ``match_distance``; their impulses go to ``normal_total``/``tangent_total``.
    ``work`` holds as many integers as there are points, new and old."""
    old_count = old_key.shape[0]
    found, unmatched = work[:pair_key.shape[0]], work[pair_key.shape[0]:]
    found[:] = -1
    lo = 0
    for g in range(first_of.shape[0]):
        start, count = first_of[g], count_of[g]
        key = pair_key[start]
        # The old points of this pair: a contiguous run (both key lists are sorted).
        while lo < old_count and old_key[lo] < key:
            lo += 1
        hi = lo
        while hi < old_count and old_key[hi] == key:
            hi += 1
        for k in range(start, start + count):
            for q in range(lo, hi):          # the last old point with this key, as a dict keeps it
                if old_feature[q] == feature[k]:
                    found[k] = q
        left = 0
        for q in range(lo, hi):
            taken = False
            for k in range(start, start + count):
                if found[k] >= 0 and old_feature[found[k]] == old_feature[q]:
                    taken = True
            if not taken:
                unmatched[left] = q
                left += 1
        for k in range(start, start + count):
            if found[k] >= 0:
                continue
            if left == 0:
                break
            nearest, best = 0, math.inf
            for u in range(left):
                d = math.hypot(old_x[unmatched[u]] - px[k], old_y[unmatched[u]] - py[k])
                if d < best:
                    nearest, best = u, d
            if best <= match_distance:
                found[k] = unmatched[nearest]
                for u in range(nearest, left - 1):
                    unmatched[u] = unmatched[u + 1]
                left -= 1
    for k in range(found.shape[0]):
        if found[k] >= 0:
            normal_total[k], tangent_total[k] = old_normal[found[k]], old_tangent[found[k]]


@njit(cache=True, inline="always")
def separations(position, angle, a, b, nx, ny, centre, start_angle, r_dot_n_a, r_dot_n_b, r_cross_n_a,
                 r_cross_n_b, depth, cos_less_1, sin, out):
    """``SoftStepSolver.separations``: each point's separation now, in manifold order
    (``cos_less_1`` and ``sin``, one per body, are work space)."""
    for i in range(angle.shape[0]):
        turned = angle[i] - start_angle[i]
        cos_less_1[i], sin[i] = math.cos(turned) - 1.0, math.sin(turned)
    for k in range(a.shape[0]):
        i, j = a[k], b[k]
        dx = (position[j, 0] - centre[j, 0]) - (position[i, 0] - centre[i, 0])
        dy = (position[j, 1] - centre[j, 1]) - (position[i, 1] - centre[i, 1])
        out[k] = (dx * nx[k] + dy * ny[k] + cos_less_1[j] * r_dot_n_b[k] + sin[j] * r_cross_n_b[k]
                  - cos_less_1[i] * r_dot_n_a[k] - sin[i] * r_cross_n_a[k] - depth[k])


# Cached machine code compiled from older sources is forgotten (solutions.compiled_cache).
forget_stale_machine_code(globals())
