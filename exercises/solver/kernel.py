# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/solver/kernel.py on the instructor's side.
"""The solver kernel: sequential impulses over constraint rows (the readable version).

One function, :func:`solve_constraints`, solves every velocity constraint of the
engine: contact points (non-penetration and friction) and distance joints, rigid or
soft, in the plain step and in the soft step.  What differs between those uses is
only its parameters (:mod:`exercises.solver.constraint_rows` explains the rows):

==========================  ==========================  ============================
use                         ``target`` (m/s)            ``mass_scale``, ``impulse_scale``
==========================  ==========================  ============================
rigid contact (plain step)  restitution or Baumgarte    1, 0
split-impulse push          Baumgarte bias (pseudo v)   1, 0
soft contact (soft step)    spring push, or ``-s / h``  from :func:`soft_coefficients`
relax pass                  0, or ``-s / h``            1, 0
restitution pass            ``-e v_n``                  1 on bouncing rows, else 0, 0
distance joint              ``-bias``                   rigid or spring
==========================  ==========================  ============================

One visit of a row is the solver exercise's
:func:`~exercises.solver.contact_point.apply_normal_impulse` (its accumulated impulse
kept in ``[lower, inf)``) and of its friction
:func:`~exercises.solver.contact_point.apply_friction_impulse` (kept within the
Coulomb bound).  Impulses are given to B along ``n`` (or ``t = (n_y, -n_x)``) and the
opposite to A, with their torques.

Order within a group: with ``friction_first`` (Box2D v2: normal impulses have the last
word), friction rows, then normal rows; else (Box2D v3) the normal rows and then
friction.  (box2d-lite visits each point's normal and then its friction; with
``accumulate=False`` the kernel does that.)  A two-point group marked ``block`` solves its normal rows together
as one 2x2 complementarity problem (:func:`block_normal_impulses`).  With
``accumulate=False`` (a teaching switch: the classic bug of clamping each increment
instead of the total) each increment is clamped, and each point's friction follows
its own normal, bounded by that sweep's normal increment.

``solver/kernel_numba.py`` of the instructor's edition is the same loop compiled by numba; the two agree
to rounding (tested to 1e-12).  SI units.
"""
from __future__ import annotations

import math

import numpy as np

from .constraint_rows import ConstraintRows
from .contact_point import ContactPoint, apply_friction_impulse, apply_normal_impulse


def block_normal_impulses(k11: float, k12: float, k22: float, b1: float, b2: float) -> tuple[float, float]:
    """The 2x2 mixed LCP of a two-point manifold, by enumerating its four cases.

    Find impulses ``x = (x1, x2) >= 0`` (N s) such that the normal velocities after
    them, ``v = K x + b`` (m/s), are ``>= 0`` and ``x_i v_i = 0`` (a point pushes only
    while it touches).  ``b`` holds the normal velocities the points would have
    without the manifold's normal impulses (the solver takes the accumulated ones
    back out: ``b = v - K x_old``), minus their targets.  The cases, tried in Box2D's
    order (``b2ContactSolver::SolveVelocityConstraints``):

    1. both points push: ``x = -K^-1 b``, accepted if ``x >= 0``;
    2. only point 1: ``x1 = -b1 / k11``, ``x2 = 0``, accepted if ``x1 >= 0`` and ``v2 >= 0``;
    3. only point 2: the same with the roles swapped;
    4. neither: ``x = 0``, accepted if ``b >= 0``.

    A positive definite ``K`` always has exactly one case that fits; if rounding
    leaves none, ``(nan, nan)`` is returned and the caller keeps its impulses.

    Examples
    --------
    A 1 kg, 1 m box resting flat on static ground (points at x = -0.5 and +0.5,
    inertia 1/6 kg m^2) after one step of gravity at 60 Hz shares its weight equally:

    >>> k11 = k22 = 1.0 + 6.0 * 0.25; k12 = 1.0 - 6.0 * 0.25
    >>> [round(x, 12) for x in block_normal_impulses(k11, k12, k22, -9.81 / 60, -9.81 / 60)]
    [0.08175, 0.08175]
    """
    det = k11 * k22 - k12 * k12
    x1 = (k12 * b2 - k22 * b1) / det             # case 1: -K^-1 b
    x2 = (k12 * b1 - k11 * b2) / det
    if x1 >= 0.0 and x2 >= 0.0:
        return x1, x2
    x1 = -b1 / k11                                # case 2: v1 = 0, x2 = 0
    if x1 >= 0.0 and k12 * x1 + b2 >= 0.0:
        return x1, 0.0
    x2 = -b2 / k22                                # case 3: v2 = 0, x1 = 0
    if x2 >= 0.0 and k12 * x2 + b1 >= 0.0:
        return 0.0, x2
    if b1 >= 0.0 and b2 >= 0.0:                   # case 4: both separate
        return 0.0, 0.0
    return math.nan, math.nan


