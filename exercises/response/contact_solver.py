# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/response/contact_solver.py on the
# instructor's side.
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
   ``(body pair, feature id)`` (or, when ``Contact.feature_ids`` is None or names a
   feature the pair did not have, by the nearest old point of the pair within
   ``warm_start_match_distance``), scaled by ``dt / previous dt``.
4. ``iterations`` sweeps, manifold by manifold.  Per manifold, the friction impulse
   of each point, then the normal impulses: the two of a two-point manifold together
   as one 2x2 linear complementarity problem (the block solver of Box2D,
   :func:`block_normal_impulses`; ``block_solver=False`` or an ill-conditioned pair
   solves them one after the other).  With ``accumulate_impulses`` the running totals
   are clamped (normal >= 0, friction within ``+-mu`` times the normal total so far),
   so a sweep can take back what an earlier one overdid; without it each increment
   is clamped, impulses can only grow, and each point's friction follows its normal.
   The manifolds are visited in batches that share no movable body
   (:func:`sweep_order`): in the given order (``order="manifolds"``: one sweep
   carries an impulse through a whole stack) or colour by colour (``"colours"``:
   fewer, larger batches; ``"auto"`` takes them for large scenes).  :func:`sweep_loop` visits the manifolds one at a time
   with plain Python floats and is the readable reference; :func:`sweep_batched`
   solves a whole batch at once with numpy, which gives the same result up to
   rounding and is faster when batches hold many manifolds (``settings.sweep``
   chooses).
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
from dataclasses import dataclass, replace

import numpy as np

from ..body import Body
from ..contact import Contact

