"""The prestep shared by both contact solvers, and their memory of last step's impulses.

:class:`ContactPreparation` gathers the bodies in contact and pre-computes, for every
contact point, what the solver kernel needs (the lever arms and effective masses of
the solver exercise's :func:`~solutions.solver.contact_sweeps.prestep_point`, pair
coefficients, the closing speeds), puts the points in sweep order as
:class:`~solutions.solver.constraint_rows.ConstraintRows`, recalls last step's
impulses for warm starting and, after the solve, remembers this step's.  The plain
step (:class:`~.contact_solver.ContactSolver`) and the soft step
(:class:`~.soft_step.SoftStepSolver`) each build on it; neither inherits the other.
Normal from body A to body B; SI units.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..body import Body
from ..contact import Contact
from ..solver.constraint_rows import ConstraintRows, block_is_well_conditioned, normal_block_matrix
from ..solver.contact_point import ContactPoint
from ..solver.contact_sweeps import contact_target, prestep_point
from ..solver.sweep_order import sweep_order
from ..made_when_asked import MadeWhenAsked
from ..twins import require_twins
from .solver_settings import SolverSettings, SolverStats

#: The twins of the solver kernel (:func:`solutions.solver.kernel.kernel`).
BACKENDS = ("python", "numba")

def closing_speeds(velocity: np.ndarray, a: np.ndarray, b: np.ndarray, nx: np.ndarray, ny: np.ndarray,
                   rn_a: np.ndarray, rn_b: np.ndarray) -> np.ndarray:
    """Relative normal velocity ``v_n`` (m/s, < 0 closing) of each contact point, from the
    velocity rows ``(vx, vy, w)`` of its bodies ``a`` and ``b`` and its normal and
    ``r x n`` lever arms.

    >>> closing_speeds(np.array([[0.0, 0.0, 0.0], [0.0, -2.0, 1.0]]), np.array([0]), np.array([1]),
    ...                np.array([0.0]), np.array([1.0]), np.array([0.0]), np.array([0.5])).tolist()
    [-1.5]
    """
    va, vb = velocity[a], velocity[b]
    return (vb[:, 0] - va[:, 0]) * nx + (vb[:, 1] - va[:, 1]) * ny + vb[:, 2] * rn_b - va[:, 2] * rn_a


def contact_targets(normal_velocity: np.ndarray, restitution: np.ndarray, depth: np.ndarray, dt: float,
                    settings: SolverSettings, bias_factor: float) -> np.ndarray:
    """The separating normal velocity (m/s) each point's normal row aims at: the solver
    exercise's :func:`~solutions.solver.contact_sweeps.contact_target` of every point, from
    its closing speed (m/s), restitution and depth (m), with the threshold, slop and
    push cap of ``settings`` and the Baumgarte ``bias_factor`` (0: no push).

    >>> contact_targets(np.array([-2.0, -0.5]), np.array([0.5, 0.5]), np.zeros(2), 0.01, SolverSettings(), 0.0).tolist()
    [1.0, 0.0]
    """
    return np.array([contact_target(vn, e, d, dt, settings.restitution_threshold, bias_factor, settings.slop,
                                    settings.max_push_velocity)
                     for vn, e, d in zip(normal_velocity.tolist(), restitution.tolist(), depth.tolist())],
                    dtype=float)


@dataclass
class PreparedContacts:
    """The contact points of one step, gathered and pre-computed once (the prestep).

    Per body in contact (rows of ``velocity``): ``members`` and their ``centre`` (m),
    ``inverse_inertia``; ``local`` maps a world body index to its row.  Per point, in
    manifold order: bodies ``a``, ``b`` (rows), ``normal``, ``point`` (m), ``depth`` (m),
    lever arms ``r_a``, ``r_b`` (m), inverse masses and inertias of A and B, pair
    ``restitution``, ``normal_velocity`` before any impulse (m/s), warm-start keys and
    the accumulated impulses ``normal_total``, ``tangent_total`` (N s).  ``columns``
    holds the per-point arrays of the prestep in manifold order; ``rows`` the kernel's
    rows (:class:`~solutions.solver.constraint_rows.ConstraintRows`) in sweep order,
    and ``order`` maps a sweep position to its index in manifold order.  Each solver
    makes its targets (:func:`~solutions.solver.contact_sweeps.contact_target`) from
    closing speeds it measures when it needs them.
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
    rows: ConstraintRows
    order: np.ndarray
    manifold_count: int
    point_count: int


