# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/body.py on the instructor's side.
"""Rigid bodies: mass properties, pose, velocities and material.

A :class:`Body` owns one collision shape in its local frame, centred on the body's
centre of mass (the body's ``position``).  Units: kg, kg m^2, m, rad, m/s, rad/s.

- A static body (``is_static=True``) has infinite mass: its inverse mass and inverse
  inertia are 0 and the solver never moves it.
- ``fixed_rotation=True`` (or an AABB shape, which cannot turn) gives infinite inertia.
- ``is_bullet=True`` asks the world for continuous detection against static bodies.
- ``restitution`` e in [0, 1] and ``friction`` mu >= 0; a pair combines them as
  products (as pymunk does): e = e_A e_B, mu = mu_A mu_B.
"""
from __future__ import annotations

import math

import numpy as np

from .body_state import BodyState
from .shapes import AABB, OBB, Circle, ConvexPolygon, Shape, as_length, polygon_centroid
from .vector import rotation_matrix


def moment_of_inertia(shape_local: Shape, mass: float) -> float:
    """Moment of inertia (kg m^2) about the local origin of a uniform-density shape.

    Disc ``m r^2 / 2``; box ``m (w^2 + h^2) / 12`` with full widths; polygon by the
    triangle-fan formula.  The local shape is assumed centred on the origin.
    """
    if isinstance(shape_local, Circle):
        offset2 = float(shape_local.center @ shape_local.center)
        return mass * (0.5 * shape_local.radius**2 + offset2)
    if isinstance(shape_local, (AABB, OBB)):
        w, h = 2 * shape_local.half_extents
        offset2 = float(shape_local.center @ shape_local.center)
        return float(mass * ((w * w + h * h) / 12.0 + offset2))
    v = shape_local.vertices
    nxt = np.roll(v, -1, axis=0)
    cr = v[:, 0] * nxt[:, 1] - v[:, 1] * nxt[:, 0]
    area2 = float(np.sum(cr))
    terms = (v * v).sum(1) + (v * nxt).sum(1) + (nxt * nxt).sum(1)
    return mass * float(np.sum(cr * terms)) / (6.0 * area2)