POSITION_CORRECTIONS = ("none", "baumgarte", "projection", "split_impulse")
SWEEPS = ("auto", "loop", "batched")
ORDERS = ("auto", "manifolds", "colours")


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
        after integration) or ``"split_impulse"`` (separate pseudo-velocities; the
        default: measured equal or better than Baumgarte on every named scene, and
        the only one that holds the 1:1000 mass ratio, since it adds no energy).
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
        Largest distance (m) between an old and a new contact point of the same body
        pair matched for warm starting when the new point has no feature id, or one
        the pair did not have last step (the narrow phase swapped the reference face,
        or clipped a different vertex).
    sweep : str
        ``"loop"``: :func:`sweep_loop`, plain Python floats, one manifold at a time (the
        reference); ``"batched"``: :func:`sweep_batched`, numpy, one batch of
        :func:`sweep_order` at a time; ``"auto"``: batched when the batches hold many
        manifolds on average.  Same results up to rounding.
    block_solver : bool
        Solve the two normal impulses of a two-point manifold together, as one 2x2
        linear complementarity problem (Box2D's block solver,
        :func:`block_normal_impulses`), instead of one point after the other.  A face
        resting on a face then gets both impulses right in one go, without the
        spurious turn a point-by-point solve leaves behind.  Manifolds whose 2x2
        matrix is ill-conditioned (:data:`MAX_CONDITION_NUMBER`) are solved point by
        point anyway.
    """

    iterations: int = 10
    accumulate_impulses: bool = True
    warm_starting: bool = True
    position_correction: str = "split_impulse"
    baumgarte: float = 0.2
    correction_percent: float = 0.8
    slop: float = 0.005
    restitution_threshold: float = 1.0
    friction: bool = True
    rotation: bool = True
    warm_start_match_distance: float = 0.05
    sweep: str = "auto"
    block_solver: bool = True
    order: str = "auto"
    max_push_velocity: float = 3.0
    contact_hertz: float = math.inf
    contact_damping_ratio: float = 10.0
    relax: bool = True

    def __post_init__(self):
        if self.position_correction not in POSITION_CORRECTIONS:
            raise ValueError(f"position_correction must be one of {POSITION_CORRECTIONS}, "
                             f"got {self.position_correction!r}")
        if self.sweep not in SWEEPS:
            raise ValueError(f"sweep must be one of {SWEEPS}, got {self.sweep!r}")
        if self.order not in ORDERS:
            raise ValueError(f"order must be one of {ORDERS}, got {self.order!r}")
        if int(self.iterations) != self.iterations or self.iterations < 0:
            raise ValueError(f"iterations must be an integer >= 0, got {self.iterations}")
        for name in ("baumgarte", "correction_percent"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(f"{name} must be in [0, 1], got {getattr(self, name)}")
        for name in ("slop", "restitution_threshold", "warm_start_match_distance", "max_push_velocity",
                     "contact_hertz", "contact_damping_ratio"):
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
    block_manifolds : int
        Two-point manifolds solved by the block solver.
    """

    manifolds: int = 0
    contact_points: int = 0
    total_normal_impulse: float = 0.0
    total_pseudo_impulse: float = 0.0
    max_penetration: float = 0.0
    warm_started_points: int = 0
    block_manifolds: int = 0


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
        self._impulses_by_feature: dict[tuple, tuple] = {}
        self._impulses_by_pair: dict[tuple[int, int], list[tuple]] = {}
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
        self._pseudo_velocities = {}
        c = self._prepare(bodies, manifolds, dt, block_solver=settings.block_solver)
        # The target separating speed: restitution, or the Baumgarte bias if larger.
        position_bias = self.position_bias(c.depth, dt)
        if settings.position_correction == "baumgarte":
            c.rows.target[:] = np.maximum(c.rows.target, position_bias[c.order])
        velocity = self.apply_impulses(c, c.velocity, c.normal_total, c.tangent_total)   # 3. warm start

        # 4. Velocity sweeps, manifold by manifold, batch by batch (see sweep_order).
        sweep = self._sweep_function(c.rows, len(manifolds))
        sweep_normal, sweep_tangent = c.normal_total[c.order], c.tangent_total[c.order]
        velocity = sweep(velocity, c.rows, settings.iterations, accumulate, sweep_normal, sweep_tangent)
        c.normal_total[c.order], c.tangent_total[c.order] = sweep_normal, sweep_tangent

        # 5. Split impulse: the same sweeps on pseudo-velocities, no friction, no warm start.
        pseudo_total = 0.0
        if settings.position_correction == "split_impulse" and c.point_count:
            pseudo_impulse = np.zeros(c.point_count)
            pseudo_rows = replace(c.rows, target=position_bias[c.order], friction=np.zeros(c.point_count))
            pseudo_velocity = sweep(np.zeros_like(velocity), pseudo_rows, settings.iterations, accumulate,
                                    pseudo_impulse, np.zeros(c.point_count))
            pseudo_total = float(pseudo_impulse.sum())
            self._pseudo_velocities = {index: tuple(pseudo_velocity[k].tolist())
                                       for index, k in c.local.items() if not c.members[k].is_static}

        # 6. Write back, remember the impulses for warm starting, report.
        self.write_velocities(c, velocity)
        self._poses_at_solve = {index: (*c.centre[k].tolist(), float(c.members[k].angle))
                                for index, k in c.local.items()}
        self.end_contacts(c, dt, total_pseudo_impulse=pseudo_total)

    # The pieces of solve(), shared with the soft step (soft_step.py) ---------------
    def _prepare(self, bodies: list[Body], manifolds: list[tuple[int, int, Contact]], dt: float,
                 block_solver: bool) -> PreparedContacts:
        """Steps 1 and 2 of :meth:`solve` and the recalled warm-start impulses (not yet applied).

        The rows' ``target`` is the restitution target (0 below the threshold).
        """
        settings = self.settings
        warm_start = settings.warm_starting and settings.accumulate_impulses
        dt_ratio = 1.0 if self._previous_dt is None else dt / self._previous_dt

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

        # Last step's accumulated impulses, matched by feature id or position.
        point_keys = self._point_keys(manifolds)
        normal_total = np.zeros(point_count)
        tangent_total = np.zeros(point_count)
        if warm_start:
            self._recall_impulses(manifolds, point_keys, normal_total, tangent_total)
            normal_total *= dt_ratio
            tangent_total *= dt_ratio if settings.friction else 0.0
        columns = dict(a=a, b=b, nx=nx, ny=ny, rn_a=rn_a, rn_b=rn_b, rt_a=rt_a, rt_b=rt_b, ima=ima, imb=imb,
                       iia=iia, iib=iib, mass_normal=mass_normal, mass_tangent=mass_tangent, target=target,
                       friction=friction)
        rows, order = self._sweep_rows(manifolds, local, counts, inverse_mass + inverse_inertia > 0.0, columns,
                                       block_solver)
        return PreparedContacts(local=local, members=members, velocity=velocity, centre=centre,
                                inverse_inertia=inverse_inertia, a=a, b=b, normal=normal, point=point, depth=depth,
                                r_a=r_a, r_b=r_b, ima=ima, imb=imb, iia=iia, iib=iib, restitution=restitution, normal_velocity=normal_velocity,
                                point_keys=point_keys, normal_total=normal_total, tangent_total=tangent_total,
                                warm_started=int(np.count_nonzero(normal_total)) if warm_start else 0,
                                columns=columns, rows=rows, order=order, manifold_count=len(manifolds),
                                point_count=point_count)

    def position_bias(self, depth: np.ndarray, dt: float) -> np.ndarray:
        """Separating speed (m/s) that removes ``baumgarte`` of the overlap beyond
        ``slop`` in one step of ``dt``, capped at ``max_push_velocity``.

        >>> ContactSolver().position_bias(np.array([0.0, 0.015, 1.0]), dt=0.01).round(12).tolist()
        [0.0, 0.2, 3.0]
        """
        bias = self.settings.baumgarte / dt * np.maximum(depth - self.settings.slop, 0.0)
        return np.minimum(bias, self.settings.max_push_velocity)

    @staticmethod
    def apply_impulses(c: PreparedContacts, velocity: np.ndarray, normal_impulse: np.ndarray,
                       tangent_impulse: np.ndarray) -> np.ndarray:
        """``velocity`` (rows of ``c.members``) after the given impulses (N s, per point in
        manifold order, along ``n`` and ``t``): +P to B, -P to A, with their torques."""
        velocity = velocity.copy()
        nx, ny = c.normal[:, 0], c.normal[:, 1]
        impulse = normal_impulse[:, None] * c.normal + tangent_impulse[:, None] * np.stack([ny, -nx], axis=1)
        np.add.at(velocity, c.a, -np.column_stack([c.ima[:, None] * impulse,
                                                   c.iia * (c.r_a[:, 0] * impulse[:, 1] - c.r_a[:, 1] * impulse[:, 0])]))
        np.add.at(velocity, c.b, np.column_stack([c.imb[:, None] * impulse,
                                                  c.iib * (c.r_b[:, 0] * impulse[:, 1] - c.r_b[:, 1] * impulse[:, 0])]))
        return velocity

    def _sweep_function(self, rows: SweepRows, manifold_count: int):
        """:func:`sweep_batched` or :func:`sweep_loop`, as ``settings.sweep`` asks."""
        batches = len(rows.bounds) - 1
        batched = (self.settings.sweep == "batched"
                   or (self.settings.sweep == "auto" and manifold_count >= BATCH_MIN_MANIFOLDS_PER_BATCH * batches))
        return sweep_batched if batched else sweep_loop

    @staticmethod
    def write_velocities(c: PreparedContacts, velocity: np.ndarray) -> None:
        """Copy rows of ``velocity`` back into the dynamic bodies of ``c``."""
        for k, body in enumerate(c.members):
            if body.is_static:
                continue
            body.velocity = velocity[k, :2].copy()
            if c.inverse_inertia[k] > 0.0:
                body.angular_velocity = float(velocity[k, 2])

    def end_contacts(self, c: PreparedContacts, dt: float, total_pseudo_impulse: float = 0.0) -> None:
        """Remember the impulses for warm starting and fill :attr:`stats` and
        :attr:`contact_impulses`."""
        self._remember_impulses(c.point_keys, c.point, c.normal_total, c.tangent_total)
        global_index = list(c.local)
        self.contact_impulses = [(global_index[ka], global_index[kb], (px, py), pn, pt)
                                 for ka, kb, (px, py), pn, pt in zip(c.a.tolist(), c.b.tolist(), c.point.tolist(),
                                                                     c.normal_total.tolist(),
                                                                     c.tangent_total.tolist())]
        self._previous_dt = dt
        self.stats = SolverStats(manifolds=c.manifold_count, contact_points=c.point_count,
                                 total_normal_impulse=float(c.normal_total.sum()),
                                 total_pseudo_impulse=total_pseudo_impulse,
                                 max_penetration=float(c.depth.max(initial=0.0)),
                                 warm_started_points=c.warm_started,
                                 block_manifolds=int(c.rows.block.sum()))

    def _sweep_rows(self, manifolds, local, counts, movable, columns,
                    block_solver: bool) -> tuple[SweepRows, np.ndarray]:
        """The points in sweep order, their manifolds, batches and 2x2 matrices ``K``.

        ``columns`` holds the per-point arrays of the prestep (names of
        :attr:`SweepRows.POINT_FIELDS`) in manifold order.  Returns the rows and
        ``order``: sweep position -> index in manifold order.
        """
        counts = np.array(counts, dtype=int)
        starts = np.cumsum(counts) - counts                      # first point of each manifold
        manifold_a = np.array([local[i] for i, _, _ in manifolds], dtype=int)
        manifold_b = np.array([local[j] for _, j, _ in manifolds], dtype=int)
        kind = self.settings.order
        if kind == "auto":
            kind = "colours" if len(manifolds) >= COLOURS_MIN_MANIFOLDS else "manifolds"
        manifold_order, bounds = sweep_order(manifold_a, manifold_b, movable, kind)
        count = counts[manifold_order]
        first = np.cumsum(count) - count                         # in sweep order
        order = (np.repeat(starts[manifold_order] - first, count) + np.arange(count.sum())).astype(int)
        point = {name: columns[name][order] for name in SweepRows.POINT_FIELDS}
        # K = J M^-1 J^T of the two normal rows of each two-point manifold (same bodies A, B).
        k11, k12, k22 = np.zeros((3, len(manifolds)))
        two = count == 2
        p1 = first[two]
        p2 = p1 + 1
        k11[two], k12[two], k22[two] = normal_block_matrix(
            *(point[name][p1] for name in ("ima", "imb", "iia", "iib")),
            point["rn_a"][p1], point["rn_b"][p1], point["rn_a"][p2], point["rn_b"][p2])
        block = two & block_solver & block_is_well_conditioned(k11, k12, k22)
        rows = SweepRows(**point, first=first, count=count, block=block, k11=np.where(block, k11, 0.0),
                         k12=np.where(block, k12, 0.0), k22=np.where(block, k22, 0.0), bounds=bounds)
        return rows, order

    # Warm-starting memory: per body pair (low, high index), the points of the last
    # step with their feature ids, positions and impulses.
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
        """Fill in the impulses remembered for each point (0 where nothing matches).

        A point takes the old point of the same pair with the same feature id; failing
        that (no id, or an id that is new: the narrow phase swapped the reference face
        or clipped a different vertex) the nearest old point of the pair not taken by
        another point, if it is within ``warm_start_match_distance``.
        """
        found = [self._impulses_by_feature.get(key) if key[1] is not None else None for key in point_keys]
        first = 0
        for _, _, contact in manifolds:
            count = len(contact.points)
            missing = [k for k in range(first, first + count) if found[k] is None]
            old_points = self._impulses_by_pair.get(point_keys[first][0]) if missing else None
            if old_points:
                taken = {found[k][0] for k in range(first, first + count) if found[k] is not None}
                unmatched = [old for old in old_points if old[0] not in taken]
                for k in missing:
                    if not unmatched:
                        break
                    px, py = contact.points[k - first].tolist()
                    distances = [math.hypot(ox - px, oy - py) for _, ox, oy, _, _ in unmatched]
                    nearest = int(np.argmin(distances))
                    if distances[nearest] <= self.settings.warm_start_match_distance:
                        found[k] = unmatched.pop(nearest)
            first += count
        for k, old in enumerate(found):
            if old is not None:
                normal_total[k], tangent_total[k] = old[3], old[4]

    def _remember_impulses(self, point_keys, point, normal_total, tangent_total) -> None:
        """Store each point as ``(key, x, y, normal impulse, tangent impulse)``, by
        ``(pair, feature id)`` and in a list per pair."""
        self._impulses_by_feature = {}
        self._impulses_by_pair = {}
        for key, (px, py), pn, pt in zip(point_keys, point.tolist(), normal_total.tolist(), tangent_total.tolist()):
            entry = (key, px, py, pn, pt)
            if key[1] is not None:
                self._impulses_by_feature[key] = entry
            self._impulses_by_pair.setdefault(key[0], []).append(entry)

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


