"""The solver kernel compiled by numba: :func:`solutions.solver.kernel.solve_constraints`
line for line, on arrays instead of Python lists.

The readable loop in :mod:`solutions.solver.kernel` is the teaching text; this twin
exists for speed and must equal it: ``tests/test_solver_kernel.py`` checks the two to
1e-12 on random rows and on every hard scene.  ``@njit(cache=True)``: the machine code
is kept between runs (in ``__pycache__``), so only the first run pays for compiling.
"""
from __future__ import annotations

### INSTRUCTOR ONLY: not in the student edition (the sequential exercise's impulses, compiled).

import numpy as np
from numba import njit

from .constraint_rows import ConstraintRows
from ..compiled_cache import forget_stale_machine_code

# The kernel takes the rows as four blocks (few arguments: each array a compiled
# function takes costs it a reference count on entry and on exit, which with 29 arrays
# was about half the cost of a pass over a small world's rows):
#: rows of the groups' integer block (5, groups): bodies, first row, row count, block solve (0/1);
GROUP_A, GROUP_B, GROUP_FIRST, GROUP_COUNT, GROUP_BLOCK = range(5)
#: rows of the groups' float block (9, groups): direction, inverse masses and inertias, K;
GROUP_NX, GROUP_NY, GROUP_IMA, GROUP_IMB, GROUP_IIA, GROUP_IIB, GROUP_K11, GROUP_K12, GROUP_K22 = range(9)
#: rows of the rows' constant block (8, rows), as in ConstraintRows;
ROW_RN_A, ROW_RN_B, ROW_RT_A, ROW_RT_B, ROW_MASS_NORMAL, ROW_MASS_TANGENT, ROW_FRICTION, ROW_LOWER = range(8)
#: rows of the pass's block (6, rows): the accumulated normal and tangent impulses (read
#: and written), the pass's target, mass scale and impulse scale, and work space.
(SOLUTION_NORMAL, SOLUTION_TANGENT, SOLUTION_TARGET, SOLUTION_MASS_SCALE, SOLUTION_IMPULSE_SCALE,
 SOLUTION_WORK) = range(6)


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
def _friction(vxa, vya, wa, vxb, vyb, wb, nx, ny, ima, imb, iia, iib, rt_a, rt_b, mass_tangent, mu, normal,
              tangent, normal_change, accumulate):
    """One row's friction visit on the two bodies' velocities (scalars in and out, as
    the readable loop keeps them in locals); returns them and the new tangent total."""
    if mu != 0.0:
        tangent_velocity = (vxb - vxa) * ny - (vyb - vya) * nx + wb * rt_b - wa * rt_a
        change = -mass_tangent * tangent_velocity
        if accumulate:
            bound = mu * normal
            total = min(max(tangent + change, -bound), bound)
            change = total - tangent
        else:
            bound = mu * normal_change
            change = min(max(change, -bound), bound)
            total = tangent + change
        vxa -= ima * change * ny
        vya += ima * change * nx
        wa -= iia * rt_a * change
        vxb += imb * change * ny
        vyb -= imb * change * nx
        wb += iib * rt_b * change
        tangent = total
    return vxa, vya, wa, vxb, vyb, wb, tangent


