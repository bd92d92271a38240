"""The contact solver a student writes: the prestep of a contact point and the sweeps
with warm starting (box2d-lite's ``Arbiter::PreStep`` and ``Arbiter::ApplyImpulse``
with the loop of ``World::Step`` around them).

Three functions, called by :class:`solutions.response.sweep_solver.SweepContactSolver`
on every step, one after the other:

1. :func:`prestep_point`: what a contact point's rows need and that does not change
   during the sweeps (its lever arms and effective masses), as a
   :class:`~solutions.solver.contact_point.ContactPoint`;
2. :func:`contact_target`: the separating normal velocity the point's normal row aims
   at: a bounce for a fast impact, a push for an overlap, else 0;
3. :func:`sweep_contacts`: the warm start (last step's impulses given again) and the
   Gauss-Seidel sweeps over the manifolds, whose visits are
   :func:`~solutions.solver.contact_point.apply_friction_impulse` and
   :func:`~solutions.solver.contact_point.apply_normal_impulse`.

Conventions: SI units; the normal ``n`` is a unit vector from body A to body B and the
tangent is ``t = (n_y, -n_x)``; an impulse along ``n`` (or ``t``) is given to B and
its opposite to A; the 2D cross product is ``a x b = a_x b_y - a_y b_x``; a velocity
is ``(vx, vy, w)`` (m/s, rad/s); ``v_n < 0`` means the two bodies close at the point.
"""
from __future__ import annotations

from typing import NamedTuple

from .contact_point import ContactPoint, apply_friction_impulse, apply_normal_impulse


class ManifoldRows(NamedTuple):
    """One contact manifold as the sweeps see it (what :func:`sweep_contacts` takes).

    ``a``, ``b``: rows of the bodies in the velocity list (``n`` points from A to B);
    ``points``: its one or two :class:`ContactPoint` (from :func:`prestep_point`);
    ``targets``: the wanted separating velocity of each point (m/s, from
    :func:`contact_target`); ``normal_total``, ``tangent_total``: each point's
    accumulated impulses remembered from the last step (N s, 0 for a new point).
    """

    a: int
    b: int
    points: list
    targets: list
    normal_total: list
    tangent_total: list


def prestep_point(point, normal, centre_a, centre_b, ima: float, imb: float, iia: float, iib: float,
                  friction: float) -> ContactPoint:
    """The rows of one contact point between bodies A and B, ready for the sweeps.

    Parameters
    ----------
    point : (float, float)
        Where the bodies touch, in world coordinates (m).
    normal : (float, float)
        Unit normal from A to B.
    centre_a, centre_b : (float, float)
        The bodies' centres of mass (m).
    ima, imb : float
        Inverse masses (1/kg; 0 for a static body).
    iia, iib : float
        Inverse moments of inertia about the centres of mass (1/(kg m^2); 0 for a body
        that cannot turn).
    friction : float
        The pair's coefficient mu (>= 0).

    Returns
    -------
    ContactPoint
        ``nx, ny`` the normal; ``rn_a, rn_b``, ``rt_a, rt_b`` the lever arms of A and B
        crossed with ``n`` and with ``t`` (m); the four inverse masses and inertias as
        given; ``mass_normal``, ``mass_tangent``: the effective masses (kg) along ``n``
        and ``t``, that is the impulse that changes the point's relative velocity along
        that direction by 1 m/s (0 when no impulse can change it: two static bodies);
        ``friction`` as given; ``lower = 0`` (a contact only pushes).

    Examples
    --------
    A 1 kg disc of radius 0.5 m (1/I = 8) on static ground, touching straight below its
    centre: along the normal it answers like a point mass of 1 kg; along the tangent the
    impulse also spins it, so 1/3 kg of impulse per m/s is enough (1/m + r^2/I = 3):

    >>> row = prestep_point((0.0, 0.0), (0.0, 1.0), (0.0, -0.5), (0.0, 0.5), 0.0, 1.0, 0.0, 8.0, 0.6)
    >>> row.rn_b, row.rt_b, row.mass_normal, round(row.mass_tangent, 12)
    (0.0, 0.5, 1.0, 0.333333333333)

    Two static bodies: nothing can move, both masses are 0.

    >>> prestep_point((0.0, 0.0), (1.0, 0.0), (-1.0, 0.0), (1.0, 0.0), 0.0, 0.0, 0.0, 0.0, 0.5).mass_normal
    0.0
    """
    ### BEGIN SOLUTION
    (px, py), (nx, ny) = point, normal
    rax, ray = px - centre_a[0], py - centre_a[1]
    rbx, rby = px - centre_b[0], py - centre_b[1]
    rn_a, rn_b = rax * ny - ray * nx, rbx * ny - rby * nx          # r x n
    rt_a, rt_b = -(rax * nx + ray * ny), -(rbx * nx + rby * ny)     # r x t, t = (ny, -nx)
    k_normal = ima + imb + iia * (rn_a * rn_a) + iib * (rn_b * rn_b)
    k_tangent = ima + imb + iia * (rt_a * rt_a) + iib * (rt_b * rt_b)
    return ContactPoint(nx, ny, rn_a, rn_b, rt_a, rt_b, ima, imb, iia, iib,
                        1.0 / k_normal if k_normal > 0.0 else 0.0, 1.0 / k_tangent if k_tangent > 0.0 else 0.0,
                        friction, 0.0)
    ### END SOLUTION


