"""One contact point, visited once by sequential impulses: its normal impulse and its
friction impulse, each with accumulated clamping.

The solver kernel (:func:`solutions.solver.kernel.solve_constraints`) sweeps over the
contact points of all manifolds again and again; at each point it calls the two
functions below, which are the heart of sequential impulses (Erin Catto's box2d-lite,
Box2D, Chipmunk).  A visit gives the point the impulse that brings its relative
velocity along one direction where it should be, with **accumulated clamping**: what
is kept within bounds is the *total* impulse of this step (a contact pushes, never
pulls; friction stays within the Coulomb bound of the normal total found so far), so
a later visit may take back part of what an earlier one applied, but never more.

Conventions: SI units; ``n`` is a unit vector from body A to body B; ``rn = r x n``
and ``rt = r x t`` for the lever arm ``r`` from a body's centre of mass to the point
(2D cross product ``r x v = r_x v_y - r_y v_x``); a velocity is ``(vx, vy, w)`` (m/s,
rad/s); impulses in N s.
"""
from __future__ import annotations

import math
from typing import NamedTuple


class ContactPoint(NamedTuple):
    """What the solver knows of one contact point between bodies A and B (SI units).

    ``nx, ny``: the unit normal from A to B; ``rn_a, rn_b``: ``r x n`` for A and B
    (m); ``rt_a, rt_b``: ``r x t`` with ``t = (ny, -nx)`` (m); ``ima, imb``: inverse
    masses (1/kg, 0 for a static body); ``iia, iib``: inverse moments of inertia
    (1/(kg m^2)); ``mass_normal``, ``mass_tangent``: the effective masses ``1 / K``
    along ``n`` and ``t`` (kg; 0 when nothing can move); ``friction``: the pair's
    coefficient mu (>= 0, finite); ``lower``: the lowest accumulated normal impulse
    allowed (N s; 0 for a contact, ``-inf`` for a joint, which may pull).
    """

    nx: float
    ny: float
    rn_a: float
    rn_b: float
    rt_a: float
    rt_b: float
    ima: float
    imb: float
    iia: float
    iib: float
    mass_normal: float
    mass_tangent: float
    friction: float
    lower: float = 0.0


def apply_normal_impulse(velocity_a, velocity_b, point: ContactPoint, normal_total: float, target: float = 0.0,
                         mass_scale: float = 1.0, impulse_scale: float = 0.0):
    """One visit of a contact point's normal row, with accumulated clamping.

    Contract: a rigid visit (``mass_scale = 1``, ``impulse_scale = 0``) leaves the
    normal velocity of B's material point relative to A's at the point (``v_n``, m/s,
    > 0 separating) equal to ``target``, unless that would take the accumulated
    normal impulse below ``point.lower``: then the total stops at ``lower`` and
    ``v_n`` stays short of the target.  The impulse given is along ``n`` to B and its
    opposite to A, through the point (so it turns the bodies too); total momentum is
    kept.  A soft visit (Box2D v3's soft constraint) goes only the fraction
    ``mass_scale`` of the way to the target and also gives back the fraction
    ``impulse_scale`` of the total so far, before the clamp.

    Parameters
    ----------
    velocity_a, velocity_b : (float, float, float)
        ``(vx, vy, w)`` of bodies A and B (m/s, rad/s).
    point : ContactPoint
        Or any sequence of its 14 fields in that order (unpack it: ``nx, ny, rn_a, ...
        = point``).
    normal_total : float
        The accumulated normal impulse of this point so far in this step (N s).
    target : float
        The wanted separating normal velocity (m/s): 0 to stop, a bounce, or a push
        out of an overlap (:func:`~solutions.solver.contact_sweeps.contact_target`).
    mass_scale, impulse_scale : float
        Soft-constraint scales (dimensionless); 1 and 0 for a rigid contact.

    Returns
    -------
    ((float, float, float), (float, float, float), float)
        The new velocities of A and B, and the new accumulated normal impulse (N s).

    Examples
    --------
    A 1 kg disc (A static below it) falling at 2 m/s onto one point straight below
    its centre is stopped by an impulse of 2 N s:

    >>> point = ContactPoint(0.0, 1.0, 0.0, 0.0, 0.0, 0.5, 0.0, 1.0, 0.0, 2.0, 1.0, 1 / 1.5, 0.3)
    >>> apply_normal_impulse((0.0, 0.0, 0.0), (0.0, -2.0, 0.0), point, 0.0)
    ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 2.0)

    A later visit that finds the disc moving away at 3 m/s would take 3 N s back to stop
    it, but the total holds only 2 N s and is clamped at 0 (a contact never pulls): the
    disc keeps 1 m/s of its separating speed.

    >>> apply_normal_impulse((0.0, 0.0, 0.0), (0.0, 3.0, 0.0), point, 2.0)
    ((0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 0.0)

    A joint row (``lower = -inf``) may pull: it takes the 3 N s back and stops the disc.

    >>> apply_normal_impulse((0.0, 0.0, 0.0), (0.0, 3.0, 0.0), point._replace(lower=-math.inf), 2.0)
    ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), -1.0)

    Hit off its centre (lever arm 0.5 m across the normal: ``rn_b = -0.5``), the disc
    also turns, and less impulse stops the point (``mass_normal = 1 / (1 + 2 * 0.25)``):

    >>> off = ContactPoint(0.0, 1.0, 0.0, -0.5, 0.0, 0.5, 0.0, 1.0, 0.0, 2.0, 1 / 1.5, 1 / 1.5, 0.3)
    >>> _, velocity_b, total = apply_normal_impulse((0.0, 0.0, 0.0), (0.0, -2.0, 0.0), off, 0.0)
    >>> [round(x, 12) for x in velocity_b], round(total, 12)
    ([0.0, -0.666666666667, -1.333333333333], 1.333333333333)
    """
    ### BEGIN SOLUTION
    vxa, vya, wa = velocity_a
    vxb, vyb, wb = velocity_b
    nx, ny, rn_a, rn_b, _, _, ima, imb, iia, iib, mass_normal, _, _, lower = point
    normal_velocity = (vxb - vxa) * nx + (vyb - vya) * ny + wb * rn_b - wa * rn_a
    change = mass_normal * mass_scale * (target - normal_velocity) - impulse_scale * normal_total
    new_total = max(normal_total + change, lower)
    change = new_total - normal_total
    return ((vxa - ima * change * nx, vya - ima * change * ny, wa - iia * rn_a * change),
            (vxb + imb * change * nx, vyb + imb * change * ny, wb + iib * rn_b * change),
            new_total)
    ### END SOLUTION