def solve_constraints(velocity: np.ndarray, rows: ConstraintRows, iterations: int, normal_total: np.ndarray,
                      tangent_total: np.ndarray, target: np.ndarray, mass_scale: np.ndarray,
                      impulse_scale: np.ndarray, accumulate: bool = True, friction_first: bool = False,
                      use_friction: bool = True, use_block: bool = True) -> None:
    """``iterations`` sweeps of sequential impulses over ``rows`` (module docstring).

    Parameters
    ----------
    velocity : numpy.ndarray, shape (n, 3)
        Rows ``(vx, vy, w)`` of the bodies (m/s, rad/s); updated in place.
    rows : ConstraintRows
        Groups and rows in sweep order.
    iterations : int
        Sweeps over all groups.
    normal_total, tangent_total : numpy.ndarray, shape (m,)
        Accumulated impulses per row (N s), in sweep order; updated in place.
    target, mass_scale, impulse_scale : numpy.ndarray, shape (m,)
        Per row: wanted separating velocity (m/s) and the soft-constraint scales.
    accumulate : bool
        Clamp the accumulated impulses (True) or each increment (False).
    friction_first : bool
        Friction rows before the normal rows of each group (Box2D v2) or after (v3).
    use_friction, use_block : bool
        Solve the friction rows; use the 2x2 block solve where ``rows.block``.

    Examples
    --------
    A static ground (body 0) and a 1 kg disc of radius 0.5 m (body 1) falling at
    1 m/s, touching at one point straight below its centre: one rigid visit stops it.

    >>> rows = ConstraintRows(*[np.array([x]) for x in (0, 1, 0.0, 1.0, 0.0, 1.0, 0.0, 2.0, 0, 1, False,
    ...                                                 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5, 1.0, 1 / 1.5, 0.0, 0.0)])
    >>> velocity = np.array([[0.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
    >>> normal = np.zeros(1)
    >>> solve_constraints(velocity, rows, 1, normal, np.zeros(1), np.zeros(1), np.ones(1), np.zeros(1))
    >>> velocity.tolist(), normal.tolist()
    ([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]], [1.0])
    """
    vx, vy, w = velocity.T.tolist()
    a_of, b_of, nx_of, ny_of = rows.a.tolist(), rows.b.tolist(), rows.nx.tolist(), rows.ny.tolist()
    ima_of, imb_of, iia_of, iib_of = rows.ima.tolist(), rows.imb.tolist(), rows.iia.tolist(), rows.iib.tolist()
    first_of, count_of, block_of = rows.first.tolist(), rows.count.tolist(), rows.block.tolist()
    k11_of, k12_of, k22_of = rows.k11.tolist(), rows.k12.tolist(), rows.k22.tolist()
    rn_a, rn_b, rt_a, rt_b = rows.rn_a.tolist(), rows.rn_b.tolist(), rows.rt_a.tolist(), rows.rt_b.tolist()
    mass_normal, mass_tangent = rows.mass_normal.tolist(), rows.mass_tangent.tolist()
    mu_of, lower_of = rows.friction.tolist(), rows.lower.tolist()
    normal, tangent = normal_total.tolist(), tangent_total.tolist()
    target, mass_scale, impulse_scale = target.tolist(), mass_scale.tolist(), impulse_scale.tolist()
    normal_change = [0.0] * len(normal)   # this sweep's normal increments (friction bound without accumulation)
    points: list[ContactPoint | None] = [None] * len(normal)   # each row seen as one contact point
    for g in range(len(first_of)):
        for k in range(first_of[g], first_of[g] + count_of[g]):
            points[k] = ContactPoint(nx_of[g], ny_of[g], rn_a[k], rn_b[k], rt_a[k], rt_b[k], ima_of[g], imb_of[g],
                                     iia_of[g], iib_of[g], mass_normal[k], mass_tangent[k], mu_of[k], lower_of[k])

    # One row's friction visit (defined once, not once per group and sweep).
    def friction(k, vxa, vya, wa, vxb, vyb, wb):
        """Row k's tangent impulse along t = (ny, -nx), within the Coulomb bound."""
        if not use_friction or mu_of[k] == 0.0:
            return vxa, vya, wa, vxb, vyb, wb
        if accumulate:
            (vxa, vya, wa), (vxb, vyb, wb), tangent[k] = apply_friction_impulse(
                (vxa, vya, wa), (vxb, vyb, wb), points[k], normal[k], tangent[k])
            return vxa, vya, wa, vxb, vyb, wb
        # Clamped increments: a visit from a total of 0 bounded by this sweep's normal
        # increment (not the total), its result added to the total.
        (vxa, vya, wa), (vxb, vyb, wb), change = apply_friction_impulse(
            (vxa, vya, wa), (vxb, vyb, wb), points[k], normal_change[k], 0.0)
        tangent[k] += change
        return vxa, vya, wa, vxb, vyb, wb

    for _ in range(iterations):
        for g in range(len(first_of)):
            a, b, nx, ny = a_of[g], b_of[g], nx_of[g], ny_of[g]
            ima, imb, iia, iib = ima_of[g], imb_of[g], iia_of[g], iib_of[g]
            group = range(first_of[g], first_of[g] + count_of[g])
            block = use_block and block_of[g]
            # The two bodies' velocities stay in locals while the group is solved.
            vxa, vya, wa, vxb, vyb, wb = vx[a], vy[a], w[a], vx[b], vy[b], w[b]

            if friction_first:
                for k in group:
                    vxa, vya, wa, vxb, vyb, wb = friction(k, vxa, vya, wa, vxb, vyb, wb)
            if block:
                # Both normal impulses at once: b = v - target - K x_old.
                k1, k2 = group
                k11, k12, k22 = k11_of[g], k12_of[g], k22_of[g]
                along = (vxb - vxa) * nx + (vyb - vya) * ny
                old1, old2 = (normal[k1], normal[k2]) if accumulate else (0.0, 0.0)
                b1 = along + wb * rn_b[k1] - wa * rn_a[k1] - target[k1] - (k11 * old1 + k12 * old2)
                b2 = along + wb * rn_b[k2] - wa * rn_a[k2] - target[k2] - (k12 * old1 + k22 * old2)
                x1, x2 = block_normal_impulses(k11, k12, k22, b1, b2)
                if x1 != x1:                      # nan: no case fits (rounding); keep the impulses
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
                for k in group:
                    old = normal[k]
                    # The exercise's visit (solutions/solver/contact_point.py).  Clamped
                    # increments (the classic mistake, kept as a switch) are the same visit
                    # with the total's floor raised to the old total plus ``lower``.
                    point = points[k] if accumulate else points[k]._replace(lower=old + lower_of[k])
                    (vxa, vya, wa), (vxb, vyb, wb), normal[k] = apply_normal_impulse(
                        (vxa, vya, wa), (vxb, vyb, wb), point, old, target[k], mass_scale[k], impulse_scale[k])
                    normal_change[k] = normal[k] - old
                    if not accumulate and not friction_first:   # each point's friction follows its normal
                        vxa, vya, wa, vxb, vyb, wb = friction(k, vxa, vya, wa, vxb, vyb, wb)
            if not friction_first and (accumulate or block):
                for k in group:
                    vxa, vya, wa, vxb, vyb, wb = friction(k, vxa, vya, wa, vxb, vyb, wb)
            vx[a], vy[a], w[a], vx[b], vy[b], w[b] = vxa, vya, wa, vxb, vyb, wb
    normal_total[:] = normal
    tangent_total[:] = tangent
    velocity[:] = np.array([vx, vy, w], dtype=float).T.reshape(-1, 3)


def kernel(backend: str = "python"):
    """:func:`solve_constraints` of the readable loop (``"python"``) or of its compiled
    twin (``"numba"``, ``solver/kernel_numba.py`` of the instructor's edition, imported only then)."""
    if backend == "python":
        return solve_constraints
    if backend == "numba":
        from ..twins import require_twins

        require_twins("backend='numba'")
        from .kernel_numba import solve_constraints as compiled

        return compiled
    raise ValueError(f"backend must be 'python' or 'numba', got {backend!r}")
