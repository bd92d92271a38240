"""Sequential impulses: the iterative contact solver of box2d-lite, Box2D and Chipmunk.

One impulse per contact point is not enough when contacts share bodies (a stack, a
pyramid): fixing one contact disturbs its neighbours.  Sequential impulses (projected
Gauss-Seidel) sweeps over all contact points again and again, each time applying the
impulse that fixes one point given everything else.  The sweeps converge to the
solution of the global problem (the LCP that a "global" solver sets up with the
Jacobian); stopping after a fixed number of sweeps trades accuracy for a predictable
cost.

Every technique has a switch in :class:`SolverSettings`, so a learner can turn one off
and watch what changes: accumulated impulses, warm starting, friction, rotation, the
block solver for two-point manifolds, the sweep order, and four ways to fix
penetration.

Calling contract
----------------
``manifolds`` is a list of ``(i, j, contact)`` in which ``contact.normal`` points from
``bodies[i]`` to ``bodies[j]``.  One solver object lives as long as the world (it
remembers last step's impulses for warm starting); body indices must keep their
meaning from one step to the next (call :meth:`ContactSolver.reset` after removing
bodies).  A simple world calls it in one go::

    def step(self, dt):
        manifolds = self.find_contacts()        # [(i, j, Contact), ...] at the current poses
        for body in self.dynamic_bodies:        # 1. forces -> velocities
            body.velocity = body.velocity + dt * (self.gravity + body.force / body.mass)
            body.angular_velocity += dt * body.torque * body.inverse_inertia
        self.solver.solve(self.bodies, manifolds, dt)         # 2. impulses -> velocities
        for body in self.dynamic_bodies:        # 3. velocities -> positions
            body.position = body.position + dt * body.velocity
            body.angle += dt * body.angular_velocity
        self.solver.finish_step(self.bodies, manifolds, dt)   # 4. position correction
        self.last_stats = self.solver.stats     # SolverStats of this step

:meth:`ContactSolver.solve` is :meth:`~ContactSolver.begin_step` (prepare the contacts)
followed by the velocity pass and :meth:`~ContactSolver.end_step` (remember the
impulses, fill the stats).  :class:`~solutions.world.World` calls those stages one by
one, as it calls the soft step's solver: ``begin_step`` before gravity,
``solve_substep(state, h, use_bias=True)`` after it, ``solve_substep(..., use_bias=False)``
(the position correction) after the positions moved, then ``end_step``.  The
restitution targets come from the velocities the velocity pass starts from, so they
see this step's gravity either way.

:meth:`ContactSolver.finish_step` dispatches on ``settings.position_correction``:

- ``"none"``, ``"baumgarte"``: nothing (Baumgarte acts inside ``solve`` as a velocity bias);
- ``"projection"``: :meth:`ContactSolver.correct_positions` ``(bodies, manifolds)``;
- ``"split_impulse"``: :meth:`ContactSolver.apply_pseudo_velocities` ``(bodies, dt)``.

A world may call those two directly instead; either must follow ``solve`` of the same
step, after position integration, with the same ``bodies`` and ``manifolds``.

What ``solve`` does, in order
-----------------------------
1. Gather the bodies in contact: one row ``(vx, vy, w)`` per body (static bodies have
   1/m = 1/I = 0; with ``rotation=False`` every 1/I and every w is taken as 0).
2. Prestep, per contact point: lever arms and effective masses along ``n`` and along
   the tangent ``t = (n_y, -n_x)`` (:func:`~solutions.solver.contact_sweeps.prestep_point`);
   the target separating speed from the velocity before any impulse
   (:func:`~solutions.solver.contact_sweeps.contact_target`): a bounce only above
   ``restitution_threshold`` (so resting contacts do not bounce) and, for
   ``"baumgarte"``, a push out of the overlap beyond ``slop``, the larger of the two.
3. Warm start: apply the accumulated impulses remembered from the last step, matched by
   ``(body pair, feature id)`` (or, when ``Contact.feature_ids`` is None or names a
   feature the pair did not have, by the nearest old point of the pair within
   ``warm_start_match_distance``), scaled by ``dt / previous dt``.
4. ``iterations`` sweeps, manifold by manifold: the solver kernel
   (:func:`~solutions.solver.kernel.solve_constraints`) with rigid rows.  Per
   manifold, the friction impulse of each point, then the normal impulses: the two of
   a two-point manifold together as one 2x2 linear complementarity problem (the block
   solver of Box2D, :func:`~solutions.solver.kernel.block_normal_impulses`;
   ``block_solver=False`` or an ill-conditioned pair solves them one after the other).
   With ``accumulate_impulses`` the running totals are clamped (normal >= 0, friction
   within ``+-mu`` times the normal total so far), so a sweep can take back what an
   earlier one overdid; without it each increment is clamped, impulses can only grow,
   and each point's friction follows its normal.  The manifolds are visited in the
   order of :func:`~solutions.solver.sweep_order.sweep_order`: as given
   (``order="manifolds"``: one sweep carries an impulse through a whole stack) or
   colour by colour (``"colours"``).
   ``backend`` chooses the readable loop or its compiled twin (equal to 1e-12).
5. ``"split_impulse"`` only: the same sweeps on separate pseudo-velocities that push
   overlapping bodies apart at ``beta / dt * max(depth - slop, 0)``; they move the
   positions in :meth:`~ContactSolver.apply_pseudo_velocities` and are then dropped,
   so they add no kinetic energy.
6. Write the velocities back, remember the impulses, fill :attr:`ContactSolver.stats`.

Pair coefficients are products, as in pymunk: e = e_A e_B, mu = mu_A mu_B.  SI units.

``python bench/bench_solver.py`` times the kernel's two twins on the contacts of
pyramids of boxes.
"""
from __future__ import annotations

