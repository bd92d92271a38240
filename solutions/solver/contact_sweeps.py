"""The contact solver a student writes: the prestep of a contact point, the sweeps with
warm starting and the step around them (box2d-lite's ``Arbiter::PreStep`` and
``Arbiter::ApplyImpulse`` with its ``World::Step``).

Four functions, each calling the ones before it:

1. :func:`prestep_point`: what a contact point's rows need and that does not change
   during the sweeps (its lever arms and effective masses), as a
   :class:`~solutions.solver.contact_point.ContactPoint`;
2. :func:`contact_target`: the separating normal velocity the point's normal row aims
   at: a bounce for a fast impact, a push for an overlap, else 0;
3. :func:`sweep_contacts`: every point's target, from the velocities the sweeps start
   from; the warm start (last step's impulses given again); then the Gauss-Seidel
   sweeps over the manifolds, whose visits are
   :func:`~solutions.solver.contact_point.apply_friction_impulse` and
   :func:`~solutions.solver.contact_point.apply_normal_impulse`;
4. :func:`step_bodies`: one step of bodies whose contacts were found at the start of
   it: gravity, the prestep, the sweeps, the new positions.

:class:`solutions.response.sweep_solver.SweepContactSolver` calls the first and the
third on the engine's contacts; :class:`solutions.response.sweep_solver.SweepWorld`
steps a whole world with the fourth.

Conventions: SI units; the normal ``n`` is a unit vector from body A to body B and the
tangent is ``t = (n_y, -n_x)``; an impulse along ``n`` (or ``t``) is given to B and
its opposite to A; the 2D cross product is ``a x b = a_x b_y - a_y b_x``; a velocity
is ``(vx, vy, w)`` (m/s, rad/s); ``v_n < 0`` means the two bodies close at the point.
"""
from __future__ import annotations

from typing import NamedTuple

from .contact_point import ContactPoint, apply_friction_impulse, apply_normal_impulse


class StepSettings(NamedTuple):
    """The constants of a step: ``dt`` (s, > 0), ``iterations`` (sweeps, >= 0), and those
    of :func:`contact_target`: ``restitution_threshold`` (m/s), ``bias_factor``
    (dimensionless; 0: no push), ``slop`` (m), ``max_push`` (m/s)."""

    dt: float = 1 / 60
    iterations: int = 10
    restitution_threshold: float = 1.0
    bias_factor: float = 0.0
    slop: float = 0.005
    max_push: float = 3.0


class ManifoldRows(NamedTuple):
    """One contact manifold as the sweeps see it (what :func:`sweep_contacts` takes).

    ``a``, ``b``: rows of the bodies in the velocity list (``n`` points from A to B);
    ``points``: its one or two :class:`ContactPoint` (from :func:`prestep_point`);
    ``restitution``: the pair's coefficient e; ``depths``: each point's overlap (m, > 0
    overlapping); ``normal_total``, ``tangent_total``: each point's accumulated
    impulses remembered from the last step (N s, 0 for a new point).
    """

    a: int
    b: int
    points: list
    restitution: float
    depths: list
    normal_total: list
    tangent_total: list


class BodyRow(NamedTuple):
    """One body as :func:`step_bodies` sees it: its centre of mass ``x``, ``y`` (m) and
    ``angle`` (rad), its velocity ``vx``, ``vy`` (m/s), ``w`` (rad/s), its inverse mass
    ``ima`` (1/kg; 0 for a static body, which gravity does not move) and inverse moment
    of inertia ``iia`` (1/(kg m^2); 0 for a body that cannot turn)."""

    x: float
    y: float
    angle: float
    vx: float
    vy: float
    w: float
    ima: float
    iia: float


class TouchingPair(NamedTuple):
    """One contact manifold as the narrow phase found it at the start of the step, with
    what the solver adds: bodies ``a``, ``b`` (rows of the body list), the unit
    ``normal`` from A to B, the one or two contact ``points`` (m) and their ``depths``
    (m, > 0 overlapping), the pair's ``friction`` mu and ``restitution`` e, and each
    point's impulses remembered from the last step, ``normal_total`` and
    ``tangent_total`` (N s, 0 for a new point)."""

    a: int
    b: int
    normal: tuple
    points: list
    depths: list
    friction: float
    restitution: float
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


