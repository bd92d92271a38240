"""Distance joints compiled: the twin of :meth:`solutions.joints.JointSolver.solve` in the soft step.

Each joint is a bilateral row of the compiled kernel
(:func:`solutions.solver.kernel_numba.sweep_groups`): a soft rod, or a spring of its own
frequency and damping ratio, warm started on the biased pass; for the compiled soft
step (:mod:`solutions.response.soft_step_numba`).

Conventions: SI units; a joint's direction points from its anchor on ``a`` to its anchor on ``b``.
"""
from __future__ import annotations

### INSTRUCTOR ONLY: not in the student edition (a twin of the joint solver).

import math

import numpy as np
from numba import njit

from .response.soft_step_layout import (JOINT_ANCHOR_AX, JOINT_ANCHOR_AY, JOINT_ANCHOR_BX, JOINT_ANCHOR_BY,
                                       JOINT_DAMPING, JOINT_FREQUENCY, JOINT_LENGTH)
from .solver.kernel_numba import (GROUP_A, GROUP_B, GROUP_COUNT, GROUP_FIRST, GROUP_IIA, GROUP_IIB, GROUP_IMA,
                                  GROUP_IMB, GROUP_NX, GROUP_NY, ROW_LOWER, ROW_MASS_NORMAL, ROW_RN_A, ROW_RN_B,
                                  SOLUTION_IMPULSE_SCALE, SOLUTION_MASS_SCALE, SOLUTION_NORMAL, SOLUTION_TARGET,
                                  sweep_groups)
from .compiled_cache import forget_stale_machine_code


@njit(cache=True, inline="always")     # (returns views: inlined into soft_step_numba._step_on_pairs)
def joint_rows(ints, floats):
    """Work space of :func:`solve_joints` for ``count`` joints, made once per step from
    ``ints`` (6, count) and ``floats`` (25, count): the kernel's four blocks (one group
    of one row per joint, no block solve, no friction, no lower bound), the joint of
    each row, and each row's length error (m) and inverse effective mass (1/kg)."""
    count = ints.shape[1]
    ints[:] = 0
    floats[:] = 0.0
    groups, joint_of = ints[:5], ints[5]
    for k in range(count):
        groups[GROUP_FIRST, k], groups[GROUP_COUNT, k] = k, 1
    rows = floats[9:17]
    rows[ROW_LOWER] = -np.inf
    return groups, floats[:9], rows, floats[17:23], joint_of, floats[23], floats[24]


@njit(cache=True)
def joint_geometry(position, angle, joint_a, joint_b, joint_floats, impulses, inverse_mass, inverse_inertia, work):
    """Each joint's row at the current poses, written into ``work`` (:func:`joint_rows`):
    bodies, direction, lever arms, masses, length error.  A joint between two static
    bodies gets no row and forgets its impulse.  Returns the number of rows."""
    groups, group_values, rows, solution, joint_of, errors, inverses = work
    a_of, b_of = groups[GROUP_A], groups[GROUP_B]
    nx, ny = group_values[GROUP_NX], group_values[GROUP_NY]
    ima, imb, iia, iib = (group_values[GROUP_IMA], group_values[GROUP_IMB], group_values[GROUP_IIA],
                          group_values[GROUP_IIB])
    rn_a, rn_b, mass = rows[ROW_RN_A], rows[ROW_RN_B], rows[ROW_MASS_NORMAL]
    r = 0
    for k in range(joint_a.shape[0]):
        a, b = joint_a[k], joint_b[k]
        ca, sa, cb, sb = math.cos(angle[a]), math.sin(angle[a]), math.cos(angle[b]), math.sin(angle[b])
        anchor_ax, anchor_ay = joint_floats[k, JOINT_ANCHOR_AX], joint_floats[k, JOINT_ANCHOR_AY]
        anchor_bx, anchor_by = joint_floats[k, JOINT_ANCHOR_BX], joint_floats[k, JOINT_ANCHOR_BY]
        pax = position[a, 0] + ca * anchor_ax - sa * anchor_ay
        pay = position[a, 1] + sa * anchor_ax + ca * anchor_ay
        pbx = position[b, 0] + cb * anchor_bx - sb * anchor_by
        pby = position[b, 1] + sb * anchor_bx + cb * anchor_by
        dx, dy = pbx - pax, pby - pay
        distance = math.hypot(dx, dy)
        if distance > 1e-12:
            ux, uy = dx / distance, dy / distance
        else:
            ux, uy = 1.0, 0.0
        cra = (pax - position[a, 0]) * uy - (pay - position[a, 1]) * ux
        crb = (pbx - position[b, 0]) * uy - (pby - position[b, 1]) * ux
        inverse = inverse_mass[a] + inverse_mass[b] + inverse_inertia[a] * cra * cra + inverse_inertia[b] * crb * crb
        if inverse == 0.0:          # two static bodies: no row, and no impulse to remember
            impulses[k] = 0.0
            continue
        a_of[r], b_of[r], joint_of[r] = a, b, k
        nx[r], ny[r], rn_a[r], rn_b[r] = ux, uy, cra, crb
        ima[r], imb[r], iia[r], iib[r] = inverse_mass[a], inverse_mass[b], inverse_inertia[a], inverse_inertia[b]
        mass[r] = 1.0 / inverse
        errors[r], inverses[r] = distance - joint_floats[k, JOINT_LENGTH], inverse
        r += 1
    return r


