"""The soft step compiled whole, for worlds of boxes or of discs: the twin of :meth:`World.step`'s soft step.

:meth:`solutions.world.World.step` with ``soft_step`` is the teaching text: broad phase, speculative
narrow phase, prestep, warm start, soft solve and relax per sub-step, restitution and
the impulse memory, each stage readable on its own.  Each stage builds Python objects
(shapes, contacts, dictionaries of remembered impulses), and on a 20-base pyramid
(210 boxes, about 540 manifolds) those cost a hundred times what the arithmetic does.
This module runs the same stages, in the same order and with the same floating-point
operations, as one compiled function over the world's
:class:`~solutions.body_state.BodyState` arrays:

1. the boxes' AABBs widened by ``SPECULATIVE_MARGIN``, and the candidate pairs from a
   sort-and-sweep on ``min_x`` (a few bodies) or the compiled strip grid
   (:mod:`solutions.broadphase.grid_numba`, from ``STRIP_GRID_MIN_BODIES``), kept in
   the world's sorted ``(i, j)`` order, no static-static pair, no joined pair;
2. the speculative manifolds of every candidate pair
   (:mod:`solutions.narrowphase.box_pairs_numba`, itself the twin of the numpy batch);
3. the prestep of :class:`~solutions.response.contact_preparation.ContactPreparation`
   (lever arms, effective masses, the restitution target, last step's impulses matched
   by feature id or else by the nearest point, the sweep order and the 2x2 blocks), as
   :func:`~solutions.response.contact_preparation_numba.prepare`;
4. the sub-steps of :class:`~solutions.response.soft_step.SoftStepSolver` (gravity,
   warm start, soft solve, positions, relax), each pass the compiled solver kernel
   (:func:`solutions.solver.kernel_numba.sweep_groups`, copied in);
5. restitution, and the impulses remembered for the next step.

It covers a world whose every body is a box (``Body.box``: an OBB centred on the body)
or every body a disc (``Body.circle``), with distance joints, without bullets under
continuous detection, with accumulated impulses on (:meth:`CompiledSoftStep.supports`);
chosen by ``WorldSettings(backend="numba", soft_step=True)``
(:attr:`World.compiled_soft_step`), every other world runs the readable stages with
their compiled twins.  Tested equal to the readable step to 1e-12 on every box scene
over 1 s, on random piles and on disc chains (``tests/test_soft_step_numba.py``).  Contacts are made into
:class:`~solutions.contact.Contact` objects only when asked for (``world.manifolds``).

Memory: the step allocates only the candidate pairs of 64 bodies or more (the strip
grid's; a few bodies are swept without allocating).  Everything else lives in arrays the
:class:`CompiledSoftStep` keeps between steps, made for a number of candidate pairs that
grows when a step finds more (the step then returns, having changed nothing, and runs
again): two buffers of contact points, the last step's (its warm start) and this
step's, and a work space of integers and of floats (:func:`~solutions.response.soft_step_layout.work_sizes`) from which the
step takes each of its blocks in turn.  After the strip grid's candidate pairs, or from
the start for a few bodies, the step runs in a function compiled without reference
counts (:func:`_step_on_pairs`), where the many views it makes of its blocks cost nothing.

Conventions: SI units; normal from body ``i`` to body ``j`` of a pair ``i < j``; a
feature id ``(ref, face, incident_face, vertex)`` is stored as one integer
(:func:`~solutions.narrowphase.box_pairs_numba.packed_feature_ids`).
"""
from __future__ import annotations

### INSTRUCTOR ONLY: not in the student edition (it carries the compiled kernel and box clipping).

import numpy as np
from numba import njit

from ..body_state import EXTENT_X, EXTENT_Y, INVERSE_INERTIA, INVERSE_MASS
from ..contact import Contact
from ..narrowphase.box_pairs_numba import (CLIPPING_FLOATS, CLIPPING_INTS, MANIFOLD_FLOATS, MANIFOLD_INTS,
                                           feature_id, indexed_manifolds, matmul_rounding, packed_feature_ids)
