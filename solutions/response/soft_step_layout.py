"""The packing of the compiled soft step's arrays (:mod:`solutions.response.soft_step_numba`).
The compiled step takes the bodies' state and two more arrays, ``ints`` and ``floats``
(each array argument costs a call about 50 ns), each a row of sections: the settings
(``PARAMETER_*``, ``SWITCH_*``), the step's figures (``FIGURE_*``), the joints'
constants (``JOINT_*``) and impulses, two buffers of contact points (``POINT_*``: the
last step's, its warm start, and this step's), and a work space from which the step
takes each block in turn (:func:`take`).  :func:`layout` says where each section
starts, :func:`sections` cuts them, :func:`work_sizes` counts the work space.
"""
from __future__ import annotations

### INSTRUCTOR ONLY: not in the student edition (the compiled soft step's arrays).

import numpy as np
from numba import njit

from ..narrowphase.box_pairs_numba import CLIPPING_FLOATS, CLIPPING_INTS, MANIFOLD_FLOATS, MANIFOLD_INTS
from ..compiled_cache import forget_stale_machine_code
from ..compiled_views import contiguous_view

#: Columns of the contact points' integer array: pair key ``i * n + j``, feature id, bodies.
POINT_PAIR, POINT_FEATURE, POINT_A, POINT_B = range(4)

#: Columns of their float array: point (m), normal, signed separation at the start of the
#: step (m), accumulated normal and tangent impulses (N s).
POINT_X, POINT_Y, POINT_NX, POINT_NY, POINT_SEPARATION, POINT_NORMAL_IMPULSE, POINT_TANGENT_IMPULSE = range(7)

#: The step's figures, an integer array it reads and writes: which of the two point
#: buffers holds the last step's points (0 or 1) and how many; then what this step
#: counted: candidate pairs, manifolds, warm-started points, manifolds solved as blocks.
(FIGURE_MEMORY, FIGURE_POINTS, FIGURE_CANDIDATE_PAIRS, FIGURE_MANIFOLDS, FIGURE_WARM_STARTED,
 FIGURE_BLOCK_MANIFOLDS) = range(6)
FIGURE_COUNT = 6

#: Rows of the joints' integer array: bodies a and b of each joint, then the joined pairs'
#: sorted keys ``i * n + j`` (as many as distinct pairs), padded with ``NO_PAIR``.
JOINT_A, JOINT_B, JOINT_PAIRS = range(3)
NO_PAIR = np.iinfo(np.int64).max

#: Columns of the joints' constant float array (one row per joint): anchors in the
#: bodies' frames (m), rest length (m), spring frequency (Hz, 0: a rod), damping ratio.
(JOINT_ANCHOR_AX, JOINT_ANCHOR_AY, JOINT_ANCHOR_BX, JOINT_ANCHOR_BY, JOINT_LENGTH, JOINT_FREQUENCY,
 JOINT_DAMPING) = range(7)

#: Positions in the step's float parameters: the ratio of this step's h to the last
#: one's, h (s), gravity (m/s^2), the largest push (m/s), the restitution threshold
#: (m/s), the warm start's match distance (m), the speculative margin (m), then the
#: (bias rate, mass scale, impulse scale) of the soft contacts, of the contacts with a
#: static body and of the joints.  (One section of ``floats``: see
#: :data:`HEADER_COUNT`.)
(PARAMETER_DT_RATIO, PARAMETER_H, PARAMETER_GRAVITY_X, PARAMETER_GRAVITY_Y, PARAMETER_MAX_PUSH,
 PARAMETER_RESTITUTION_THRESHOLD, PARAMETER_MATCH_DISTANCE, PARAMETER_MARGIN) = range(8)
PARAMETER_SOFT, PARAMETER_STIFF, PARAMETER_JOINT_SOFTNESS = 8, 11, 14
PARAMETER_COUNT = 17

#: Positions in the step's integer switches: sub-steps, sweeps per pass, relax,
#: friction, warm starting, block solver, colour order, the two matmul roundings
#: (:func:`~solutions.narrowphase.box_pairs_numba.matmul_rounding`), discs (else
#: boxes), rotation.
(SWITCH_SUBSTEPS, SWITCH_ITERATIONS, SWITCH_RELAX, SWITCH_FRICTION, SWITCH_WARM_START, SWITCH_BLOCK_SOLVER,
 SWITCH_COLOURS, SWITCH_CORNER_ROUNDING, SWITCH_INCIDENT_ROUNDING, SWITCH_CIRCLES, SWITCH_ROTATION) = range(11)
SWITCH_COUNT = 11

