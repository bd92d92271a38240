# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/response/sweep_solver.py on the instructor's
# side.
"""The plain step with the solver exercise's functions as its heart.

- :class:`SweepContactSolver` is a :class:`~.contact_solver.ContactSolver` whose velocity
  pass is written point by point, as box2d-lite writes it: the prestep of each contact
  point (:func:`~exercises.solver.contact_sweeps.prestep_point`) and the targets, warm
  start and sweeps (:func:`~exercises.solver.contact_sweeps.sweep_contacts`).
  Everything else is the engine's: the gathering of the bodies, last step's impulses
  matched by feature, the sweep order, split impulses and position projection.  Put it
  in a world with ``world.solver = SweepContactSolver(settings)``.
- :class:`SweepWorld` is a :class:`~exercises.world.World` whose whole step after the
  contact search is the exercise's :func:`~exercises.solver.contact_sweeps.step_bodies`
  (gravity, prestep, sweeps, new positions); the engine finds the contacts, matches
  last step's impulses and corrects positions after it.

The exercise's functions are called in batches, one batch per function and step,
through ``call_many(name, argument_tuples) -> results`` (by default the functions of
:mod:`exercises.solver.contact_sweeps`; the grader passes its sandbox's, so the worlds
step with a student's functions).  The two points of a manifold are solved one after
the other (no block solve), with accumulated impulses: ``block_solver`` must be False
and ``accumulate_impulses`` True.  SI units.
"""
from __future__ import annotations

import math

import numpy as np

from ..body import Body
from ..solver import contact_sweeps
from ..solver.contact_sweeps import BodyRow, ManifoldRows, StepSettings, TouchingPair
from ..world import World, WorldSettings
from .contact_preparation import PreparedContacts
from .contact_solver import ContactSolver
from .solver_settings import SolverSettings


def call_locally(name: str, cases: list) -> list:
    """``contact_sweeps.<name>(*case)`` for every argument tuple in ``cases``."""
    function = getattr(contact_sweeps, name)
    return [function(*case) for case in cases]


def step_settings(settings: SolverSettings, dt: float) -> StepSettings:
    """The exercise's :class:`StepSettings` of a step of ``dt`` (s) with ``settings``: the
    Baumgarte push only for ``position_correction="baumgarte"`` (split impulses and
    projection correct positions after the step)."""
    bias_factor = settings.baumgarte if settings.position_correction == "baumgarte" else 0.0
    return StepSettings(dt, settings.iterations, settings.restitution_threshold, bias_factor, settings.slop,
                        settings.max_push_velocity)


def manifold_members(c: PreparedContacts) -> list[tuple[int, int, list[int]]]:
    """Per manifold in sweep order: its bodies' rows ``a``, ``b`` and its points' indices
    in manifold order (the order of ``c.point``, ``c.depth`` ...)."""
    found = []
    for g in range(c.rows.group_count):
        first = int(c.rows.first[g])
        found.append((int(c.rows.a[g]), int(c.rows.b[g]), c.order[first:first + int(c.rows.count[g])].tolist()))
    return found


class SweepContactSolver(ContactSolver):
    """A :class:`ContactSolver` whose prestep and sweeps are the exercise's functions.

    Parameters
    ----------
    settings : SolverSettings, optional
        As for :class:`ContactSolver`, with ``block_solver=False``.
    call_many : callable, optional
        ``call_many(name, cases)``: the results of the function ``name`` of
        :mod:`exercises.solver.contact_sweeps` on each argument tuple of ``cases``.

    Examples
    --------
    A 1 kg box falling at 1 m/s onto static ground is stopped in one step, as by the
    engine's own solver:

    >>> from exercises.contact import Contact
    >>> ground = Body.box(10.0, 1.0, position=(0.0, -0.5), is_static=True)
    >>> box = Body.box(1.0, 1.0, position=(0.0, 0.5), velocity=(0.0, -1.0))
    >>> contact = Contact((0.0, 1.0), 0.0, [(-0.5, 0.0), (0.5, 0.0)], feature_ids=("left", "right"))
    >>> solver = SweepContactSolver(SolverSettings(position_correction="none", block_solver=False))
    >>> solver.solve([ground, box], [(0, 1, contact)], dt=1 / 60)
    >>> bool(np.abs(box.velocity).max() < 1e-12), round(solver.stats.total_normal_impulse, 12)
    (True, 1.0)
    """

    def __init__(self, settings: SolverSettings | None = None, call_many=call_locally):
        settings = SolverSettings(block_solver=False) if settings is None else settings
        if settings.block_solver or not settings.accumulate_impulses:
            raise ValueError("SweepContactSolver solves the points one by one with accumulated impulses: use "
                             "SolverSettings(block_solver=False, accumulate_impulses=True), got "
                             f"block_solver={settings.block_solver}, "
                             f"accumulate_impulses={settings.accumulate_impulses}")
        super().__init__(settings)
        self.call_many = call_many

    def _solve_velocities(self, c: PreparedContacts, velocity: np.ndarray, dt: float) -> np.ndarray:
        """The prestep, targets, warm start and sweeps by the exercise's functions; then
        split impulses as :class:`ContactSolver` (its module docstring, steps 2 to 5)."""
        if not c.point_count:
            self._split_impulse(c, velocity, np.zeros(0))
            return velocity
        centre_a, centre_b = c.centre[c.a].tolist(), c.centre[c.b].tolist()
        points = self.call_many("prestep_point", [
            (p, n, ca, cb, ima, imb, iia, iib, mu) for p, n, ca, cb, ima, imb, iia, iib, mu in zip(
                c.point.tolist(), c.normal.tolist(), centre_a, centre_b, c.ima.tolist(), c.imb.tolist(),
                c.iia.tolist(), c.iib.tolist(), c.columns["friction"].tolist())])
        groups = manifold_members(c)
        manifolds = [ManifoldRows(a, b, [points[k] for k in members], float(c.restitution[members[0]]),
                                  c.depth[members].tolist(), c.normal_total[members].tolist(),
                                  c.tangent_total[members].tolist()) for a, b, members in groups]
        swept, normal, tangent = self.call_many("sweep_contacts", [(velocity.tolist(), manifolds,
                                                                    step_settings(self.settings, dt))])[0]
        velocity = np.array(swept, dtype=float).reshape(-1, 3)
        self.keep_impulses(c, groups, normal, tangent, dt)
        return velocity

    def keep_impulses(self, c: PreparedContacts, groups: list, normal: list, tangent: list, dt: float) -> None:
        """Store the accumulated impulses the exercise's functions returned, per manifold of
        ``groups`` (:func:`manifold_members`), as this step's totals; then the split
        impulses of the step of ``dt`` (s) (step 5 of :class:`ContactSolver`)."""
        for (_, _, members), normal_totals, tangent_totals in zip(groups, normal, tangent):
            c.normal_total[members] = normal_totals
            c.tangent_total[members] = tangent_totals
        self._split_impulse(c, np.zeros((len(c.members), 3)), self.position_bias(c.depth, dt))


