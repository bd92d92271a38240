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
Euler stays accurate.  Settings: ``contact_hertz``, ``contact_damping_ratio`` and
``relax`` of :class:`~solutions.response.solver_settings.SoftStepSettings`, and
``max_push_velocity`` and ``iterations`` (sweeps per pass) of
:class:`~solutions.response.solver_settings.SolverSettings`.

Each sweep solves every manifold's normal impulses and then its friction impulses
(Box2D v3's order), the friction bounded by ``mu`` times the accumulated normal
impulse.  Normal from body A to body B, SI units.
"""
from __future__ import annotations

import math

import numpy as np

from ..body import Body
from ..body_state import BodyState
from ..contact import Contact
from ..solver.kernel import kernel
from .contact_preparation import ContactPreparation, contact_targets
from .solver_settings import SoftStepSettings, SolverSettings


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


class SoftStepSolver(ContactPreparation):
    """Contact solver of the soft step; :class:`~solutions.world.World` drives it.

    Calling contract, per step of ``dt`` with ``n`` sub-steps of ``h``, on the
    :class:`~solutions.body_state.BodyState` that the bodies are rows of::

        solver.begin_step(bodies, manifolds, h)
        for _ in range(n):
            state.integrate_velocities(gravity, h)
            solver.solve_substep(state, h, use_bias=True)     # warm start + soft solve
            state.integrate_positions(h)
            solver.solve_substep(state, h, use_bias=False)    # relax (if soft.relax)
        solver.end_step(state, h)                              # restitution, memory, stats

    Every pass is the solver kernel (:func:`~solutions.solver.kernel.solve_constraints`)
    with soft or rigid rows, in Box2D v3's order (normal, then friction).

    Examples
    --------
    A 1 kg box resting flat on static ground, 1 cm deep: four sub-steps push it
    up without leaving it an upward velocity.

    >>> ground = Body.box(10.0, 1.0, position=(0.0, -0.5), is_static=True)
    >>> box = Body.box(1.0, 1.0, position=(0.0, 0.49))
    >>> sunk = Contact((0.0, 1.0), 0.01, [(-0.5, -0.005), (0.5, -0.005)], feature_ids=(0, 1))
    >>> solver, h, gravity = SoftStepSolver(), 1 / 240, np.array([0.0, -9.81])
    >>> state = BodyState.gather([ground, box])
    >>> solver.begin_step([ground, box], [(0, 1, sunk)], h)
    >>> for _ in range(4):
    ...     state.integrate_velocities(gravity, h)
    ...     solver.solve_substep(state, h, use_bias=True)
    ...     state.integrate_positions(h)
    ...     solver.solve_substep(state, h, use_bias=False)
    >>> solver.end_step(state, h)
    >>> bool(0.49 < box.position[1] < 0.5), bool(abs(box.velocity[1]) < 1e-9)
    (True, True)
    """

    def __init__(self, settings: SolverSettings | None = None, soft: SoftStepSettings | None = None,
                 backend: str = "python"):
        super().__init__(settings, backend)
        self.soft = SoftStepSettings() if soft is None else soft

    def begin_step(self, bodies: list[Body], manifolds: list[tuple[int, int, Contact]], h: float) -> None:
        """Prepare the contacts found at the start of the step for sub-steps of ``h`` (s).

        Each point starts from its contact's signed separation (``Contact.separations``,
        m, > 0 for the speculative points of :mod:`~solutions.narrowphase.speculative`).
        """
        settings = self.settings
        if not h > 0.0:
            raise ValueError(f"h must be > 0 s, got {h}")
        if not settings.accumulate_impulses:
            raise ValueError("the soft step needs accumulate_impulses=True (its spring acts on the totals)")
        c = self.prepare(bodies, manifolds, h, block_solver=settings.block_solver)
        c.depth = -np.concatenate([contact.separations for _, _, contact in manifolds]) if manifolds else np.zeros(0)
        self._contacts = c
        self._rows = np.array(list(c.local), dtype=int)      # world index of each member
        self._start_angle = np.array([float(body.angle) for body in c.members])
        self._separation = -c.depth                            # at the poses of the start (manifold order)
        nx, ny = c.normal[:, 0], c.normal[:, 1]
        self._r_dot_n_a, self._r_dot_n_b = c.r_a[:, 0] * nx + c.r_a[:, 1] * ny, c.r_b[:, 0] * nx + c.r_b[:, 1] * ny
        self._r_cross_n_a, self._r_cross_n_b = c.columns["rn_a"], c.columns["rn_b"]
        hertz = min(self.soft.contact_hertz, 0.25 / h)
        soft = soft_coefficients(hertz, self.soft.contact_damping_ratio, h)
        stiff = soft_coefficients(2.0 * hertz, self.soft.contact_damping_ratio, h)
        against_static = ((c.ima == 0.0) | (c.imb == 0.0))[c.order]
        # Per point in sweep order (the kernel's order).
        self._bias_rate, self._mass_scale, self._impulse_scale = (
            np.where(against_static, s2, s1) for s1, s2 in zip(soft, stiff))
        self._max_normal = np.zeros(c.point_count)

    def separations(self, state: BodyState) -> np.ndarray:
        """Separation (m, < 0 overlapping) of each contact point now, per point in
        manifold order: the separation at the start of the step, plus how far the two
        material points that touched there have moved apart along the normal."""
        c = self.prepared
        moved = state.position[self._rows] - c.centre
        turned = state.angle[self._rows] - self._start_angle
        cos_less_1, sin = np.cos(turned) - 1.0, np.sin(turned)
        # ((R - I) r) . n = (cos - 1) (r . n) + sin (r x n) for a turn R of the lever arm r.
        a, b = c.a, c.b
        return (np.einsum("ij,ij->i", moved[b] - moved[a], c.normal)
                + cos_less_1[b] * self._r_dot_n_b + sin[b] * self._r_cross_n_b
                - cos_less_1[a] * self._r_dot_n_a - sin[a] * self._r_cross_n_a - c.depth)

    def solve_substep(self, state: BodyState, h: float, use_bias: bool) -> None:
        """One pass of ``iterations`` sweeps on ``state``: warm start and soft solve
        (``use_bias``), or relax (rigid, no push; skipped when ``soft.relax`` is off).

        The biased pass must come before the sub-step's position update, the relax
        pass after it.
        """
        settings = self.settings
        c = self.prepared
        if not c.point_count or (not use_bias and not self.soft.relax):
            return
        velocity = state.velocity[self._rows]
        if use_bias:
            velocity = self.apply_impulses(c, velocity, c.normal_total, c.tangent_total)
            separation = self._separation if self._separation is not None else self.separations(state)
            self._separation = None                             # positions move next
        else:
            separation = self._separation = self.separations(state)
        separation = separation[c.order]
        opened = separation > 0.0
        target = np.where(opened, -separation / h, 0.0)       # closing allowed up to s / h (m/s)
        if use_bias:
            push = np.minimum(-self._bias_rate * separation, settings.max_push_velocity)
            target = np.where(opened, target, push)
            mass_scale = np.where(opened, 1.0, self._mass_scale)
            impulse_scale = np.where(opened, 0.0, self._impulse_scale)
        else:
            mass_scale, impulse_scale = np.ones(c.point_count), np.zeros(c.point_count)
        normal, tangent = c.normal_total[c.order], c.tangent_total[c.order]
        kernel(self.backend)(velocity, c.rows, settings.iterations, normal, tangent, target, mass_scale,
                                 impulse_scale)
        c.normal_total[c.order], c.tangent_total[c.order] = normal, tangent
        if use_bias:
            np.maximum(self._max_normal, c.normal_total, out=self._max_normal)
        state.velocity[self._rows] = velocity * state.dynamic[self._rows, None]

    def end_step(self, state: BodyState, h: float) -> None:
        """Restitution, then remember the impulses and fill ``stats``.

        Restitution: one sweep over the points that pushed in some sub-step and whose
        closing speed at the start of the step earns a bounce, aiming at that bounce
        (:func:`~solutions.solver.contact_sweeps.contact_target` without a push).
        """
        c = self.prepared
        if c.point_count:
            rebound = contact_targets(c.normal_velocity, c.restitution, np.zeros(c.point_count), h, self.settings,
                                      0.0)
            bounce = (rebound > 0.0) & (self._max_normal > 0.0)
            if bounce.any():
                velocity = state.velocity[self._rows]
                normal, tangent = c.normal_total[c.order], c.tangent_total[c.order]
                kernel(self.backend)(velocity, c.rows, 1, normal, tangent, rebound[c.order],
                                     bounce[c.order].astype(float), np.zeros(c.point_count),
                                     use_friction=False, use_block=False)
                c.normal_total[c.order], c.tangent_total[c.order] = normal, tangent
                state.velocity[self._rows] = velocity * state.dynamic[self._rows, None]
        self.end_contacts(c, h)
