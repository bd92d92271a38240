"""The compiled soft step's contact preparation: twins of :mod:`solutions.response.contact_preparation`.

:func:`prepare` is ``ContactPreparation.prepare`` on arrays (manifolds to points, lever
arms, effective masses, closing speeds, the recalled impulses, the rows in sweep order
and the 2x2 blocks), :func:`recall_impulses` its ``_recall_impulses`` (the warm start's
matching of last step's points), and :func:`separations` is
``SoftStepSolver.separations`` (each point's separation at the current poses), for the
compiled soft step (:mod:`solutions.response.soft_step_numba`).

Conventions: SI units; normal from body ``a`` to body ``b``; points in manifold order.
"""
from __future__ import annotations

### INSTRUCTOR ONLY: not in the student edition (the compiled soft step's prestep).

import math

from numba import njit

from ..body_state import FRICTION, INVERSE_INERTIA, INVERSE_MASS, RESTITUTION
from ..narrowphase.box_pairs_numba import (MANIFOLD_COUNT, MANIFOLD_FOUND, MANIFOLD_NX, MANIFOLD_NY, MANIFOLD_POINT,
                                           MANIFOLD_SEPARATION)
from ..solver.constraint_rows import MAX_CONDITION_NUMBER
from ..solver.kernel_numba import (GROUP_A, GROUP_B, GROUP_BLOCK, GROUP_COUNT, GROUP_FIRST, SOLUTION_NORMAL,
                                   SOLUTION_TANGENT)
from ..solver.sweep_order_numba import sweep_order
from .soft_step_layout import (PARAMETER_DT_RATIO, PARAMETER_MATCH_DISTANCE, PARAMETER_SOFT, PARAMETER_STIFF,
                               POINT_FEATURE, POINT_NORMAL_IMPULSE, POINT_PAIR, POINT_TANGENT_IMPULSE, POINT_X,
                               POINT_Y, SWITCH_BLOCK_SOLVER, SWITCH_COLOURS, SWITCH_FRICTION, SWITCH_ROTATION,
                               SWITCH_WARM_START, take)
from ..compiled_cache import forget_stale_machine_code
from ..compiled_views import contiguous_view


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
        missing = 0
        for k in range(start, start + count):
            missing += found[k] < 0
        if missing == 0:        # (every point kept its feature, as in a resting pile: no nearest to look for)
            continue
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
                r_cross_n_b, depth, body_work, out):
    """``SoftStepSolver.separations``: each point's separation now, in manifold order
    (``body_work``, (4, bodies), is work space: each body's cos - 1 and sin of its turn
    and its move, made once per body rather than once per point)."""
    cos_less_1, sin, moved_x, moved_y = body_work[0], body_work[1], body_work[2], body_work[3]
    for i in range(angle.shape[0]):
        turned = angle[i] - start_angle[i]
        cos_less_1[i], sin[i] = math.cos(turned) - 1.0, math.sin(turned)
        moved_x[i], moved_y[i] = position[i, 0] - centre[i, 0], position[i, 1] - centre[i, 1]
    for k in range(a.shape[0]):
        i, j = a[k], b[k]
        dx, dy = moved_x[j] - moved_x[i], moved_y[j] - moved_y[i]
        out[k] = (dx * nx[k] + dy * ny[k] + cos_less_1[j] * r_dot_n_b[k] + sin[j] * r_cross_n_b[k]
                  - cos_less_1[i] * r_dot_n_a[k] - sin[i] * r_cross_n_a[k] - depth[k])


