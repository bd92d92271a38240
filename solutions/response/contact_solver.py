"""Sequential impulses: the iterative contact solver of box2d-lite, Box2D and Chipmunk.

One impulse per contact point is not enough when contacts share bodies (a stack, a
pyramid): fixing one contact disturbs its neighbours.  Sequential impulses (projected
Gauss-Seidel) sweeps over all contact points again and again, each time applying the
impulse that fixes one point given everything else.  The sweeps converge to the
solution of the global problem (the LCP that a "global" solver sets up with the
Jacobian); stopping after a fixed number of sweeps trades accuracy for a predictable
cost.

Every technique has a switch in :class:`SolverSettings`, so a learner can turn one off
and watch what changes: accumulated impulses, warm starting, friction, rotation, and
four ways to fix penetration.

Calling contract (how ``World.step`` uses the solver)
-----------------------------------------------------
``manifolds`` is a list of ``(i, j, contact)`` in which ``contact.normal`` points from
``bodies[i]`` to ``bodies[j]``.  One solver object lives as long as the world (it
remembers last step's impulses for warm starting); body indices must keep their
meaning from one step to the next (call :meth:`ContactSolver.reset` after removing
bodies)::

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
2. Prestep, per contact point (vectorised over all points): lever arms ``r_A``, ``r_B`` from the centres of mass;
   effective masses along ``n`` and along the tangent ``t = (n_y, -n_x)``; the
   restitution target ``-e v_n`` from the velocity before any impulse, used only when
   the closing speed exceeds ``restitution_threshold`` (so resting contacts do not
   bounce); for ``"baumgarte"`` the bias ``beta / dt * max(depth - slop, 0)``.  The
   target separating speed is the larger of the two.
3. Warm start: apply the accumulated impulses remembered from the last step, matched by
   ``(body pair, feature id)`` (or, when ``Contact.feature_ids`` is None, by the nearest
   old point within ``warm_start_match_distance``), scaled by ``dt / previous dt``.
4. ``iterations`` sweeps; per point the normal impulse, then the friction impulse.
   With ``accumulate_impulses`` the running total is clamped (normal >= 0, friction
   within ``+-mu`` times the normal total), so a sweep can take back what an earlier
   one overdid; without it each increment is clamped and impulses can only grow.
   The points are visited colour by colour (:func:`sweep_order`: the points of one
   colour share no movable body).  :func:`sweep_loop` visits them one at a time with
   plain Python floats and is the readable reference; :func:`sweep_batched` solves a
   whole colour at once with numpy, which gives the same result up to rounding and is
   faster when colours hold many points (``settings.sweep`` chooses).
5. ``"split_impulse"`` only: the same sweeps on separate pseudo-velocities that push
   overlapping bodies apart at ``beta / dt * max(depth - slop, 0)``; they move the
   positions in :meth:`~ContactSolver.apply_pseudo_velocities` and are then dropped,
   so they add no kinetic energy.
6. Write the velocities back, remember the impulses, fill :attr:`ContactSolver.stats`.

Pair coefficients are products, as in pymunk: e = e_A e_B, mu = mu_A mu_B.  SI units.

Run ``python -m solutions.response.contact_solver`` for the time per step of the
contacts of a pyramid of boxes.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..body import Body
from ..contact import Contact

POSITION_CORRECTIONS = ("none", "baumgarte", "projection", "split_impulse")
SWEEPS = ("auto", "loop", "batched")


@dataclass
class SolverSettings:
    """Switches and constants of :class:`ContactSolver`.

    Attributes
    ----------
    iterations : int
        Velocity sweeps per step (also the number of pseudo-velocity sweeps).
    accumulate_impulses : bool
        Clamp the accumulated impulse (normal >= 0), not each increment.
    warm_starting : bool
        Start from last step's impulses.  Needs ``accumulate_impulses`` (without it
        there is no total to remember); ignored otherwise.
    position_correction : str
        ``"none"``, ``"baumgarte"`` (velocity bias), ``"projection"`` (linear projection
        after integration) or ``"split_impulse"`` (separate pseudo-velocities).
    baumgarte : float
        beta in [0, 1] (dimensionless): fraction of the overlap beyond ``slop``
        removed per step by ``"baumgarte"`` and by ``"split_impulse"``.
    correction_percent : float
        Fraction in [0, 1] of the overlap beyond ``slop`` removed by ``"projection"``.
    slop : float
        Overlap allowed to remain (m).
    restitution_threshold : float
        Closing speed (m/s) below which e is treated as 0.
    friction : bool
        Apply Coulomb friction.
    rotation : bool
        False skips every angular term (enough for circles without friction).
    warm_start_match_distance : float
        Largest distance (m) between an old and a new contact point matched for warm
        starting when the contact has no feature ids.
    sweep : str
        ``"loop"``: :func:`sweep_loop`, plain Python floats, one point at a time (the
        reference); ``"batched"``: :func:`sweep_batched`, numpy, one colour at a time;
        ``"auto"``: batched when there are many points per colour.  Same results up
        to rounding.
    """

    iterations: int = 10
    accumulate_impulses: bool = True
    warm_starting: bool = True
    position_correction: str = "baumgarte"
    baumgarte: float = 0.2
    correction_percent: float = 0.8
    slop: float = 0.005
    restitution_threshold: float = 1.0
    friction: bool = True
    rotation: bool = True
    warm_start_match_distance: float = 0.05
    sweep: str = "auto"

    def __post_init__(self):
        if self.position_correction not in POSITION_CORRECTIONS:
            raise ValueError(f"position_correction must be one of {POSITION_CORRECTIONS}, "
                             f"got {self.position_correction!r}")
        if self.sweep not in SWEEPS:
            raise ValueError(f"sweep must be one of {SWEEPS}, got {self.sweep!r}")
        if int(self.iterations) != self.iterations or self.iterations < 0:
            raise ValueError(f"iterations must be an integer >= 0, got {self.iterations}")
        for name in ("baumgarte", "correction_percent"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(f"{name} must be in [0, 1], got {getattr(self, name)}")
        for name in ("slop", "restitution_threshold", "warm_start_match_distance"):
            if not getattr(self, name) >= 0.0:
                raise ValueError(f"{name} must be >= 0, got {getattr(self, name)}")


@dataclass
class SolverStats:
    """What one call of :meth:`ContactSolver.solve` saw and did.

    Attributes
    ----------
    manifolds, contact_points : int
        Manifolds and contact points solved.
    total_normal_impulse : float
        Sum over the points of the normal impulse of this step, warm start included
        (N s); divided by ``dt`` it is the total contact force (N).
    total_pseudo_impulse : float
        The same for the split-impulse pseudo-velocities (N s); 0 in other modes.
    max_penetration : float
        Largest contact depth in the manifolds (m).
    warm_started_points : int
        Points that found an impulse from the previous step.
    """

    manifolds: int = 0
    contact_points: int = 0
    total_normal_impulse: float = 0.0
    total_pseudo_impulse: float = 0.0
    max_penetration: float = 0.0
    warm_started_points: int = 0


class ContactSolver:
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

    def __init__(self, settings: SolverSettings | None = None):
        self.settings = SolverSettings() if settings is None else settings
        self.stats = SolverStats()
        self.contact_impulses: list[tuple] = []
        self.reset()

    def reset(self) -> None:
        """Forget last step's impulses and pending corrections (for example after
        bodies were removed and indices changed meaning).

        >>> ContactSolver().reset()
        """
        self._impulses_by_feature: dict[tuple, tuple[float, float]] = {}
        self._impulses_by_point: dict[tuple[int, int], list[tuple[float, float, float, float]]] = {}
        self._previous_dt: float | None = None
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
        settings = self.settings
        if not dt > 0.0:
            raise ValueError(f"dt must be > 0 s, got {dt}")
        accumulate = settings.accumulate_impulses
        warm_start = settings.warm_starting and accumulate
        dt_ratio = 1.0 if self._previous_dt is None else dt / self._previous_dt
        self._pseudo_velocities = {}

        # 1. The bodies in contact, numbered 0..n-1 here; velocity rows are (vx, vy, w).
        local: dict[int, int] = {}
        for i, j, _ in manifolds:
            if i == j:
                raise ValueError(f"a body cannot touch itself: manifold ({i}, {j})")
            local.setdefault(i, len(local))
            local.setdefault(j, len(local))
        members = [bodies[index] for index in local]
        velocity = np.array([(*body.velocity.tolist(), float(body.angular_velocity)) for body in members],
                            dtype=float).reshape(-1, 3)
        centre = np.array([body.position.tolist() for body in members], dtype=float).reshape(-1, 2)
        inverse_mass = np.array([body.inverse_mass for body in members], dtype=float)
        inverse_inertia = np.array([body.inverse_inertia for body in members], dtype=float)
        if not settings.rotation:
            velocity[:, 2] = 0.0
            inverse_inertia[:] = 0.0

        # 2. Prestep, all contact points at once.
        counts = [len(contact.points) for _, _, contact in manifolds]
        point_count = sum(counts)
        a = np.repeat(np.array([local[i] for i, _, _ in manifolds], dtype=int), counts)
        b = np.repeat(np.array([local[j] for _, j, _ in manifolds], dtype=int), counts)
        normal = np.repeat(np.array([c.normal for _, _, c in manifolds]).reshape(-1, 2), counts, axis=0)
        point = np.concatenate([c.points for _, _, c in manifolds]) if manifolds else np.zeros((0, 2))
        depth = np.concatenate([c.depths for _, _, c in manifolds]) if manifolds else np.zeros(0)
        restitution = np.repeat([bodies[i].restitution * bodies[j].restitution for i, j, _ in manifolds], counts)
        friction = np.repeat([bodies[i].friction * bodies[j].friction for i, j, _ in manifolds], counts)
        if not settings.friction:
            friction[:] = 0.0
        nx, ny = normal[:, 0], normal[:, 1]
        r_a, r_b = point - centre[a], point - centre[b]
        rn_a = r_a[:, 0] * ny - r_a[:, 1] * nx       # r x n
        rn_b = r_b[:, 0] * ny - r_b[:, 1] * nx
        rt_a = -(r_a[:, 0] * nx + r_a[:, 1] * ny)    # r x t with t = (ny, -nx)
        rt_b = -(r_b[:, 0] * nx + r_b[:, 1] * ny)
        ima, imb = inverse_mass[a], inverse_mass[b]
        iia, iib = inverse_inertia[a], inverse_inertia[b]
        k_normal = ima + imb + iia * rn_a**2 + iib * rn_b**2
        k_tangent = ima + imb + iia * rt_a**2 + iib * rt_b**2
        # A point between two static bodies gets mass 0: no impulse can move them.
        mass_normal = np.divide(1.0, k_normal, out=np.zeros(point_count), where=k_normal > 0.0)
        mass_tangent = np.divide(1.0, k_tangent, out=np.zeros(point_count), where=k_tangent > 0.0)
        va, vb = velocity[a], velocity[b]
        normal_velocity = ((vb[:, 0] - va[:, 0]) * nx + (vb[:, 1] - va[:, 1]) * ny
                           + vb[:, 2] * rn_b - va[:, 2] * rn_a)
        target = np.where(normal_velocity < -settings.restitution_threshold, -restitution * normal_velocity, 0.0)
        position_bias = settings.baumgarte / dt * np.maximum(depth - settings.slop, 0.0)
        if settings.position_correction == "baumgarte":
            target = np.maximum(target, position_bias)

        # 3. Warm start from last step's accumulated impulses.
        point_keys = self._point_keys(manifolds)
        normal_total = np.zeros(point_count)
        tangent_total = np.zeros(point_count)
        if warm_start:
            self._recall_impulses(manifolds, point_keys, normal_total, tangent_total)
            normal_total *= dt_ratio
            tangent_total *= dt_ratio if settings.friction else 0.0
            impulse = normal_total[:, None] * normal + tangent_total[:, None] * np.stack([ny, -nx], axis=1)
            np.add.at(velocity, a, -np.column_stack([ima[:, None] * impulse,
                                                     iia * (r_a[:, 0] * impulse[:, 1] - r_a[:, 1] * impulse[:, 0])]))
            np.add.at(velocity, b, np.column_stack([imb[:, None] * impulse,
                                                    iib * (r_b[:, 0] * impulse[:, 1] - r_b[:, 1] * impulse[:, 0])]))
        warm_started = int(np.count_nonzero(normal_total)) if warm_start else 0

        # 4. Velocity sweeps, colour by colour (see sweep_order).
        order, bounds = sweep_order(a, b, inverse_mass + inverse_inertia > 0.0)
        columns = [x[order] for x in (a, b, nx, ny, rn_a, rn_b, rt_a, rt_b, ima, imb, iia, iib,
                                      mass_normal, mass_tangent)]
        batched = (settings.sweep == "batched"
                   or (settings.sweep == "auto" and point_count >= BATCH_MIN_POINTS_PER_COLOUR * (len(bounds) - 1)))
        sweep = sweep_batched if batched else sweep_loop
        sweep_normal, sweep_tangent = normal_total[order], tangent_total[order]
        velocity = sweep(velocity, columns, target[order], friction[order], bounds,
                         settings.iterations, accumulate, sweep_normal, sweep_tangent)
        normal_total[order], tangent_total[order] = sweep_normal, sweep_tangent

        # 5. Split impulse: the same sweeps on pseudo-velocities, no friction, no warm start.
        pseudo_total = 0.0
        if settings.position_correction == "split_impulse" and point_count:
            pseudo_impulse = np.zeros(point_count)
            pseudo_velocity = sweep(np.zeros_like(velocity), columns, position_bias[order], np.zeros(point_count),
                                    bounds, settings.iterations, accumulate, pseudo_impulse, np.zeros(point_count))
            pseudo_total = float(pseudo_impulse.sum())
            self._pseudo_velocities = {index: tuple(pseudo_velocity[k].tolist())
                                       for index, k in local.items() if not members[k].is_static}

        # 6. Write back, remember the impulses for warm starting, report.
        for k, body in enumerate(members):
            if body.is_static:
                continue
            body.velocity = velocity[k, :2].copy()
            if inverse_inertia[k] > 0.0:
                body.angular_velocity = float(velocity[k, 2])
        self._remember_impulses(point_keys, point, normal_total, tangent_total)
        global_index = list(local)
        self.contact_impulses = [(global_index[ka], global_index[kb], (px, py), pn, pt)
                                 for ka, kb, (px, py), pn, pt in zip(a.tolist(), b.tolist(), point.tolist(),
                                                                     normal_total.tolist(), tangent_total.tolist())]
        self._poses_at_solve = {index: (*centre[k].tolist(), float(members[k].angle)) for index, k in local.items()}
        self._previous_dt = dt
        self.stats = SolverStats(manifolds=len(manifolds), contact_points=point_count,
                                 total_normal_impulse=float(normal_total.sum()),
                                 total_pseudo_impulse=pseudo_total,
                                 max_penetration=float(depth.max(initial=0.0)),
                                 warm_started_points=warm_started)

    # Warm-starting memory: impulses keyed by (pair, feature id), or by point position
    # for manifolds without feature ids.
    @staticmethod
    def _point_keys(manifolds) -> list[tuple]:
        """``(pair, feature id or None)`` of every contact point, pair = (low, high) index."""
        keys = []
        for i, j, contact in manifolds:
            pair = (i, j) if i < j else (j, i)
            features = contact.feature_ids if contact.feature_ids is not None else (None,) * len(contact.points)
            keys.extend((pair, feature) for feature in features)
        return keys

    def _recall_impulses(self, manifolds, point_keys, normal_total, tangent_total) -> None:
        """Fill in the impulses remembered for each point (0 where nothing matches)."""
        first = 0
        for i, j, contact in manifolds:
            count = len(contact.points)
            if contact.feature_ids is not None:
                for k in range(first, first + count):
                    old = self._impulses_by_feature.get(point_keys[k])
                    if old is not None:
                        normal_total[k], tangent_total[k] = old
            else:
                unmatched = list(self._impulses_by_point.get((min(i, j), max(i, j)), ()))
                for k, (px, py) in enumerate(contact.points.tolist(), start=first):
                    if not unmatched:
                        break
                    distances = [math.hypot(ox - px, oy - py) for ox, oy, _, _ in unmatched]
                    nearest = int(np.argmin(distances))
                    if distances[nearest] <= self.settings.warm_start_match_distance:
                        normal_total[k], tangent_total[k] = unmatched.pop(nearest)[2:]
            first += count

    def _remember_impulses(self, point_keys, point, normal_total, tangent_total) -> None:
        self._impulses_by_feature = {}
        self._impulses_by_point = {}
        for (pair, feature), (px, py), pn, pt in zip(point_keys, point.tolist(),
                                                     normal_total.tolist(), tangent_total.tolist()):
            if feature is None:
                self._impulses_by_point.setdefault(pair, []).append((px, py, pn, pt))
            else:
                self._impulses_by_feature[(pair, feature)] = (pn, pt)

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


#: ``sweep="auto"`` uses :func:`sweep_batched` when there are at least this many
#: contact points per colour (measured break-even: one numpy batch costs about as much
#: as 20 points of the Python loop).
BATCH_MIN_POINTS_PER_COLOUR = 20


def sweep_order(body_a: np.ndarray, body_b: np.ndarray, movable: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Order in which the sweeps visit the contact points, grouped by colour.

    Greedy colouring: each point, in manifold order, takes the smallest colour not yet
    used by a movable body it touches, so the points of one colour share no movable
    body and can be solved at the same time (:func:`sweep_batched`) with the same
    result as one after the other (:func:`sweep_loop`).  Static bodies may appear in
    many points of one colour: their velocity never changes.

    Parameters
    ----------
    body_a, body_b : numpy.ndarray of int, shape (m,)
        Local body numbers of each point.
    movable : numpy.ndarray of bool, shape (n,)
        Whether each body can move (finite mass or inertia).

    Returns
    -------
    order : numpy.ndarray of int, shape (m,)
        Point indices, colour by colour (stable within a colour).
    bounds : numpy.ndarray of int, shape (colours + 1,)
        Colour ``c`` is ``order[bounds[c]:bounds[c + 1]]``.

    Examples
    --------
    Points 0-1, 1-2 and 0-2 between a static body 0 and movable bodies 1 and 2:
    points 0 and 2 share only the static body (colour 0), point 1 shares body 1 with
    point 0 and body 2 with point 2 (colour 1).

    >>> order, bounds = sweep_order(np.array([0, 1, 0]), np.array([1, 2, 2]), np.array([False, True, True]))
    >>> order.tolist(), bounds.tolist()
    ([0, 2, 1], [0, 2, 3])
    """
    used = [0] * len(movable)  # bit c set: the body already has a point of colour c
    movable = movable.tolist()
    colour = []
    for i, j in zip(body_a.tolist(), body_b.tolist()):
        taken = (used[i] if movable[i] else 0) | (used[j] if movable[j] else 0)
        c = ((~taken) & (taken + 1)).bit_length() - 1  # lowest free colour
        colour.append(c)
        if movable[i]:
            used[i] |= 1 << c
        if movable[j]:
            used[j] |= 1 << c
    colour = np.array(colour, dtype=int)
    order = np.argsort(colour, kind="stable")
    bounds = np.searchsorted(colour[order], np.arange(colour.max(initial=-1) + 2))
    return order, bounds


