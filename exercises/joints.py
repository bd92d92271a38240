# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/joints.py on the instructor's side.
"""Distance joints: two anchor points kept at a distance, rigidly or as a soft spring.

A :class:`DistanceJoint` ties an anchor on body ``a`` to an anchor on body ``b``
(anchors in each body's local frame, m).  Its constraint is ``C = |p_B - p_A| - L``;
the solver applies equal and opposite impulses along ``u = (p_B - p_A) / |p_B - p_A|``
until the anchors' relative velocity along ``u`` is zero (plus a position bias).

- ``frequency == 0``: a rigid rod; the position error is fed back with a Baumgarte
  bias ``beta / h * C``.
- ``frequency > 0``: a damped spring of natural frequency ``f`` (Hz) and damping ratio
  ``zeta`` (dimensionless: 1 is critical damping), through Erin Catto's soft constraint
  with ``omega = 2 pi f``, ``k = m omega^2`` and ``c = 2 m zeta omega`` for the
  effective mass ``m`` of the joint (erratum 25 of the notes: zeta is not a stiffness).

:class:`JointSolver` runs the velocity iterations over all joints, with warm starting
(the accumulated impulses of the last step are applied first); each joint is a row
of the same solver kernel as the contacts (:mod:`exercises.solver.kernel`).  The world solves
joints after contacts in each step.  Units: SI.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .body import Body
from .solver.constraint_rows import ConstraintRows
from .solver.kernel import kernel


@dataclass
class DistanceJoint:
    """Anchor ``anchor_a`` (local to body ``a``) kept at ``length`` (m) from ``anchor_b``.

    ``a`` and ``b`` are indices into the world's body list.
    """

    a: int
    b: int
    anchor_a: tuple[float, float] = (0.0, 0.0)
    anchor_b: tuple[float, float] = (0.0, 0.0)
    length: float = 1.0
    frequency: float = 0.0
    damping_ratio: float = 0.0

    def __post_init__(self):
        if self.a == self.b:
            raise ValueError("a joint needs two different bodies")
        for name in ("length", "frequency", "damping_ratio"):
            value = float(getattr(self, name))
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"joint {name} must be a finite number >= 0, got {value}")
            setattr(self, name, value)


def anchor_world(body: Body, anchor_local) -> tuple[float, float]:
    """World position (m) of a point given in the body's local frame."""
    c, s = math.cos(body.angle), math.sin(body.angle)
    x, y = anchor_local
    return body.position[0] + c * x - s * y, body.position[1] + s * x + c * y


def spring_coefficients(mass: float, frequency: float, damping_ratio: float) -> tuple[float, float]:
    """Stiffness ``k`` (N/m) and damping ``c`` (N s/m) of a spring of natural frequency
    ``frequency`` (Hz) and damping ratio ``damping_ratio`` acting on ``mass`` (kg).

    >>> k, c = spring_coefficients(2.0, 1.0, 0.5)
    >>> round(k, 4), round(c, 4)
    (78.9568, 12.5664)
    """
    omega = 2 * math.pi * frequency
    return mass * omega * omega, 2 * mass * damping_ratio * omega