from ..broadphase.pairs_numba import STRIP_GRID_MIN_BODIES, candidate_pairs, faces_and_aabbs, few_candidate_pairs
from .soft_step_layout import (FIGURE_BLOCK_MANIFOLDS, FIGURE_CANDIDATE_PAIRS, FIGURE_MANIFOLDS, FIGURE_MEMORY,
                               FIGURE_POINTS, FIGURE_WARM_STARTED, HEADER_CAPACITY, HEADER_COUNT, HEADER_JOINTS,
                               JOINT_A, JOINT_B, JOINT_PAIRS, NO_PAIR, PARAMETER_DT_RATIO, PARAMETER_GRAVITY_X,
                               PARAMETER_GRAVITY_Y, PARAMETER_H, PARAMETER_JOINT_SOFTNESS, PARAMETER_MARGIN,
                               PARAMETER_MATCH_DISTANCE, PARAMETER_MAX_PUSH, PARAMETER_RESTITUTION_THRESHOLD,
                               PARAMETER_SOFT, PARAMETER_STIFF, POINT_A, POINT_B, POINT_FEATURE,
                               POINT_NORMAL_IMPULSE, POINT_NX, POINT_NY, POINT_PAIR, POINT_SEPARATION,
                               POINT_TANGENT_IMPULSE, POINT_X, POINT_Y, SWITCH_CIRCLES, SWITCH_CORNER_ROUNDING,
                               SWITCH_INCIDENT_ROUNDING, SWITCH_ITERATIONS, SWITCH_RELAX, SWITCH_SUBSTEPS,
                               SWITCH_WARM_START, layout, sections, take)
from ..narrowphase.speculative import SPECULATIVE_MARGIN
from ..joints import DistanceJoint
from ..shapes import OBB, Circle
from ..solver.kernel_numba import (GROUP_BLOCK, SOLUTION_IMPULSE_SCALE, SOLUTION_MASS_SCALE, SOLUTION_NORMAL,
                                   SOLUTION_TANGENT, SOLUTION_TARGET, sweep_groups)
from .soft_step import JOINT_DAMPING_RATIO, JOINT_HERTZ, soft_coefficients
from .solver_settings import SolverStats
from ..compiled_cache import forget_stale_machine_code
from ..compiled_views import contiguous_view
from ..no_alias_compiler import NoAliasCompiler
from ..narrowphase.circle_pairs_numba import CIRCLE_FEATURE, circle_manifolds
from .contact_preparation_numba import prepare, separations
from ..joints_numba import joint_rows, solve_joints
from ..body_state_numba import integrate_positions, integrate_velocities, state_arrays


@njit(cache=True, inline="always")
def _zero_static_velocities(velocity, static_members):
    """The readable step's ``velocity * dynamic`` after a pass, on the static bodies in contact."""
    for i in static_members:
        velocity[i, 0] *= 0.0
        velocity[i, 1] *= 0.0
        velocity[i, 2] *= 0.0


@njit(cache=True, inline="always")
def warm_start(velocity, a, b, nx, ny, ima, imb, iia, iib, rax, ray, rbx, rby, normal, tangent, sweep_position):
    """The accumulated impulses (``normal`` and ``tangent``, sweep order) applied again,
    points in manifold order, to all bodies A, then all bodies B (``SoftStepSolver.solve_substep``'s
    ``apply_impulses``).  A body's velocity stays in locals over a run of points on it
    (the same additions in the same order; through memory each waited for the last)."""
    if a.shape[0] == 0:
        return
    for side in range(2):
        body, sign = (a, -1.0) if side == 0 else (b, 1.0)
        im, ii, rx, ry = (ima, iia, rax, ray) if side == 0 else (imb, iib, rbx, rby)
        held = body[0]
        vx, vy, w = velocity[held, 0], velocity[held, 1], velocity[held, 2]
        for k in range(a.shape[0]):
            if body[k] != held:
                velocity[held, 0], velocity[held, 1], velocity[held, 2] = vx, vy, w
                held = body[k]
                vx, vy, w = velocity[held, 0], velocity[held, 1], velocity[held, 2]
            pn, pt = normal[sweep_position[k]], tangent[sweep_position[k]]
            ix, iy = pn * nx[k] + pt * ny[k], pn * ny[k] + pt * (-nx[k])
            vx += sign * (im[k] * ix)
            vy += sign * (im[k] * iy)
            w += sign * (ii[k] * (rx[k] * iy - ry[k] * ix))
        velocity[held, 0], velocity[held, 1], velocity[held, 2] = vx, vy, w


