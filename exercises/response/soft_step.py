# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/response/soft_step.py on the instructor's
# side.
"""Soft step: sub-stepping with soft contacts and relaxation, after Box2D v3.

A plain step finds contacts, solves velocities with many iterations and corrects
positions.  The soft step finds contacts once per step of ``dt`` and then takes ``n``
sub-steps of ``h = dt / n``, each with a single sweep, following Erin Catto's
"Solver2D" soft step (the solver of Box2D v3)::

    find contacts once            manifolds at the poses of the start of the step
    prepare                       lever arms, effective masses, last step's impulses
    for each sub-step:
        apply gravity             v += h g
        warm start                apply the accumulated impulses
        solve (biased, soft)      a stiff damped spring pushes the overlap apart
        integrate positions       x += h v, angle += h w
        relax (rigid, no bias)    take the push velocity back out
    restitution                   one pass, from the closing speeds at the start
    remember impulses             for the next step's warm start

Between sub-steps the separation of each contact point is updated from how far its
two bodies moved and turned since the start of the step (the contact's normal and
lever arms stay those of the start), so the push fades as the overlap closes.  Small
sub-steps make the stack's impulses travel as far as many iterations would, the
spring keeps the push smooth, and relaxing removes the push velocity that Baumgarte
would leave in (no energy gain).

Soft contact
------------
A contact point with separation ``s`` (m, < 0 when overlapping) is a spring of
natural frequency ``f`` (Hz) and damping ratio ``zeta`` acting on the point's
effective mass.  Implicit Euler over ``h`` gives, with ``omega = 2 pi f``
(:func:`soft_coefficients`)::

    bias_rate     = omega / (2 zeta + h omega)                        (1/s)
    mass_scale    = h omega (2 zeta + h omega) / (1 + h omega (2 zeta + h omega))
    impulse_scale = 1 / (1 + h omega (2 zeta + h omega))

and the normal impulse of one sweep is ``-m_n mass_scale (v_n + bias) - impulse_scale
P_acc`` with ``bias = max(bias_rate * s, -max_push_velocity)`` for ``s <= 0``: no
slop, the spring itself decides how deep a loaded contact rests.  A
point that has opened (``s > 0``) may close at up to ``s / h`` and is rigid.  Contacts
against static bodies use twice the frequency (they must carry whole stacks).  The
frequency is capped at a quarter of the sub-step rate, ``1 / (4 h)``, where implicit
Euler stays accurate.  Settings: ``contact_hertz``, ``contact_damping_ratio``,
``relax``, ``max_push_velocity`` and ``iterations`` (sweeps per pass) of
:class:`~solutions.response.contact_solver.SolverSettings`.

Each sweep solves every manifold's normal impulses and then its friction impulses
(Box2D v3's order), the friction bounded by ``mu`` times the accumulated normal
impulse.  Normal from body A to body B, SI units.
"""
from __future__ import annotations

import math

import numpy as np

from ..body import Body
from ..contact import Contact
from .contact_solver import (COLOURS_MIN_MANIFOLDS, ContactSolver, block_is_well_conditioned, block_normal_impulses,
                             block_normal_impulses_many, jacobian_rows, normal_block_matrix, sweep_order)


#: Rigid distance joints in the soft step are springs of this frequency (Hz, capped at
#: a quarter of the sub-step rate: inf takes the cap) and damping ratio.  Box2D v3 uses
#: 60 Hz and 2; on the 40-link chain the cap and critical damping stretch a link at most
#: 3 cm instead of 6 cm (the plain solver's Baumgarte rods: 47 cm).
JOINT_HERTZ = math.inf
JOINT_DAMPING_RATIO = 1.0