#: ``sweep="auto"`` uses :func:`sweep_batched` when the batches of :func:`sweep_order`
#: hold at least this many manifolds on average (measured break-even: the numpy
#: operations of one batch cost about as much as this many manifolds of the loop).
BATCH_MIN_MANIFOLDS_PER_BATCH = 24

#: ``order="auto"`` sweeps colour by colour from this many manifolds on (measured:
#: below it the Python loop over the manifolds in their own order is as fast as the
#: numpy batches of the colours; pyramid_10 has 145 manifolds, pyramid_20 about 540).
COLOURS_MIN_MANIFOLDS = 256

#: The block solver needs cond(K) below about this (dimensionless); above it the two
#: normal rows of a manifold are nearly dependent (points close together, or no
#: rotation), the 2x2 solve would amplify rounding, and the points are solved one
#: after the other instead.  Box2D's ``k_maxConditionNumber``.
MAX_CONDITION_NUMBER = 1000.0


@dataclass
class PreparedContacts:
    """The contact points of one step, gathered and pre-computed once (the prestep).

    Per body in contact (rows of ``velocity``): ``members`` and their ``centre`` (m),
    ``inverse_inertia``; ``local`` maps a world body index to its row.  Per point, in
    manifold order: bodies ``a``, ``b`` (rows), ``normal``, ``point`` (m), ``depth`` (m),
    lever arms ``r_a``, ``r_b`` (m), inverse masses and inertias of A and B, pair
    ``restitution``, ``normal_velocity`` before any impulse (m/s), warm-start keys and
    the accumulated impulses ``normal_total``, ``tangent_total`` (N s).  ``columns``
    holds the per-point arrays of :attr:`SweepRows.POINT_FIELDS` in manifold order, and
    ``rows`` the same points in sweep order: ``rows.x == columns["x"][order]``.
    """

    local: dict
    members: list
    velocity: np.ndarray
    centre: np.ndarray
    inverse_inertia: np.ndarray
    a: np.ndarray
    b: np.ndarray
    normal: np.ndarray
    point: np.ndarray
    depth: np.ndarray
    r_a: np.ndarray
    r_b: np.ndarray
    ima: np.ndarray
    imb: np.ndarray
    iia: np.ndarray
    iib: np.ndarray
    restitution: np.ndarray
    normal_velocity: np.ndarray
    point_keys: list
    normal_total: np.ndarray
    tangent_total: np.ndarray
    warm_started: int
    columns: dict
    rows: "SweepRows"
    order: np.ndarray
    manifold_count: int
    point_count: int