@njit(cache=True, inline="always")
def solve_contacts(use_bias, separation_is_current, velocity, position, angle, h, max_push, iterations, contacts,
                   blocks, soft_rows, static_members):
    """``SoftStepSolver.solve_substep`` after its warm start: one pass of ``iterations``
    sweeps of the kernel, soft and pushing apart (``use_bias``, before the positions
    move) or rigid without a push (relax, after them); a point still open may close by
    its separation over ``h`` (s).  ``separation_is_current``: the separations in
    ``contacts`` are those of the current poses (made again otherwise).  Returns
    whether they are current after this pass (the positions move after a biased one)."""
    (a, b, nx, ny, centre, start_angle, r_dot_n_a, r_dot_n_b, rn_a, rn_b, depth, body_work, separation,
     order) = contacts
    groups, group_floats, rows, solution = blocks
    bias_rate, soft_mass_scale, soft_impulse_scale, max_normal = soft_rows
    target, mass_scale = solution[SOLUTION_TARGET], solution[SOLUTION_MASS_SCALE]
    impulse_scale, normal = solution[SOLUTION_IMPULSE_SCALE], solution[SOLUTION_NORMAL]
    if not (use_bias and separation_is_current):
        separations(position, angle, a, b, nx, ny, centre, start_angle, r_dot_n_a, r_dot_n_b, rn_a, rn_b, depth,
                    body_work, separation)
    for r in range(order.shape[0]):
        s = separation[order[r]]
        if s > 0.0:
            target[r], mass_scale[r], impulse_scale[r] = -s / h, 1.0, 0.0
        elif use_bias:
            target[r] = min(-bias_rate[r] * s, max_push)
            mass_scale[r], impulse_scale[r] = soft_mass_scale[r], soft_impulse_scale[r]
        else:
            target[r], mass_scale[r], impulse_scale[r] = 0.0, 1.0, 0.0
    sweep_groups(velocity, groups, group_floats, rows, solution, iterations, True, False, True, True)
    if use_bias:
        for r in range(order.shape[0]):
            max_normal[r] = max(max_normal[r], normal[r])
    _zero_static_velocities(velocity, static_members)
    return not use_bias


@njit(cache=True, inline="always")
def apply_restitution(velocity, order, normal_velocity, restitution, threshold, max_normal, blocks, static_members):
    """``SoftStepSolver.end_step``'s restitution: one sweep without friction over the
    points that pushed in some sub-step (``max_normal`` > 0) and closed faster than
    ``threshold`` (m/s) at the start of the step, aiming at ``restitution`` times that speed."""
    groups, group_floats, rows, solution = blocks
    target, mass_scale, impulse_scale = (solution[SOLUTION_TARGET], solution[SOLUTION_MASS_SCALE],
                                         solution[SOLUTION_IMPULSE_SCALE])
    bouncing = False
    for r in range(order.shape[0]):
        k = order[r]
        bounce = normal_velocity[k] < -threshold and max_normal[r] > 0.0 and restitution[k] > 0.0
        target[r] = -restitution[k] * normal_velocity[k]
        mass_scale[r] = 1.0 if bounce else 0.0
        bouncing = bouncing or bounce
    if bouncing:
        impulse_scale[:] = 0.0
        sweep_groups(velocity, groups, group_floats, rows, solution, 1, True, False, False, False)
        _zero_static_velocities(velocity, static_members)


@njit(cache=True, inline="always")
def store_impulses(order, normal, tangent, normal_total, tangent_total, pair_key, feature, a, b, px, py, nx, ny,
                   separation, kept_ints, kept_floats):
    """``SoftStepSolver.end_step``'s memory: the accumulated impulses (sweep order) back
    in manifold order, and every point (``POINT_*`` columns) into ``kept_ints`` and
    ``kept_floats``, for the caller and as the next step's warm start."""
    for r in range(order.shape[0]):
        normal_total[order[r]], tangent_total[order[r]] = normal[r], tangent[r]
    for k in range(order.shape[0]):
        kept_ints[k, POINT_PAIR], kept_ints[k, POINT_FEATURE] = pair_key[k], feature[k]
        kept_ints[k, POINT_A], kept_ints[k, POINT_B] = a[k], b[k]
        kept_floats[k, POINT_X], kept_floats[k, POINT_Y] = px[k], py[k]
        kept_floats[k, POINT_NX], kept_floats[k, POINT_NY] = nx[k], ny[k]
        kept_floats[k, POINT_SEPARATION] = separation[k]
        kept_floats[k, POINT_NORMAL_IMPULSE], kept_floats[k, POINT_TANGENT_IMPULSE] = normal_total[k], tangent_total[k]