@njit(cache=True, error_model="numpy")
def sweep_groups(v, groups, group_values, rows, solution, iterations, accumulate, friction_first, use_friction,
            use_block):
    """The sweeps of :func:`solutions.solver.kernel.solve_constraints` (module docstring)
    over the blocks ``groups``, ``group_values``, ``rows`` and ``solution`` (``GROUP_*``,
    ``ROW_*``, ``SOLUTION_*``)."""
    a_of, b_of, first_of, count_of = groups[GROUP_A], groups[GROUP_B], groups[GROUP_FIRST], groups[GROUP_COUNT]
    block_of = groups[GROUP_BLOCK]
    nx_of, ny_of = group_values[GROUP_NX], group_values[GROUP_NY]
    ima_of, imb_of, iia_of, iib_of = (group_values[GROUP_IMA], group_values[GROUP_IMB], group_values[GROUP_IIA],
                                      group_values[GROUP_IIB])
    k11_of, k12_of, k22_of = group_values[GROUP_K11], group_values[GROUP_K12], group_values[GROUP_K22]
    rn_a, rn_b, rt_a, rt_b = rows[ROW_RN_A], rows[ROW_RN_B], rows[ROW_RT_A], rows[ROW_RT_B]
    mass_normal, mass_tangent = rows[ROW_MASS_NORMAL], rows[ROW_MASS_TANGENT]
    mu_of, lower_of = rows[ROW_FRICTION], rows[ROW_LOWER]
    normal, tangent, target = solution[SOLUTION_NORMAL], solution[SOLUTION_TANGENT], solution[SOLUTION_TARGET]
    mass_scale, impulse_scale = solution[SOLUTION_MASS_SCALE], solution[SOLUTION_IMPULSE_SCALE]
    normal_change = solution[SOLUTION_WORK]
    for k in range(normal_change.shape[0]):
        normal_change[k] = 0.0
    for _ in range(iterations):
        for g in range(first_of.shape[0]):
            a, b, nx, ny = a_of[g], b_of[g], nx_of[g], ny_of[g]
            ima, imb, iia, iib = ima_of[g], imb_of[g], iia_of[g], iib_of[g]
            start, stop = first_of[g], first_of[g] + count_of[g]
            block = use_block and block_of[g] != 0
            # The two bodies' velocities stay in locals while the group is solved (as
            # in the readable loop; writing them through memory at every visit made
            # each row about ten times slower: 75 against 8 ns, measured).
            vxa, vya, wa, vxb, vyb, wb = v[a, 0], v[a, 1], v[a, 2], v[b, 0], v[b, 1], v[b, 2]
            if friction_first and use_friction:
                for k in range(start, stop):
                    vxa, vya, wa, vxb, vyb, wb, tangent[k] = _friction(
                        vxa, vya, wa, vxb, vyb, wb, nx, ny, ima, imb, iia, iib, rt_a[k], rt_b[k],
                        mass_tangent[k], mu_of[k], normal[k], tangent[k], normal_change[k], accumulate)
            if block:
                k1, k2 = start, start + 1
                k11, k12, k22 = k11_of[g], k12_of[g], k22_of[g]
                along = (vxb - vxa) * nx + (vyb - vya) * ny
                if accumulate:
                    old1, old2 = normal[k1], normal[k2]
                else:
                    old1, old2 = 0.0, 0.0
                b1 = along + wb * rn_b[k1] - wa * rn_a[k1] - target[k1] - (k11 * old1 + k12 * old2)
                b2 = along + wb * rn_b[k2] - wa * rn_a[k2] - target[k2] - (k12 * old1 + k22 * old2)
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
                vxa -= ima * change * nx
                vya -= ima * change * ny
                wa -= iia * (rn_a[k1] * change1 + rn_a[k2] * change2)
                vxb += imb * change * nx
                vyb += imb * change * ny
                wb += iib * (rn_b[k1] * change1 + rn_b[k2] * change2)
            else:
                for k in range(start, stop):
                    normal_velocity = (vxb - vxa) * nx + (vyb - vya) * ny + wb * rn_b[k] - wa * rn_a[k]
                    old = normal[k]
                    change = mass_normal[k] * mass_scale[k] * (target[k] - normal_velocity) - impulse_scale[k] * old
                    if accumulate:
                        normal[k] = max(old + change, lower_of[k])
                        change = normal[k] - old
                    else:
                        change = max(change, lower_of[k])
                        normal[k] += change
                    normal_change[k] = change
                    vxa -= ima * change * nx
                    vya -= ima * change * ny
                    wa -= iia * rn_a[k] * change
                    vxb += imb * change * nx
                    vyb += imb * change * ny
                    wb += iib * rn_b[k] * change
                    if not accumulate and not friction_first and use_friction:
                        vxa, vya, wa, vxb, vyb, wb, tangent[k] = _friction(
                            vxa, vya, wa, vxb, vyb, wb, nx, ny, ima, imb, iia, iib, rt_a[k], rt_b[k],
                            mass_tangent[k], mu_of[k], normal[k], tangent[k], normal_change[k], accumulate)
            if not friction_first and (accumulate or block) and use_friction:
                for k in range(start, stop):
                    vxa, vya, wa, vxb, vyb, wb, tangent[k] = _friction(
                        vxa, vya, wa, vxb, vyb, wb, nx, ny, ima, imb, iia, iib, rt_a[k], rt_b[k],
                        mass_tangent[k], mu_of[k], normal[k], tangent[k], normal_change[k], accumulate)
            v[a, 0], v[a, 1], v[a, 2], v[b, 0], v[b, 1], v[b, 2] = vxa, vya, wa, vxb, vyb, wb


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
    groups = np.array([rows.a, rows.b, rows.first, rows.count, rows.block], dtype=np.int64)
    group_values = np.array([rows.nx, rows.ny, rows.ima, rows.imb, rows.iia, rows.iib, rows.k11, rows.k12, rows.k22],
                            dtype=np.float64)
    row_values = np.array([getattr(rows, name) for name in ConstraintRows.ROW_FIELDS], dtype=np.float64)
    solution = np.zeros((6, rows.row_count))
    solution[SOLUTION_NORMAL], solution[SOLUTION_TANGENT] = normal_total, tangent_total
    solution[SOLUTION_TARGET], solution[SOLUTION_MASS_SCALE] = target, mass_scale
    solution[SOLUTION_IMPULSE_SCALE] = impulse_scale
    sweep_groups(velocity, groups, group_values, row_values, solution,
            int(iterations), bool(accumulate), bool(friction_first), bool(use_friction), bool(use_block))
    normal_total[:], tangent_total[:] = solution[SOLUTION_NORMAL], solution[SOLUTION_TANGENT]


# Cached machine code compiled from older sources is forgotten (solutions.compiled_cache).
forget_stale_machine_code(globals())