def soft_coefficients(hertz: float, damping_ratio: float, h: float) -> tuple[float, float, float]:
    """``(bias_rate, mass_scale, impulse_scale)`` of a soft constraint (module docstring).

    Parameters
    ----------
    hertz : float
        Natural frequency f (Hz), >= 0; 0 gives a rigid constraint without bias.
    damping_ratio : float
        zeta (dimensionless), >= 0.
    h : float
        Sub-step (s), > 0.

    Returns
    -------
    (float, float, float)
        bias rate (1/s), mass scale and impulse scale (dimensionless, both in [0, 1]).

    Examples
    --------
    >>> [round(x, 6) for x in soft_coefficients(30.0, 10.0, 1 / 240)]
    [9.068653, 0.942279, 0.057721]
    >>> soft_coefficients(0.0, 1.0, 0.01)
    (0.0, 1.0, 0.0)
    """
    if hertz == 0.0:
        return 0.0, 1.0, 0.0
    omega = 2.0 * math.pi * hertz
    a1 = 2.0 * damping_ratio + h * omega
    a2 = h * omega * a1
    a3 = 1.0 / (1.0 + a2)
    return omega / a1, a2 * a3, a3


class BodyStates:
    """Poses and velocities of all bodies as arrays, for the sub-steps of one step.

    ``position`` (N, 2) m, ``angle`` (N,) rad, ``velocity`` (N, 3) rows ``(vx, vy, w)``
    in m/s and rad/s; ``dynamic`` and ``turning`` (N,) say which bodies move and which
    turn (finite inertia).  :meth:`write` copies them back into the bodies.
    """

    def __init__(self, bodies: list[Body]):
        self.dynamic = np.array([not body.is_static for body in bodies], dtype=bool)
        self.turning = np.array([body.inverse_inertia > 0.0 for body in bodies], dtype=bool)
        self.read(bodies)

    def read(self, bodies: list[Body]) -> None:
        """Take the poses and velocities from the bodies."""
        self.position = np.array([body.position.tolist() for body in bodies], dtype=float).reshape(-1, 2)
        self.angle = np.array([float(body.angle) for body in bodies])
        self.velocity = np.array([(*body.velocity.tolist(), float(body.angular_velocity)) for body in bodies],
                                 dtype=float).reshape(-1, 3)
        self.velocity[~self.turning, 2] = 0.0

    def write(self, bodies: list[Body]) -> None:
        """Put the poses and velocities of the dynamic bodies back into them."""
        for k in np.flatnonzero(self.dynamic).tolist():
            body = bodies[k]
            body.position = self.position[k].copy()
            body.velocity = self.velocity[k, :2].copy()
            if self.turning[k]:
                body.angle = float(self.angle[k])
                body.angular_velocity = float(self.velocity[k, 2])

    def integrate_velocities(self, gravity: np.ndarray, h: float) -> None:
        """v += h g for the dynamic bodies."""
        self.velocity[self.dynamic, :2] += h * gravity

    def integrate_positions(self, h: float) -> None:
        """x += h v, angle += h w (static bodies have v = 0)."""
        self.position += h * self.velocity[:, :2]
        self.angle += h * self.velocity[:, 2]