def sweep_contacts(velocity, manifolds, settings: StepSettings):
    """The targets, the warm start, then ``settings.iterations`` sweeps of sequential
    impulses over ``manifolds``.

    The target of each point (:func:`contact_target`: a bounce, a push or 0) is set once,
    from the velocities as given (after this step's forces, before any impulse of this
    step), and kept through the sweeps.  Warm starting: each point's remembered impulses
    (``normal_total`` along ``n`` and ``tangent_total`` along ``t``, from the last step)
    are given to its bodies again before the first sweep, and the accumulated totals
    start from them.  A sweep visits the manifolds in the given order; in each manifold
    first every point's friction row (:func:`apply_friction_impulse`), then every
    point's normal row (:func:`apply_normal_impulse`, aiming at the point's target),
    each visit seeing the velocities the visits before it left.

    Parameters
    ----------
    velocity : list of (float, float, float)
        ``(vx, vy, w)`` of every body (m/s, rad/s); a static body has inverse mass and
        inertia 0 in every point, so it never changes.
    manifolds : list of ManifoldRows
        Or sequences of its seven fields in that order.
    settings : StepSettings
        Or a sequence of its six fields in that order.

    Returns
    -------
    (list, list, list)
        The velocities after the sweeps (one ``(vx, vy, w)`` per body), and per
        manifold the list of its points' accumulated normal impulses and the list of
        their accumulated friction impulses (N s).  The arguments are not changed.

    Examples
    --------
    A 1 kg disc (body 1, radius 0.5 m) falling at 2 m/s onto static ground (body 0),
    nothing remembered: one sweep stops it with 2 N s (closing slower than the
    restitution threshold of 1 m/s, it does not bounce).

    >>> disc = prestep_point((0.0, 0.0), (0.0, 1.0), (0.0, -0.5), (0.0, 0.5), 0.0, 1.0, 0.0, 8.0, 0.5)
    >>> one_sweep = StepSettings(iterations=1, restitution_threshold=3.0)
    >>> sweep_contacts([(0.0, 0.0, 0.0), (0.0, -2.0, 0.0)], [ManifoldRows(0, 1, [disc], 0.5, [0.0], [0.0], [0.0])],
    ...                one_sweep)
    ([(0.0, 0.0, 0.0), (0.0, 0.0, 0.0)], [[2.0]], [[0.0]])

    With e = 0.5 above a threshold of 1 m/s it leaves at 1 m/s, after one sweep as after
    ten: the target is set before the sweeps.

    >>> bouncy = [ManifoldRows(0, 1, [disc], 0.5, [0.0], [0.0], [0.0])]
    >>> [sweep_contacts([(0.0, 0.0, 0.0), (0.0, -2.0, 0.0)], bouncy, StepSettings(iterations=n))[0][1] for n in (1, 10)]
    [(0.0, 1.0, 0.0), (0.0, 1.0, 0.0)]

    The same disc remembering 2 N s: the warm start alone stops it, and with no sweep
    the total stays.

    >>> sweep_contacts([(0.0, 0.0, 0.0), (0.0, -2.0, 0.0)], [ManifoldRows(0, 1, [disc], 0.0, [0.0], [2.0], [0.0])],
    ...                StepSettings(iterations=0))
    ([(0.0, 0.0, 0.0), (0.0, 0.0, 0.0)], [[2.0]], [[0.0]])
    """
    ### BEGIN SOLUTION
    dt, iterations, threshold, bias_factor, slop, max_push = settings
    velocity = [tuple(v) for v in velocity]
    normal = [list(m[5]) for m in manifolds]
    tangent = [list(m[6]) for m in manifolds]
    targets = []
    for a, b, points, restitution, depths, _, _ in manifolds:
        (vxa, vya, wa), (vxb, vyb, wb) = velocity[a], velocity[b]
        targets.append([])
        for point, depth in zip(points, depths):
            normal_velocity = (vxb - vxa) * point[0] + (vyb - vya) * point[1] + wb * point[3] - wa * point[2]
            targets[-1].append(contact_target(normal_velocity, restitution, depth, dt, threshold, bias_factor, slop,
                                              max_push))
    for m, (a, b, points, _, _, _, _) in enumerate(manifolds):
        for k, point in enumerate(points):
            nx, ny, rn_a, rn_b, rt_a, rt_b, ima, imb, iia, iib = point[:10]
            pn, pt = normal[m][k], tangent[m][k]
            px, py = pn * nx + pt * ny, pn * ny - pt * nx          # P = pn n + pt t
            vxa, vya, wa = velocity[a]
            vxb, vyb, wb = velocity[b]
            velocity[a] = (vxa - ima * px, vya - ima * py, wa - iia * (rn_a * pn + rt_a * pt))
            velocity[b] = (vxb + imb * px, vyb + imb * py, wb + iib * (rn_b * pn + rt_b * pt))
    for _ in range(iterations):
        for m, (a, b, points, _, _, _, _) in enumerate(manifolds):
            for k, point in enumerate(points):
                velocity[a], velocity[b], tangent[m][k] = apply_friction_impulse(
                    velocity[a], velocity[b], point, normal[m][k], tangent[m][k])
            for k, point in enumerate(points):
                velocity[a], velocity[b], normal[m][k] = apply_normal_impulse(
                    velocity[a], velocity[b], point, normal[m][k], targets[m][k])
    return velocity, normal, tangent
    ### END SOLUTION