@dataclass
class SweepRows:
    """What the velocity sweeps need, in sweep order (batch by batch, manifold by manifold).

    Symbols: ``n`` the normal (from A to B), ``t = (n_y, -n_x)`` the tangent,
    ``rn = r x n`` and ``rt = r x t`` for the lever arms ``r`` from the centres of mass.

    Attributes
    ----------
    a, b : numpy.ndarray of int, shape (m,)
        Local body numbers (rows of ``velocity``) of each contact point.
    nx, ny : numpy.ndarray, shape (m,)
        Normal of each point.
    rn_a, rn_b, rt_a, rt_b : numpy.ndarray, shape (m,)
        ``r x n`` and ``r x t`` for bodies A and B (m).
    ima, imb, iia, iib : numpy.ndarray, shape (m,)
        Inverse masses (1/kg) and inverse inertias (1/(kg m^2)) of A and B.
    mass_normal, mass_tangent : numpy.ndarray, shape (m,)
        Effective masses ``1 / K`` along ``n`` and ``t`` (kg); 0 if nothing can move.
    target : numpy.ndarray, shape (m,)
        Separating normal velocity wanted at each point (m/s).
    friction : numpy.ndarray, shape (m,)
        Pair friction coefficient mu of each point.
    first, count : numpy.ndarray of int, shape (k,)
        Each manifold's first point and number of points (1 or 2); the points of
        manifold ``c`` are ``first[c], first[c] + 1, ...``.
    block : numpy.ndarray of bool, shape (k,)
        Solve the two normal impulses of the manifold together (:func:`block_normal_impulses`).
    k11, k12, k22 : numpy.ndarray, shape (k,)
        ``K = J M^-1 J^T`` of the two normal rows (1/kg): the normal velocity change at
        point i per unit normal impulse at point j.  Set where ``block``.
    bounds : numpy.ndarray of int, shape (batches + 1,)
        Batch ``c`` is manifolds ``bounds[c]:bounds[c + 1]`` (see :func:`sweep_order`).
    """

    a: np.ndarray
    b: np.ndarray
    nx: np.ndarray
    ny: np.ndarray
    rn_a: np.ndarray
    rn_b: np.ndarray
    rt_a: np.ndarray
    rt_b: np.ndarray
    ima: np.ndarray
    imb: np.ndarray
    iia: np.ndarray
    iib: np.ndarray
    mass_normal: np.ndarray
    mass_tangent: np.ndarray
    target: np.ndarray
    friction: np.ndarray
    first: np.ndarray
    count: np.ndarray
    block: np.ndarray
    k11: np.ndarray
    k12: np.ndarray
    k22: np.ndarray
    bounds: np.ndarray

    POINT_FIELDS = ("a", "b", "nx", "ny", "rn_a", "rn_b", "rt_a", "rt_b", "ima", "imb", "iia", "iib",
                    "mass_normal", "mass_tangent", "target", "friction")


def normal_block_matrix(ima, imb, iia, iib, rn_a1, rn_b1, rn_a2, rn_b2):
    """``(k11, k12, k22)`` of ``K = J M^-1 J^T`` for the two normal rows of a two-point
    manifold between bodies A and B (1/kg), from the inverse masses and inertias and
    the points' ``r x n``; floats or arrays.

    >>> normal_block_matrix(0.0, 1.0, 0.0, 6.0, 0.0, -0.5, 0.0, 0.5)
    (2.5, -0.5, 2.5)
    """
    k11 = ima + imb + iia * rn_a1 * rn_a1 + iib * rn_b1 * rn_b1
    k22 = ima + imb + iia * rn_a2 * rn_a2 + iib * rn_b2 * rn_b2
    k12 = ima + imb + iia * rn_a1 * rn_a2 + iib * rn_b1 * rn_b2
    return k11, k12, k22


def block_is_well_conditioned(k11, k12, k22):
    """cond(K) < :data:`MAX_CONDITION_NUMBER`, tested as Box2D does (k11^2 < c det K) but
    with the larger diagonal entry, so that the answer does not depend on the point
    order; floats or arrays.

    >>> bool(block_is_well_conditioned(2.5, -0.5, 2.5)), bool(block_is_well_conditioned(1.0, 1.0, 1.0))
    (True, False)
    """
    return np.maximum(k11, k22) ** 2 < MAX_CONDITION_NUMBER * (k11 * k22 - k12 * k12)