class SoftStepSolver(ContactSolver):
    """Contact solver of the soft step; :class:`~solutions.world.World` drives it.

    Calling contract, per step of ``dt`` with ``n`` sub-steps of ``h``, on the
    :class:`BodyStates` of the world's bodies::

        solver.begin_step(bodies, manifolds, h, separations)
        states = BodyStates(bodies)
        for _ in range(n):
            states.integrate_velocities(gravity, h)
            solver.solve_substep(states, h, use_bias=True)    # warm start + soft solve
            states.integrate_positions(h)
            solver.solve_substep(states, h, use_bias=False)   # relax (if settings.relax)
        solver.end_step(states, h)                             # restitution, memory, stats
        states.write(bodies)

    Examples
    --------
    A 1 kg box resting flat on static ground, 1 cm deep: four sub-steps push it
    up without leaving it an upward velocity.

    >>> ground = Body.box(10.0, 1.0, position=(0.0, -0.5), is_static=True)
    >>> box = Body.box(1.0, 1.0, position=(0.0, 0.49))
    >>> sunk = Contact((0.0, 1.0), 0.01, [(-0.5, -0.005), (0.5, -0.005)], feature_ids=(0, 1))
    >>> solver, h, gravity = SoftStepSolver(), 1 / 240, np.array([0.0, -9.81])
    >>> solver.begin_step([ground, box], [(0, 1, sunk)], h)
    >>> states = BodyStates([ground, box])
    >>> for _ in range(4):
    ...     states.integrate_velocities(gravity, h)
    ...     solver.solve_substep(states, h, use_bias=True)
    ...     states.integrate_positions(h)
    ...     solver.solve_substep(states, h, use_bias=False)
    >>> solver.end_step(states, h)
    >>> states.write([ground, box])
    >>> bool(0.49 < box.position[1] < 0.5), bool(abs(box.velocity[1]) < 1e-9)
    (True, True)
    """

    def begin_step(self, bodies: list[Body], manifolds: list[tuple[int, int, Contact]], h: float,
                   separations: list[np.ndarray] | None = None) -> None:
        """Prepare the contacts found at the start of the step for sub-steps of ``h`` (s).

        ``separations``: per manifold, the signed separation of each point (m, > 0 for
        the speculative points of :mod:`~solutions.narrowphase.speculative`); by
        default ``-contact.depths``.
        """
        settings = self.settings
        if not h > 0.0:
            raise ValueError(f"h must be > 0 s, got {h}")
        if not settings.accumulate_impulses:
            raise ValueError("the soft step needs accumulate_impulses=True (its spring acts on the totals)")
        c = self._prepare(bodies, manifolds, h, block_solver=False)
        if separations is not None:
            if [len(s) for s in separations] != [len(contact.points) for _, _, contact in manifolds]:
                raise ValueError("separations must give one value per contact point of each manifold")
            c.depth = -np.concatenate(separations) if separations else np.zeros(0)
        self._contacts = c
        self._rows = np.array(list(c.local), dtype=int)      # world index of each member
        self._start_angle = np.array([float(body.angle) for body in c.members])
        self._separation = -c.depth                            # at the poses of the start
        nx, ny = c.normal[:, 0], c.normal[:, 1]
        self._r_dot_n_a, self._r_dot_n_b = c.r_a[:, 0] * nx + c.r_a[:, 1] * ny, c.r_b[:, 0] * nx + c.r_b[:, 1] * ny
        self._r_cross_n_a = c.r_a[:, 0] * ny - c.r_a[:, 1] * nx
        self._r_cross_n_b = c.r_b[:, 0] * ny - c.r_b[:, 1] * nx
        hertz = min(settings.contact_hertz, 0.25 / h)
        soft = soft_coefficients(hertz, settings.contact_damping_ratio, h)
        stiff = soft_coefficients(2.0 * hertz, settings.contact_damping_ratio, h)
        against_static = (c.ima == 0.0) | (c.imb == 0.0)
        self._bias_rate, self._mass_scale, self._impulse_scale = (
            np.where(against_static, s2, s1) for s1, s2 in zip(soft, stiff))
        self._max_normal = np.zeros(c.point_count)
        # One entry per manifold: bodies, normal, inverse masses and its points
        # (index, r_A x n, r_B x n, r_A x t, r_B x t, 1/K_n, 1/K_t, mu), in manifold order.
        columns = list(zip(range(c.point_count), *(c.columns[name].tolist() for name in (
            "rn_a", "rn_b", "rt_a", "rt_b", "mass_normal", "mass_tangent", "friction"))))
        self._program = []
        first = 0
        for _, _, contact in manifolds:
            k = first
            first += len(contact.points)
            ima, imb, iia, iib = float(c.ima[k]), float(c.imb[k]), float(c.iia[k]), float(c.iib[k])
            block = None
            if settings.block_solver and first - k == 2:
                (_, rn_a1, rn_b1, *_), (_, rn_a2, rn_b2, *_) = columns[k:first]
                matrix = normal_block_matrix(ima, imb, iia, iib, rn_a1, rn_b1, rn_a2, rn_b2)
                if block_is_well_conditioned(*matrix):
                    block = matrix
            self._program.append((int(c.a[k]), int(c.b[k]), float(nx[k]), float(ny[k]), ima, imb, iia, iib,
                                  columns[k:first], block))
        batched = settings.sweep == "batched" or (settings.sweep == "auto" and len(manifolds) >= COLOURS_MIN_MANIFOLDS)
        self._groups = colour_groups(self._program, c.ima, c.imb, c.a, c.b) if batched and manifolds else None

    def separations(self, states: BodyStates) -> np.ndarray:
        """Separation (m, < 0 overlapping) of each contact point now, per point in
        manifold order: the separation at the start of the step, plus how far the two
        material points that touched there have moved apart along the normal."""
        c = self._contacts
        moved = states.position[self._rows] - c.centre
        turned = states.angle[self._rows] - self._start_angle
        cos_less_1, sin = np.cos(turned) - 1.0, np.sin(turned)
        # ((R - I) r) . n = (cos - 1) (r . n) + sin (r x n) for a turn R of the lever arm r.
        a, b = c.a, c.b
        return (np.einsum("ij,ij->i", moved[b] - moved[a], c.normal)
                + cos_less_1[b] * self._r_dot_n_b + sin[b] * self._r_cross_n_b
                - cos_less_1[a] * self._r_dot_n_a - sin[a] * self._r_cross_n_a - c.depth)

    def solve_substep(self, states: BodyStates, h: float, use_bias: bool) -> None:
        """One pass of ``iterations`` sweeps on ``states``: warm start and soft solve
        (``use_bias``), or relax (rigid, no push; skipped when ``settings.relax`` is off).

        The biased pass must come before the sub-step's position update, the relax
        pass after it.
        """
        settings = self.settings
        c = self._contacts
        if not c.point_count or (not use_bias and not settings.relax):
            return
        velocity = states.velocity[self._rows]
        if use_bias:
            velocity = self.apply_impulses(c, velocity, c.normal_total, c.tangent_total)
            separation = self._separation if self._separation is not None else self.separations(states)
            self._separation = None                             # positions move next
        else:
            separation = self._separation = self.separations(states)
        opened = separation > 0.0
        target = np.where(opened, -separation / h, 0.0)       # closing allowed up to s / h (m/s)
        if use_bias:
            push = np.minimum(-self._bias_rate * separation, settings.max_push_velocity)
            target = np.where(opened, target, push)
            mass_scale = np.where(opened, 1.0, self._mass_scale)
            impulse_scale = np.where(opened, 0.0, self._impulse_scale)
        else:
            mass_scale, impulse_scale = np.ones(c.point_count), np.zeros(c.point_count)
        if self._groups is not None:
            velocity = soft_sweeps_batched(velocity, self._groups, settings.iterations, c.normal_total,
                                           c.tangent_total, target, mass_scale, impulse_scale)
        else:
            velocity = soft_sweeps(velocity, self._program, settings.iterations, c.normal_total, c.tangent_total,
                                   target, mass_scale, impulse_scale, friction=True)
        if use_bias:
            np.maximum(self._max_normal, c.normal_total, out=self._max_normal)
        states.velocity[self._rows] = velocity * states.dynamic[self._rows, None]

    def end_step(self, states: BodyStates, h: float) -> None:
        """Restitution, then remember the impulses and fill ``stats``.

        Restitution: one sweep over the points that closed faster than
        ``restitution_threshold`` at the start of the step and pushed in some
        sub-step, aiming at ``-e`` times that closing speed.
        """
        c = self._contacts
        if c.point_count:
            bounce = ((c.normal_velocity < -self.settings.restitution_threshold) & (self._max_normal > 0.0)
                      & (c.restitution > 0.0))
            if bounce.any():
                velocity = soft_sweeps(states.velocity[self._rows], self._program, 1, c.normal_total,
                                       c.tangent_total, -c.restitution * c.normal_velocity, bounce.astype(float),
                                       np.zeros(c.point_count), friction=False, block=False)
                states.velocity[self._rows] = velocity * states.dynamic[self._rows, None]
        self.end_contacts(c, h)
        self.stats.block_manifolds = sum(entry[-1] is not None for entry in self._program)