class ContactPreparation:
    """Prestep and impulse memory of a contact solver (module docstring).

    Parameters
    ----------
    settings : SolverSettings, optional
        Switches and constants; the defaults follow box2d-lite.
    backend : str
        Which twin of the solver kernel runs the sweeps: ``"python"``, the readable
        loop of :mod:`solutions.solver.kernel` (the teaching version), or ``"numba"``,
        the same loop compiled (:mod:`solutions.solver.kernel_numba`, tested equal to
        1e-12; numba is imported only when asked for).  Not a setting of the physics:
        both give the same motion.

    Attributes
    ----------
    settings : SolverSettings
    stats : SolverStats
        Figures of the last step.
    contact_impulses : list of tuple
        One ``(i, j, point, normal_impulse, tangent_impulse)`` per contact point of the
        last step; impulses in N s, given to body j and the opposite to body i, the
        tangent one along ``(n_y, -n_x)``.
    """

    # After a compiled step, made when first read (see the class docstring for both).
    stats = MadeWhenAsked()
    contact_impulses = MadeWhenAsked()

    def __init__(self, settings: SolverSettings | None = None, backend: str = "python"):
        self.settings = SolverSettings() if settings is None else settings
        if backend not in BACKENDS:
            raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
        if backend == "numba":
            require_twins("backend='numba'")
        self.backend = backend
        self.stats = SolverStats()
        self.contact_impulses: list[tuple] = []
        self.reset()

    def reset(self) -> None:
        """Forget last step's impulses (for example after bodies were removed and
        indices changed meaning)."""
        self._impulses_by_feature: dict[tuple, tuple] = {}
        self._impulses_by_pair: dict[tuple[int, int], list[tuple]] = {}
        self._previous_dt: float | None = None
        self._contacts: PreparedContacts | None = None

    @property
    def prepared(self) -> PreparedContacts:
        """The contacts of the step that ``begin_step`` began (RuntimeError before it)."""
        if self._contacts is None:
            raise RuntimeError(f"{type(self).__name__}: call begin_step() before solving or ending a step")
        return self._contacts

    def prepare(self, bodies: list[Body], manifolds: list[tuple[int, int, Contact]], dt: float,
                 block_solver: bool) -> PreparedContacts:
        """Steps 1 and 2 of :meth:`solve` and the recalled warm-start impulses (not yet applied)."""
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
        ima, imb = inverse_mass[a], inverse_mass[b]
        iia, iib = inverse_inertia[a], inverse_inertia[b]
        # Each point's lever arms and effective masses: the solver exercise's prestep (in the
        # student edition the student's own), one row of ContactPoint's fields per point.
        prestep = np.array([prestep_point(*arguments) for arguments in zip(
            point.tolist(), normal.tolist(), centre[a].tolist(), centre[b].tolist(), ima.tolist(), imb.tolist(),
            iia.tolist(), iib.tolist(), friction.tolist())], dtype=float).reshape(-1, len(ContactPoint._fields))
        field = dict(zip(ContactPoint._fields, prestep.T))
        rn_a, rn_b, rt_a, rt_b = field["rn_a"], field["rn_b"], field["rt_a"], field["rt_b"]
        mass_normal, mass_tangent = field["mass_normal"], field["mass_tangent"]
        normal_velocity = closing_speeds(velocity, a, b, nx, ny, rn_a, rn_b)

        # Last step's accumulated impulses, matched by feature id or position.
        point_keys = self._point_keys(manifolds)
        normal_total = np.zeros(point_count)
        tangent_total = np.zeros(point_count)
        if warm_start:
            self._recall_impulses(manifolds, point_keys, normal_total, tangent_total)
            normal_total *= dt_ratio
            tangent_total *= dt_ratio if settings.friction else 0.0
        columns = dict(a=a, b=b, nx=nx, ny=ny, rn_a=rn_a, rn_b=rn_b, rt_a=rt_a, rt_b=rt_b, ima=ima, imb=imb,
                       iia=iia, iib=iib, mass_normal=mass_normal, mass_tangent=mass_tangent,
                       friction=friction)
        rows, order = self._sweep_rows(manifolds, local, counts, inverse_mass + inverse_inertia > 0.0, columns,
                                       block_solver)
        return PreparedContacts(local=local, members=members, velocity=velocity, centre=centre,
                                inverse_inertia=inverse_inertia, a=a, b=b, normal=normal, point=point, depth=depth,
                                r_a=r_a, r_b=r_b, ima=ima, imb=imb, iia=iia, iib=iib, restitution=restitution,
                                normal_velocity=normal_velocity,
                                point_keys=point_keys, normal_total=normal_total, tangent_total=tangent_total,
                                warm_started=int(np.count_nonzero(normal_total)) if warm_start else 0,
                                columns=columns, rows=rows, order=order,
                                manifold_count=len(manifolds),
                                point_count=point_count)



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
                    block_solver: bool) -> tuple[ConstraintRows, np.ndarray]:
        """The kernel's rows: points and manifolds in sweep order, with the 2x2 matrices
        ``K`` of the manifolds solved as blocks.

        ``columns`` holds the per-point arrays of the prestep in manifold order.
        Returns the rows and ``order``: sweep position -> index in manifold order.
        """
        counts = np.array(counts, dtype=int)
        starts = np.cumsum(counts) - counts                      # first point of each manifold
        manifold_a = np.array([local[i] for i, _, _ in manifolds], dtype=int)
        manifold_b = np.array([local[j] for _, j, _ in manifolds], dtype=int)
        manifold_order, _ = sweep_order(manifold_a, manifold_b, movable, self.settings.order)
        count = counts[manifold_order]
        first = np.cumsum(count) - count                         # in sweep order
        order = (np.repeat(starts[manifold_order] - first, count) + np.arange(count.sum())).astype(int)
        point = {name: columns[name][order] for name in columns}
        # K = J M^-1 J^T of the two normal rows of each two-point manifold (same bodies A, B).
        k11, k12, k22 = np.zeros((3, len(manifolds)))
        two = count == 2
        p1 = first[two]
        p2 = p1 + 1
        k11[two], k12[two], k22[two] = normal_block_matrix(
            *(point[name][p1] for name in ("ima", "imb", "iia", "iib")),
            point["rn_a"][p1], point["rn_b"][p1], point["rn_a"][p2], point["rn_b"][p2])
        block = two & block_solver & block_is_well_conditioned(k11, k12, k22)
        rows = ConstraintRows(
            **{name: point[name][first] for name in ("a", "b", "nx", "ny", "ima", "imb", "iia", "iib")},
            first=first, count=count, block=block, k11=np.where(block, k11, 0.0), k12=np.where(block, k12, 0.0),
            k22=np.where(block, k22, 0.0),
            **{name: point[name] for name in ("rn_a", "rn_b", "rt_a", "rt_b", "mass_normal", "mass_tangent",
                                             "friction")},
            lower=np.zeros(len(order)))
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