def sweep_loop(velocity, columns, target, friction, bounds, iterations, accumulate,
               normal_total, tangent_total) -> np.ndarray:
    """Sequential-impulse sweeps, one contact point at a time (the reference version).

    ``velocity`` (n, 3) rows ``(vx, vy, w)`` of the bodies in contact; ``columns`` the
    per-point arrays ``(a, b, nx, ny, rn_a, rn_b, rt_a, rt_b, 1/m_a, 1/m_b, 1/I_a,
    1/I_b, normal mass, tangent mass)`` in sweep order, where ``rn = r x n`` and
    ``rt = r x t`` with ``t = (ny, -nx)``; ``target`` the separating normal velocity
    wanted at each point (m/s); ``friction`` mu per point.  ``normal_total`` and
    ``tangent_total`` hold the accumulated impulses (N s) and are updated in place.
    ``bounds`` is unused here (the loop visits points in order).  Returns the new
    velocities.

    >>> velocity = np.array([[0.0, 0.0, 0.0], [0.0, -1.0, 0.0]])   # static ground, falling disc
    >>> columns = [np.array([x]) for x in (0, 1, 0.0, 1.0, 0.0, 0.0, 0.0, 0.5, 0.0, 1.0, 0.0, 2.0, 1.0, 1 / 1.5)]
    >>> totals = np.zeros(1), np.zeros(1)
    >>> sweep_loop(velocity, columns, np.zeros(1), np.zeros(1), None, 1, True, *totals).tolist()
    [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
    """
    vx, vy, w = velocity.T.tolist()
    rows = list(zip(*(column.tolist() for column in columns), target.tolist(), friction.tolist()))
    normal_list, tangent_list = normal_total.tolist(), tangent_total.tolist()
    for _ in range(iterations):
        for k, (a, b, nx, ny, rn_a, rn_b, rt_a, rt_b, ima, imb, iia, iib,
                mass_normal, mass_tangent, wanted, mu) in enumerate(rows):
            wa, wb = w[a], w[b]
            # Normal: v_n = (v_B + w_B x r_B - v_A - w_A x r_A) . n
            normal_velocity = (vx[b] - vx[a]) * nx + (vy[b] - vy[a]) * ny + wb * rn_b - wa * rn_a
            normal_change = mass_normal * (wanted - normal_velocity)
            if accumulate:
                old = normal_list[k]
                total = max(old + normal_change, 0.0)
                normal_change = total - old
            else:
                normal_change = max(normal_change, 0.0)
                total = normal_list[k] + normal_change
            normal_list[k] = total
            vx[a] -= ima * normal_change * nx
            vy[a] -= ima * normal_change * ny
            wa -= iia * rn_a * normal_change
            vx[b] += imb * normal_change * nx
            vy[b] += imb * normal_change * ny
            wb += iib * rn_b * normal_change
            if mu != 0.0:
                # Friction along t = (ny, -nx), Coulomb bound mu times the normal impulse.
                tangent_velocity = (vx[b] - vx[a]) * ny - (vy[b] - vy[a]) * nx + wb * rt_b - wa * rt_a
                tangent_change = -mass_tangent * tangent_velocity
                if accumulate:
                    bound = mu * total
                    old = tangent_list[k]
                    new = min(max(old + tangent_change, -bound), bound)
                    tangent_change = new - old
                else:
                    bound = mu * normal_change
                    tangent_change = min(max(tangent_change, -bound), bound)
                    new = tangent_list[k] + tangent_change
                tangent_list[k] = new
                vx[a] -= ima * tangent_change * ny
                vy[a] += ima * tangent_change * nx
                wa -= iia * rt_a * tangent_change
                vx[b] += imb * tangent_change * ny
                vy[b] -= imb * tangent_change * nx
                wb += iib * rt_b * tangent_change
            w[a], w[b] = wa, wb
    normal_total[:] = normal_list
    tangent_total[:] = tangent_list
    return np.array([vx, vy, w], dtype=float).T.reshape(-1, 3)