def jacobian_rows(a, b, nx, ny, rn_a, rn_b, rt_a, rt_b, ima, imb, iia, iib) -> tuple[np.ndarray, ...]:
    """Per point, the rows over the six velocities ``(vx_A, vy_A, w_A, vx_B, vy_B, w_B)``:
    ``where`` (their places in ``velocity.reshape(-1)``, from the body rows ``a``,
    ``b``), the Jacobians ``J_n`` and ``J_t`` (so that ``v_n = J_n . v``) and the
    velocity changes per unit impulse ``M^-1 J^T``.  Returns ``(where, j_normal,
    response_normal, j_tangent, response_tangent)``, each of shape (m, 6).

    >>> where, jn, mn, jt, mt = jacobian_rows(*[np.array([x]) for x in (0, 1, 0.0, 1.0, 0.0, 0.0, 0.0, 0.5,
    ...                                                                  0.0, 1.0, 0.0, 2.0)])
    >>> where.tolist(), jn.tolist(), mt.tolist()
    ([[0, 1, 2, 3, 4, 5]], [[0.0, -1.0, 0.0, 0.0, 1.0, 0.0]], [[-0.0, 0.0, 0.0, 1.0, 0.0, 1.0]])
    """
    zero = np.zeros_like(nx, dtype=float)
    j_normal = np.column_stack([-nx, -ny, -rn_a, nx, ny, rn_b]) + zero[:, None]
    j_tangent = np.column_stack([-ny, nx, -rt_a, ny, -nx, rt_b]) + zero[:, None]
    inverse_masses = np.column_stack([ima, ima, iia, imb, imb, iib])
    where = np.column_stack([3 * a, 3 * a + 1, 3 * a + 2, 3 * b, 3 * b + 1, 3 * b + 2])
    return where, j_normal, j_normal * inverse_masses, j_tangent, j_tangent * inverse_masses


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

    Parameters
    ----------
    k11, k12, k22 : float
        Entries of the symmetric 2x2 matrix ``K`` (1/kg), with ``k11 k22 > k12^2``.
    b1, b2 : float
        Normal velocities without the manifold's normal impulses, minus the targets (m/s).

    Returns
    -------
    (float, float)
        ``(x1, x2)`` (N s).

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