@njit(cache=True)
def solve_joints(velocity, position, angle, joint_a, joint_b, joint_floats, impulses,
                  inverse_mass, inverse_inertia, h, iterations, use_bias, softness, warm_starting, work,
                  rows_made):
    """:meth:`solutions.joints.JointSolver.solve` of the soft step on arrays: each joint
    a bilateral row of the kernel (soft rod, or spring), warm started on the biased pass;
    ``impulses`` (per joint, N s) are read and replaced; ``work`` from :func:`joint_rows`.

    ``rows_made``: -1, or the rows the last call made in ``work`` if the poses have not
    moved since (the biased pass after a relax pass): their directions, lever arms and
    masses are the same numbers, and only the targets and scales are made again.
    Returns the number of rows, for the next call."""
    groups, group_values, rows, solution, joint_of, errors, inverses = work
    a_of, b_of = groups[GROUP_A], groups[GROUP_B]
    nx, ny = group_values[GROUP_NX], group_values[GROUP_NY]
    ima, imb, iia, iib = (group_values[GROUP_IMA], group_values[GROUP_IMB], group_values[GROUP_IIA],
                          group_values[GROUP_IIB])
    rn_a, rn_b = rows[ROW_RN_A], rows[ROW_RN_B]
    total, target = solution[SOLUTION_NORMAL], solution[SOLUTION_TARGET]
    mass_scale, impulse_scale = solution[SOLUTION_MASS_SCALE], solution[SOLUTION_IMPULSE_SCALE]
    r = rows_made if rows_made >= 0 else joint_geometry(position, angle, joint_a, joint_b, joint_floats, impulses,
                                                         inverse_mass, inverse_inertia, work)
    for q in range(r):
        k = joint_of[q]
        error, inverse = errors[q], inverses[q]
        frequency = joint_floats[k, JOINT_FREQUENCY]
        if frequency > 0:
            omega = 2 * math.pi * frequency
            spring_mass = 1.0 / inverse
            k_spring, c_damp = spring_mass * omega * omega, 2 * spring_mass * joint_floats[k, JOINT_DAMPING] * omega
            gamma = h * (c_damp + h * k_spring)
            gamma = 1.0 / gamma if gamma > 0 else 0.0
            target[q] = -error * h * k_spring * gamma
            mass_scale[q], impulse_scale[q] = inverse / (inverse + gamma), gamma / (inverse + gamma)
        elif not use_bias:
            target[q], mass_scale[q], impulse_scale[q] = 0.0, 1.0, 0.0
        else:
            target[q], mass_scale[q], impulse_scale[q] = -softness[0] * error, softness[1], softness[2]
        total[q] = impulses[k] if (warm_starting or not use_bias) else 0.0
    if r == 0:
        return r
    if use_bias:        # warm start: last impulses first, A then B
        for q in range(r):
            impulse = total[q]
            if impulse != 0.0:
                a, b = a_of[q], b_of[q]
                velocity[a, 0] -= ima[q] * impulse * nx[q]
                velocity[a, 1] -= ima[q] * impulse * ny[q]
                velocity[a, 2] -= iia[q] * rn_a[q] * impulse
                velocity[b, 0] += imb[q] * impulse * nx[q]
                velocity[b, 1] += imb[q] * impulse * ny[q]
                velocity[b, 2] += iib[q] * rn_b[q] * impulse
    if r == joint_a.shape[0]:
        sweep_groups(velocity, groups, group_values, rows, solution, iterations, True, False, False, False)
    else:           # some joints hold two static bodies: the first r rows only
        sweep_groups(velocity, groups[:, :r], group_values[:, :r], rows[:, :r], solution[:, :r], iterations, True, False,
                False, False)
    for q in range(r):
        impulses[joint_of[q]] = total[q]
    return r


# Cached machine code compiled from older sources is forgotten (solutions.compiled_cache).
forget_stale_machine_code(globals())