def sweep_batched(velocity, columns, target, friction, bounds, iterations, accumulate,
                  normal_total, tangent_total) -> np.ndarray:
    """The same sweeps as :func:`sweep_loop`, one colour (numpy batch) at a time.

    Within a colour no movable body appears twice, so solving its points together
    gives what the loop gives point by point, up to rounding.  Same parameters and
    result as :func:`sweep_loop`; ``bounds`` delimits the colours.

    >>> velocity = np.array([[0.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
    >>> columns = [np.array([x]) for x in (0, 1, 0.0, 1.0, 0.0, 0.0, 0.0, 0.5, 0.0, 1.0, 0.0, 2.0, 1.0, 1 / 1.5)]
    >>> totals = np.zeros(1), np.zeros(1)
    >>> sweep_batched(velocity, columns, np.zeros(1), np.zeros(1), np.array([0, 1]), 1, True, *totals).tolist()
    [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
    """
    a, b, nx, ny, rn_a, rn_b, rt_a, rt_b, ima, imb, iia, iib, mass_normal, mass_tangent = columns
    # Per point and body (axis 0: A, B): Jacobian rows J (v_n = sum of J . (vx, vy, w))
    # and the velocity change per unit impulse M^-1 J^T.
    jacobian_normal = np.stack([np.column_stack([-nx, -ny, -rn_a]), np.column_stack([nx, ny, rn_b])])
    response_normal = jacobian_normal * np.stack([np.column_stack([ima, ima, iia]),
                                                  np.column_stack([imb, imb, iib])])
    jacobian_tangent = np.stack([np.column_stack([-ny, nx, -rt_a]), np.column_stack([ny, -nx, rt_b])])
    response_tangent = jacobian_tangent * np.stack([np.column_stack([ima, ima, iia]),
                                                    np.column_stack([imb, imb, iib])])
    batches = []
    for start, stop in zip(bounds[:-1].tolist(), bounds[1:].tolist()):
        part = slice(start, stop)
        batches.append((part, np.concatenate([a[part], b[part]]), stop - start,
                        jacobian_normal[:, part], response_normal[:, part],
                        jacobian_tangent[:, part], response_tangent[:, part],
                        mass_normal[part], mass_tangent[part], target[part], friction[part],
                        bool(np.any(friction[part] != 0.0))))
    velocity = velocity.copy()
    for _ in range(iterations):
        for (part, bodies_ab, size, j_normal, m_normal, j_tangent, m_tangent,
             mass_n, mass_t, wanted, mu, has_friction) in batches:
            v = velocity[bodies_ab].reshape(2, size, 3)
            normal_velocity = (v * j_normal).sum(axis=2).sum(axis=0)
            normal_change = mass_n * (wanted - normal_velocity)
            total = normal_total[part]  # a view: updated in place
            if accumulate:
                new = np.maximum(total + normal_change, 0.0)
                normal_change = new - total
                total[:] = new
            else:
                np.maximum(normal_change, 0.0, out=normal_change)
                total += normal_change
            v += m_normal * normal_change[:, None]
            if has_friction:
                tangent_velocity = (v * j_tangent).sum(axis=2).sum(axis=0)
                tangent_change = -mass_t * tangent_velocity
                bound = mu * (total if accumulate else normal_change)
                tangent = tangent_total[part]
                if accumulate:
                    new = np.clip(tangent + tangent_change, -bound, bound)
                    tangent_change = new - tangent
                    tangent[:] = new
                else:
                    tangent_change = np.clip(tangent_change, -bound, bound)
                    tangent += tangent_change
                v += m_tangent * tangent_change[:, None]
            velocity[bodies_ab] = v.reshape(-1, 3)
    return velocity