def soft_sweeps(velocity: np.ndarray, program: list, iterations: int, normal_total: np.ndarray,
                tangent_total: np.ndarray, target: np.ndarray, mass_scale: np.ndarray,
                impulse_scale: np.ndarray, friction: bool, block: bool = True) -> np.ndarray:
    """Sweeps of soft sequential impulses, manifold by manifold.

    Per point ``k`` the normal impulse change is ``m_n mass_scale[k] (target[k] - v_n)
    - impulse_scale[k] P_k`` with the accumulated ``P_k`` clamped to >= 0; then (if
    ``friction``) the tangent impulses, accumulated within ``+-mu P_k``.
    ``mass_scale = 1``, ``impulse_scale = 0`` is the rigid sequential impulse of
    :func:`~solutions.response.contact_solver.sweep_loop`; ``mass_scale = 0`` leaves a
    point out.

    With ``block``, a manifold that carries its 2x2 matrix ``K`` solves its two normal
    impulses together: when ``mass_scale + impulse_scale = 1`` (every soft or rigid
    point) one update above is ``P_new = mass_scale x``, where ``x`` is the impulse
    that would bring the point exactly to its target, so the pair takes
    ``P_new = mass_scale * x`` with ``x`` from the 2x2 complementarity problem of
    :func:`~solutions.response.contact_solver.block_normal_impulses`.

    Parameters
    ----------
    velocity : numpy.ndarray, shape (n, 3)
        Rows ``(vx, vy, w)`` (m/s, rad/s).
    program : list
        Per manifold ``(a, b, nx, ny, 1/m_A, 1/m_B, 1/I_A, 1/I_B, points, K)`` with points
        ``(k, r_A x n, r_B x n, r_A x t, r_B x t, m_n, m_t, mu)`` and ``K = (k11, k12,
        k22)`` (1/kg) for a two-point manifold solved as a block, else None.
    iterations : int
        Sweeps.
    normal_total, tangent_total : numpy.ndarray, shape (m,)
        Accumulated impulses (N s), updated in place.
    target : numpy.ndarray, shape (m,)
        Wanted separating normal velocity (m/s).
    mass_scale, impulse_scale : numpy.ndarray, shape (m,)
        Soft-constraint scales (dimensionless).
    friction : bool
        Solve the tangent impulses too.
    block : bool
        Use the manifolds' ``K`` (False: point by point, needed when a ``mass_scale``
        masks points out).

    Returns
    -------
    numpy.ndarray, shape (n, 3)

    Examples
    --------
    A 1 kg disc falling at 1 m/s on static ground, rigid: one sweep stops it.

    >>> program = [(0, 1, 0.0, 1.0, 0.0, 1.0, 0.0, 2.0, [(0, 0.0, 0.0, 0.0, 0.5, 1.0, 1 / 1.5, 0.0)], None)]
    >>> soft_sweeps(np.array([[0.0, 0.0, 0.0], [0.0, -1.0, 0.0]]), program, 1, np.zeros(1), np.zeros(1),
    ...             np.zeros(1), np.ones(1), np.zeros(1), friction=True).tolist()
    [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
    """
    vx, vy, w = velocity.T.tolist()
    normal, tangent = normal_total.tolist(), tangent_total.tolist()
    target, mass_scale, impulse_scale = target.tolist(), mass_scale.tolist(), impulse_scale.tolist()
    for _ in range(iterations):
        for a, b, nx, ny, ima, imb, iia, iib, points, matrix in program:
            vxa, vya, wa, vxb, vyb, wb = vx[a], vy[a], w[a], vx[b], vy[b], w[b]
            if block and matrix is not None:
                (k1, rn_a1, rn_b1, *_), (k2, rn_a2, rn_b2, *_) = points
                k11, k12, k22 = matrix
                along = (vxb - vxa) * nx + (vyb - vya) * ny
                old1, old2 = normal[k1], normal[k2]
                b1 = along + wb * rn_b1 - wa * rn_a1 - target[k1] - (k11 * old1 + k12 * old2)
                b2 = along + wb * rn_b2 - wa * rn_a2 - target[k2] - (k12 * old1 + k22 * old2)
                x1, x2 = block_normal_impulses(k11, k12, k22, b1, b2)
                if x1 != x1:  # nan: no case fits (rounding); keep the impulses
                    x1, x2 = old1, old2
                else:
                    x1, x2 = mass_scale[k1] * x1, mass_scale[k2] * x2
                change1, change2 = x1 - old1, x2 - old2
                normal[k1], normal[k2] = x1, x2
                change = change1 + change2
                vxa -= ima * change * nx
                vya -= ima * change * ny
                wa -= iia * (rn_a1 * change1 + rn_a2 * change2)
                vxb += imb * change * nx
                vyb += imb * change * ny
                wb += iib * (rn_b1 * change1 + rn_b2 * change2)
                points_by_one = ()
            else:
                points_by_one = points
            for k, rn_a, rn_b, _, _, mass_normal, _, _ in points_by_one:
                normal_velocity = (vxb - vxa) * nx + (vyb - vya) * ny + wb * rn_b - wa * rn_a
                old = normal[k]
                change = mass_normal * mass_scale[k] * (target[k] - normal_velocity) - impulse_scale[k] * old
                normal[k] = max(old + change, 0.0)
                change = normal[k] - old
                vxa -= ima * change * nx
                vya -= ima * change * ny
                wa -= iia * rn_a * change
                vxb += imb * change * nx
                vyb += imb * change * ny
                wb += iib * rn_b * change
            if friction:
                for k, _, _, rt_a, rt_b, _, mass_tangent, mu in points:
                    if mu == 0.0:
                        continue
                    # Along t = (ny, -nx), within the Coulomb bound mu P_k.
                    tangent_velocity = (vxb - vxa) * ny - (vyb - vya) * nx + wb * rt_b - wa * rt_a
                    bound = mu * normal[k]
                    old = tangent[k]
                    tangent[k] = min(max(old - mass_tangent * tangent_velocity, -bound), bound)
                    change = tangent[k] - old
                    vxa -= ima * change * ny
                    vya += ima * change * nx
                    wa -= iia * rt_a * change
                    vxb += imb * change * ny
                    vyb -= imb * change * nx
                    wb += iib * rt_b * change
            vx[a], vy[a], w[a], vx[b], vy[b], w[b] = vxa, vya, wa, vxb, vyb, wb
    normal_total[:] = normal
    tangent_total[:] = tangent
    return np.array([vx, vy, w], dtype=float).T.reshape(-1, 3)


