# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/body_state.py on the instructor's side.
"""The one body state: poses, velocities, masses, materials and sizes of a world's bodies as arrays.

A :class:`~exercises.body.Body` does not hold its own position, velocity, mass or
friction: it is a handle on one row (its *slot*) of a :class:`BodyState`, whose
properties read the row and whose setters write it (as pymunk's write its C struct).  A body made on its own gets a
state of one row; a :class:`~exercises.world.World` gathers its bodies into one state
of ``n`` rows and binds each body to its row, so that every stage of the step (and the
compiled twins) reads and writes the same arrays, every step: ``body.position`` always
says where the world has put the body, and ``body.friction = 0`` set after the world
was made is what the next step uses.  Nothing is copied between stages.

Arrays (row ``k`` is the body in slot ``k``):

- ``position`` (n, 2): centre of mass (m);
- ``angle`` (n,): rad, counter-clockwise;
- ``velocity`` (n, 3): rows ``(vx, vy, w)`` in m/s and rad/s;
- ``dynamic`` (n,): the body moves (not static);
- ``turning`` (n,): the body turns (finite inertia);
- ``properties`` (n, ``PROPERTY_COUNT``): one row of numbers per body, columns
  ``EXTENT_X``, ``EXTENT_Y``: half the width and height of its shape in its own frame
  (m: a box's half-extents, a disc's radius twice, a polygon's local bounding box);
  ``INVERSE_MASS`` (1/kg, 0 for a static body), ``INVERSE_INERTIA`` (1/(kg m^2), 0
  for a body that cannot turn), ``FRICTION``, ``RESTITUTION``, ``MASS`` (kg) and
  ``INERTIA`` (kg m^2, inf for a body that cannot turn).

``position``, ``angle``, ``velocity`` and ``properties`` are consecutive blocks of one
array, ``numbers`` (:func:`state_arrays`), so that the compiled step takes them as one
argument (each array a compiled function is called with costs the call about 0.2 us).

>>> state = BodyState(2)
>>> state.position[1] = (3.0, 4.0)
>>> state.position.tolist(), state.velocity.shape
([[0.0, 0.0], [3.0, 4.0]], (2, 3))
"""
from __future__ import annotations

import numpy as np

#: Columns of :attr:`BodyState.properties` (module docstring).
EXTENT_X, EXTENT_Y, INVERSE_MASS, INVERSE_INERTIA, FRICTION, RESTITUTION, MASS, INERTIA = range(8)
PROPERTY_COUNT = 8
#: Numbers per body in :attr:`BodyState.numbers`: position (2), angle (1), velocity (3), properties.
NUMBERS_PER_BODY = 6 + PROPERTY_COUNT


def state_arrays(numbers: np.ndarray) -> tuple:
    """The views ``position`` (n, 2), ``angle`` (n,), ``velocity`` (n, 3) and
    ``properties`` (n, ``PROPERTY_COUNT``) of a state's ``numbers``, blocks one after the other.

    >>> position, angle, velocity, properties = state_arrays(np.arange(2.0 * NUMBERS_PER_BODY))
    >>> position.tolist(), angle.tolist(), velocity[1].tolist()
    ([[0.0, 1.0], [2.0, 3.0]], [4.0, 5.0], [9.0, 10.0, 11.0])
    """
    n = numbers.shape[0] // NUMBERS_PER_BODY
    return (numbers[:2 * n].reshape((n, 2)), numbers[2 * n:3 * n], numbers[3 * n:6 * n].reshape((n, 3)),
            numbers[6 * n:].reshape((n, PROPERTY_COUNT)))


class BodyState:
    """Poses, velocities and properties of ``n`` bodies (module docstring)."""

    def __init__(self, n: int):
        self.numbers = np.zeros(NUMBERS_PER_BODY * n)
        self.position, self.angle, self.velocity, self.properties = state_arrays(self.numbers)
        self.dynamic = np.zeros(n, dtype=bool)
        self.turning = np.zeros(n, dtype=bool)
        #: Counts the changes a world keeps something for (its static bodies' world
        #: shapes, its choice of compiled step): a shape replaced, a static or bullet
        #: flag switched, a static body moved.  The world looks again when it grows.
        self.changes = 0

    def __len__(self) -> int:
        return len(self.angle)

    @classmethod
    def gather(cls, bodies) -> "BodyState":
        """One state holding every body's pose, velocity and properties, each body
        bound to its row (slot ``k`` for ``bodies[k]``); a body bound before (on its
        own or in another world) moves here with its current values."""
        state = cls(len(bodies))
        for slot, body in enumerate(bodies):
            state.position[slot] = body.position
            state.angle[slot] = body.angle
            state.velocity[slot, :2] = body.velocity
            state.properties[slot] = body.property_row()
            state.dynamic[slot] = not body.is_static
            state.turning[slot] = body.inverse_inertia > 0.0
            # A body that cannot turn has no angular velocity (the solver never gives it one).
            state.velocity[slot, 2] = body.angular_velocity if state.turning[slot] else 0.0
            body.bind(state, slot)
        return state

    def integrate_velocities(self, gravity: np.ndarray, h: float) -> None:
        """v += h g for the dynamic bodies (``gravity`` in m/s^2, ``h`` in s)."""
        self.velocity[self.dynamic, :2] += h * gravity

    def integrate_positions(self, h: float) -> None:
        """x += h v for the dynamic bodies, angle += h w for the turning ones."""
        self.position[self.dynamic] += h * self.velocity[self.dynamic, :2]
        self.angle[self.turning] += h * self.velocity[self.turning, 2]
