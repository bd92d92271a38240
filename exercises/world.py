# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/world.py on the instructor's side.
"""The world step: find contacts, prepare them, integrate forces, resolve, integrate.

:meth:`World.step` reads like the algorithm, one outline in Box2D v3's order for both
of its steps::

    for each round of contacts:
        find contacts             broad phase: candidate pairs (i, j), i < j, never static-static;
                                  narrow phase: manifolds (i, j, Contact), normal from i to j
        prepare contacts          lever arms, effective masses, last step's impulses
        for each sub-step of length h:
            integrate velocities  v += h g                      (dynamic bodies)
            solve contacts        warm start, then sequential impulses on velocities
            solve joints          the same kernel on the distance joints
            integrate positions   x += h v, angle += h w        (plain: bullets stop at first contact)
            relax joints          (soft step)
            relax contacts        soft step: a rigid pass without push;
                                  plain step: position correction (projection or split impulse)
        end contacts              restitution (soft step), impulses remembered for the next step
        (soft step) stop bullets  continuous detection over the whole step

The two steps are two configurations of this outline:

- the **plain step** (box2d-lite, Box2D v2; :class:`~exercises.response.contact_solver.ContactSolver`):
  one sub-step per round of contacts, found again every sub-step; rigid rows, the
  restitution target and the Baumgarte bias inside the solve (restitution aims at the
  closing speeds after gravity, as box2d-lite measures them); bullets swept every
  sub-step;
- the **soft step** (Box2D v3; :class:`~exercises.response.soft_step.SoftStepSolver`,
  ``soft_step=True``): one round of speculative contacts per step and ``substeps``
  sub-steps on it; soft rows that push with a damped spring, a relax pass, a
  restitution pass at the end (from the closing speeds at the start); bullets swept
  once per step.

Both solvers prepare their contacts with the same prestep
(:class:`~exercises.response.contact_preparation.ContactPreparation`), and every pass
of either is the same solver kernel (:mod:`exercises.solver.kernel`) with other
targets, mass scales and impulse scales.  ``backend="numba"`` runs the soft step of a
world of boxes or of discs compiled whole (``response/soft_step_numba.py`` of the instructor's edition).

Every technique is a switch of :class:`WorldSettings`, of the solvers'
:class:`~exercises.response.solver_settings.SolverSettings` or of the soft step's
:class:`~exercises.response.solver_settings.SoftStepSettings`, so a learner can turn one
off and watch what changes.  A scene (:mod:`exercises.scenes`) sets only what it needs.
Units: SI; ``gravity`` in m/s^2, ``dt`` in s.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .body import Body
from .body_state import BodyState
from .broadphase.aabb_array import aabb_array
from .broadphase.brute_force import pairs_brute_force
from .broadphase.quadtree import pairs_quadtree
from .broadphase.sorted_grid_numpy import pairs_grid_numpy
from .broadphase.uniform_grid import pairs_uniform_grid, suggest_cell_size
from .continuous import swept_aabb, time_of_impact
from .contact import Contact
from .joints import DistanceJoint, JointSolver
from .made_when_asked import MadeWhenAsked
from .narrowphase.dispatch import collide
from .narrowphase.speculative import SPECULATIVE_MARGIN, speculative_polygon_manifold
from .response.contact_solver import BACKENDS, ContactSolver, SolverSettings
from .response.solver_settings import CountsChanges, SoftStepSettings
from .response.soft_step import JOINT_DAMPING_RATIO, JOINT_HERTZ, SoftStepSolver, soft_coefficients
from .shapes import AABB, OBB, Circle, Shape, bounding_aabb
from .twins import HAS_TWINS, require_twins

BROAD_PHASES = ("auto", "all_pairs", "brute_force", "uniform_grid", "quadtree", "numpy_grid")

#: ``broad_phase="auto"`` takes the method measured fastest for the scene
#: (bench/bench_auto_broad_phase.py: processor time of one step's detection, broad plus
#: narrow phase, 2 to 160 bodies; balls among box walls as in the speed chapter, boxes on a
#: ground, balls or boxes scattered).  Testing every pair directly wins only where the
#: narrow phase costs less than building the AABBs: in scenes of at most this many
#: bodies ...
AUTO_ALL_PAIRS_MAX_BODIES = 2
#: ... and in scenes of circles only (a test of two apart circles takes under 1 us) of
#: at most this many bodies.
AUTO_ALL_PAIRS_MAX_CIRCLES = 40
#: Otherwise the brute-force AABB test is fastest below this many bodies (5 to 20 times
#: faster than all pairs for scattered bodies of 8 to 64; at most 15 % slower for 3 to 6
#: boxes that all touch) and the numpy grid from it on (within 10 % of each other from
#: 64 to 96 bodies, the grid ahead beyond).
AUTO_GRID_MIN_BODIES = 80


def auto_broad_phase(shapes: list[Shape]) -> str:
    """The broad phase ``"auto"`` runs for these world shapes (see ``AUTO_*`` above).

    >>> auto_broad_phase([Circle((0, 0), 1)] * 10), auto_broad_phase([AABB((0, 0), (1, 1))] * 10)
    ('all_pairs', 'brute_force')
    """
    n = len(shapes)
    if n <= AUTO_ALL_PAIRS_MAX_BODIES or (n <= AUTO_ALL_PAIRS_MAX_CIRCLES
                                          and all(isinstance(shape, Circle) for shape in shapes)):
        return "all_pairs"
    return "brute_force" if n < AUTO_GRID_MIN_BODIES else "numpy_grid"


@dataclass
class WorldSettings(CountsChanges):
    """Switches of the world step.

    Attributes
    ----------
    gravity : (float, float)
        Acceleration of gravity (m/s^2).
    broad_phase : str
        One of ``BROAD_PHASES``; every method gives the same contacts, only the time
        differs.  ``"auto"`` takes the one measured fastest for the scene
        (:func:`auto_broad_phase`): all pairs directly for two bodies and for up to 40
        circles, the brute-force AABB test below 80 bodies, the numpy grid from 80 on.
    continuous : bool
        Sweep bodies flagged ``is_bullet`` against static bodies (no tunnelling).
    substeps : int
        Sub-steps per call of :meth:`World.step`.  Plain: each sub-step is a whole
        step (contacts found again, ``solver.iterations`` sweeps, position correction).
        With ``soft_step``: contacts are found once per step and each sub-step sweeps
        ``solver.iterations`` times, soft and then relaxed.
    soft_step : bool
        Step as Box2D v3 does (:mod:`~exercises.response.soft_step`): soft contacts
        and relaxation inside the sub-steps, instead of ``solver.position_correction``.
    solver : SolverSettings
        Switches of the contact solvers (both steps).
    soft : SoftStepSettings
        The soft step's own settings: its contact springs and relax pass.
    backend : str
        ``"python"``: every stage in readable Python and numpy (the teaching text);
        ``"numba"``: the compiled twins of the solver kernel (contacts and joints,
        ``solver/kernel_numba.py`` of the instructor's edition), of the numpy grid broad phase
        (``broadphase/grid_numba.py`` of the instructor's edition) and of the box-pair manifolds of the
        soft step (``narrowphase/box_pairs_numba.py`` of the instructor's edition), each tested equal to
        its readable version, and the world to 1e-12 on every hard scene.  Not a
        setting of the physics: both give the same motion, to rounding.
    """

    gravity: tuple[float, float] = (0.0, -9.81)
    broad_phase: str = "auto"
    continuous: bool = True
    substeps: int = 1
    soft_step: bool = False
    solver: SolverSettings = field(default_factory=SolverSettings)
    soft: SoftStepSettings = field(default_factory=SoftStepSettings)
    backend: str = "python"

    def __setattr__(self, name: str, value) -> None:
        if name == "gravity":
            # Kept as a tuple: changed by assignment only, which every step sees (a list
            # edited in place would go unseen by a world that keeps its compiled settings).
            given = value
            try:
                value = tuple(float(g) for g in given)
            except (TypeError, ValueError):
                value = ()
            if len(value) != 2 or not all(math.isfinite(g) for g in value):
                raise ValueError(f"gravity must be a finite (gx, gy), got {given!r}")
        super().__setattr__(name, value)

    def __post_init__(self):
        if self.backend not in BACKENDS:
            raise ValueError(f"backend must be one of {BACKENDS}, got {self.backend!r}")
        if self.backend == "numba":
            require_twins("backend='numba'")
        if self.broad_phase not in BROAD_PHASES:
            raise ValueError(f"broad_phase must be one of {BROAD_PHASES}, got {self.broad_phase!r}")
        if int(self.substeps) != self.substeps or self.substeps < 1:
            raise ValueError(f"substeps must be a whole number >= 1, got {self.substeps}")


@dataclass
class StepStats:
    """What the last sub-step saw: pair counts and the deepest penetration (m)."""

    candidate_pairs: int = 0
    manifolds: int = 0
    contact_points: int = 0
    max_penetration: float = 0.0
    bullets_stopped: int = 0


class World:
    """A list of bodies stepped under :class:`WorldSettings`.

    >>> from exercises.body import Body
    >>> ground = Body.box(10, 1, is_static=True, position=(0, -0.5))
    >>> ball = Body.circle(0.5, mass=1.0, position=(0, 2))
    >>> world = World([ground, ball])
    >>> for _ in range(120):
    ...     world.step(1 / 60)
    >>> bool(0.45 < ball.position[1] < 0.55)   # resting on the ground
    True
    """

    # The last (sub-)step's manifolds ``(i, j, Contact)`` and figures (:class:`StepStats`);
    # after a compiled step, made when first read.
    manifolds = MadeWhenAsked()
    stats = MadeWhenAsked()

    def __init__(self, bodies: list[Body], settings: WorldSettings | None = None,
                 joints: list[DistanceJoint] | None = None):
        self.bodies = list(bodies)
        # The one body state: every stage reads and writes these arrays, and each body
        # is a handle on its row (a body in two worlds belongs to the last one).
        self.state = BodyState.gather(self.bodies)
        self.settings = settings or WorldSettings()
        self.joints = list(joints or [])
        for joint in self.joints:
            if not (0 <= joint.a < len(self.bodies) and 0 <= joint.b < len(self.bodies)):
                raise ValueError(f"joint between bodies {joint.a} and {joint.b}: no such body")
        # Bodies joined by a joint do not collide with each other (Box2D's collideConnected = false).
        self._jointed = {(min(j.a, j.b), max(j.a, j.b)) for j in self.joints}
        backend = self.settings.backend
        if self.settings.soft_step:
            self.solver = SoftStepSolver(self.settings.solver, self.settings.soft, backend)
        else:
            self.solver = ContactSolver(self.settings.solver, backend)
        self.joint_solver = JointSolver(self.settings.solver.iterations, self.settings.solver.baumgarte,
                                        self.settings.solver.warm_starting, backend)
        self.time = 0.0
        self.manifolds = []
        #: The soft step compiled whole (``response/soft_step_numba.py`` of the instructor's edition), for a
        #: world of boxes or of discs with ``backend="numba"``; None where the readable stages run.
        self.compiled_soft_step = None
        self.stats = StepStats()
        self._static_shapes: dict[int, Shape] = {}
        self.look_again()

    def look_again(self) -> None:
        """Forget what the world keeps about its bodies between steps, and choose again
        whether the compiled soft step can run it: after a body's shape, its static or
        bullet flag or a static body's pose changed (``state.changes`` counts those;
        :meth:`step` calls this when it grows).  Masses and materials need nothing:
        every step reads them from the state."""
        self._changes_seen = self.state.changes
        self._static_shapes.clear()
        self._same_step = None
        compiled = None
        if self.settings.backend == "numba" and self.settings.soft_step:
            from .response.soft_step_numba import CompiledSoftStep  # deferred: compiles numba on first use

            if CompiledSoftStep.supports(self):
                compiled = self.compiled_soft_step
                circles = bool(self.bodies) and isinstance(self.bodies[0].shape, Circle)
                if compiled is None or compiled.circles != circles:
                    compiled = CompiledSoftStep(self.bodies, self.joints)
                # After each compiled step, contacts and figures are made when first read.
                self._compiled_world_recipes = {"_manifolds": compiled.contacts, "_stats": self._compiled_stats}
                self._compiled_solver_recipes = {"_stats": compiled.solver_stats,
                                                 "_contact_impulses": compiled.contact_impulses}
        self.compiled_soft_step = compiled

    # The algorithm --------------------------------------------------------------
    def step(self, dt: float) -> None:
        """Advance the world by ``dt`` seconds (``substeps`` sub-steps of ``h``)."""
        if self._same_step == (dt, id(self.settings), CountsChanges.changes, self.state.changes, len(self.bodies)):
            self.compiled_step_again(dt)      # as the last step: settings, bodies and dt unchanged
            return
        if not (0.0 < dt < math.inf):
            raise ValueError(f"dt must be a positive number of seconds, got {dt}")
        if len(self.bodies) != len(self.state.angle):
            raise ValueError(f"the world was made with {len(self.state)} bodies and now lists {len(self.bodies)}: "
                             "bodies cannot be added or removed; make a new World with the new list")
        h = dt / self.settings.substeps
        if self.state.changes != self._changes_seen:
            self.look_again()
        if self.compiled_soft_step is not None:        # the same soft step, compiled whole
            self.compiled_step(h)
            # The next step of the same dt under the same settings and bodies needs only
            # the compiled call (compiled_step_again); a settings field set (counted by
            # CountsChanges), other settings, a body change the state counts or another
            # dt takes this path again.
            self._same_step = ((dt, id(self.settings), CountsChanges.changes, self.state.changes, len(self.bodies))
                               if self.compiled_soft_step.settled(h) else None)
            return
        soft = self.settings.soft_step
        # The plain step finds contacts again for every sub-step (each is a whole step of
        # h); the soft step finds them once and takes all its sub-steps on them.
        rounds, substeps = (1, self.settings.substeps) if soft else (self.settings.substeps, 1)
        gravity = np.asarray(self.settings.gravity, dtype=float)
        state = self.state
        for _ in range(rounds):
            shapes = self.world_shapes()
            self.manifolds = self.find_contacts(shapes)
            self.solver.begin_step(self.bodies, self.manifolds, h)
            starts = self.bullet_starts() if soft else {}
            for _ in range(substeps):
                state.integrate_velocities(gravity, h)
                self.solver.solve_substep(state, h, use_bias=True)
                self.solve_joints(h, use_bias=True)
                moves = {} if soft else self.sweep_bullets(shapes, h)
                self.integrate_positions(moves, h)
                self.solve_joints(h, use_bias=False)
                self.solver.solve_substep(state, h, use_bias=False)
                self.time += h
            self.solver.end_step(state, h)
            self.stop_bullets(shapes, starts)

    def compiled_step(self, h: float) -> None:
        """The soft step (:meth:`step` with ``soft_step``) as one compiled function
        (``response/soft_step_numba.py`` of the instructor's edition)."""
        settings = self.settings
        self.compiled_soft_step.step(self.state, h, settings)
        for _ in range(settings.substeps):
            self.time += h
        MadeWhenAsked.set_recipes(self, self._compiled_world_recipes)
        MadeWhenAsked.set_recipes(self.solver, self._compiled_solver_recipes)
        self._same_h = (h,) * settings.substeps

    def compiled_step_again(self, dt: float) -> None:
        """:meth:`compiled_step` for the ``dt`` of the last step, whose parameters it keeps."""
        self.compiled_soft_step.step_again(self.state.numbers)
        for h in self._same_h:
            self.time += h
        self.__dict__.update(self._compiled_world_recipes)      # MadeWhenAsked.set_recipes, without its call
        self.solver.__dict__.update(self._compiled_solver_recipes)

    def _compiled_stats(self) -> StepStats:
        """The figures of the last compiled step (the recipe of :attr:`stats`)."""
        compiled = self.compiled_soft_step
        return StepStats(candidate_pairs=int(compiled.candidate_pairs), manifolds=compiled.manifold_count,
                         contact_points=len(compiled.point_floats),
                         max_penetration=compiled.solver_stats().max_penetration)

    # The stages -----------------------------------------------------------------
    def find_contacts(self, shapes: list[Shape]) -> list[tuple[int, int, Contact]]:
        """Broad and narrow phase: the manifolds ``(i, j, Contact)`` at the current poses.
        The soft step's are speculative: points up to ``SPECULATIVE_MARGIN`` apart, each
        with its signed separation."""
        if self.settings.soft_step:
            return self.speculative_narrow_phase(shapes, self.broad_phase(shapes, margin=SPECULATIVE_MARGIN))
        return self.narrow_phase(shapes, self.broad_phase(shapes))

    def solve_joints(self, h: float, use_bias: bool) -> None:
        """The distance joints' pass of a sub-step: biased after the contacts' velocity
        pass, unbiased (the soft step's relax, if on) after the positions moved.  The
        plain step's rods are rigid with a Baumgarte bias; the soft step's are stiff
        springs (``JOINT_HERTZ``, capped at a quarter of the sub-step rate)."""
        if not self.joints:
            return
        if not self.settings.soft_step:
            if use_bias:
                self.joint_solver.solve(self.bodies, self.joints, h)
        elif use_bias:
            softness = soft_coefficients(min(JOINT_HERTZ, 0.25 / h), JOINT_DAMPING_RATIO, h)
            self.joint_solver.solve(self.bodies, self.joints, h, softness=softness)
        elif self.settings.soft.relax:
            self.joint_solver.solve(self.bodies, self.joints, h, use_bias=False)

    def bullet_starts(self) -> dict[int, np.ndarray]:
        """Where each bullet is at the start of a soft step, which sweeps them once per
        step, at its end (:meth:`stop_bullets`), as Box2D v3 does."""
        if not self.settings.continuous:
            return {}
        return {k: self.state.position[k].copy() for k, body in enumerate(self.bodies)
                if body.is_bullet and not body.is_static}

    def stop_bullets(self, shapes: list[Shape], starts: dict[int, np.ndarray]) -> None:
        """A bullet whose path from ``starts`` crossed a static body goes back to where
        it first touched it; the next step's contacts turn it round."""
        for index, start in starts.items():
            move = self.state.position[index] - start
            first = self.time_of_first_hit(shapes[index], move)
            if first < 1.0:
                self.state.position[index] = start + first * move
                self.stats.bullets_stopped += 1

    def apply_gravity(self, h: float) -> None:
        """v += h g for every dynamic body."""
        self.state.integrate_velocities(np.asarray(self.settings.gravity, dtype=float), h)

    def world_shapes(self) -> list[Shape]:
        """Every body's shape in world coordinates (static ones computed once)."""
        shapes = []
        for index, body in enumerate(self.bodies):
            if body.is_static:
                if index not in self._static_shapes:
                    self._static_shapes[index] = body.world_shape()
                shapes.append(self._static_shapes[index])
            else:
                shapes.append(body.world_shape())
        return shapes

    def broad_phase(self, shapes: list[Shape], margin: float = 0.0) -> list[tuple[int, int]]:
        """Candidate pairs (i, j), i < j, whose AABBs overlap, touch, or are less than
        ``margin`` (m) apart; no static-static pair."""
        method = self.settings.broad_phase
        n = len(shapes)
        if method == "auto":
            method = auto_broad_phase(shapes)
        if method == "all_pairs":
            pairs = ((i, j) for i in range(n) for j in range(i + 1, n))
        else:
            aabbs = aabb_array(shapes) + 0.5 * margin * np.array([-1.0, -1.0, 1.0, 1.0])
            if method == "brute_force":
                pairs = sorted(pairs_brute_force(aabbs))
            elif method == "uniform_grid":
                pairs = sorted(pairs_uniform_grid(aabbs, cell_size=suggest_cell_size(aabbs)))
            elif method == "quadtree":
                pairs = sorted(pairs_quadtree(aabbs))
            elif self.settings.backend == "numba":       # the numpy grid's compiled twin
                from .broadphase.grid_numba import pairs_grid_numba

                pairs = [tuple(p) for p in pairs_grid_numba(aabbs).tolist()]
            else:
                pairs = [tuple(p) for p in pairs_grid_numpy(aabbs).tolist()]
        static = [b.is_static for b in self.bodies]
        kept = [(i, j) for i, j in pairs if not (static[i] and static[j]) and (i, j) not in self._jointed]
        self.stats = StepStats(candidate_pairs=len(kept))
        return kept

    def narrow_phase(self, shapes: list[Shape], pairs) -> list[tuple[int, int, Contact]]:
        """Contact manifolds of the candidate pairs that really touch."""
        manifolds = []
        for i, j in pairs:
            contact = collide(shapes[i], shapes[j])
            if contact is not None:
                manifolds.append((i, j, contact))
        self.stats.manifolds = len(manifolds)
        self.stats.contact_points = sum(len(c.points) for _, _, c in manifolds)
        self.stats.max_penetration = max((c.depth for _, _, c in manifolds), default=0.0)
        return manifolds

    def speculative_narrow_phase(self, shapes: list[Shape], pairs) -> list[tuple[int, int, Contact]]:
        """Manifolds of the pairs closer than ``SPECULATIVE_MARGIN`` (polygons) or
        touching (circles); each contact carries the signed separation of its points
        (``Contact.separations``, m, > 0 apart)."""
        found = [None] * len(pairs)
        # Every box-box pair at once with numpy (the loop over speculative_polygon_manifold
        # gives the same contacts to rounding), from the first pair: the soft contact
        # switches from rigid to spring where a separation crosses 0, so a rounding
        # difference of 1e-16 m at an exactly touching contact (a box resting on a slope)
        # changes the motion by up to 1e-6 m/s, and the compiled step
        # (``response/soft_step_numba.py`` of the instructor's edition) follows the numpy arithmetic exactly.
        # The student edition has no batch twin and takes the loop below.
        boxes = [k for k, (i, j) in enumerate(pairs) if isinstance(shapes[i], (AABB, OBB))
                 and isinstance(shapes[j], (AABB, OBB))] if HAS_TWINS else []
        batched = set(boxes)
        if boxes:
            from .narrowphase.speculative_batch import box_pose, manifolds_as_contacts, speculative_box_manifolds

            if self.settings.backend == "numba":   # the numpy version's compiled twin, equal to it
                from .narrowphase.box_pairs_numba import speculative_box_manifolds_numba as box_manifolds
            else:
                box_manifolds = speculative_box_manifolds
            a = [box_pose(shapes[pairs[k][0]]) for k in boxes]
            b = [box_pose(shapes[pairs[k][1]]) for k in boxes]
            batch = box_manifolds(*(np.array(column) for column in zip(*a)),
                                  *(np.array(column) for column in zip(*b)), SPECULATIVE_MARGIN)
            for k, contact in zip(boxes, manifolds_as_contacts(batch)):
                found[k] = contact
        for k, (i, j) in enumerate(pairs):
            if isinstance(shapes[i], Circle) or isinstance(shapes[j], Circle):
                found[k] = collide(shapes[i], shapes[j])
            elif k not in batched:
                found[k] = speculative_polygon_manifold(shapes[i], shapes[j], SPECULATIVE_MARGIN)
        manifolds = [(i, j, contact) for (i, j), contact in zip(pairs, found) if contact is not None]
        self.stats.manifolds = len(manifolds)
        self.stats.contact_points = sum(len(c.points) for _, _, c in manifolds)
        self.stats.max_penetration = max((c.depth for _, _, c in manifolds), default=0.0)
        return manifolds

    def sweep_bullets(self, shapes: list[Shape] | None, h: float) -> dict[int, np.ndarray]:
        """Displacements of bullets cut short at their first contact with a static body.

        ``shapes``: every body's world shape at the current poses, or None to compute
        the ones needed.
        """
        displacements: dict[int, np.ndarray] = {}
        if not self.settings.continuous:
            return displacements
        for index, body in enumerate(self.bodies):
            if not body.is_bullet or body.is_static:
                continue
            move = h * body.velocity
            first = self.time_of_first_hit(shapes[index] if shapes is not None else body.world_shape(), move)
            if first < 1.0:
                displacements[index] = first * move
                self.stats.bullets_stopped += 1
        return displacements

    def time_of_first_hit(self, shape: Shape, move: np.ndarray) -> float:
        """Fraction in (0, 1] of ``move`` (m) that ``shape`` travels before it first
        touches a static body (1: it touches none on the way)."""
        sweep = swept_aabb(shape, move)
        first = 1.0
        for k, body in enumerate(self.bodies):
            if not body.is_static:
                continue
            if k not in self._static_shapes:
                self._static_shapes[k] = body.world_shape()
            box = bounding_aabb(self._static_shapes[k])
            if np.all(box.min_corner <= sweep.max_corner) and np.all(sweep.min_corner <= box.max_corner):
                t = time_of_impact(shape, move, self._static_shapes[k])
                if t is not None and t > 0.0:
                    first = min(first, t)
        return first

    def integrate_positions(self, displacements: dict[int, np.ndarray], h: float) -> None:
        """x += h v (or a bullet's cut-short displacement), angle += h w."""
        starts = {index: self.state.position[index].copy() for index in displacements}
        self.state.integrate_positions(h)
        for index, move in displacements.items():
            self.state.position[index] = starts[index] + move
