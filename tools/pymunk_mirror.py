"""Build the same scene in pymunk (the oracle engine) and copy its state back.

pymunk 7.3.1 facts this relies on (measured): restitution and friction of a pair are
products of the two shapes' values, as in the reference engine; ``collision_slop``
defaults to 0.1 (pixel scale), so it is set to the solver's slop for metre scenes.
"""
from __future__ import annotations

import math

import numpy as np
import pymunk

from solutions.body import Body
from solutions.shapes import AABB, OBB, Circle, ConvexPolygon, box_vertices


def pymunk_shape(body: Body, pm_body: pymunk.Body) -> pymunk.Shape:
    """The pymunk shape of ``body.shape`` (local frame) attached to ``pm_body``."""
    s = body.shape
    if isinstance(s, Circle):
        return pymunk.Circle(pm_body, s.radius, offset=tuple(s.center))
    if isinstance(s, AABB):
        vertices = s.vertices()
    elif isinstance(s, OBB):
        vertices = box_vertices(s.center, s.half_extents, s.angle)
    else:
        vertices = s.vertices
    return pymunk.Poly(pm_body, [tuple(v) for v in np.asarray(vertices)], radius=0.0)


def build_space(bodies: list[Body], gravity=(0.0, -9.81), iterations: int = 10,
                collision_slop: float = 0.005, joints=None) -> tuple[pymunk.Space, list[pymunk.Body]]:
    """A pymunk Space mirroring ``bodies`` (and distance ``joints``: a PinJoint when
    rigid, a DampedSpring of the same frequency and damping ratio otherwise); returns
    it and the pymunk bodies in order.  Jointed bodies do not collide with each other."""
    space = pymunk.Space()
    space.gravity = tuple(gravity)
    space.iterations = iterations
    space.collision_slop = collision_slop
    pm_bodies = []
    for body in bodies:
        if body.is_static:
            pm_body = pymunk.Body(body_type=pymunk.Body.STATIC)
        else:
            moment = math.inf if math.isinf(body.inertia) else body.inertia
            pm_body = pymunk.Body(body.mass, moment)
        pm_body.position = tuple(body.position)
        pm_body.angle = body.angle
        pm_body.velocity = tuple(body.velocity)
        pm_body.angular_velocity = body.angular_velocity
        shape = pymunk_shape(body, pm_body)
        shape.elasticity = body.restitution
        shape.friction = body.friction
        space.add(pm_body, shape)
        pm_bodies.append(pm_body)
    for joint in joints or []:
        space.add(pymunk_joint(joint, bodies, pm_bodies))
    return space, pm_bodies


def pymunk_joint(joint, bodies: list[Body], pm_bodies: list[pymunk.Body]) -> pymunk.Constraint:
    """The pymunk constraint of a reference :class:`~solutions.joints.DistanceJoint`."""
    from solutions.joints import spring_coefficients

    a, b = pm_bodies[joint.a], pm_bodies[joint.b]
    if joint.frequency > 0:
        inverse = sum(0.0 if bodies[k].is_static else 1.0 / bodies[k].mass for k in (joint.a, joint.b))
        stiffness, damping = spring_coefficients(1.0 / inverse, joint.frequency, joint.damping_ratio)
        constraint = pymunk.DampedSpring(a, b, tuple(joint.anchor_a), tuple(joint.anchor_b), joint.length,
                                         stiffness, damping)
    else:
        constraint = pymunk.PinJoint(a, b, tuple(joint.anchor_a), tuple(joint.anchor_b))
        constraint.distance = joint.length
    constraint.collide_bodies = False
    return constraint


def copy_state(pm_bodies: list[pymunk.Body], bodies: list[Body]) -> None:
    """Copy pymunk's positions, angles and velocities into the reference bodies."""
    for pm_body, body in zip(pm_bodies, bodies):
        if body.is_static:
            continue
        body.position = np.array(pm_body.position, dtype=float)
        body.angle = float(pm_body.angle)
        body.velocity = np.array(pm_body.velocity, dtype=float)
        body.angular_velocity = float(pm_body.angular_velocity)