class Body:
    """A rigid body; see the module docstring for units and conventions.

    Its pose and velocities live in one row (its slot) of a
    :class:`~exercises.body_state.BodyState`: its own until a
    :class:`~exercises.world.World` gathers it into the world's state.  Reading
    ``position`` or ``velocity`` gives a copy of the row (what the body was doing
    then); assigning them, ``body.velocity = v`` or ``body.velocity += dv``, writes the
    row.  Changing one item of the copy (``body.velocity[0] = 0``) changes only the copy.
    """

    def __init__(self, shape: Shape, mass: float = 1.0, position=(0.0, 0.0), angle: float = 0.0,
                 velocity=(0.0, 0.0), angular_velocity: float = 0.0, restitution: float = 0.0,
                 friction: float = 0.0, is_static: bool = False, fixed_rotation: bool = False,
                 is_bullet: bool = False, name: str = ""):
        self.shape = shape
        self.mass = mass
        self.is_static = is_static
        self.fixed_rotation = fixed_rotation
        self.is_bullet = is_bullet
        self.name = name
        position = np.array(position, dtype=float).reshape(2)
        velocity = np.array(velocity, dtype=float).reshape(2)
        for label, vec in (("position", position), ("velocity", velocity)):
            if not np.all(np.isfinite(vec)):
                raise ValueError(f"body {label} must be finite, got {vec.tolist()}")
        angle, angular_velocity = float(angle), float(angular_velocity)
        if not (math.isfinite(angle) and math.isfinite(angular_velocity)):
            raise ValueError("body angle and angular_velocity must be finite")
        if not self.is_static:
            self.mass = as_length("body mass", self.mass)
            if self.mass == 0:
                raise ValueError("a dynamic body needs a mass > 0 (use is_static=True for an immovable one)")
        self.restitution = as_length("restitution", restitution)
        self.friction = as_length("friction", friction)
        if isinstance(self.shape, AABB):
            self.fixed_rotation = True
        self.inertia = math.inf if (self.is_static or self.fixed_rotation) else moment_of_inertia(self.shape, self.mass)
        self.bind(BodyState(1), 0)
        self.position, self.angle, self.velocity, self.angular_velocity = position, angle, velocity, angular_velocity
        self._state.dynamic[0], self._state.turning[0] = not self.is_static, self.inverse_inertia > 0.0

    def bind(self, state: BodyState, slot: int) -> None:
        """Make row ``slot`` of ``state`` this body's pose and velocity (the row must
        already hold them: :meth:`BodyState.gather` fills it first)."""
        self._state, self._slot = state, slot

    # Pose and velocities: the body's row of its state, given out as copies.
    @property
    def position(self) -> np.ndarray:
        """Centre of mass (m), shape (2,)."""
        return self._state.position[self._slot].copy()

    @position.setter
    def position(self, value) -> None:
        self._state.position[self._slot] = value

    @property
    def angle(self) -> float:
        """Rotation (rad, counter-clockwise)."""
        return float(self._state.angle[self._slot])

    @angle.setter
    def angle(self, value: float) -> None:
        self._state.angle[self._slot] = value

    @property
    def velocity(self) -> np.ndarray:
        """Velocity of the centre of mass (m/s), shape (2,)."""
        return self._state.velocity[self._slot, :2].copy()

    @velocity.setter
    def velocity(self, value) -> None:
        self._state.velocity[self._slot, :2] = value

    @property
    def angular_velocity(self) -> float:
        """Angular velocity (rad/s, counter-clockwise)."""
        return float(self._state.velocity[self._slot, 2])

    @angular_velocity.setter
    def angular_velocity(self, value: float) -> None:
        self._state.velocity[self._slot, 2] = value

    def __repr__(self) -> str:
        return (f"Body(shape={self.shape!r}, mass={self.mass!r}, position={self.position.tolist()}, "
                f"angle={self.angle!r}, velocity={self.velocity.tolist()}, "
                f"angular_velocity={self.angular_velocity!r}, restitution={self.restitution!r}, "
                f"friction={self.friction!r}, is_static={self.is_static!r}, "
                f"fixed_rotation={self.fixed_rotation!r}, is_bullet={self.is_bullet!r}, name={self.name!r})")

    # Constructors for shapes centred on the centre of mass.
    @classmethod
    def circle(cls, radius: float, **kwargs) -> "Body":
        """A disc of ``radius`` (m) centred on the body."""
        return cls(Circle((0.0, 0.0), radius), **kwargs)

    @classmethod
    def box(cls, width: float, height: float, **kwargs) -> "Body":
        """A box ``width`` x ``height`` (m, full sizes) centred on the body."""
        return cls(OBB((0.0, 0.0), (width / 2, height / 2), 0.0), **kwargs)

    @classmethod
    def polygon(cls, vertices_local, **kwargs) -> "Body":
        """A convex CCW polygon, shifted so that its centroid is the body origin."""
        v = np.asarray(vertices_local, dtype=float)
        return cls(ConvexPolygon(v - polygon_centroid(v)), **kwargs)

    @property
    def inverse_mass(self) -> float:
        """1/m (1/kg); 0 for a static body."""
        return 0.0 if self.is_static else 1.0 / self.mass

    @property
    def inverse_inertia(self) -> float:
        """1/I (1/(kg m^2)); 0 for a static body or a fixed rotation."""
        return 0.0 if math.isinf(self.inertia) else 1.0 / self.inertia

    def world_shape(self) -> Shape:
        """The body's shape placed at its current position and angle (world frame)."""
        s = self.shape
        if isinstance(s, Circle):
            return Circle(self.position + rotation_matrix(self.angle) @ s.center, s.radius)
        if isinstance(s, AABB):
            return AABB(s.min_corner + self.position, s.max_corner + self.position)
        if isinstance(s, OBB):
            return OBB(self.position + rotation_matrix(self.angle) @ s.center, s.half_extents, s.angle + self.angle)
        return ConvexPolygon(s.vertices @ rotation_matrix(self.angle).T + self.position)

    def velocity_at(self, point_world) -> np.ndarray:
        """Velocity (m/s) of the material point at ``point_world``: v + w x r."""
        r = np.asarray(point_world, dtype=float) - self.position
        return self.velocity + self.angular_velocity * np.array([-r[1], r[0]])

    def kinetic_energy(self) -> float:
        """Translational plus rotational kinetic energy (J); 0 for a static body."""
        if self.is_static:
            return 0.0
        rot = 0.0 if math.isinf(self.inertia) else 0.5 * self.inertia * self.angular_velocity**2
        return 0.5 * self.mass * float(self.velocity @ self.velocity) + rot