def colour_groups(program: list, ima: np.ndarray, imb: np.ndarray, a: np.ndarray, b: np.ndarray) -> list:
    """The manifolds of ``program`` as :class:`SoftGroup` batches for
    :func:`soft_sweeps_batched`: colour by colour (:func:`sweep_order`), and within
    a colour one group per kind (block pairs, other pairs, single points).

    ``ima``, ``imb``, ``a``, ``b``: per point (manifold order) inverse masses and body
    rows, to tell movable bodies from static ones.
    """
    rows = int(max(a.max(initial=-1), b.max(initial=-1))) + 1
    movable = np.zeros(rows, dtype=bool)
    movable[a[ima > 0.0]] = True
    movable[b[imb > 0.0]] = True
    body_a = np.array([entry[0] for entry in program], dtype=int)
    body_b = np.array([entry[1] for entry in program], dtype=int)
    order, bounds = sweep_order(body_a, body_b, movable, "colours")
    groups = []
    for start, stop in zip(bounds[:-1].tolist(), bounds[1:].tolist()):
        kinds: dict[str, list] = {"block": [], "pair": [], "single": []}
        for m in order[start:stop].tolist():
            entry = program[m]
            kinds["block" if entry[9] is not None else "pair" if len(entry[8]) == 2 else "single"].append(entry)
        groups.extend(SoftGroup(entries, kind == "block") for kind, entries in kinds.items() if entries)
    return groups