@njit(cache=True)
def _soft_step(numbers, ints, floats):
    """One soft step of the world (module docstring) on its state (its ``numbers``, cut
    into ``position``, ``angle``, ``velocity`` and ``properties``: the bodies' extents, inverse masses and
    inertias, friction and restitution, read every step, columns as
    :mod:`~solutions.body_state` names them; a body is dynamic where its inverse mass is
    not 0 and turns where its inverse inertia is not, as the state's ``dynamic`` and
    ``turning`` say)
    with the sections of ``ints`` and ``floats`` (:func:`~solutions.response.soft_step_layout.layout`): ``parameters`` and
    ``switches`` (``PARAMETER_*``, ``SWITCH_*``), the joints' constants (``JOINT_*``)
    and impulses.  The contact
    points (``POINT_*``) live in two buffers, ``memory_*[0]`` and ``memory_*[1]``, of
    ``2 * capacity`` points each: the step reads the last step's from the one ``figures``
    names and writes its own into the other, then updates ``figures`` (``FIGURE_*``).
    Every other array of the step is a view of the work spaces (:func:`~solutions.response.soft_step_layout.work_sizes`).
    Returns 0, or, having changed nothing, the number of candidate pairs the buffers
    must be made for (more than ``capacity``)."""
    position, angle, velocity, properties = state_arrays(numbers)
    # 1. Candidate pairs: from STRIP_GRID_MIN_BODIES bodies on, the strip grid's, which
    # allocates, here; fewer bodies are swept in _step_on_pairs, without allocating.
    if angle.shape[0] < STRIP_GRID_MIN_BODIES:
        none = ints[:0]
        return _step_on_pairs(none, none, none, position, angle, velocity, properties, ints, floats)
    switches, _, joint_ints, _, _, parameters, _, _, _, work_floats = sections(angle.shape[0], ints, floats)
    _, aabb = faces_and_aabbs(position, angle, properties[:, EXTENT_X:EXTENT_Y + 1], parameters[PARAMETER_MARGIN],
                               switches[SWITCH_CIRCLES] != 0, switches[SWITCH_CORNER_ROUNDING], work_floats)
    keys, key_i, key_j = candidate_pairs(aabb, properties[:, INVERSE_MASS], joint_ints[JOINT_PAIRS])
    return _step_on_pairs(keys, key_i, key_j, position, angle, velocity, properties, ints, floats)


