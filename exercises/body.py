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

Every one of these may be set after the body is in a world (``box.friction = 0``): the
setters write the body's row of the world's state, which every stage of the step reads.
"""
from __future__ import annotations

import math

import numpy as np

from .body_state import (EXTENT_X, EXTENT_Y, FRICTION, INERTIA, INVERSE_INERTIA, INVERSE_MASS, MASS, RESTITUTION,
                         BodyState)
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


def as_shape(value) -> Shape:
    """``value`` if it is a shape (:data:`~exercises.shapes.Shape`); TypeError otherwise."""
    if not isinstance(value, (Circle, AABB, OBB, ConvexPolygon)):
        raise TypeError(f"a body's shape must be a Circle, AABB, OBB or ConvexPolygon, got {type(value).__name__}")
    return value


def shape_extents(shape_local: Shape) -> tuple[float, float]:
    """Half the width and height (m) of a shape in its own frame: a box's half-extents
    (an OBB's along its axes), a disc's radius twice, half a polygon's bounding box."""
    if isinstance(shape_local, Circle):
        return shape_local.radius, shape_local.radius
    if isinstance(shape_local, (AABB, OBB)):
        return float(shape_local.half_extents[0]), float(shape_local.half_extents[1])
    half = np.ptp(shape_local.vertices, axis=0) / 2
    return float(half[0]), float(half[1])


class Body:
    """A rigid body; see the module docstring for units and conventions.

    Its pose, velocities, mass, inertia, material and extents live in one row (its
    slot) of a :class:`~exercises.body_state.BodyState`: its own until a
    :class:`~exercises.world.World` gathers it into the world's state.  Reading
    ``position`` or ``velocity`` gives a copy of the row (what the body was doing
    then); assigning them, ``body.velocity = v`` or ``body.velocity += dv``, writes the
    row.  Changing one item of the copy (``body.velocity[0] = 0``) changes only the copy.
    """

    def __init__(self, shape: Shape, mass: float = 1.0, position=(0.0, 0.0), angle: float = 0.0,
                 velocity=(0.0, 0.0), angular_velocity: float = 0.0, restitution: float = 0.0,
                 friction: float = 0.0, is_static: bool = False, fixed_rotation: bool = False,
                 is_bullet: bool = False, name: str = ""):
        self.name = name
        position = np.array(position, dtype=float).reshape(2)
        velocity = np.array(velocity, dtype=float).reshape(2)
        for label, vec in (("position", position), ("velocity", velocity)):
            if not np.all(np.isfinite(vec)):
                raise ValueError(f"body {label} must be finite, got {vec.tolist()}")
        angle, angular_velocity = float(angle), float(angular_velocity)
        if not (math.isfinite(angle) and math.isfinite(angular_velocity)):
            raise ValueError("body angle and angular_velocity must be finite")
        self.bind(BodyState(1), 0)
        # What the mass properties are made from (_write_mass_properties): the flags,
        # the shape, the mass and an inertia set by hand (None: the shape's).
        self._is_static, self._fixed_rotation, self._is_bullet = bool(is_static), bool(fixed_rotation), bool(is_bullet)
        self._shape, self._inertia_set = as_shape(shape), None
        self._write_extents()
        self.mass = mass
        self.restitution = restitution
        self.friction = friction
        self.position, self.angle, self.velocity, self.angular_velocity = position, angle, velocity, angular_velocity

    def bind(self, state: BodyState, slot: int) -> None:
        """Make row ``slot`` of ``state`` this body's pose, velocity and properties (the
        row must already hold them: :meth:`BodyState.gather` fills it first)."""
        self._state, self._slot = state, slot

    def property_row(self) -> np.ndarray:
        """A copy of the body's row of :attr:`BodyState.properties` (columns as named there)."""
        return self._state.properties[self._slot].copy()

    # Mass, material, shape and flags: the body's row of its state, written by the setters.
    @property
    def mass(self) -> float:
        """Mass (kg).  Setting it keeps the inertia the shape gives that mass (or the
        one set by hand); a static body keeps an inverse mass of 0."""
        return float(self._state.properties[self._slot, MASS])

    @mass.setter
    def mass(self, value: float) -> None:
        mass = float(value) if self._is_static else as_length("body mass", value)
        if mass == 0 and not self._is_static:
            raise ValueError("a dynamic body needs a mass > 0 (use is_static=True for an immovable one)")
        self._state.properties[self._slot, MASS] = mass
        self._write_mass_properties()

    @property
    def inertia(self) -> float:
        """Moment of inertia about the centre of mass (kg m^2): the shape's for the
        body's mass (:func:`moment_of_inertia`) unless set by hand; inf for a static
        body or a fixed rotation.  Setting it (> 0; inf: the body cannot turn) keeps
        that value through later changes of mass or shape."""
        return float(self._state.properties[self._slot, INERTIA])

    @inertia.setter
    def inertia(self, value: float) -> None:
        inertia = as_length("body inertia", value) if value != math.inf else math.inf
        if inertia == 0:
            raise ValueError("a body's inertia must be > 0 (inf: it cannot turn)")
        self._inertia_set = inertia
        self._write_mass_properties()

    @property
    def friction(self) -> float:
        """Friction coefficient mu >= 0 (a pair's is the product of its bodies')."""
        return float(self._state.properties[self._slot, FRICTION])

    @friction.setter
    def friction(self, value: float) -> None:
        self._state.properties[self._slot, FRICTION] = as_length("friction", value)

    @property
    def restitution(self) -> float:
        """Restitution e >= 0 (a pair's is the product of its bodies')."""
        return float(self._state.properties[self._slot, RESTITUTION])

    @restitution.setter
    def restitution(self, value: float) -> None:
        self._state.properties[self._slot, RESTITUTION] = as_length("restitution", value)

    @property
    def shape(self) -> Shape:
        """The collision shape in the body's frame (centred on the centre of mass).
        Setting it writes the extents and (unless set by hand) the inertia."""
        return self._shape

    @shape.setter
    def shape(self, value: Shape) -> None:
        self._shape = as_shape(value)
        self._write_extents()
        self._write_mass_properties()
        self._state.changes += 1

    @property
    def is_static(self) -> bool:
        """Infinite mass: the solver never moves the body."""
        return self._is_static

    @is_static.setter
    def is_static(self, value: bool) -> None:
        if not value and self._is_static:       # the mass it had as a static body must do now
            mass = as_length("body mass", self.mass)
            if mass == 0:
                raise ValueError("a dynamic body needs a mass > 0: set its mass first")
        self._is_static = bool(value)
        self._write_mass_properties()
        self._state.changes += 1

    @property
    def fixed_rotation(self) -> bool:
        """The body cannot turn (infinite inertia); always True for an AABB shape."""
        return self._fixed_rotation or isinstance(self._shape, AABB)

    @fixed_rotation.setter
    def fixed_rotation(self, value: bool) -> None:
        self._fixed_rotation = bool(value)
        self._write_mass_properties()

    @property
    def is_bullet(self) -> bool:
        """The world sweeps the body against static ones (continuous detection)."""
        return self._is_bullet

    @is_bullet.setter
    def is_bullet(self, value: bool) -> None:
        self._is_bullet = bool(value)
        self._state.changes += 1

    def _write_mass_properties(self) -> None:
        """The row's inverse mass, inertia and inverse inertia, and the flags ``dynamic``
        and ``turning``, from the mass, the flags, the shape and a hand-set inertia.  A
        body that stops turning stops its angular velocity (the solver never gives it one)."""
        row, slot, state = self._state.properties[self._slot], self._slot, self._state
        mass = row[MASS]
        if self._is_static or self.fixed_rotation:
            inertia = math.inf
        else:
            inertia = self._inertia_set if self._inertia_set is not None else moment_of_inertia(self._shape, mass)
        row[INVERSE_MASS] = 0.0 if self._is_static else 1.0 / mass
        row[INERTIA] = inertia
        row[INVERSE_INERTIA] = 0.0 if math.isinf(inertia) else 1.0 / inertia
        if state.turning[slot] and not row[INVERSE_INERTIA] > 0.0:
            state.velocity[slot, 2] = 0.0
        state.dynamic[slot], state.turning[slot] = not self._is_static, row[INVERSE_INERTIA] > 0.0

    def _write_extents(self) -> None:
        """The row's extents: half the width and height of the shape in the body's frame."""
        self._state.properties[self._slot, EXTENT_X:EXTENT_Y + 1] = shape_extents(self._shape)

    # Pose and velocities: the body's row of its state, given out as copies.
    @property
    def position(self) -> np.ndarray:
        """Centre of mass (m), shape (2,)."""
        return self._state.position[self._slot].copy()

    @position.setter
    def position(self, value) -> None:
        self._state.position[self._slot] = value
        if self._is_static:
            self._state.changes += 1

    @property
    def angle(self) -> float:
        """Rotation (rad, counter-clockwise)."""
        return float(self._state.angle[self._slot])

    @angle.setter
    def angle(self, value: float) -> None:
        self._state.angle[self._slot] = value
        if self._is_static:
            self._state.changes += 1

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
        return float(self._state.properties[self._slot, INVERSE_MASS])

    @property
    def inverse_inertia(self) -> float:
        """1/I (1/(kg m^2)); 0 for a static body or a fixed rotation."""
        return float(self._state.properties[self._slot, INVERSE_INERTIA])

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
