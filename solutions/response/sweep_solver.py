"""The plain step's contact solver with the solver exercise's functions as its heart.

:class:`SweepContactSolver` is a :class:`~.contact_solver.ContactSolver` whose velocity
pass is written point by point, as box2d-lite writes it: the prestep of each contact
point (:func:`~solutions.solver.contact_sweeps.prestep_point` and
:func:`~solutions.solver.contact_sweeps.contact_target`) and the warm start and sweeps
(:func:`~solutions.solver.contact_sweeps.sweep_contacts`).  Everything else is the
engine's: the gathering of the bodies, last step's impulses matched by feature, the
sweep order, split impulses and position projection.  Put it in a world with
``world.solver = SweepContactSolver(settings)``: the world then steps with those
functions (a student's, in the student package).

The three functions are called in batches, one batch per function and step, through
``call_many(name, argument_tuples) -> results`` (by default the functions of
:mod:`solutions.solver.contact_sweeps`; the grader passes its sandbox's).  The two
points of a manifold are solved one after the other (no block solve), with
accumulated impulses: ``block_solver`` must be False and ``accumulate_impulses`` True.
SI units.
"""
from __future__ import annotations

import numpy as np

from ..solver import contact_sweeps
from ..solver.contact_sweeps import ManifoldRows
from .contact_preparation import PreparedContacts, closing_speeds
from .contact_solver import ContactSolver
from .solver_settings import SolverSettings


def call_locally(name: str, cases: list) -> list:
    """``contact_sweeps.<name>(*case)`` for every argument tuple in ``cases``."""
    function = getattr(contact_sweeps, name)
    return [function(*case) for case in cases]


class SweepContactSolver(ContactSolver):
    """A :class:`ContactSolver` whose prestep and sweeps are the exercise's functions.

    Parameters
    ----------
    settings : SolverSettings, optional
        As for :class:`ContactSolver`, with ``block_solver=False``.
    call_many : callable, optional
        ``call_many(name, cases)``: the results of the function ``name`` of
        :mod:`solutions.solver.contact_sweeps` on each argument tuple of ``cases``.

    Examples
    --------
    A 1 kg box falling at 1 m/s onto static ground is stopped in one step, as by the
    engine's own solver:

    >>> from solutions.body import Body
    >>> from solutions.contact import Contact
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
        """The prestep, warm start and sweeps by the exercise's functions; then split
        impulses as :class:`ContactSolver` (its module docstring, steps 2 to 5)."""
        settings = self.settings
        if not c.point_count:
            self._split_impulse(c, velocity, np.zeros(0))
            return velocity
        centre_a, centre_b = c.centre[c.a].tolist(), c.centre[c.b].tolist()
        points = self.call_many("prestep_point", [
            (p, n, ca, cb, ima, imb, iia, iib, mu) for p, n, ca, cb, ima, imb, iia, iib, mu in zip(
                c.point.tolist(), c.normal.tolist(), centre_a, centre_b, c.ima.tolist(), c.imb.tolist(),
                c.iia.tolist(), c.iib.tolist(), c.columns["friction"].tolist())])
        # The closing speeds after this step's forces, with the lever arms just found.
        rows = np.array(points, dtype=float).reshape(-1, 14)
        normal_velocity = closing_speeds(velocity, c.a, c.b, c.normal[:, 0], c.normal[:, 1], rows[:, 2], rows[:, 3])
        bias_factor = settings.baumgarte if settings.position_correction == "baumgarte" else 0.0
        targets = self.call_many("contact_target", [
            (vn, e, depth, dt, settings.restitution_threshold, bias_factor, settings.slop,
             settings.max_push_velocity)
            for vn, e, depth in zip(normal_velocity.tolist(), c.restitution.tolist(), c.depth.tolist())])

        # The manifolds in sweep order, each with its points in manifold order.
        manifolds = []
        for g in range(c.rows.group_count):
            first = int(c.rows.first[g])
            members = c.order[first:first + int(c.rows.count[g])].tolist()
            manifolds.append(ManifoldRows(int(c.rows.a[g]), int(c.rows.b[g]), [points[k] for k in members],
                                          [targets[k] for k in members], c.normal_total[members].tolist(),
                                          c.tangent_total[members].tolist()))
        swept, normal, tangent = self.call_many("sweep_contacts",
                                                [(velocity.tolist(), manifolds, settings.iterations)])[0]
        velocity = np.array(swept, dtype=float).reshape(-1, 3)
        for g, (normal_totals, tangent_totals) in enumerate(zip(normal, tangent)):
            first = int(c.rows.first[g])
            members = c.order[first:first + int(c.rows.count[g])]
            c.normal_total[members] = normal_totals
            c.tangent_total[members] = tangent_totals
        self._split_impulse(c, velocity, self.position_bias(c.depth, dt))
        return velocity