def pyramid_contacts(base: int = 20, size: float = 1.0, gap: float = 0.125,
                     depth: float = 0.001) -> tuple[list[Body], list[tuple[int, int, Contact]]]:
    """Bodies and hand-made 2-point manifolds of a pyramid of boxes on static ground.

    Row ``r`` (0 at the bottom) holds ``base - r`` boxes of side ``size`` (m), ``gap``
    (m) apart, each resting on the two boxes below it, every contact ``depth`` (m)
    deep.  ``base = 20`` gives 210 boxes and 800 contact points.  Used to time the
    solver without a narrow phase.

    >>> bodies, manifolds = pyramid_contacts(base=3)
    >>> len(bodies), len(manifolds), sum(len(c.points) for _, _, c in manifolds)
    (7, 9, 18)
    """
    bodies = [Body.box(2.0 * base * (size + gap), size, position=(0.0, -size / 2), is_static=True)]
    manifolds = []
    below: list[int] = []
    pitch = size + gap
    for row in range(base):
        this_row = []
        for column in range(base - row):
            x = (column - (base - row - 1) / 2) * pitch
            y = size / 2 + row * (size - depth)
            bodies.append(Body.box(size, size, position=(x, y), friction=0.6))
            index = len(bodies) - 1
            this_row.append(index)
            bottom = y - size / 2 + depth / 2
            supports = [0] if row == 0 else below[column:column + 2]
            for support in supports:
                left = max(x, float(bodies[support].position[0]) if support else x) - size / 2
                right = min(x, float(bodies[support].position[0]) if support else x) + size / 2
                manifolds.append((support, index, Contact((0.0, 1.0), depth, [(left, bottom), (right, bottom)],
                                                          feature_ids=("left", "right"))))
        below = this_row
    return bodies, manifolds


def main(steps: int = 20, dt: float = 1 / 60) -> None:
    """Print the time of one :meth:`ContactSolver.solve` on the contacts of pyramids.

    The boxes start each step at rest plus one step of gravity; the figure is the
    fastest of ``steps`` warm-started solves (other processes only add time).
    """
    print("pyramid contacts, time per ContactSolver.solve() (best of %d)" % steps)
    for base in (16, 20):
        bodies, manifolds = pyramid_contacts(base)
        points = sum(len(c.points) for _, _, c in manifolds)
        for iterations in (10, 30):
            for sweep in ("loop", "batched"):
                solver = ContactSolver(SolverSettings(iterations=iterations, sweep=sweep))
                elapsed = []
                for _ in range(steps):
                    for body in bodies[1:]:
                        body.velocity = np.array((0.0, -9.81 * dt))
                        body.angular_velocity = 0.0
                    start = time.perf_counter()
                    solver.solve(bodies, manifolds, dt)
                    elapsed.append(time.perf_counter() - start)
                print(f"  {len(bodies) - 1:4d} boxes {points:4d} points {iterations:3d} iterations "
                      f"{sweep:8s} {1e3 * min(elapsed):7.2f} ms")


if __name__ == "__main__":
    main()
