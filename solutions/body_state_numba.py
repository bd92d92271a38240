"""The bodies' state compiled: twins of :func:`~solutions.body_state.state_arrays`, :meth:`BodyState.integrate_velocities` and :meth:`World.integrate_positions`.

Explicit (symplectic) Euler on the world's :class:`~solutions.body_state.BodyState`
arrays, for the compiled soft step (:mod:`solutions.response.soft_step_numba`): the
velocities first (gravity), the positions from the new velocities.  A body moves
where its inverse mass is not 0 and turns where its inverse inertia is not, as the
state's ``dynamic`` and ``turning`` say.

Conventions: SI units; ``velocity`` rows (vx, vy, omega) in m/s and rad/s.
"""
from __future__ import annotations

### INSTRUCTOR ONLY: not in the student edition (the compiled soft step's integration).

from numba import njit

from . import body_state
from .compiled_cache import forget_stale_machine_code

#: :func:`solutions.body_state.state_arrays` compiled as it is (the views of a state's
#: ``numbers``: position, angle, velocity, properties), for the compiled step to cut them
#: from the one array it is called with.
state_arrays = njit(inline="always")(body_state.state_arrays)


@njit(cache=True, inline="always")
def integrate_velocities(velocity, inverse_mass, h, gravity_x, gravity_y):
    """Gravity (m/s^2) over ``h`` (s) added to every dynamic body's velocity."""
    for i in range(velocity.shape[0]):
        if inverse_mass[i] != 0.0:      # dynamic
            velocity[i, 0] += h * gravity_x
            velocity[i, 1] += h * gravity_y


@njit(cache=True, inline="always")
def integrate_positions(position, angle, velocity, inverse_mass, inverse_inertia, h):
    """Each dynamic body moved, and each turning body turned, by its velocity over ``h`` (s)."""
    for i in range(velocity.shape[0]):
        if inverse_mass[i] != 0.0:      # dynamic
            position[i, 0] += h * velocity[i, 0]
            position[i, 1] += h * velocity[i, 1]
        if inverse_inertia[i] != 0.0:       # turning
            angle[i] += h * velocity[i, 2]


# Cached machine code compiled from older sources is forgotten (solutions.compiled_cache).
forget_stale_machine_code(globals())