def colour_order(program: list, ima: np.ndarray, imb: np.ndarray, a: np.ndarray, b: np.ndarray) -> list:
    """``program`` reordered as :func:`colour_groups` visits it (to compare with the loop)."""
    return [entry for group in colour_groups(program, ima, imb, a, b) for entry in group.entries]


class SoftGroup:
    """Manifolds of one colour with the same number of points and the same normal
    solve; they share no movable body, so numpy solves them all at once.

    Per slot ``s`` (first or second point of each manifold): point indices, Jacobian
    rows ``J`` over the six velocities ``(vx_A, vy_A, w_A, vx_B, vy_B, w_B)`` and the
    velocity change per unit impulse ``M^-1 J^T``, along ``n`` and along ``t``.
    """

    def __init__(self, entries: list, block: bool):
        self.entries = entries
        self.block = block
        a, b, nx, ny, ima, imb, iia, iib = (np.array([entry[f] for entry in entries]) for f in range(8))
        self.slots = []
        for slot in range(len(entries[0][8])):
            k, rn_a, rn_b, rt_a, rt_b, mass_normal, mass_tangent, mu = (
                np.array([entry[8][slot][f] for entry in entries]) for f in range(8))
            self.where, j_normal, response_normal, j_tangent, response_tangent = jacobian_rows(
                a, b, nx, ny, rn_a, rn_b, rt_a, rt_b, ima, imb, iia, iib)      # where: same for both slots
            self.slots.append((k.astype(int), j_normal, response_normal, mass_normal, j_tangent, response_tangent,
                               mass_tangent, mu, bool(np.any(mu != 0.0))))
        if block:
            self.k11, self.k12, self.k22 = (np.array([entry[9][f] for entry in entries]) for f in range(3))
            det = self.k11 * self.k22 - self.k12 * self.k12
            self.inverse = (self.k22 / det, -self.k12 / det, self.k11 / det)

    def sweep(self, flat, normal, tangent, target, mass_scale, impulse_scale) -> None:
        """One sweep of the group, as :func:`soft_sweeps` does each of its manifolds."""
        v = flat[self.where]
        if self.block:
            (k1, jn1, mn1, *_), (k2, jn2, mn2, *_) = self.slots
            old1, old2 = normal[k1], normal[k2]
            b1 = np.einsum("ij,ij->i", v, jn1) - target[k1] - (self.k11 * old1 + self.k12 * old2)
            b2 = np.einsum("ij,ij->i", v, jn2) - target[k2] - (self.k12 * old1 + self.k22 * old2)
            x1, x2, stuck = block_normal_impulses_many(self.k11, self.k12, self.k22, b1, b2, self.inverse)
            x1 = np.where(stuck, old1, mass_scale[k1] * x1)
            x2 = np.where(stuck, old2, mass_scale[k2] * x2)
            normal[k1], normal[k2] = x1, x2
            v += mn1 * (x1 - old1)[:, None] + mn2 * (x2 - old2)[:, None]
        else:
            for k, jn, mn, mass_normal, *_ in self.slots:
                old = normal[k]
                change = (mass_normal * mass_scale[k] * (target[k] - np.einsum("ij,ij->i", v, jn))
                          - impulse_scale[k] * old)
                new = np.maximum(old + change, 0.0)
                normal[k] = new
                v += mn * (new - old)[:, None]
        for k, _, _, _, jt, mt, mass_tangent, mu, has_friction in self.slots:
            if not has_friction:
                continue
            old = tangent[k]
            bound = mu * normal[k]
            new = np.clip(old - mass_tangent * np.einsum("ij,ij->i", v, jt), -bound, bound)
            tangent[k] = new
            v += mt * (new - old)[:, None]
        flat[self.where] = v