@njit(cache=True, inline="always")     # (returns views: inlined into soft_step_numba._step_on_pairs)
def prepare(keys, key_i, key_j, features, manifold_ints, manifold_floats, position, angle, velocity, properties,
            parameters, switches, old_ints, old_floats, work_ints, ii, work_floats, fi):
    """``ContactPreparation.prepare`` and ``SoftStepSolver.begin_step`` on arrays: the
    found manifolds of the candidate pairs ``keys`` (``i * n + j``, bodies ``key_i`` and
    ``key_j``; ``MANIFOLD_*`` rows of ``manifold_ints`` and ``manifold_floats``, feature
    ids ``features``) become points in manifold order with their lever arms, effective
    masses, closing speeds and last step's impulses (``old_ints``, ``old_floats``:
    ``POINT_*`` columns), then the kernel's groups and rows in sweep order with the 2x2
    blocks (``_sweep_rows``).  Every block is taken from ``work_ints`` at ``ii`` and
    ``work_floats`` at ``fi``.  Returns the points (manifold order), the per-point and
    per-body arrays :func:`separations` reads (``contacts``), the kernel's ``blocks``,
    the soft rows, the static bodies in contact, how many points were warm started,
    and the next free ``ii`` and ``fi``."""
    n = angle.shape[0]
    m = keys.shape[0]
    inverse_mass, inverse_inertia = properties[:, INVERSE_MASS], properties[:, INVERSE_INERTIA]
    friction_of, restitution_of = properties[:, FRICTION], properties[:, RESTITUTION]
    dt_ratio, match_distance = parameters[PARAMETER_DT_RATIO], parameters[PARAMETER_MATCH_DISTANCE]
    rotation, use_friction = switches[SWITCH_ROTATION] != 0, switches[SWITCH_FRICTION] != 0
    warm_start_on, block_solver = switches[SWITCH_WARM_START] != 0, switches[SWITCH_BLOCK_SOLVER] != 0
    colours = switches[SWITCH_COLOURS] != 0
    found, count = manifold_ints[MANIFOLD_FOUND], manifold_ints[MANIFOLD_COUNT]
    old_key, old_feature = old_ints[:, POINT_PAIR], old_ints[:, POINT_FEATURE]
    old_x, old_y = old_floats[:, POINT_X], old_floats[:, POINT_Y]
    old_normal, old_tangent = old_floats[:, POINT_NORMAL_IMPULSE], old_floats[:, POINT_TANGENT_IMPULSE]
    # The manifolds in pair order and their points in manifold order.
    g_count = 0
    p_count = 0
    for k in range(m):
        if found[k]:
            g_count += 1
            p_count += count[k]
    # Each array below is a row of a block of the work space (allocations were half the
    # cost of a step of a small world).
    block, ii = take(work_ints, ii, 5 * g_count)
    group_ints = contiguous_view(block, (5, g_count))
    man_pair, man_count, man_first = group_ints[0], group_ints[1], group_ints[2]
    block, ii = take(work_ints, ii, 6 * p_count)
    point_ints = contiguous_view(block, (6, p_count))
    a, b, feature, pair_key = point_ints[0], point_ints[1], point_ints[2], point_ints[3]
    block, fi = take(work_floats, fi, 27 * p_count)
    points_in_order = contiguous_view(block, (27, p_count))      # manifold order
    nx, ny, px, py, sep = (points_in_order[0], points_in_order[1], points_in_order[2], points_in_order[3],
                           points_in_order[4])
    g = 0
    p = 0
    for k in range(m):
        if not found[k]:
            continue
        man_pair[g], man_count[g], man_first[g] = keys[k], count[k], p
        for s in range(count[k]):
            a[p], b[p] = key_i[k], key_j[k]
            nx[p], ny[p] = manifold_floats[MANIFOLD_NX, k], manifold_floats[MANIFOLD_NY, k]
            px[p], py[p] = manifold_floats[MANIFOLD_POINT + 2 * s, k], manifold_floats[MANIFOLD_POINT + 2 * s + 1, k]
            sep[p] = manifold_floats[MANIFOLD_SEPARATION + s, k]
            feature[p] = features[k, s]
            pair_key[p] = keys[k]
            p += 1
        g += 1

    # The prestep.
    # Without rotation the contacts see no inertia and no angular velocity.
    block, fi = take(work_floats, fi, 8 * n)
    body_floats = contiguous_view(block[:2 * n], (2, n))
    body_floats[:] = 0.0
    contact_inertia = inverse_inertia if rotation else body_floats[0]
    start_angle = body_floats[1]
    body_work = contiguous_view(block[4 * n:], (4, n))       # separations' work space
    for i in range(n):      # (loops, not slice copies: those may allocate, to guard against overlap)
        start_angle[i] = angle[i]
    centre = contiguous_view(block[2 * n:4 * n], (n, 2))
    for i in range(n):
        centre[i, 0], centre[i, 1] = position[i, 0], position[i, 1]
    column = points_in_order
    depth, rn_a, rn_b, rt_a, rt_b = column[5], column[6], column[7], column[8], column[9]
    r_dot_n_a, r_dot_n_b, ima, imb, iia, iib = column[10], column[11], column[12], column[13], column[14], column[15]
    mass_normal, mass_tangent, mu, restitution = column[16], column[17], column[18], column[19]
    normal_velocity, rax, ray, rbx, rby = column[20], column[21], column[22], column[23], column[24]
    for k in range(p_count):
        i, j = a[k], b[k]
        depth[k] = -sep[k]
        restitution[k] = restitution_of[i] * restitution_of[j]
        mu[k] = friction_of[i] * friction_of[j] if use_friction else 0.0
        rax[k], ray[k] = px[k] - centre[i, 0], py[k] - centre[i, 1]
        rbx[k], rby[k] = px[k] - centre[j, 0], py[k] - centre[j, 1]
        rn_a[k] = rax[k] * ny[k] - ray[k] * nx[k]
        rn_b[k] = rbx[k] * ny[k] - rby[k] * nx[k]
        rt_a[k] = -(rax[k] * nx[k] + ray[k] * ny[k])
        rt_b[k] = -(rbx[k] * nx[k] + rby[k] * ny[k])
        r_dot_n_a[k] = rax[k] * nx[k] + ray[k] * ny[k]
        r_dot_n_b[k] = rbx[k] * nx[k] + rby[k] * ny[k]
        ima[k], imb[k], iia[k], iib[k] = inverse_mass[i], inverse_mass[j], contact_inertia[i], contact_inertia[j]
        k_normal = ima[k] + imb[k] + iia[k] * (rn_a[k] * rn_a[k]) + iib[k] * (rn_b[k] * rn_b[k])
        k_tangent = ima[k] + imb[k] + iia[k] * (rt_a[k] * rt_a[k]) + iib[k] * (rt_b[k] * rt_b[k])
        mass_normal[k] = 1.0 / k_normal if k_normal > 0.0 else 0.0
        mass_tangent[k] = 1.0 / k_tangent if k_tangent > 0.0 else 0.0
        wi, wj = (velocity[i, 2], velocity[j, 2]) if rotation else (0.0, 0.0)
        normal_velocity[k] = ((velocity[j, 0] - velocity[i, 0]) * nx[k] + (velocity[j, 1] - velocity[i, 1]) * ny[k]
                              + wj * rn_b[k] - wi * rn_a[k])
    normal_total, tangent_total = column[25], column[26]
    normal_total[:] = 0.0
    tangent_total[:] = 0.0
    if warm_start_on:
        recall_work, _ = take(work_ints, ii, p_count + old_key.shape[0])
        recall_impulses(pair_key, feature, px, py, old_key, old_feature, old_x, old_y, old_normal, old_tangent,
                man_first, man_count, match_distance, normal_total, tangent_total, recall_work)
        for k in range(p_count):
            normal_total[k] *= dt_ratio
            tangent_total[k] *= dt_ratio if use_friction else 0.0
    warm_started = 0
    if warm_start_on:
        for k in range(p_count):
            if normal_total[k] != 0.0:
                warm_started += 1

    # The rows in sweep order (ContactPreparation._sweep_rows).
    ii += p_count + old_key.shape[0]      # (the matching's work space)
    block, ii = take(work_ints, ii, 2 * n)
    body_flags = contiguous_view(block, (2, n))
    body_flags[:] = 0
    movable, in_contact = body_flags[0], body_flags[1]
    for i in range(n):
        movable[i] = inverse_mass[i] + contact_inertia[i] > 0.0
    body_a, body_b = group_ints[3], group_ints[4]
    for q in range(g_count):
        body_a[q], body_b[q] = a[man_first[q]], b[man_first[q]]
    block, ii = take(work_ints, ii, 2 * g_count + n + 2)
    manifold_order, ii = take(work_ints, ii, g_count)
    sweep_order(body_a, body_b, movable, colours, block, manifold_order)
    order, sweep_position = point_ints[4], point_ints[5]
    # The kernel's blocks (solutions.solver.kernel_numba): groups and rows in sweep order.
    block, ii = take(work_ints, ii, 5 * g_count)
    groups = contiguous_view(block, (5, g_count))
    groups[:] = 0
    g_a, g_b, first, row_count = groups[GROUP_A], groups[GROUP_B], groups[GROUP_FIRST], groups[GROUP_COUNT]
    solved_as_block = groups[GROUP_BLOCK]
    r = 0
    for q in range(g_count):
        src = manifold_order[q]
        first[q], row_count[q] = r, man_count[src]
        for s in range(man_count[src]):
            order[r] = man_first[src] + s
            r += 1
    block, fi = take(work_floats, fi, 9 * g_count)
    group_floats = contiguous_view(block, (9, g_count))
    group_floats[:] = 0.0
    g_nx, g_ny, g_ima, g_imb, g_iia = group_floats[0], group_floats[1], group_floats[2], group_floats[3], group_floats[4]
    g_iib, k11, k12, k22 = group_floats[5], group_floats[6], group_floats[7], group_floats[8]
    for q in range(g_count):
        k1 = order[first[q]]
        g_a[q], g_b[q], g_nx[q], g_ny[q] = a[k1], b[k1], nx[k1], ny[k1]
        g_ima[q], g_imb[q], g_iia[q], g_iib[q] = ima[k1], imb[k1], iia[k1], iib[k1]
        if row_count[q] == 2:
            k2 = order[first[q] + 1]
            c11 = ima[k1] + imb[k1] + iia[k1] * rn_a[k1] * rn_a[k1] + iib[k1] * rn_b[k1] * rn_b[k1]
            c22 = ima[k1] + imb[k1] + iia[k1] * rn_a[k2] * rn_a[k2] + iib[k1] * rn_b[k2] * rn_b[k2]
            c12 = ima[k1] + imb[k1] + iia[k1] * rn_a[k1] * rn_a[k2] + iib[k1] * rn_b[k1] * rn_b[k2]
            if block_solver and max(c11, c22) ** 2 < MAX_CONDITION_NUMBER * (c11 * c22 - c12 * c12):
                solved_as_block[q] = 1
                k11[q], k12[q], k22[q] = c11, c12, c22
    block, fi = take(work_floats, fi, 19 * p_count)
    block[:] = 0.0
    # ROW_*: rn_a, rn_b, rt_a, rt_b, masses, friction, lower bound; SOLUTION_*: impulses, targets, scales, work
    rows = contiguous_view(block[:8 * p_count], (8, p_count))
    s_rn_a, s_rn_b, s_rt_a, s_rt_b, s_mass_normal = rows[0], rows[1], rows[2], rows[3], rows[4]
    s_mass_tangent, s_mu = rows[5], rows[6]
    solution = contiguous_view(block[8 * p_count:14 * p_count], (6, p_count))
    normal_s, tangent_s = solution[SOLUTION_NORMAL], solution[SOLUTION_TANGENT]
    row_extra = contiguous_view(block[14 * p_count:], (5, p_count))
    bias_rate, mass_scale_soft, impulse_scale_soft = row_extra[0], row_extra[1], row_extra[2]
    max_normal, separation = row_extra[3], row_extra[4]
    for r in range(p_count):
        k = order[r]
        s_rn_a[r], s_rn_b[r], s_rt_a[r], s_rt_b[r] = rn_a[k], rn_b[k], rt_a[k], rt_b[k]
        s_mass_normal[r], s_mass_tangent[r], s_mu[r] = mass_normal[k], mass_tangent[k], mu[k]
        normal_s[r], tangent_s[r] = normal_total[k], tangent_total[k]
        at = PARAMETER_STIFF if (ima[k] == 0.0 or imb[k] == 0.0) else PARAMETER_SOFT    # (not an array per row)
        bias_rate[r], mass_scale_soft[r], impulse_scale_soft[r] = parameters[at], parameters[at + 1], parameters[at + 2]
        sweep_position[k] = r                       # manifold order -> sweep order
    for k in range(p_count):
        in_contact[a[k]] = in_contact[b[k]] = True
    static_count = 0
    for i in range(n):
        static_count += 1 if in_contact[i] and inverse_mass[i] == 0.0 else 0
    static_members, ii = take(work_ints, ii, static_count)
    static_count = 0
    for i in range(n):
        if in_contact[i] and inverse_mass[i] == 0.0:
            static_members[static_count] = i
            static_count += 1
    for k in range(p_count):         # manifold order; the start's for the first biased pass
        separation[k] = sep[k]

    points = (a, b, nx, ny, px, py, sep, pair_key, feature, ima, imb, iia, iib, rax, ray, rbx, rby, normal_velocity,
              restitution, normal_total, tangent_total, order, sweep_position)
    contacts = (a, b, nx, ny, centre, start_angle, r_dot_n_a, r_dot_n_b, rn_a, rn_b, depth, body_work, separation,
                order)
    blocks = (groups, group_floats, rows, solution)
    soft_rows = (bias_rate, mass_scale_soft, impulse_scale_soft, max_normal)
    return points, contacts, blocks, soft_rows, static_members, warm_started, ii, fi


# Cached machine code compiled from older sources is forgotten (solutions.compiled_cache).
forget_stale_machine_code(globals())