def contact_target(normal_velocity: float, restitution: float, depth: float, dt: float,
                   restitution_threshold: float = 1.0, bias_factor: float = 0.0, slop: float = 0.005,
                   max_push: float = 3.0) -> float:
    """The separating normal velocity a contact point's normal row aims at (m/s, >= 0).

    Two wishes, and the larger wins:

    - **a bounce**: a point that closes faster than ``restitution_threshold`` leaves at
      ``e`` times its closing speed; a slower one (a resting contact, which gravity
      makes close a little every step) does not bounce at all;
    - **a push** (Baumgarte): the speed that would remove the fraction ``bias_factor``
      of the overlap beyond ``slop`` in one step of ``dt``, never above ``max_push``.
      ``bias_factor = 0`` turns it off (another stage corrects positions).

    Parameters
    ----------
    normal_velocity : float
        The point's relative normal velocity before any impulse of this step (m/s,
        < 0 closing).
    restitution : float
        The pair's coefficient e in [0, 1].
    depth : float
        The overlap at the point (m, > 0 overlapping).
    dt : float
        The step (s), > 0.
    restitution_threshold, bias_factor, slop, max_push : float
        m/s, dimensionless, m, m/s.

    Examples
    --------
    A ball hitting the ground at 4 m/s with e = 0.5 leaves at 2 m/s; at 0.5 m/s it stays:

    >>> contact_target(-4.0, 0.5, 0.0, 1 / 60), contact_target(-0.5, 0.5, 0.0, 1 / 60)
    (2.0, 0.0)

    A box 0.105 m deep, pushed out by 20 % of 0.1 m in 0.01 s (2 m/s), or at most 1 m/s:

    >>> round(contact_target(0.0, 0.0, 0.105, 0.01, bias_factor=0.2), 12)
    2.0
    >>> contact_target(0.0, 0.0, 0.105, 0.01, bias_factor=0.2, max_push=1.0)
    1.0
    """
    ### BEGIN SOLUTION
    bounce = -restitution * normal_velocity if normal_velocity < -restitution_threshold else 0.0
    push = min(bias_factor / dt * max(depth - slop, 0.0), max_push)
    return max(bounce, push)
    ### END SOLUTION


def sweep_contacts(velocity, manifolds, iterations: int):
    """Warm start, then ``iterations`` sweeps of sequential impulses over ``manifolds``.

    Warm starting: each point's remembered impulses (``normal_total`` along ``n`` and
    ``tangent_total`` along ``t``, from the last step) are given to its bodies again
    before the first sweep, and the accumulated totals start from them.  A sweep visits
    the manifolds in the given order; in each manifold first every point's friction row
    (:func:`apply_friction_impulse`), then every point's normal row
    (:func:`apply_normal_impulse`, aiming at the point's target), each visit seeing the
    velocities the visits before it left.

    Parameters
    ----------
    velocity : list of (float, float, float)
        ``(vx, vy, w)`` of every body (m/s, rad/s); a static body has inverse mass and
        inertia 0 in every point, so it never changes.
    manifolds : list of ManifoldRows
        Or sequences of its six fields in that order.
    iterations : int
        Sweeps (>= 0).

    Returns
    -------
    (list, list, list)
        The velocities after the sweeps (one ``(vx, vy, w)`` per body), and per
        manifold the list of its points' accumulated normal impulses and the list of
        their accumulated friction impulses (N s).  The arguments are not changed.

    Examples
    --------
    A 1 kg disc (body 1, radius 0.5 m) falling at 2 m/s onto static ground (body 0),
    nothing remembered: one sweep stops it with 2 N s.

    >>> disc = prestep_point((0.0, 0.0), (0.0, 1.0), (0.0, -0.5), (0.0, 0.5), 0.0, 1.0, 0.0, 8.0, 0.5)
    >>> sweep_contacts([(0.0, 0.0, 0.0), (0.0, -2.0, 0.0)], [ManifoldRows(0, 1, [disc], [0.0], [0.0], [0.0])], 1)
    ([(0.0, 0.0, 0.0), (0.0, 0.0, 0.0)], [[2.0]], [[0.0]])

    The same disc remembering 2 N s: the warm start alone stops it, and with no sweep
    the total stays.

    >>> sweep_contacts([(0.0, 0.0, 0.0), (0.0, -2.0, 0.0)], [ManifoldRows(0, 1, [disc], [0.0], [2.0], [0.0])], 0)
    ([(0.0, 0.0, 0.0), (0.0, 0.0, 0.0)], [[2.0]], [[0.0]])
    """
    ### BEGIN SOLUTION
    velocity = [tuple(v) for v in velocity]
    normal = [list(m[4]) for m in manifolds]
    tangent = [list(m[5]) for m in manifolds]
    for m, (a, b, points, _, _, _) in enumerate(manifolds):
        for k, point in enumerate(points):
            nx, ny, rn_a, rn_b, rt_a, rt_b, ima, imb, iia, iib = point[:10]
            pn, pt = normal[m][k], tangent[m][k]
            px, py = pn * nx + pt * ny, pn * ny - pt * nx          # P = pn n + pt t
            vxa, vya, wa = velocity[a]
            vxb, vyb, wb = velocity[b]
            velocity[a] = (vxa - ima * px, vya - ima * py, wa - iia * (rn_a * pn + rt_a * pt))
            velocity[b] = (vxb + imb * px, vyb + imb * py, wb + iib * (rn_b * pn + rt_b * pt))
    for _ in range(iterations):
        for m, (a, b, points, targets, _, _) in enumerate(manifolds):
            for k, point in enumerate(points):
                velocity[a], velocity[b], tangent[m][k] = apply_friction_impulse(
                    velocity[a], velocity[b], point, normal[m][k], tangent[m][k])
            for k, point in enumerate(points):
                velocity[a], velocity[b], normal[m][k] = apply_normal_impulse(
                    velocity[a], velocity[b], point, normal[m][k], targets[k])
    return velocity, normal, tangent
    ### END SOLUTION
