# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/response/solver_settings.py on the
# instructor's side.
"""Settings and figures of the contact solvers: :class:`SolverSettings`, read by both
(:mod:`.contact_solver`, the plain step, and :mod:`.soft_step`, the soft step; its
position corrections by the plain step only), and :class:`SoftStepSettings`, the soft
step's own (its contact springs and relax pass).  SI units."""
from __future__ import annotations

import math
from dataclasses import dataclass

POSITION_CORRECTIONS = ("none", "baumgarte", "projection", "split_impulse")
ORDERS = ("manifolds", "colours")


class CountsChanges:
    """Settings whose every field set (at creation or after) adds one to ``CountsChanges.changes``,
    one count for all settings objects: a world that keeps what it made of its settings
    (the compiled soft step's parameters) makes it again only when the count moved.

    >>> before = CountsChanges.changes
    >>> SoftStepSettings().relax = False
    >>> CountsChanges.changes > before
    True
    """

    changes = 0

    def __setattr__(self, name: str, value) -> None:
        object.__setattr__(self, name, value)
        CountsChanges.changes += 1


@dataclass
class SolverSettings(CountsChanges):
    """Switches and constants of the contact solvers (:class:`~.contact_solver.ContactSolver`
    and :class:`~.soft_step.SoftStepSolver`; the soft step corrects positions with its
    springs and relax pass, :class:`SoftStepSettings`, instead of ``position_correction``,
    ``baumgarte``, ``correction_percent`` and ``slop``).

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
    block_solver : bool
        Solve the two normal impulses of a two-point manifold together, as one 2x2
        linear complementarity problem (Box2D's block solver,
        :func:`~exercises.solver.kernel.block_normal_impulses`), instead of one point
        after the other.  A face resting on a face then gets both impulses right in
        one go, without the spurious turn a point-by-point solve leaves behind.
        Manifolds whose 2x2 matrix is ill-conditioned
        (:data:`~exercises.solver.constraint_rows.MAX_CONDITION_NUMBER`) are solved
        point by point anyway.
    order : str
        The order in which the sweeps visit the manifolds
        (:func:`~exercises.solver.sweep_order.sweep_order`): ``"manifolds"`` (as
        found: one sweep carries an impulse through a whole stack) or ``"colours"``
        (colour by colour: the batches a parallel solver would solve at once; an
        impulse then travels about one contact per colour and sweep, so a stack sinks
        more).  Both cost the same here, one manifold after the other.
    max_push_velocity : float
        Cap (m/s) on the separating speed that removes overlap: the Baumgarte and
        split-impulse bias of the plain step, the soft contact's push in the soft step.
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
    block_solver: bool = True
    order: str = "manifolds"
    max_push_velocity: float = 3.0

    def __post_init__(self):
        if self.position_correction not in POSITION_CORRECTIONS:
            raise ValueError(f"position_correction must be one of {POSITION_CORRECTIONS}, "
                             f"got {self.position_correction!r}")
        if self.order not in ORDERS:
            raise ValueError(f"order must be one of {ORDERS}, got {self.order!r}")
        if int(self.iterations) != self.iterations or self.iterations < 0:
            raise ValueError(f"iterations must be an integer >= 0, got {self.iterations}")
        for name in ("baumgarte", "correction_percent"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(f"{name} must be in [0, 1], got {getattr(self, name)}")
        for name in ("slop", "restitution_threshold", "warm_start_match_distance", "max_push_velocity"):
            if not getattr(self, name) >= 0.0:
                raise ValueError(f"{name} must be >= 0, got {getattr(self, name)}")


@dataclass
class SoftStepSettings(CountsChanges):
    """The soft step's own settings (:mod:`.soft_step`); the plain step has none of these.

    Attributes
    ----------
    contact_hertz : float
        Natural frequency (Hz) of the soft contact spring, capped at a quarter of the
        sub-step rate (``inf``: the cap).  Contacts against static bodies use twice the
        frequency.
    contact_damping_ratio : float
        Damping ratio of the soft contact spring (dimensionless; 1 is critical damping).
    relax : bool
        After each sub-step's positions move, solve once more without the push (rigid,
        no bias), so that the push velocity is not kept; joints too.
    """

    contact_hertz: float = math.inf
    contact_damping_ratio: float = 10.0
    relax: bool = True

    def __post_init__(self):
        for name in ("contact_hertz", "contact_damping_ratio"):
            if not getattr(self, name) >= 0.0:
                raise ValueError(f"{name} must be >= 0, got {getattr(self, name)}")


def split_overrides(overrides: dict) -> tuple[dict, dict]:
    """Keyword settings split into those of :class:`SolverSettings` and those of
    :class:`SoftStepSettings`; a name of neither raises a TypeError that lists both.

    >>> split_overrides(dict(iterations=1, relax=False))
    ({'iterations': 1}, {'relax': False})
    """
    solver_names = set(SolverSettings.__dataclass_fields__)
    soft_names = set(SoftStepSettings.__dataclass_fields__)
    unknown = sorted(set(overrides) - solver_names - soft_names)
    if unknown:
        raise TypeError(f"unknown solver setting(s) {', '.join(unknown)}; SolverSettings has "
                        f"{', '.join(sorted(solver_names))} and SoftStepSettings {', '.join(sorted(soft_names))}")
    return ({k: v for k, v in overrides.items() if k in solver_names},
            {k: v for k, v in overrides.items() if k in soft_names})


@dataclass
class SolverStats:
    """What one step of a contact solver saw and did.

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