class SweepWorld(World):
    """A plain-step :class:`~exercises.world.World` whose step, once the contacts are
    found, is the exercise's :func:`~exercises.solver.contact_sweeps.step_bodies`.

    Each :meth:`step`: the broad and narrow phase at the current poses; the prestep of
    :class:`SweepContactSolver` (last step's impulses matched by feature, the sweep
    order); ``step_bodies`` on every body and the manifolds in sweep order, through
    ``call_many``; its poses, velocities and impulses written back (only dynamic bodies
    move, only turning ones turn); then the solver's position correction and memory.

    Parameters
    ----------
    bodies : list of Body
    settings : WorldSettings, optional
        One sub-step, no soft step; ``settings.solver`` as for :class:`SweepContactSolver`.
    call_many : callable, optional
        As for :class:`SweepContactSolver`.

    Examples
    --------
    A box resting on the ground stays there, as in the engine's own world:

    >>> ground = Body.box(10.0, 1.0, position=(0.0, -0.5), is_static=True)
    >>> box = Body.box(1.0, 1.0, position=(0.0, 0.5))
    >>> world = SweepWorld([ground, box], WorldSettings(solver=SolverSettings(block_solver=False)))
    >>> for _ in range(60):
    ...     world.step(1 / 60)
    >>> bool(abs(box.position[1] - 0.5) < 1e-6 and abs(box.velocity[1]) < 1e-9)
    True
    """

    def __init__(self, bodies: list[Body], settings: WorldSettings | None = None, call_many=call_locally):
        settings = settings or WorldSettings(solver=SolverSettings(block_solver=False))
        if settings.soft_step or settings.substeps != 1 or not settings.solver.rotation:
            raise ValueError("SweepWorld takes one plain sub-step with rotation: use WorldSettings(soft_step=False, "
                             f"substeps=1) and SolverSettings(rotation=True), got soft_step={settings.soft_step}, "
                             f"substeps={settings.substeps}, rotation={settings.solver.rotation}")
        super().__init__(bodies, settings)
        self.solver = SweepContactSolver(settings.solver, call_many)

    def step(self, dt: float) -> None:
        """Advance the world by ``dt`` seconds with ``step_bodies`` (see the class)."""
        if not (0.0 < dt < math.inf):
            raise ValueError(f"dt must be a positive number of seconds, got {dt}")
        if self.state.changes != self._changes_seen:
            self.look_again()
        state, solver = self.state, self.solver
        self.manifolds = self.find_contacts(self.world_shapes())
        solver.begin_step(self.bodies, self.manifolds, dt)
        c = solver.prepared
        world_index = {k: index for index, k in c.local.items()}
        groups = manifold_members(c)
        bodies = [BodyRow(*state.position[i].tolist(), float(state.angle[i]), *state.velocity[i].tolist(),
                          body.inverse_mass, body.inverse_inertia) for i, body in enumerate(self.bodies)]
        pairs = [TouchingPair(world_index[a], world_index[b], tuple(c.normal[members[0]].tolist()),
                              c.point[members].tolist(), c.depth[members].tolist(),
                              float(c.columns["friction"][members[0]]), float(c.restitution[members[0]]),
                              c.normal_total[members].tolist(), c.tangent_total[members].tolist())
                 for a, b, members in groups]
        moved, normal, tangent = self.call_step(bodies, pairs, dt)
        solver.keep_impulses(c, groups, normal, tangent, dt)
        state.position[state.dynamic] = moved[state.dynamic, :2]
        state.velocity[state.dynamic, :2] = moved[state.dynamic, 3:5]
        state.angle[state.turning] = moved[state.turning, 2]
        state.velocity[state.turning, 2] = moved[state.turning, 5]
        solver.finish_step(self.bodies, self.manifolds, dt)
        solver.end_step(state, dt)
        self.time += dt

    def call_step(self, bodies: list[BodyRow], pairs: list[TouchingPair], dt: float):
        """``step_bodies`` through the solver's ``call_many``: the new ``(x, y, angle, vx, vy,
        w)`` rows (an array) and the impulses per pair."""
        gravity = tuple(float(g) for g in self.settings.gravity)
        moved, normal, tangent = self.solver.call_many("step_bodies", [
            (bodies, pairs, gravity, step_settings(self.settings.solver, dt))])[0]
        return np.array(moved, dtype=float).reshape(-1, 6), normal, tangent
