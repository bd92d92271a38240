"""One contact point, visited once by sequential impulses: its normal impulse and its
friction impulse, each with accumulated clamping.

The solver kernel (:func:`solutions.solver.kernel.solve_constraints`) sweeps over the
contact points of all manifolds again and again; at each point it calls the two
functions below, which are the heart of sequential impulses (Erin Catto's box2d-lite,
Box2D, Chipmunk):

1. the velocity of B's material point relative to A's, along the normal ``n``;
2. the impulse change that would bring it to the wanted ``target``, through the
   point's effective mass ``m_n = 1 / K_n``;
3. **accumulated clamping**: the *total* impulse of this step stays ``>= 0`` (a
   contact pushes, never pulls), so a later visit may take back part of what an
   earlier one applied, but never more;
4. the change is applied to B along ``n`` and the opposite to A, with its torques;
5. friction along ``t = (n_y, -n_x)`` the same way, its total kept within the
   Coulomb bound ``[-mu P, mu P]`` of the normal total ``P`` (so friction is weighed
   with the normal impulse found so far).

Conventions: SI units; ``n`` is a unit vector from body A to body B; ``rn = r x n``
and ``rt = r x t`` for the lever arm ``r`` from a body's centre of mass to the point
(2D cross product ``r x v = r_x v_y - r_y v_x``); a velocity is ``(vx, vy, w)`` (m/s,
rad/s); impulses in N s.
"""
from __future__ import annotations

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

    The normal velocity of B's material point relative to A's is ``v_n = (v_B + w_B x
    r_B - v_A - w_A x r_A) . n = (vx_B - vx_A) n_x + (vy_B - vy_A) n_y + w_B rn_B -
    w_A rn_A``.  The impulse change is ``dP = m_n mass_scale (target - v_n) -
    impulse_scale P`` (rigid: ``mass_scale = 1``, ``impulse_scale = 0``, so that
    ``v_n`` becomes ``target``); the accumulated impulse becomes ``max(P + dP,
    lower)`` and only the clamped change is applied: ``+change n`` to B, ``-change n``
    to A, with the angular parts ``w_B += iib rn_B change`` and ``w_A -= iia rn_A
    change``.

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
        The wanted separating normal velocity (m/s): 0 to stop, ``-e v_n0`` for
        restitution, a bias to push an overlap apart.
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

    The tangent velocity of B's material point relative to A's, along ``t = (n_y,
    -n_x)``, is ``v_t = (vx_B - vx_A) n_y - (vy_B - vy_A) n_x + w_B rt_B - w_A rt_A``.
    The change that would stop the sliding is ``dT = -m_t v_t``; the accumulated
    friction impulse becomes ``T + dT`` clamped to ``[-mu P, mu P]`` (Coulomb, with
    ``P`` the accumulated normal impulse so far), and only the clamped change is
    applied: ``+change t`` to B, ``-change t`` to A, with ``w_B += iib rt_B change``
    and ``w_A -= iia rt_A change``.

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