def soft_sweeps_batched(velocity: np.ndarray, groups: list, iterations: int, normal_total: np.ndarray,
                        tangent_total: np.ndarray, target: np.ndarray, mass_scale: np.ndarray,
                        impulse_scale: np.ndarray) -> np.ndarray:
    """:func:`soft_sweeps` (with friction and the block solver) one colour at a time.

    Gives the loop's result, up to rounding, for the program in :func:`colour_order`.
    Same parameters as :func:`soft_sweeps` but ``groups`` from :func:`colour_groups`;
    ``normal_total`` and ``tangent_total`` are updated in place.

    >>> program = [(0, 1, 0.0, 1.0, 0.0, 1.0, 0.0, 2.0, [(0, 0.0, 0.0, 0.0, 0.5, 1.0, 1 / 1.5, 0.0)], None)]
    >>> groups = colour_groups(program, np.zeros(1), np.ones(1), np.zeros(1, int), np.ones(1, int))
    >>> soft_sweeps_batched(np.array([[0.0, 0.0, 0.0], [0.0, -1.0, 0.0]]), groups, 1, np.zeros(1), np.zeros(1),
    ...                     np.zeros(1), np.ones(1), np.zeros(1)).tolist()
    [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
    """
    velocity = np.array(velocity, dtype=float, order="C")
    flat = velocity.reshape(-1)
    for _ in range(iterations):
        for group in groups:
            group.sweep(flat, normal_total, tangent_total, target, mass_scale, impulse_scale)
    return velocity
