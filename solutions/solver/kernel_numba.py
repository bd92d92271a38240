"""The solver kernel compiled by numba: :func:`solutions.solver.kernel.solve_constraints`
line for line, on arrays instead of Python lists.

The readable loop in :mod:`solutions.solver.kernel` is the teaching text; this twin
exists for speed and must equal it: ``tests/test_solver_kernel.py`` checks the two to
1e-12 on random rows and on every hard scene.  ``@njit(cache=True)``: the machine code
is kept between runs (in ``__pycache__``), so only the first run pays for compiling.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .constraint_rows import ConstraintRows


@njit(cache=True, inline="always", error_model="numpy")
def _block_normal_impulses(k11, k12, k22, b1, b2):
    det = k11 * k22 - k12 * k12
    x1 = (k12 * b2 - k22 * b1) / det
    x2 = (k12 * b1 - k11 * b2) / det
    if x1 >= 0.0 and x2 >= 0.0:
        return x1, x2
    x1 = -b1 / k11
    if x1 >= 0.0 and k12 * x1 + b2 >= 0.0:
        return x1, 0.0
    x2 = -b2 / k22
    if x2 >= 0.0 and k12 * x2 + b1 >= 0.0:
        return 0.0, x2
    if b1 >= 0.0 and b2 >= 0.0:
        return 0.0, 0.0
    return np.nan, np.nan


@njit(cache=True, inline="always", error_model="numpy")
def _friction(k, v, a, b, nx, ny, ima, imb, iia, iib, rt_a, rt_b, mass_tangent, mu_of, normal, tangent,
              normal_change, accumulate):
    mu = mu_of[k]
    if mu == 0.0:
        return
    tangent_velocity = ((v[b, 0] - v[a, 0]) * ny - (v[b, 1] - v[a, 1]) * nx + v[b, 2] * rt_b[k]
                        - v[a, 2] * rt_a[k])
    change = -mass_tangent[k] * tangent_velocity
    if accumulate:
        bound = mu * normal[k]
        old = tangent[k]
        tangent[k] = min(max(old + change, -bound), bound)
        change = tangent[k] - old
    else:
        bound = mu * normal_change[k]
        change = min(max(change, -bound), bound)
        tangent[k] += change
    v[a, 0] -= ima * change * ny
    v[a, 1] += ima * change * nx
    v[a, 2] -= iia * rt_a[k] * change
    v[b, 0] += imb * change * ny
    v[b, 1] -= imb * change * nx
    v[b, 2] += iib * rt_b[k] * change


@njit(cache=True, error_model="numpy")
def _solve(v, a_of, b_of, nx_of, ny_of, ima_of, imb_of, iia_of, iib_of, first_of, count_of, block_of,
           k11_of, k12_of, k22_of, rn_a, rn_b, rt_a, rt_b, mass_normal, mass_tangent, mu_of, lower_of,
           iterations, normal, tangent, target, mass_scale, impulse_scale, accumulate, friction_first,
           use_friction, use_block):
    normal_change = np.zeros(normal.shape[0])
    for _ in range(iterations):
        for g in range(first_of.shape[0]):
            a, b, nx, ny = a_of[g], b_of[g], nx_of[g], ny_of[g]
            ima, imb, iia, iib = ima_of[g], imb_of[g], iia_of[g], iib_of[g]
            start, stop = first_of[g], first_of[g] + count_of[g]
            block = use_block and block_of[g]
            if friction_first and use_friction:
                for k in range(start, stop):
                    _friction(k, v, a, b, nx, ny, ima, imb, iia, iib, rt_a, rt_b, mass_tangent, mu_of, normal,
                              tangent, normal_change, accumulate)
            if block:
                k1, k2 = start, start + 1
                k11, k12, k22 = k11_of[g], k12_of[g], k22_of[g]
                along = (v[b, 0] - v[a, 0]) * nx + (v[b, 1] - v[a, 1]) * ny
                if accumulate:
                    old1, old2 = normal[k1], normal[k2]
                else:
                    old1, old2 = 0.0, 0.0
                b1 = along + v[b, 2] * rn_b[k1] - v[a, 2] * rn_a[k1] - target[k1] - (k11 * old1 + k12 * old2)
                b2 = along + v[b, 2] * rn_b[k2] - v[a, 2] * rn_a[k2] - target[k2] - (k12 * old1 + k22 * old2)
                x1, x2 = _block_normal_impulses(k11, k12, k22, b1, b2)
                if x1 != x1:
                    x1, x2 = old1, old2
                else:
                    x1, x2 = mass_scale[k1] * x1, mass_scale[k2] * x2
                change1, change2 = x1 - old1, x2 - old2
                normal[k1] += change1
                normal[k2] += change2
                normal_change[k1], normal_change[k2] = change1, change2
                change = change1 + change2
                v[a, 0] -= ima * change * nx
                v[a, 1] -= ima * change * ny
                v[a, 2] -= iia * (rn_a[k1] * change1 + rn_a[k2] * change2)
                v[b, 0] += imb * change * nx
                v[b, 1] += imb * change * ny
                v[b, 2] += iib * (rn_b[k1] * change1 + rn_b[k2] * change2)
            else:
                for k in range(start, stop):
                    normal_velocity = ((v[b, 0] - v[a, 0]) * nx + (v[b, 1] - v[a, 1]) * ny + v[b, 2] * rn_b[k]
                                       - v[a, 2] * rn_a[k])
                    old = normal[k]
                    change = mass_normal[k] * mass_scale[k] * (target[k] - normal_velocity) - impulse_scale[k] * old
                    if accumulate:
                        normal[k] = max(old + change, lower_of[k])
                        change = normal[k] - old
                    else:
                        change = max(change, lower_of[k])
                        normal[k] += change
                    normal_change[k] = change
                    v[a, 0] -= ima * change * nx
                    v[a, 1] -= ima * change * ny
                    v[a, 2] -= iia * rn_a[k] * change
                    v[b, 0] += imb * change * nx
                    v[b, 1] += imb * change * ny
                    v[b, 2] += iib * rn_b[k] * change
                    if not accumulate and not friction_first and use_friction:
                        _friction(k, v, a, b, nx, ny, ima, imb, iia, iib, rt_a, rt_b, mass_tangent, mu_of, normal,
                                  tangent, normal_change, accumulate)
            if not friction_first and (accumulate or block) and use_friction:
                for k in range(start, stop):
                    _friction(k, v, a, b, nx, ny, ima, imb, iia, iib, rt_a, rt_b, mass_tangent, mu_of, normal,
                              tangent, normal_change, accumulate)


def solve_constraints(velocity: np.ndarray, rows: ConstraintRows, iterations: int, normal_total: np.ndarray,
                      tangent_total: np.ndarray, target: np.ndarray, mass_scale: np.ndarray,
                      impulse_scale: np.ndarray, accumulate: bool = True, friction_first: bool = False,
                      use_friction: bool = True, use_block: bool = True) -> None:
    """:func:`solutions.solver.kernel.solve_constraints`, compiled; same parameters and
    effects (``velocity``, ``normal_total`` and ``tangent_total`` updated in place)."""
    if rows.group_count == 0 or iterations <= 0:
        return
    for name, array in (("velocity", velocity), ("normal_total", normal_total), ("tangent_total", tangent_total)):
        if array.dtype != np.float64 or not array.flags.c_contiguous:
            raise TypeError(f"{name} must be a C-contiguous float64 array (it is updated in place)")
    _solve(velocity, *rows.arrays(), int(iterations), normal_total, tangent_total,
           np.ascontiguousarray(target, dtype=np.float64), np.ascontiguousarray(mass_scale, dtype=np.float64),
           np.ascontiguousarray(impulse_scale, dtype=np.float64), bool(accumulate), bool(friction_first),
           bool(use_friction), bool(use_block))