import math

import numpy as np

from ..body import Body
from ..body_state import BodyState
from ..contact import Contact
from ..solver.kernel import kernel
from .contact_preparation import BACKENDS, ContactPreparation, PreparedContacts, closing_speeds, contact_targets
from .solver_settings import ORDERS, POSITION_CORRECTIONS, SolverSettings, SolverStats

# The settings and figures live in solver_settings.py (the soft step reads them too).
__all__ = ["ContactSolver", "SolverSettings", "SolverStats", "POSITION_CORRECTIONS", "ORDERS", "BACKENDS"]

class ContactSolver(ContactPreparation):
    """Sequential-impulse contact solver; the module docstring gives the contract.

    Parameters
    ----------
    settings : SolverSettings, optional
        Switches and constants; the defaults follow box2d-lite.

    Attributes
    ----------
    settings : SolverSettings
    stats : SolverStats
        Figures of the last :meth:`solve`.
    contact_impulses : list of tuple
        One ``(i, j, point, normal_impulse, tangent_impulse)`` per contact point of the
        last :meth:`solve`; impulses in N s, given to body j and the opposite to body
        i, the tangent one along ``(n_y, -n_x)``.

    Examples
    --------
    A 1 kg box falling at 1 m/s onto static ground is stopped in one step:

    >>> ground = Body.box(10.0, 1.0, position=(0.0, -0.5), is_static=True)
    >>> box = Body.box(1.0, 1.0, position=(0.0, 0.5), velocity=(0.0, -1.0))
    >>> contact = Contact((0.0, 1.0), 0.0, [(-0.5, 0.0), (0.5, 0.0)], feature_ids=("left", "right"))
    >>> solver = ContactSolver(SolverSettings(position_correction="none"))
    >>> solver.solve([ground, box], [(0, 1, contact)], dt=1 / 60)
    >>> bool(np.abs(box.velocity).max() < 1e-12), round(solver.stats.total_normal_impulse, 12)
    (True, 1.0)
    """

    def reset(self) -> None:
        """Forget last step's impulses and pending corrections (for example after
        bodies were removed and indices changed meaning).

        >>> ContactSolver().reset()
        """
        super().reset()
        self._pseudo_velocities: dict[int, tuple[float, float, float]] = {}
        self._poses_at_solve: dict[int, tuple[float, float, float]] = {}

    def solve(self, bodies: list[Body], manifolds: list[tuple[int, int, Contact]], dt: float) -> None:
        """Apply the contact impulses of one step of ``dt`` to the bodies' velocities.

        Call after forces have been integrated into velocities and before positions
        are integrated.  Changes ``velocity`` (the array is replaced) and
        ``angular_velocity`` of the dynamic bodies in contact, and fills :attr:`stats`.

        Parameters
        ----------
        bodies : list of Body
        manifolds : list of (int, int, Contact)
            ``(i, j, contact)`` with ``contact.normal`` from ``bodies[i]`` to ``bodies[j]``.
        dt : float
            Time step (s), > 0.

        Examples
        --------
        Two 1 kg discs meeting head on at 2 m/s each with e = 1 swap velocities:

        >>> a = Body.circle(0.5, position=(-0.5, 0.0), velocity=(2.0, 0.0), restitution=1.0)
        >>> b = Body.circle(0.5, position=(0.5, 0.0), velocity=(-2.0, 0.0), restitution=1.0)
        >>> touching = Contact((1.0, 0.0), 0.0, [(0.0, 0.0)])
        >>> ContactSolver().solve([a, b], [(0, 1, touching)], dt=1 / 60)
        >>> a.velocity.tolist(), b.velocity.tolist()
        ([-2.0, 0.0], [2.0, 0.0])
        """
        self.begin_step(bodies, manifolds, dt)
        c = self.prepared
        self.write_velocities(c, self._solve_velocities(c, c.velocity, dt))
        self.end_step(None, dt)

    # The stages of the world's step (the soft step's solver has the same three) ----
    def begin_step(self, bodies: list[Body], manifolds: list[tuple[int, int, Contact]], h: float) -> None:
        """Prepare the contacts of a (sub-)step of ``h`` (s): steps 1 and 2 of the module
        docstring and the recalled impulses (applied by :meth:`solve_substep`)."""
        if not h > 0.0:
            raise ValueError(f"dt must be > 0 s, got {h}")
        self._pseudo_velocities = {}
        self._pseudo_total = 0.0
        self._bodies, self._manifolds = bodies, manifolds
        self._contacts = self.prepare(bodies, manifolds, h, block_solver=self.settings.block_solver)

    def solve_substep(self, state: BodyState, h: float, use_bias: bool) -> None:
        """``use_bias``: the velocity pass on ``state`` (warm start, sweeps, split
        impulses; after gravity, before positions move); otherwise the position
        correction (:meth:`finish_step`; after positions moved)."""
        c = self.prepared
        if not use_bias:
            self.finish_step(self._bodies, self._manifolds, h)
            return
        rows = np.array(list(c.local), dtype=int)           # world index of each member
        velocity = state.velocity[rows]
        if not self.settings.rotation:
            velocity[:, 2] = 0.0
        velocity = self._solve_velocities(c, velocity, h)
        moves = state.dynamic[rows]
        turns = moves & (c.inverse_inertia > 0.0)
        state.velocity[rows[moves], :2] = velocity[moves, :2]
        state.velocity[rows[turns], 2] = velocity[turns, 2]

    def end_step(self, state: BodyState | None, h: float) -> None:
        """Remember the impulses for the next step's warm start; fill :attr:`stats`."""
        self.end_contacts(self.prepared, h, total_pseudo_impulse=self._pseudo_total)

    def _solve_velocities(self, c: PreparedContacts, velocity: np.ndarray, dt: float) -> np.ndarray:
        """Steps 3 to 5 of the module docstring on the members' ``velocity`` rows; returns
        the new rows (the restitution targets come from ``velocity``: the closing speeds
        after this step's forces, as box2d-lite measures them)."""
        settings = self.settings
        accumulate = settings.accumulate_impulses
        # The target separating speed: restitution, or the Baumgarte bias if larger.
        position_bias = self.position_bias(c.depth, dt)
        nx, ny = c.normal[:, 0], c.normal[:, 1]
        normal_velocity = closing_speeds(velocity, c.a, c.b, nx, ny, c.columns["rn_a"], c.columns["rn_b"])
        bias_factor = settings.baumgarte if settings.position_correction == "baumgarte" else 0.0
        target = contact_targets(normal_velocity, c.restitution, c.depth, dt, settings, bias_factor)[c.order]
        velocity = self.apply_impulses(c, velocity, c.normal_total, c.tangent_total)   # 3. warm start

        # 4. Velocity sweeps, manifold by manifold in sweep order: the solver kernel with
        # rigid rows (mass scale 1, impulse scale 0) and Box2D v2's order (friction first).
        solve_constraints = kernel(self.backend)
        rigid, no_softness = np.ones(c.point_count), np.zeros(c.point_count)
        sweep_normal, sweep_tangent = c.normal_total[c.order], c.tangent_total[c.order]
        solve_constraints(velocity, c.rows, settings.iterations, sweep_normal, sweep_tangent, target, rigid,
                          no_softness, accumulate=accumulate, friction_first=accumulate)
        c.normal_total[c.order], c.tangent_total[c.order] = sweep_normal, sweep_tangent
        self._split_impulse(c, velocity, position_bias)
        return velocity

    def _split_impulse(self, c: PreparedContacts, velocity: np.ndarray, position_bias: np.ndarray) -> None:
        """Step 5 of the module docstring (with ``position_correction="split_impulse"``), and
        the poses at the solve that :meth:`correct_positions` measures from."""
        settings = self.settings
        accumulate = settings.accumulate_impulses
        solve_constraints = kernel(self.backend)
        rigid, no_softness = np.ones(c.point_count), np.zeros(c.point_count)
        # 5. Split impulse: the same sweeps on pseudo-velocities, no friction, no warm start.
        if settings.position_correction == "split_impulse" and c.point_count:
            pseudo_impulse = np.zeros(c.point_count)
            pseudo_velocity = np.zeros_like(velocity)
            solve_constraints(pseudo_velocity, c.rows, settings.iterations, pseudo_impulse, np.zeros(c.point_count),
                              position_bias[c.order], rigid, no_softness, accumulate=accumulate,
                              friction_first=accumulate, use_friction=False)
            self._pseudo_total = float(pseudo_impulse.sum())
            self._pseudo_velocities = {index: tuple(pseudo_velocity[k].tolist())
                                       for index, k in c.local.items() if not c.members[k].is_static}
        self._poses_at_solve = {index: (*c.centre[k].tolist(), float(c.members[k].angle))
                                for index, k in c.local.items()}

    def position_bias(self, depth: np.ndarray, dt: float) -> np.ndarray:
        """Separating speed (m/s) that removes ``baumgarte`` of the overlap beyond
        ``slop`` in one step of ``dt``, capped at ``max_push_velocity``: the push of
        :func:`~solutions.solver.contact_sweeps.contact_target` at rest, without bounce.

        >>> ContactSolver().position_bias(np.array([0.0, 0.015, 1.0]), dt=0.01).round(12).tolist()
        [0.0, 0.2, 3.0]
        """
        at_rest = np.zeros(len(depth))
        return contact_targets(at_rest, at_rest, depth, dt, self.settings, self.settings.baumgarte)

    def correct_positions(self, bodies: list[Body], manifolds: list[tuple[int, int, Contact]]) -> None:
        """Linear projection (``position_correction="projection"``), after integration.

        For each manifold, in order, estimate the overlap now: each point's depth from
        :meth:`solve` minus how far the two material points that touched there have
        moved apart along ``n`` since then (rotation included).  Then move the two
        bodies apart along ``n`` by ``correction_percent * max(depth_now - slop, 0)``,
        split by inverse mass (static bodies stay; angles are not changed).  Later
        manifolds see the corrections of earlier ones.

        Parameters
        ----------
        bodies : list of Body
            ``position`` arrays of dynamic bodies are replaced.
        manifolds : list of (int, int, Contact)
            The manifolds given to :meth:`solve` in this step.

        Examples
        --------
        A box resting 0.1 m deep in static ground is lifted by 80 % of 0.1 - 0.005 m:

        >>> ground = Body.box(10.0, 1.0, position=(0.0, -0.5), is_static=True)
        >>> box = Body.box(1.0, 1.0, position=(0.0, 0.4))
        >>> sunk = Contact((0.0, 1.0), 0.1, [(-0.5, -0.05), (0.5, -0.05)], feature_ids=(0, 1))
        >>> solver = ContactSolver(SolverSettings(position_correction="projection"))
        >>> solver.solve([ground, box], [(0, 1, sunk)], dt=1 / 60)
        >>> solver.correct_positions([ground, box], [(0, 1, sunk)])
        >>> round(float(box.position[1]), 12)
        0.476
        """
        settings = self.settings
        position = {}
        turn = {}
        for i, j, _ in manifolds:
            for index in (i, j):
                if index in position:
                    continue
                if index not in self._poses_at_solve:
                    raise RuntimeError("correct_positions needs solve() of the same step first")
                position[index] = bodies[index].position.tolist()
                rotated_by = float(bodies[index].angle) - self._poses_at_solve[index][2]
                turn[index] = (math.cos(rotated_by), math.sin(rotated_by))

        def material_point_now(index, px, py):
            """Where the point of body ``index`` that was at (px, py) in solve() is now."""
            x0, y0, _ = self._poses_at_solve[index]
            c, s = turn[index]
            rx, ry = px - x0, py - y0
            x, y = position[index]
            return x + c * rx - s * ry, y + s * rx + c * ry

        for i, j, contact in manifolds:
            ima, imb = float(bodies[i].inverse_mass), float(bodies[j].inverse_mass)
            if ima + imb == 0.0:
                continue
            nx, ny = contact.normal.tolist()
            deepest = 0.0
            for (px, py), depth in zip(contact.points.tolist(), contact.depths.tolist()):
                ax, ay = material_point_now(i, px, py)
                bx, by = material_point_now(j, px, py)
                deepest = max(deepest, depth - ((bx - ax) * nx + (by - ay) * ny))
            correction = settings.correction_percent * max(deepest - settings.slop, 0.0) / (ima + imb)  # kg m
            if correction == 0.0:
                continue
            position[i][0] -= ima * correction * nx
            position[i][1] -= ima * correction * ny
            position[j][0] += imb * correction * nx
            position[j][1] += imb * correction * ny
        for index, (x, y) in position.items():
            if not bodies[index].is_static:
                bodies[index].position = np.array((x, y))

    def apply_pseudo_velocities(self, bodies: list[Body], dt: float) -> None:
        """Move bodies by the split-impulse pseudo-velocities of the last :meth:`solve`.

        ``x += dt * v_pseudo``, ``angle += dt * w_pseudo``; call after position
        integration.  The pseudo-velocities are then forgotten: they never enter
        ``velocity``, so pushing bodies apart adds no kinetic energy.

        Parameters
        ----------
        bodies : list of Body
            ``position`` arrays of the moved bodies are replaced.
        dt : float
            The step's time step (s).

        Examples
        --------
        A box resting 0.105 m deep is lifted by beta = 0.2 of 0.1 m:

        >>> ground = Body.box(10.0, 1.0, position=(0.0, -0.5), is_static=True)
        >>> box = Body.box(1.0, 1.0, position=(0.0, 0.395))
        >>> sunk = Contact((0.0, 1.0), 0.105, [(-0.5, -0.05), (0.5, -0.05)], feature_ids=(0, 1))
        >>> solver = ContactSolver(SolverSettings(position_correction="split_impulse", iterations=30))
        >>> solver.solve([ground, box], [(0, 1, sunk)], dt=0.01)
        >>> box.velocity.tolist()
        [0.0, 0.0]
        >>> solver.apply_pseudo_velocities([ground, box], dt=0.01)
        >>> round(float(box.position[1]), 9)
        0.415
        """
        for index, (pvx, pvy, pw) in self._pseudo_velocities.items():
            body = bodies[index]
            body.position = body.position + dt * np.array((pvx, pvy))
            if body.inverse_inertia > 0.0:
                body.angle += dt * pw
        self._pseudo_velocities = {}

    def finish_step(self, bodies: list[Body], manifolds: list[tuple[int, int, Contact]], dt: float) -> None:
        """Position correction after position integration, as the settings ask.

        ``"projection"``: :meth:`correct_positions`; ``"split_impulse"``:
        :meth:`apply_pseudo_velocities`; ``"none"`` and ``"baumgarte"``: nothing.

        >>> ContactSolver().finish_step([], [], dt=1 / 60)
        """
        mode = self.settings.position_correction
        if mode == "projection":
            self.correct_positions(bodies, manifolds)
        elif mode == "split_impulse":
            self.apply_pseudo_velocities(bodies, dt)