#: Compiled without numba's reference counts (``_nrt=False``): each array view a
#: function makes (a row of a block) otherwise costs an atomic increment and decrement
#: of its parent's count, and on a three-box world those were two thirds of the step
#: (perf: NRT_incref and NRT_decref).  Such a function, and every function it calls, may
#: make views but no new array, nor return one: every array here is an argument or a view
#: of one, and the caller holds the arguments for the whole call.  Its arguments are
#: distinct arrays, which LLVM is told (:class:`~solutions.no_alias_compiler.NoAliasCompiler`).
@njit(cache=True, _nrt=False, pipeline_class=NoAliasCompiler)
def _step_on_pairs(keys, key_i, key_j, position, angle, velocity, properties, ints, floats):
    """The rest of :func:`_soft_step` from the candidate pairs ``keys`` (``i * n + j``),
    ``key_i`` and ``key_j``: manifolds, prestep, sub-steps, restitution, memory.  For
    fewer than ``STRIP_GRID_MIN_BODIES`` bodies the pairs come empty and are found here
    (:func:`few_candidate_pairs`)."""
    (switches, figures, joint_ints, memory_ints, work_ints, parameters, joint_floats, joint_impulses,
     memory_floats, work_floats) = sections(angle.shape[0], ints, floats)
    h = parameters[PARAMETER_H]
    gravity_x, gravity_y = parameters[PARAMETER_GRAVITY_X], parameters[PARAMETER_GRAVITY_Y]
    max_push, restitution_threshold = parameters[PARAMETER_MAX_PUSH], parameters[PARAMETER_RESTITUTION_THRESHOLD]
    margin = parameters[PARAMETER_MARGIN]
    joint_softness = parameters[PARAMETER_JOINT_SOFTNESS:PARAMETER_JOINT_SOFTNESS + 3]
    substeps, iterations = switches[SWITCH_SUBSTEPS], switches[SWITCH_ITERATIONS]
    relax, circles = switches[SWITCH_RELAX] != 0, switches[SWITCH_CIRCLES] != 0
    warm_start_on = switches[SWITCH_WARM_START] != 0
    corner_rounding, incident_rounding = switches[SWITCH_CORNER_ROUNDING], switches[SWITCH_INCIDENT_ROUNDING]
    joint_a, joint_b, jointed = joint_ints[JOINT_A], joint_ints[JOINT_B], joint_ints[JOINT_PAIRS]
    last = figures[FIGURE_MEMORY]
    old_ints, old_floats = memory_ints[last, :figures[FIGURE_POINTS]], memory_floats[last, :figures[FIGURE_POINTS]]
    n = angle.shape[0]
    half = properties[:, EXTENT_X:EXTENT_Y + 1]
    inverse_mass, inverse_inertia = properties[:, INVERSE_MASS], properties[:, INVERSE_INERTIA]
    # Work space: blocks taken in turn from work_ints (at ``ii``) and work_floats (at
    # ``fi``), after the faces, the AABBs and the sweep's copy of them.
    fi = 24 * n
    capacity = memory_ints.shape[1] // 2
    few_work, ii = take(work_ints, 0, 2 * n + 3 * capacity + 1)
    few_keys, ii = take(work_ints, ii, capacity)
    few_i, ii = take(work_ints, ii, capacity)
    few_j, ii = take(work_ints, ii, capacity)
    if n < STRIP_GRID_MIN_BODIES:       # 1. candidate pairs (for more bodies: _soft_step's)
        faces, aabb = faces_and_aabbs(position, angle, half, margin, circles, corner_rounding, work_floats)
        m = few_candidate_pairs(aabb, inverse_mass, jointed, few_work,
                                contiguous_view(work_floats[20 * n:24 * n], (n, 4)), few_keys, few_i, few_j)
        if m < 0:
            return capacity + n
        keys, key_i, key_j = few_keys[:m], few_i[:m], few_j[:m]
    else:
        faces = contiguous_view(work_floats[:16 * n], (n, 2, 4, 2))
    # 2. Speculative manifolds of every pair.
    m = keys.shape[0]
    if 2 * m > memory_ints.shape[1]:
        return m
    block, ii = take(work_ints, ii, 2 * m)
    features = contiguous_view(block, (m, 2))
    features[:] = CIRCLE_FEATURE
    block, ii = take(work_ints, ii, MANIFOLD_INTS * m)
    manifold_ints = contiguous_view(block, (MANIFOLD_INTS, m))
    block, fi = take(work_floats, fi, MANIFOLD_FLOATS * m)
    manifold_floats = contiguous_view(block, (MANIFOLD_FLOATS, m))
    if circles:
        circle_manifolds(key_i, key_j, position, half, manifold_ints, manifold_floats)
    else:
        clipping_floats, fi = take(work_floats, fi, CLIPPING_FLOATS)
        clipping_ints, ii = take(work_ints, ii, CLIPPING_INTS)
        indexed_manifolds(faces, key_i, key_j, margin, incident_rounding, manifold_ints, manifold_floats,
                           clipping_floats, clipping_ints)
        packed_feature_ids(manifold_ints, features)

    # 3. The prestep (ContactPreparation.prepare and SoftStepSolver.begin_step).
    points, contacts, blocks, soft_rows, static_members, warm_started, ii, fi = prepare(
        keys, key_i, key_j, features, manifold_ints, manifold_floats, position, angle, velocity, properties,
        parameters, switches, old_ints, old_floats, work_ints, ii, work_floats, fi)
    (a, b, nx, ny, px, py, sep, pair_key, feature, ima, imb, iia, iib, rax, ray, rbx, rby, normal_velocity,
     restitution, normal_total, tangent_total, order, sweep_position) = points
    groups, group_floats, rows, solution = blocks
    normal_s, tangent_s, max_normal = solution[SOLUTION_NORMAL], solution[SOLUTION_TANGENT], soft_rows[3]
    p_count, g_count, solved_as_block = a.shape[0], groups.shape[1], groups[GROUP_BLOCK]

    # 4. The sub-steps.
    separation_is_current = True     # (later: the relax pass's, or computed again without relax)
    joint_count = joint_a.shape[0]
    joint_block, ii = take(work_ints, ii, 6 * joint_count)
    joint_values, fi = take(work_floats, fi, 25 * joint_count)
    joint_work = joint_rows(contiguous_view(joint_block, (6, joint_count)),
                            contiguous_view(joint_values, (25, joint_count)))
    joint_rows_made = -1     # joint rows made at the current poses (-1: none yet)
    # The stages of World.step, in its order (each inlined).
    for _ in range(substeps):
        integrate_velocities(velocity, inverse_mass, h, gravity_x, gravity_y)
        if p_count:
            warm_start(velocity, a, b, nx, ny, ima, imb, iia, iib, rax, ray, rbx, rby, normal_s, tangent_s,
                       sweep_position)
            separation_is_current = solve_contacts(True, separation_is_current, velocity, position, angle, h, max_push,
                                                   iterations, contacts, blocks, soft_rows, static_members)
        if joint_count:     # the joints: soft rods after the contacts
            solve_joints(velocity, position, angle, joint_a, joint_b, joint_floats, joint_impulses, inverse_mass,
                         inverse_inertia, h, iterations, True, joint_softness, warm_start_on, joint_work,
                         joint_rows_made)
        integrate_positions(position, angle, velocity, inverse_mass, inverse_inertia, h)
        joint_rows_made = -1
        if relax and joint_count:
            joint_rows_made = solve_joints(velocity, position, angle, joint_a, joint_b, joint_floats, joint_impulses,
                                           inverse_mass, inverse_inertia, h, iterations, False, joint_softness,
                                           warm_start_on, joint_work, -1)
        if p_count and relax:
            separation_is_current = solve_contacts(False, separation_is_current, velocity, position, angle, h,
                                                   max_push, iterations, contacts, blocks, soft_rows, static_members)
    if p_count:
        apply_restitution(velocity, order, normal_velocity, restitution, restitution_threshold, max_normal, blocks,
                          static_members)
    store_impulses(order, normal_s, tangent_s, normal_total, tangent_total, pair_key, feature, a, b, px, py, nx, ny,
                   sep, memory_ints[1 - last], memory_floats[1 - last])
    block_count = 0
    for q in range(g_count):
        if solved_as_block[q] != 0:
            block_count += 1
    figures[FIGURE_MEMORY], figures[FIGURE_POINTS] = 1 - last, p_count
    figures[FIGURE_CANDIDATE_PAIRS], figures[FIGURE_MANIFOLDS] = m, g_count
    figures[FIGURE_WARM_STARTED], figures[FIGURE_BLOCK_MANIFOLDS] = warm_started, block_count
    return 0