def step_bodies(bodies, pairs, gravity, settings: StepSettings):
    """One step of ``settings.dt`` of the bodies, whose contacts ``pairs`` were found at
    the poses they start from, in the order of box2d-lite's ``World::Step``.

    Contract: gravity changes the velocity of every body with mass (``ima > 0``); the
    contacts then correct those velocities (each pair's points through
    :func:`prestep_point`, all of them through :func:`sweep_contacts`); and only then
    do the bodies move, each by ``dt`` times its corrected velocity (``angle`` by ``dt``
    times ``w``).  So a body resting on the ground neither sinks nor lifts, a body
    touching nothing falls freely, and the remembered impulses warm start the sweeps.

    Parameters
    ----------
    bodies : list of BodyRow
        Or sequences of its eight fields in that order.
    pairs : list of TouchingPair
        Or sequences of its nine fields in that order; their ``a`` and ``b`` are rows of
        ``bodies``, and the sweeps visit them in this order.
    gravity : (float, float)
        m/s^2.
    settings : StepSettings
        Or a sequence of its six fields in that order.

    Returns
    -------
    (list, list, list)
        Every body's new ``(x, y, angle, vx, vy, w)``, and per pair the list of its
        points' accumulated normal impulses and the list of their accumulated friction
        impulses (N s), to remember for the next step.  The arguments are not changed.

    Examples
    --------
    A 1 kg disc of radius 0.5 m (1/I = 8) resting on static ground, at 10 m/s^2 and a
    step of 0.1 s: gravity makes it close at 1 m/s, 1 N s stops it, and it stays where
    it is.  The ground is body 0, its centre 0.5 m below the surface.

    >>> ground, disc = BodyRow(0.0, -0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0), BodyRow(0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 1.0, 8.0)
    >>> resting = TouchingPair(0, 1, (0.0, 1.0), [(0.0, 0.0)], [0.0], 0.5, 0.0, [0.0], [0.0])
    >>> step_bodies([ground, disc], [resting], (0.0, -10.0), StepSettings(dt=0.1, restitution_threshold=2.0))
    ([(0.0, -0.5, 0.0, 0.0, 0.0, 0.0), (0.0, 0.5, 0.0, 0.0, 0.0, 0.0)], [[1.0]], [[0.0]])

    Touching nothing, it falls at 1 m/s after the step and has moved 0.1 m down.

    >>> step_bodies([disc], [], (0.0, -10.0), StepSettings(dt=0.1))
    ([(0.0, 0.4, 0.0, 0.0, -1.0, 0.0)], [], [])
    """
    ### BEGIN SOLUTION
    dt = settings[0]
    gx, gy = gravity
    velocity = [(vx + dt * gx, vy + dt * gy, w) if ima > 0.0 else (vx, vy, w)
                for _, _, _, vx, vy, w, ima, _ in bodies]
    manifolds = []
    for a, b, normal, points, depths, friction, restitution, normal_total, tangent_total in pairs:
        xa, ya, _, _, _, _, ima, iia = bodies[a]
        xb, yb, _, _, _, _, imb, iib = bodies[b]
        rows = [prestep_point(point, normal, (xa, ya), (xb, yb), ima, imb, iia, iib, friction) for point in points]
        manifolds.append(ManifoldRows(a, b, rows, restitution, depths, normal_total, tangent_total))
    velocity, normal, tangent = sweep_contacts(velocity, manifolds, settings)
    moved = [(x + dt * vx, y + dt * vy, angle + dt * w, vx, vy, w)
             for (x, y, angle, *_), (vx, vy, w) in zip(bodies, velocity)]
    return moved, normal, tangent
    ### END SOLUTION