class JointSolver:
    """Sequential impulses over distance joints, with warm starting: each joint is one
    constraint row of the solver kernel (:func:`~exercises.solver.kernel.solve_constraints`),
    bilateral (its impulse may pull as well as push), without friction.

    Parameters
    ----------
    iterations : int
        Velocity iterations per step.
    baumgarte : float
        Fraction of a rigid joint's length error fed back per step (dimensionless).
    warm_starting : bool
        Start from last step's accumulated impulses.
    backend : str
        ``"python"`` (the readable kernel) or ``"numba"`` (its compiled twin).
    """

    def __init__(self, iterations: int = 10, baumgarte: float = 0.2, warm_starting: bool = True,
                 backend: str = "python"):
        self.iterations = int(iterations)
        self.baumgarte = float(baumgarte)
        self.warm_starting = warm_starting
        self.backend = backend
        self.impulses: dict[int, float] = {}

    def solve(self, bodies: list[Body], joints: list[DistanceJoint], dt: float, use_bias: bool = True,
              softness: tuple[float, float, float] | None = None) -> None:
        """Apply the joint impulses of one step of ``dt`` (s) to the bodies' velocities.

        Each joint is a row along ``u`` with ``K = 1/m_A + 1/m_B + (r_A x u)^2 / I_A +
        (r_B x u)^2 / I_B`` and the kernel's update ``dP = (mass_scale / K) (target -
        v_u) - impulse_scale P``:

        - rigid rod, Baumgarte: ``target = -beta / dt * C``, scales ``(1, 0)``;
        - rigid rod in the soft step (``softness = (bias_rate, mass_scale,
          impulse_scale)`` of :func:`~exercises.response.soft_step.soft_coefficients`):
          ``target = -bias_rate * C`` with those scales: a stiff spring instead of a
          Baumgarte rod;
        - spring joint (``frequency > 0``), Catto's soft constraint with ``gamma = 1 /
          (dt (c + dt k))``: ``target = -dt k gamma C``, ``mass_scale = K / (K + gamma)``,
          ``impulse_scale = gamma / (K + gamma)``;
        - ``use_bias=False`` (the soft step's relax pass): rigid rods without bias and
          without a second warm start; springs as above.
        """
        if not joints:
            return
        members: dict[int, int] = {}
        columns: dict[str, list] = {name: [] for name in ConstraintRows.GROUP_FIELDS + ConstraintRows.ROW_FIELDS}
        target, mass_scale, impulse_scale, total, which = [], [], [], [], []
        for k, joint in enumerate(joints):
            a, b = bodies[joint.a], bodies[joint.b]
            pa, pb = anchor_world(a, joint.anchor_a), anchor_world(b, joint.anchor_b)
            dx, dy = pb[0] - pa[0], pb[1] - pa[1]
            distance = math.hypot(dx, dy)
            ux, uy = (dx / distance, dy / distance) if distance > 1e-12 else (1.0, 0.0)
            rax, ray = pa[0] - a.position[0], pa[1] - a.position[1]
            rbx, rby = pb[0] - b.position[0], pb[1] - b.position[1]
            cra, crb = rax * uy - ray * ux, rbx * uy - rby * ux
            inverse = (a.inverse_mass + b.inverse_mass + a.inverse_inertia * cra * cra
                       + b.inverse_inertia * crb * crb)
            if inverse == 0.0:
                continue
            error = distance - joint.length
            if joint.frequency > 0:
                k_spring, c_damp = spring_coefficients(1.0 / inverse, joint.frequency, joint.damping_ratio)
                gamma = dt * (c_damp + dt * k_spring)
                gamma = 1.0 / gamma if gamma > 0 else 0.0
                row = (-error * dt * k_spring * gamma, inverse / (inverse + gamma), gamma / (inverse + gamma))
            elif not use_bias:
                row = (0.0, 1.0, 0.0)
            elif softness is not None:
                bias_rate, soft_mass, soft_impulse = softness
                row = (-bias_rate * error, soft_mass, soft_impulse)
            else:
                row = (-self.baumgarte / dt * error, 1.0, 0.0)
            for index in (joint.a, joint.b):
                members.setdefault(index, len(members))
            group = dict(a=members[joint.a], b=members[joint.b], nx=ux, ny=uy, ima=a.inverse_mass,
                         imb=b.inverse_mass, iia=a.inverse_inertia, iib=b.inverse_inertia, first=len(which),
                         count=1, block=False, k11=0.0, k12=0.0, k22=0.0, rn_a=cra, rn_b=crb, rt_a=0.0, rt_b=0.0,
                         mass_normal=1.0 / inverse, mass_tangent=0.0, friction=0.0, lower=-math.inf)
            for name, value in group.items():
                columns[name].append(value)
            target.append(row[0])
            mass_scale.append(row[1])
            impulse_scale.append(row[2])
            total.append(self.impulses.get(k, 0.0) if (self.warm_starting or not use_bias) else 0.0)
            which.append(k)
        if not which:
            self.impulses = {}
            return
        rows = ConstraintRows(**{name: np.array(values) for name, values in columns.items()})
        order = list(members)
        velocity = np.array([(*bodies[i].velocity.tolist(), float(bodies[i].angular_velocity)) for i in order],
                            dtype=float).reshape(-1, 3)
        normal_total = np.array(total, dtype=float)
        if use_bias:   # warm start: last step's impulses first
            for g, impulse in enumerate(total):
                if impulse:
                    _apply(velocity, rows, g, impulse)
        kernel(self.backend)(velocity, rows, self.iterations, normal_total, np.zeros(len(which)),
                             np.array(target), np.array(mass_scale), np.array(impulse_scale), use_friction=False,
                             use_block=False)
        for row, index in enumerate(order):
            body = bodies[index]
            if not body.is_static:
                body.velocity = velocity[row, :2].copy()
                body.angular_velocity = float(velocity[row, 2])
        self.impulses = dict(zip(which, normal_total.tolist()))


def _apply(velocity: np.ndarray, rows: ConstraintRows, g: int, impulse: float) -> None:
    """Impulse ``impulse`` (N s) along group ``g``'s direction to B, the opposite to A."""
    a, b = int(rows.a[g]), int(rows.b[g])
    nx, ny = float(rows.nx[g]), float(rows.ny[g])
    velocity[a] -= (rows.ima[g] * impulse * nx, rows.ima[g] * impulse * ny, rows.iia[g] * rows.rn_a[g] * impulse)
    velocity[b] += (rows.imb[g] * impulse * nx, rows.imb[g] * impulse * ny, rows.iib[g] * rows.rn_b[g] * impulse)
