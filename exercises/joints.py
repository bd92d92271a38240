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
(the accumulated impulses of the last step are applied first).  The world solves
joints after contacts in each step.  Units: SI.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .body import Body


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
    """Sequential impulses over distance joints, with warm starting.

    Parameters
    ----------
    iterations : int
        Velocity iterations per step.
    baumgarte : float
        Fraction of a rigid joint's length error fed back per step (dimensionless).
    warm_starting : bool
        Start from last step's accumulated impulses.
    """

    def __init__(self, iterations: int = 10, baumgarte: float = 0.2, warm_starting: bool = True):
        self.iterations = int(iterations)
        self.baumgarte = float(baumgarte)
        self.warm_starting = warm_starting
        self.impulses: dict[int, float] = {}

    def solve(self, bodies: list[Body], joints: list[DistanceJoint], dt: float, use_bias: bool = True,
              softness: tuple[float, float, float] | None = None) -> None:
        """Apply the joint impulses of one step of ``dt`` (s) to the bodies' velocities.

        The soft step (:mod:`~solutions.response.soft_step`) calls it twice per
        sub-step: before the positions move with ``softness = (bias_rate, mass_scale,
        impulse_scale)`` of :func:`~solutions.response.soft_step.soft_coefficients`,
        which makes rigid joints stiff springs instead of Baumgarte rods, and after
        with ``use_bias=False``: rigid joints without bias and without a second warm
        start (the relax pass).  Spring joints are solved the same way in both calls.
        """
        if not joints:
            return
        rows = []
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
                bias = error * dt * k_spring * gamma
            elif not use_bias:
                gamma, bias = 0.0, 0.0
            elif softness is not None:
                # -m mass_scale (v + bias_rate C) - impulse_scale P, written as
                # -m' (v + bias + gamma P) with m' = m mass_scale, gamma = impulse_scale / m'.
                bias_rate, mass_scale, impulse_scale = softness
                gamma, bias = impulse_scale * inverse / mass_scale, bias_rate * error
            else:
                gamma, bias = 0.0, self.baumgarte / dt * error
            mass = 1.0 / (inverse + gamma) if softness is None or not use_bias or joint.frequency > 0 \
                else softness[1] / inverse
            accumulated = self.impulses.get(k, 0.0) if (self.warm_starting or not use_bias) else 0.0
            rows.append([a, b, ux, uy, rax, ray, rbx, rby, mass, bias, gamma, accumulated, k])
            if accumulated and use_bias:
                self._apply(a, b, ux * accumulated, uy * accumulated, rax, ray, rbx, rby)
        for _ in range(self.iterations):
            for row in rows:
                a, b, ux, uy, rax, ray, rbx, rby, mass, bias, gamma, accumulated, _ = row
                vax = a.velocity[0] - a.angular_velocity * ray
                vay = a.velocity[1] + a.angular_velocity * rax
                vbx = b.velocity[0] - b.angular_velocity * rby
                vby = b.velocity[1] + b.angular_velocity * rbx
                speed = (vbx - vax) * ux + (vby - vay) * uy
                impulse = -mass * (speed + bias + gamma * accumulated)
                row[11] = accumulated + impulse
                self._apply(a, b, ux * impulse, uy * impulse, rax, ray, rbx, rby)
        self.impulses = {row[12]: row[11] for row in rows}

    @staticmethod
    def _apply(a: Body, b: Body, px: float, py: float, rax, ray, rbx, rby) -> None:
        """Impulse (px, py) to B at its anchor, the opposite to A."""
        if not a.is_static:
            a.velocity = a.velocity - a.inverse_mass * np.array([px, py])
            a.angular_velocity -= a.inverse_inertia * (rax * py - ray * px)
        if not b.is_static:
            b.velocity = b.velocity + b.inverse_mass * np.array([px, py])
            b.angular_velocity += b.inverse_inertia * (rbx * py - rby * px)