class CompiledSoftStep:
    """The soft step of :meth:`World.step` compiled whole, for a world of boxes or of discs (module docstring).

    Holds two arrays, ``ints`` and ``floats``, whose sections (:func:`~solutions.response.soft_step_layout.layout`) are also
    its attributes: the settings (``parameters``, ``switches``), the step's ``figures``,
    the joints (``joint_ints``, ``joint_floats``) with their last impulses, two buffers of contact points
    (``memory_ints``, ``memory_floats``; columns ``POINT_*``): the last step's, which are
    also the next step's warm start, and the next step's; and the step's work space.
    The buffers are made for up to ``capacity`` candidate pairs.  The bodies' masses,
    materials and extents are not copied: each step reads them from the world's
    :class:`~solutions.body_state.BodyState` (``properties``), where ``Body`` setters write.
    """

    #: Candidate pairs the buffers are made for at first; a step that finds more makes
    #: them again for twice as many.
    INITIAL_PAIR_CAPACITY = 8

    def __init__(self, bodies, joints=()):
        self.circles = bool(bodies) and isinstance(bodies[0].shape, Circle)
        self.body_count = n = len(bodies)
        self.joint_count = len(joints)
        joined = np.unique(np.array([min(j.a, j.b) * n + max(j.a, j.b) for j in joints], dtype=np.int64))
        joint_ints = np.full((3, len(joints)), NO_PAIR, dtype=np.int64)
        joint_ints[JOINT_A] = [joint.a for joint in joints]
        joint_ints[JOINT_B] = [joint.b for joint in joints]
        joint_ints[JOINT_PAIRS, :len(joined)] = joined
        joint_floats = np.array([[*joint.anchor_a, *joint.anchor_b, joint.length, joint.frequency,
                                  joint.damping_ratio] for joint in joints], dtype=float).reshape(-1, 7)
        self._constants = joint_ints, joint_floats
        self.reset()

    @staticmethod
    def supports(world) -> bool:
        """Whether this twin can step ``world``: every body a ``Body.box`` (an OBB centred
        on it) or every body a ``Body.circle`` (a disc centred on it), joints distance
        joints, no bullet under continuous detection, accumulated impulses on."""
        settings = world.settings
        bodies = world.bodies
        boxes = all(isinstance(b.shape, OBB) and not b.shape.center.any() and b.shape.angle == 0.0 for b in bodies)
        discs = all(isinstance(b.shape, Circle) and not b.shape.center.any() for b in bodies)
        return (settings.soft_step and settings.backend == "numba" and settings.solver.accumulate_impulses
                and all(isinstance(joint, DistanceJoint) for joint in world.joints)
                and not (settings.continuous and any(b.is_bullet and not b.is_static for b in bodies))
                and (boxes or discs))

    def reset(self) -> None:
        """Forget last step's impulses."""
        self.ints = self.floats = None
        self.make_buffers(self.INITIAL_PAIR_CAPACITY)
        self.joint_ints[:], self.joint_floats[:] = self._constants
        self.previous_h = None
        self._settings_key = None
        self._machine_code = None

    def step(self, state, h: float, settings) -> None:
        """One step of ``settings.substeps`` sub-steps of ``h`` (s) on ``state`` (updated
        in place), under the world's ``settings``."""
        solver, springs = settings.solver, settings.soft
        gravity_x, gravity_y = settings.gravity
        # The settings as read now; parameters and switches are written again only when they change.
        key = (h, self.previous_h, settings.substeps, gravity_x, gravity_y, solver.iterations, solver.friction,
               solver.warm_starting, solver.warm_start_match_distance, solver.block_solver, solver.order,
               solver.rotation, solver.max_push_velocity, solver.restitution_threshold, springs.contact_hertz,
               springs.contact_damping_ratio, springs.relax)
        if key != self._settings_key:
            self._write_parameters(h, settings)
            self._settings_key = key
        self.step_again(state.numbers)
        self.previous_h = h

    def settled(self, h: float) -> bool:
        """Whether the next step of ``h`` (s) under unchanged settings would write no
        parameter: the last one was written for ``h`` after a step of ``h``."""
        key = self._settings_key
        return key is not None and key[0] == h and key[1] == h

    def step_again(self, numbers: np.ndarray) -> None:
        """One step of the state's ``numbers`` under the parameters last written
        (:meth:`step` after :meth:`settled`: the caller has checked the settings)."""
        if self._machine_code is None:
            needed = _soft_step(numbers, self.ints, self.floats)
            # numba's machine code for these argument types, called without the dispatcher
            # choosing it again (0.15 of its 0.35 us a call); every later call passes arrays
            # of the same types (float64, int64, float64; one dimension, contiguous).
            argument_types = tuple(_soft_step.typeof_pyval(x) for x in (numbers, self.ints, self.floats))
            self._machine_code = _soft_step.overloads[argument_types].entry_point
        else:
            needed = self._machine_code(numbers, self.ints, self.floats)
        while needed:
            self.make_buffers(2 * needed)        # nothing changed: step again
            needed = _soft_step(numbers, self.ints, self.floats)

    def make_buffers(self, capacity: int) -> None:
        """``ints`` and ``floats`` (:func:`~solutions.response.soft_step_layout.layout`) for ``capacity`` candidate pairs (up to
        ``2 * capacity`` points), everything but the work space kept: the settings, the
        figures, the joints' constants and impulses and the last step's points (which
        must fit); and each section as an attribute (a view)."""
        held = self.ints is not None
        if held and not 2 * capacity >= self.figures[FIGURE_POINTS]:
            raise ValueError(f"buffers for {capacity} pairs cannot keep the last step's "
                             f"{self.figures[FIGURE_POINTS]} points")
        n, joints = self.body_count, self.joint_count
        sizes = layout(n, joints, capacity)
        ints, floats = np.zeros(sizes[5], np.int64), np.zeros(sizes[10])
        ints[HEADER_JOINTS], ints[HEADER_CAPACITY] = joints, capacity
        if held:
            points = min(self.memory_ints.shape[1], 2 * capacity)
            old_ints, old_floats, old_points = self.ints, self.floats, (self.memory_ints, self.memory_floats)
            old_layout = layout(n, joints, self.capacity)
            ints[HEADER_COUNT:sizes[3]] = old_ints[HEADER_COUNT:old_layout[3]]        # up to the point buffers
            floats[:sizes[8]] = old_floats[:old_layout[8]]
        (switches, figures, joint_ints, memory_ints, work_ints, ints_end, joint_floats, impulses,
         memory_floats, work_floats, floats_end) = sizes
        self.ints, self.floats, self.capacity = ints, floats, capacity
        self.switches, self.figures = ints[switches:figures], ints[figures:joint_ints]
        self.joint_ints = ints[joint_ints:memory_ints].reshape(3, joints)
        self.memory_ints = ints[memory_ints:work_ints].reshape(2, 2 * capacity, 4)
        self.work_ints = ints[work_ints:ints_end]
        self.parameters = floats[:joint_floats]
        self.joint_floats = floats[joint_floats:impulses].reshape(joints, 7)
        self.joint_impulses = floats[impulses:memory_floats]
        self.memory_floats = floats[memory_floats:work_floats].reshape(2, 2 * capacity, 7)
        self.work_floats = floats[work_floats:floats_end]
        if held:
            self.memory_ints[:, :points], self.memory_floats[:, :points] = (old_points[0][:, :points],
                                                                            old_points[1][:, :points])

    @property
    def point_ints(self) -> np.ndarray:
        """The last step's contact points, integer columns ``POINT_PAIR`` to ``POINT_B``."""
        return self.memory_ints[self.figures[FIGURE_MEMORY], :self.figures[FIGURE_POINTS]]

    @property
    def point_floats(self) -> np.ndarray:
        """The last step's contact points, float columns ``POINT_X`` to ``POINT_TANGENT_IMPULSE``."""
        return self.memory_floats[self.figures[FIGURE_MEMORY], :self.figures[FIGURE_POINTS]]

    @property
    def candidate_pairs(self) -> int:
        return int(self.figures[FIGURE_CANDIDATE_PAIRS])

    @property
    def manifold_count(self) -> int:
        return int(self.figures[FIGURE_MANIFOLDS])

    def _write_parameters(self, h: float, settings) -> None:
        """The step's ``parameters`` and ``switches`` from ``settings`` and ``h`` (s)."""
        solver, springs = settings.solver, settings.soft
        hertz = min(springs.contact_hertz, 0.25 / h)
        parameters = self.parameters
        parameters[PARAMETER_DT_RATIO] = 1.0 if self.previous_h is None else h / self.previous_h
        parameters[PARAMETER_H] = h
        parameters[PARAMETER_GRAVITY_X], parameters[PARAMETER_GRAVITY_Y] = settings.gravity
        parameters[PARAMETER_MAX_PUSH] = solver.max_push_velocity
        parameters[PARAMETER_RESTITUTION_THRESHOLD] = solver.restitution_threshold
        parameters[PARAMETER_MATCH_DISTANCE] = solver.warm_start_match_distance
        parameters[PARAMETER_MARGIN] = SPECULATIVE_MARGIN
        parameters[PARAMETER_SOFT:PARAMETER_SOFT + 3] = soft_coefficients(hertz, springs.contact_damping_ratio, h)
        parameters[PARAMETER_STIFF:PARAMETER_STIFF + 3] = soft_coefficients(2.0 * hertz,
                                                                              springs.contact_damping_ratio, h)
        parameters[PARAMETER_JOINT_SOFTNESS:PARAMETER_JOINT_SOFTNESS + 3] = soft_coefficients(
            min(JOINT_HERTZ, 0.25 / h), JOINT_DAMPING_RATIO, h)
        corner_rounding, incident_rounding = matmul_rounding()[:2]
        self.switches[:] = (settings.substeps, solver.iterations, springs.relax, solver.friction,
                            solver.warm_starting, solver.block_solver, solver.order == "colours", corner_rounding,
                            incident_rounding, self.circles, solver.rotation)

    def solver_stats(self) -> SolverStats:
        """The last step's :class:`SolverStats`, as the readable soft step fills them."""
        floats = self.point_floats
        return SolverStats(manifolds=self.manifold_count, contact_points=len(floats),
                           total_normal_impulse=float(floats[:, POINT_NORMAL_IMPULSE].sum()),
                           max_penetration=float((-floats[:, POINT_SEPARATION]).max(initial=0.0)),
                           warm_started_points=int(self.figures[FIGURE_WARM_STARTED]),
                           block_manifolds=int(self.figures[FIGURE_BLOCK_MANIFOLDS]))

    def contacts(self) -> list:
        """The last step's manifolds as ``(i, j, Contact)``, as the readable step gives them."""
        ints, floats, n = self.point_ints, self.point_floats, self.body_count
        out, p = [], 0
        while p < len(ints):
            key = int(ints[p, POINT_PAIR])
            count = 2 if p + 1 < len(ints) and ints[p + 1, POINT_PAIR] == key else 1
            rows = floats[p:p + count]
            depths = np.maximum(-rows[:, POINT_SEPARATION], 0.0)
            ids = []
            for code in ints[p:p + count, POINT_FEATURE].tolist():
                ids.append(("circle", "circle") if code == CIRCLE_FEATURE else feature_id(code))
            out.append((key // n, key % n, Contact(rows[0, POINT_NX:POINT_NY + 1], depths.max(),
                                                   rows[:, POINT_X:POINT_Y + 1], depths, tuple(ids),
                                                   rows[:, POINT_SEPARATION])))
            p += count
        return out

    def contact_impulses(self) -> list[tuple]:
        """``(i, j, point, normal_impulse, tangent_impulse)`` per contact point of the last step."""
        ints, floats = self.point_ints, self.point_floats
        return list(zip(ints[:, POINT_A].tolist(), ints[:, POINT_B].tolist(),
                        zip(floats[:, POINT_X].tolist(), floats[:, POINT_Y].tolist()),
                        floats[:, POINT_NORMAL_IMPULSE].tolist(), floats[:, POINT_TANGENT_IMPULSE].tolist()))


# Cached machine code compiled from older sources is forgotten (solutions.compiled_cache).
forget_stale_machine_code(globals())