def block_normal_impulses_many(k11: np.ndarray, k12: np.ndarray, k22: np.ndarray, b1: np.ndarray,
                                b2: np.ndarray, inverse: tuple | None = None
                                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`block_normal_impulses` for many manifolds at once (arrays of equal shape).

    ``inverse``: ``K^-1`` as ``(n11, n12, n22)`` if already known.  Returns ``(x1,
    x2, stuck)``: the impulses (N s) and where no case fits (rounding), in which
    case ``x1``, ``x2`` are 0 there and the caller keeps its old impulses.

    >>> k = np.array([2.5]), np.array([-0.5]), np.array([2.5])
    >>> x1, x2, stuck = block_normal_impulses_many(*k, np.array([-9.81 / 60]), np.array([-9.81 / 60]))
    >>> x1.round(12).tolist(), x2.round(12).tolist(), stuck.tolist()
    ([0.08175], [0.08175], [False])
    """
    if inverse is None:
        det = k11 * k22 - k12 * k12
        inverse = (k22 / det, -k12 / det, k11 / det)
    n11, n12, n22 = inverse
    x1, x2 = -(n11 * b1 + n12 * b2), -(n12 * b1 + n22 * b2)       # case 1: both push
    both = (x1 >= 0.0) & (x2 >= 0.0)
    if both.all():
        return x1, x2, np.zeros(x1.shape, dtype=bool)
    # Cases 2-4 where case 1 does not fit; the first that fits wins.
    only1, only2 = -b1 / k11, -b2 / k22
    case_1 = ~both & (only1 >= 0.0) & (k12 * only1 + b2 >= 0.0)
    case_2 = ~both & ~case_1 & (only2 >= 0.0) & (k12 * only2 + b1 >= 0.0)
    stuck = ~(both | case_1 | case_2 | ((b1 >= 0.0) & (b2 >= 0.0)))
    x1 = np.where(both, x1, np.where(case_1, only1, 0.0))
    x2 = np.where(both, x2, np.where(case_2, only2, 0.0))
    return x1, x2, stuck


def sweep_order(body_a: np.ndarray, body_b: np.ndarray, movable: np.ndarray,
                order: str = "manifolds") -> tuple[np.ndarray, np.ndarray]:
    """Order in which the sweeps visit the manifolds, in batches that share no movable body.

    The manifolds of one batch share no movable body, so they can be solved at the
    same time (:func:`sweep_batched`) with the same result as one after the other
    (:func:`sweep_loop`).  Static bodies may appear in many manifolds of one batch:
    their velocity never changes.

    - ``"manifolds"``: Gauss-Seidel in the given order, as Box2D and box2d-lite sweep
      their contact lists.  Each manifold goes into the batch after the last one that
      holds an earlier manifold sharing one of its movable bodies, so solving batch by
      batch is solving in the given order.  A chain (a stack) is then one manifold
      per batch, and one sweep carries an impulse from one end of it to the other.
    - ``"colours"``: greedy colouring: each manifold, in the given order, takes the
      smallest colour not yet used by a movable body it touches.  Fewer, larger
      batches (faster with :func:`sweep_batched`), but a chain becomes red-black
      (every other contact, then the rest) and an impulse travels only about one
      contact per colour and sweep.

    Parameters
    ----------
    body_a, body_b : numpy.ndarray of int, shape (m,)
        Local body numbers of each manifold.
    movable : numpy.ndarray of bool, shape (n,)
        Whether each body can move (finite mass or inertia).
    order : str
        ``"manifolds"`` or ``"colours"``.

    Returns
    -------
    order : numpy.ndarray of int, shape (m,)
        Manifold indices, batch by batch (stable within a batch).
    bounds : numpy.ndarray of int, shape (batches + 1,)
        Batch ``c`` is ``order[bounds[c]:bounds[c + 1]]``.

    Examples
    --------
    Manifolds 0-1, 1-2 and 0-2 between a static body 0 and movable bodies 1 and 2.
    In the given order, manifold 1 must wait for manifold 0 (body 1) and manifold 2
    for manifold 1 (body 2); by colours, manifolds 0 and 2 share only the static
    body and go together, manifold 1 comes after them.

    >>> pairs = np.array([0, 1, 0]), np.array([1, 2, 2]), np.array([False, True, True])
    >>> [(o.tolist(), b.tolist()) for o, b in (sweep_order(*pairs), sweep_order(*pairs, order="colours"))]
    [([0, 1, 2], [0, 1, 2, 3]), ([0, 2, 1], [0, 2, 3])]
    """
    if order not in ("manifolds", "colours"):
        raise ValueError(f"order must be 'manifolds' or 'colours', got {order!r}")
    movable = movable.tolist()
    batch = []
    if order == "manifolds":
        after = [0] * len(movable)  # the first batch a new manifold of each body may join
        for i, j in zip(body_a.tolist(), body_b.tolist()):
            c = max(after[i] if movable[i] else 0, after[j] if movable[j] else 0)
            batch.append(c)
            for k in (i, j):
                if movable[k]:
                    after[k] = c + 1
    else:
        used = [0] * len(movable)  # bit c set: the body already has a manifold of colour c
        for i, j in zip(body_a.tolist(), body_b.tolist()):
            taken = (used[i] if movable[i] else 0) | (used[j] if movable[j] else 0)
            c = ((~taken) & (taken + 1)).bit_length() - 1  # lowest free colour
            batch.append(c)
            for k in (i, j):
                if movable[k]:
                    used[k] |= 1 << c
    batch = np.array(batch, dtype=int)
    indices = np.argsort(batch, kind="stable")
    bounds = np.searchsorted(batch[indices], np.arange(batch.max(initial=-1) + 2))
    return indices, bounds


def sweep_loop(velocity: np.ndarray, rows: SweepRows, iterations: int, accumulate: bool,
               normal_total: np.ndarray, tangent_total: np.ndarray) -> np.ndarray:
    """Sequential-impulse sweeps, one manifold at a time (the reference version).

    Per manifold, with ``accumulate`` (Box2D's order): the friction impulse of each
    point, its running total clamped to ``+-mu`` times the normal total so far, then
    the normal impulses (both together if ``rows.block``, else point by point), their
    totals clamped to >= 0.  Without ``accumulate`` each increment is clamped, and
    each point's friction follows its normal, bounded by ``mu`` times that normal
    increment.

    Parameters
    ----------
    velocity : numpy.ndarray, shape (n, 3)
        Rows ``(vx, vy, w)`` of the bodies in contact (m/s, rad/s).
    rows : SweepRows
        The contact points and manifolds in sweep order.
    iterations : int
        Number of sweeps.
    accumulate : bool
        Clamp accumulated impulses (True) or increments (False).
    normal_total, tangent_total : numpy.ndarray, shape (m,)
        Accumulated impulses per point (N s), in sweep order; updated in place.

    Returns
    -------
    numpy.ndarray, shape (n, 3)
        The new velocities.

    Examples
    --------
    A static ground and a 1 kg disc of radius 0.5 m falling at 1 m/s, one point
    straight below the centre (``r x t = 0.5``):

    >>> rows = SweepRows(*[np.array([x]) for x in (0, 1, 0.0, 1.0, 0.0, 0.0, 0.0, 0.5, 0.0, 1.0, 0.0, 2.0,
    ...                                            1.0, 1 / 1.5, 0.0, 0.0, 0, 1, False, 0.0, 0.0, 0.0)],
    ...                  bounds=np.array([0, 1]))
    >>> sweep_loop(np.array([[0.0, 0.0, 0.0], [0.0, -1.0, 0.0]]), rows, 1, True, np.zeros(1), np.zeros(1)).tolist()
    [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
    """
    vx, vy, w = velocity.T.tolist()
    columns = {name: getattr(rows, name).tolist() for name in SweepRows.POINT_FIELDS}
    normal_list, tangent_list = normal_total.tolist(), tangent_total.tolist()
    normal_change = [0.0] * len(normal_list)  # this sweep's normal increments (friction bound without accumulation)
    # With accumulated impulses friction comes first, as in Box2D, bounded by the normal
    # totals so far, so that the normal impulses have the last word in every sweep.
    # Clamped increments need this sweep's normal increment, so friction comes after.
    friction_first = accumulate
    NORMAL, FRICTION, BLOCK = 0, 1, 2

    # One row per manifold: its bodies, normal and inverse masses (shared by its points)
    # and its program: (step, point index, rn_a, rn_b, rt_a, rt_b, 1/K_n, 1/K_t, target,
    # mu), where step is NORMAL or FRICTION for one point, or BLOCK for the normal pair
    # (then the row also carries the second point's index, rn_a, rn_b and target).
    all_points = list(zip(range(len(normal_list)), *(columns[name] for name in (
        "rn_a", "rn_b", "rt_a", "rt_b", "mass_normal", "mass_tangent", "target", "friction"))))
    manifolds = []
    for first, count, block, k11, k12, k22 in zip(rows.first.tolist(), rows.count.tolist(), rows.block.tolist(),
                                                  rows.k11.tolist(), rows.k12.tolist(), rows.k22.tolist()):
        points = all_points[first:first + count]
        frictions = [(FRICTION, *point) for point in points if point[-1] != 0.0]
        if block:
            (k1, rn_a1, rn_b1, *_, wanted1, _), (k2, rn_a2, rn_b2, *_, wanted2, _) = points
            normals = [(BLOCK, k1, rn_a1, rn_b1, wanted1, k2, rn_a2, rn_b2, wanted2, k11, k12, k22)]
        else:
            normals = [(NORMAL, *point) for point in points]
        if friction_first:
            program = frictions + normals
        elif block:
            program = normals + frictions
        else:   # each point's normal, then its friction
            program = [step for point in points
                       for step in [(NORMAL, *point)] + [(FRICTION, *point)] * (point[-1] != 0.0)]
        if program:
            manifolds.append((columns["a"][first], columns["b"][first], columns["nx"][first], columns["ny"][first],
                              columns["ima"][first], columns["imb"][first], columns["iia"][first],
                              columns["iib"][first], program))

    for _ in range(iterations):
        for a, b, nx, ny, ima, imb, iia, iib, program in manifolds:
            # The two bodies' velocities stay in locals while the manifold is solved.
            vxa, vya, wa, vxb, vyb, wb = vx[a], vy[a], w[a], vx[b], vy[b], w[b]
            for step in program:
                if step[0] == NORMAL:
                    _, k, rn_a, rn_b, _, _, mass_normal, _, wanted, _ = step
                    # v_n = (v_B + w_B x r_B - v_A - w_A x r_A) . n
                    normal_velocity = (vxb - vxa) * nx + (vyb - vya) * ny + wb * rn_b - wa * rn_a
                    change = mass_normal * (wanted - normal_velocity)
                    if accumulate:
                        old = normal_list[k]
                        normal_list[k] = max(old + change, 0.0)
                        change = normal_list[k] - old
                    else:
                        change = max(change, 0.0)
                        normal_list[k] += change
                    normal_change[k] = change
                    vxa -= ima * change * nx
                    vya -= ima * change * ny
                    wa -= iia * rn_a * change
                    vxb += imb * change * nx
                    vyb += imb * change * ny
                    wb += iib * rn_b * change
                elif step[0] == FRICTION:
                    _, k, _, _, rt_a, rt_b, _, mass_tangent, _, mu = step
                    # Along t = (ny, -nx), Coulomb bound mu times the normal impulse.
                    tangent_velocity = (vxb - vxa) * ny - (vyb - vya) * nx + wb * rt_b - wa * rt_a
                    change = -mass_tangent * tangent_velocity
                    if accumulate:
                        bound = mu * normal_list[k]
                        old = tangent_list[k]
                        tangent_list[k] = min(max(old + change, -bound), bound)
                        change = tangent_list[k] - old
                    else:
                        bound = mu * normal_change[k]
                        change = min(max(change, -bound), bound)
                        tangent_list[k] += change
                    vxa -= ima * change * ny
                    vya += ima * change * nx
                    wa -= iia * rt_a * change
                    vxb += imb * change * ny
                    vyb -= imb * change * nx
                    wb += iib * rt_b * change
                else:
                    # Both normal impulses at once (block_normal_impulses), b = v - target - K x_old.
                    _, k1, rn_a1, rn_b1, wanted1, k2, rn_a2, rn_b2, wanted2, k11, k12, k22 = step
                    along = (vxb - vxa) * nx + (vyb - vya) * ny
                    old1, old2 = (normal_list[k1], normal_list[k2]) if accumulate else (0.0, 0.0)
                    b1 = along + wb * rn_b1 - wa * rn_a1 - wanted1 - (k11 * old1 + k12 * old2)
                    b2 = along + wb * rn_b2 - wa * rn_a2 - wanted2 - (k12 * old1 + k22 * old2)
                    x1, x2 = block_normal_impulses(k11, k12, k22, b1, b2)
                    if x1 != x1:  # nan: no case fits (rounding); keep the impulses
                        x1, x2 = old1, old2
                    change1, change2 = x1 - old1, x2 - old2
                    normal_list[k1] += change1
                    normal_list[k2] += change2
                    normal_change[k1], normal_change[k2] = change1, change2
                    change = change1 + change2
                    vxa -= ima * change * nx
                    vya -= ima * change * ny
                    wa -= iia * (rn_a1 * change1 + rn_a2 * change2)
                    vxb += imb * change * nx
                    vyb += imb * change * ny
                    wb += iib * (rn_b1 * change1 + rn_b2 * change2)
            vx[a], vy[a], w[a], vx[b], vy[b], w[b] = vxa, vya, wa, vxb, vyb, wb
    normal_total[:] = normal_list
    tangent_total[:] = tangent_list
    return np.array([vx, vy, w], dtype=float).T.reshape(-1, 3)


def sweep_batched(velocity: np.ndarray, rows: SweepRows, iterations: int, accumulate: bool,
                  normal_total: np.ndarray, tangent_total: np.ndarray) -> np.ndarray:
    """The same sweeps as :func:`sweep_loop`, one batch of manifolds at a time with numpy.

    Within a batch (``rows.bounds``) no movable body appears twice, so its manifolds
    can be solved together, a few numpy operations per batch instead of a Python loop
    over its points.  Each manifold sees its impulses in the same order as in the
    loop, so the result is the same up to rounding.  Same parameters and result as
    :func:`sweep_loop`.

    >>> rows = SweepRows(*[np.array([x]) for x in (0, 1, 0.0, 1.0, 0.0, 0.0, 0.0, 0.5, 0.0, 1.0, 0.0, 2.0,
    ...                                            1.0, 1 / 1.5, 0.0, 0.0, 0, 1, False, 0.0, 0.0, 0.0)],
    ...                  bounds=np.array([0, 1]))
    >>> sweep_batched(np.array([[0.0, 0.0, 0.0], [0.0, -1.0, 0.0]]), rows, 1, True, np.zeros(1), np.zeros(1)).tolist()
    [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
    """
    r = rows
    where, jacobian_normal, response_normal, jacobian_tangent, response_tangent = jacobian_rows(
        r.a, r.b, r.nx, r.ny, r.rn_a, r.rn_b, r.rt_a, r.rt_b, r.ima, r.imb, r.iia, r.iib)

    # Each batch splits into up to three groups: block manifolds, other two-point
    # manifolds, one-point manifolds.  A group's manifolds share no movable body, so
    # its velocities are gathered once, updated by the same steps as each manifold in
    # sweep_loop (one numpy operation doing that step for all of them) and scattered.
    groups = []
    for start, stop in zip(r.bounds[:-1].tolist(), r.bounds[1:].tolist()):
        first, count, block = r.first[start:stop], r.count[start:stop], r.block[start:stop]
        for members in (block, ~block & (count == 2), count == 1):
            if members.any():
                points = [first[members] + slot for slot in range(int(count[members][0]))]
                groups.append(_BatchGroup(r, points, where, bool(block[members][0]), r.k11[start:stop][members],
                                          r.k12[start:stop][members], r.k22[start:stop][members],
                                          jacobian_normal, response_normal, jacobian_tangent, response_tangent,
                                          normal_total, tangent_total))
    velocity = np.array(velocity, dtype=float, order="C")   # a copy; flat is a view of it
    flat = velocity.reshape(-1)
    for _ in range(iterations):
        for group in groups:
            group.solve(flat, accumulate)
    for group in groups:
        group.write_totals(normal_total, tangent_total)
    return velocity


class _BatchGroup:
    """Manifolds of one batch with the same number of points and the same normal solve.

    Lists hold one entry per slot (first or second point of each manifold): arrays of
    shape (size,), or (size, 6) for Jacobians and responses over the six velocities
    of bodies A and B.
    """

    def __init__(self, r, points, where, block, k11, k12, k22, jacobian_normal, response_normal,
                 jacobian_tangent, response_tangent, normal_total, tangent_total):
        self.points = points
        self.where = where[points[0]]                                # both points: same bodies
        self.block = block
        self.j_normal = [jacobian_normal[p] for p in points]
        self.m_normal = [response_normal[p] for p in points]
        self.j_tangent = [jacobian_tangent[p] for p in points]
        self.m_tangent = [response_tangent[p] for p in points]
        self.mass_normal = [r.mass_normal[p] for p in points]
        self.minus_mass_tangent = [-r.mass_tangent[p] for p in points]
        self.target = [r.target[p] for p in points]
        self.mu = [r.friction[p] for p in points]
        self.has_friction = [bool(np.any(mu != 0.0)) for mu in self.mu]
        self.normal = [normal_total[p].copy() for p in points]       # accumulated impulses (N s)
        self.tangent = [tangent_total[p].copy() for p in points]
        self.normal_change = [np.zeros(len(p)) for p in points]       # this sweep's increments
        if block:
            self.k11, self.k12, self.k22 = k11, k12, k22
            det = k11 * k22 - k12 * k12
            self.inverse = (k22 / det, -k12 / det, k11 / det)         # K^-1 (kg)

    def solve(self, flat, accumulate) -> None:
        """One sweep over the group's manifolds; ``flat`` is the velocity array, raveled."""
        v = flat[self.where]
        slots = range(len(self.points))
        if accumulate:                      # friction first, as in sweep_loop
            for s in slots:
                self._friction(v, s, accumulate)
        if self.block:
            self._block(v, accumulate)
        for s in slots:
            if not self.block:
                self._normal(v, s, accumulate)
            if not accumulate:
                self._friction(v, s, accumulate)
        flat[self.where] = v

    def _normal(self, v, s, accumulate) -> None:
        change = self.mass_normal[s] * (self.target[s] - np.einsum("ij,ij->i", v, self.j_normal[s]))
        total = self.normal[s]
        if accumulate:
            new = np.maximum(total + change, 0.0)
            change = new - total
            total[:] = new
        else:
            np.maximum(change, 0.0, out=change)
            total += change
        self.normal_change[s] = change
        v += self.m_normal[s] * change[:, None]

    def _friction(self, v, s, accumulate) -> None:
        if not self.has_friction[s]:
            return
        change = self.minus_mass_tangent[s] * np.einsum("ij,ij->i", v, self.j_tangent[s])
        bound = self.mu[s] * (self.normal[s] if accumulate else self.normal_change[s])
        tangent = self.tangent[s]
        if accumulate:
            new = np.minimum(np.maximum(tangent + change, -bound), bound)
            change = new - tangent
            tangent[:] = new
        else:
            change = np.minimum(np.maximum(change, -bound), bound)
            tangent += change
        v += self.m_tangent[s] * change[:, None]

    def _block(self, v, accumulate) -> None:
        """:func:`block_normal_impulses` for all manifolds of the group at once."""
        k11, k12, k22 = self.k11, self.k12, self.k22
        old1, old2 = (self.normal[0], self.normal[1]) if accumulate else (0.0, 0.0)
        b1 = np.einsum("ij,ij->i", v, self.j_normal[0]) - self.target[0] - (k11 * old1 + k12 * old2)
        b2 = np.einsum("ij,ij->i", v, self.j_normal[1]) - self.target[1] - (k12 * old1 + k22 * old2)
        x1, x2, stuck = block_normal_impulses_many(k11, k12, k22, b1, b2, self.inverse)
        if stuck.any():                     # no case fits, by rounding: keep the impulses
            x1, x2 = np.where(stuck, old1, x1), np.where(stuck, old2, x2)
        change1, change2 = x1 - old1, x2 - old2
        self.normal[0] += change1
        self.normal[1] += change2
        self.normal_change[0], self.normal_change[1] = change1, change2
        v += self.m_normal[0] * change1[:, None] + self.m_normal[1] * change2[:, None]

    def write_totals(self, normal_total, tangent_total) -> None:
        for p, normal, tangent in zip(self.points, self.normal, self.tangent):
            normal_total[p] = normal
            tangent_total[p] = tangent


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
            for order in ("manifolds", "colours"):
                for sweep in ("loop", "batched"):
                    solver = ContactSolver(SolverSettings(iterations=iterations, sweep=sweep, order=order))
                    elapsed = []
                    for _ in range(steps):
                        for body in bodies[1:]:
                            body.velocity = np.array((0.0, -9.81 * dt))
                            body.angular_velocity = 0.0
                        start = time.perf_counter()
                        solver.solve(bodies, manifolds, dt)
                        elapsed.append(time.perf_counter() - start)
                    print(f"  {len(bodies) - 1:4d} boxes {points:4d} points {iterations:3d} iterations "
                          f"{order:9s} {sweep:8s} {1e3 * min(elapsed):7.2f} ms")


if __name__ == "__main__":
    main()