#: The step takes two arrays besides the bodies' state (each array argument costs a
#: call about 50 ns): ``ints`` and ``floats``, each a row of sections (:func:`layout`).
#: ``ints`` starts with a header: the number of joints, and the number of candidate
#: pairs the buffers are made for.
HEADER_JOINTS, HEADER_CAPACITY = range(2)
HEADER_COUNT = 2


@njit(cache=True)
def layout(bodies, joints, capacity):
    """Where each section of the step's ``ints`` and ``floats`` starts, and their sizes,
    for ``bodies`` bodies, ``joints`` joints and buffers for ``capacity`` candidate pairs:

    - ``ints``: the header, ``switches`` (``SWITCH_*``), ``figures`` (``FIGURE_*``), the
      joints' integers (3, joints), the two point buffers (2, 2 * capacity, 4), the work space;
    - ``floats``: ``parameters`` (``PARAMETER_*``), the joints' constants (joints, 7),
      their impulses (joints), the two point buffers (2, 2 * capacity, 7), the work space.

    (The bodies' masses, materials and extents are not here: the step reads them from
    the world's :class:`~solutions.body_state.BodyState` every step.)
    """
    work_ints, work_floats = work_sizes(bodies, joints, capacity)
    switches = HEADER_COUNT
    figures = switches + SWITCH_COUNT
    joint_ints = figures + FIGURE_COUNT
    memory_ints = joint_ints + 3 * joints
    work = memory_ints + 2 * 2 * capacity * 4
    joint_floats = PARAMETER_COUNT
    impulses = joint_floats + 7 * joints
    memory_floats = impulses + joints
    work_space = memory_floats + 2 * 2 * capacity * 7
    return (switches, figures, joint_ints, memory_ints, work, work + work_ints,
            joint_floats, impulses, memory_floats, work_space, work_space + work_floats)


@njit(cache=True)
def work_sizes(bodies, joints, pairs):
    """Integers and floats of the step's work space (``work_ints``, ``work_floats``) for
    ``bodies`` bodies, ``joints`` joints and up to ``pairs`` candidate pairs (up to
    ``pairs`` manifolds and ``2 * pairs`` points; the last step's points are up to
    ``2 * pairs`` too).  Each block is counted where :func:`~solutions.response.soft_step_numba._step_on_pairs` takes it."""
    ints = (2 * bodies + 6 * pairs + 1                           # a few bodies' candidate pairs
            + 2 * pairs + MANIFOLD_INTS * pairs + CLIPPING_INTS  # features, manifolds, clipping
            + 5 * pairs + 6 * 2 * pairs + 2 * bodies             # groups and points in pair order, body flags
            + 3 * pairs + bodies + 2                             # the sweep order
            + 5 * pairs + bodies + 6 * joints                    # the kernel's groups, static bodies, joints
            + 2 * pairs + 2 * pairs)                             # the warm start's matching
    floats = (32 * bodies + MANIFOLD_FLOATS * pairs + CLIPPING_FLOATS    # faces, AABBs, sweep, bodies; manifolds
              + 27 * 2 * pairs + 9 * pairs + (8 + 6 + 5) * 2 * pairs     # points, groups, rows
              + 25 * joints)
    return ints, floats


@njit(cache=True, inline="always")
def take(work, at, size):
    """``size`` values of the work space ``work`` from ``at``, and where the next block starts."""
    return work[at:at + size], at + size


@njit(cache=True, inline="always")
def sections(n, ints, floats):
    """The sections of ``ints`` and ``floats`` (:func:`layout`) as arrays: switches,
    figures, joint integers, point buffers, work space; parameters, joint floats, joint
    impulses, point buffers, work space."""
    joints, capacity = ints[HEADER_JOINTS], ints[HEADER_CAPACITY]
    (switches_at, figures_at, joint_ints_at, memory_ints_at, work_ints_at, ints_end, joint_floats_at,
     impulses_at, memory_floats_at, work_floats_at, floats_end) = layout(n, joints, capacity)
    return (ints[switches_at:figures_at], ints[figures_at:joint_ints_at],
            contiguous_view(ints[joint_ints_at:memory_ints_at], (3, joints)),
            contiguous_view(ints[memory_ints_at:work_ints_at], (2, 2 * capacity, 4)), ints[work_ints_at:ints_end],
            floats[:joint_floats_at], contiguous_view(floats[joint_floats_at:impulses_at], (joints, 7)),
            floats[impulses_at:memory_floats_at],
            contiguous_view(floats[memory_floats_at:work_floats_at], (2, 2 * capacity, 7)),
            floats[work_floats_at:floats_end])


# Cached machine code compiled from older sources is forgotten (solutions.compiled_cache).
forget_stale_machine_code(globals())