def apply_friction_impulse(velocity_a, velocity_b, point: ContactPoint, normal_total: float, tangent_total: float):
    """One visit of a contact point's friction row, with accumulated clamping.

    Contract: the visit stops the sliding of B's material point relative to A's along
    the tangent ``t = (n_y, -n_x)`` (m/s), unless that would take the accumulated
    friction impulse out of the Coulomb bound, ``mu`` times the accumulated normal
    impulse ``normal_total``, either way: then the total stops at the bound and the
    point keeps sliding, slower.  The impulse is along ``t`` to B and its opposite to
    A, through the point; total momentum is kept.

    Parameters
    ----------
    velocity_a, velocity_b : (float, float, float)
        ``(vx, vy, w)`` of bodies A and B (m/s, rad/s).
    point : ContactPoint
        Or any sequence of its 14 fields in that order.
    normal_total : float
        The accumulated normal impulse of this point (N s, >= 0).
    tangent_total : float
        The accumulated friction impulse of this point so far in this step (N s).

    Returns
    -------
    ((float, float, float), (float, float, float), float)
        The new velocities of A and B, and the new accumulated friction impulse (N s).

    Examples
    --------
    A 1 kg box that cannot turn (1/I = 0) sliding at 3 m/s along x on static ground
    (n = (0, 1), so t = (1, 0)), mu = 0.5, pressed by a normal total of 2 N s: the
    friction total stops at mu P = 1 N s, and the box slows to 2 m/s.

    >>> point = ContactPoint(0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.5)
    >>> apply_friction_impulse((0.0, 0.0, 0.0), (3.0, 0.0, 0.0), point, 2.0, 0.0)
    ((0.0, 0.0, 0.0), (2.0, 0.0, 0.0), -1.0)

    Pressed by 10 N s, the bound is 5 N s: 3 N s stop it.  A later visit that finds it
    sliding back at 1 m/s may take back 1 N s of them.

    >>> apply_friction_impulse((0.0, 0.0, 0.0), (3.0, 0.0, 0.0), point, 10.0, 0.0)
    ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), -3.0)
    >>> apply_friction_impulse((0.0, 0.0, 0.0), (-1.0, 0.0, 0.0), point, 10.0, -3.0)
    ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), -2.0)
    """
    ### BEGIN SOLUTION
    vxa, vya, wa = velocity_a
    vxb, vyb, wb = velocity_b
    nx, ny, _, _, rt_a, rt_b, ima, imb, iia, iib, _, mass_tangent, friction, _ = point
    tangent_velocity = (vxb - vxa) * ny - (vyb - vya) * nx + wb * rt_b - wa * rt_a
    change = -mass_tangent * tangent_velocity
    bound = friction * normal_total
    new_total = min(max(tangent_total + change, -bound), bound)
    change = new_total - tangent_total
    return ((vxa - ima * change * ny, vya + ima * change * nx, wa - iia * rt_a * change),
            (vxb + imb * change * ny, vyb - imb * change * nx, wb + iib * rt_b * change),
            new_total)
    ### END SOLUTION
