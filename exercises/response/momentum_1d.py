# Exercise file of the collision course: write the functions that raise NotImplementedError, then
# check them with `grader check momentum`.
# Handed out with the course; generated from solutions/response/momentum_1d.py on the instructor's
# side.
"""Head-on collisions of two bodies moving along one line (point masses).

Body 1 and body 2 move along the x axis with velocities ``v1`` and ``v2`` (m/s, signed:
positive means +x).  The functions assume the bodies do collide (they approach each
other); they do not know where the bodies are, so they do not check it.

Two laws fix the velocities just after the impact, ``v1'`` and ``v2'``:

- momentum is conserved (no outside impulse during the short impact)::

      m1 v1 + m2 v2 = m1 v1' + m2 v2'

- the coefficient of restitution e in [0, 1] scales the speed of separation::

      v2' - v1' = -e (v2 - v1)

e = 1 is an elastic collision (kinetic energy conserved), 0 < e < 1 an inelastic one
(energy lost to deformation, heat, sound), e = 0 perfectly inelastic (the bodies move on
together).  Written with inverse masses w = 1/m the solution is a single impulse ``J``
(N s, given to body 2 and taken from body 1)::

      J = (1 + e) (v1 - v2) / (w1 + w2),    v1' = v1 - w1 J,    v2' = v2 + w2 J

which also covers an immovable wall: ``m = math.inf`` gives ``w = 0``.

Units: kg, m/s, N s = kg m/s, J.
"""
from __future__ import annotations

import math

import numpy as np


def _checked_mass(name: str, mass: float) -> float:
    """``mass`` as a float > 0 (``math.inf`` allowed); ValueError otherwise."""
    mass = float(mass)
    if math.isnan(mass) or mass <= 0:
        raise ValueError(f"{name} must be > 0 (math.inf for an immovable body), got {mass}")
    return mass


def _checked_velocity(name: str, velocity: float) -> float:
    velocity = float(velocity)
    if not math.isfinite(velocity):
        raise ValueError(f"{name} must be finite, got {velocity}")
    return velocity


def _checked_restitution(restitution: float) -> float:
    restitution = float(restitution)
    if not 0.0 <= restitution <= 1.0:  # also rejects NaN
        raise ValueError(f"restitution must be in [0, 1], got {restitution}")
    return restitution


def _checked_pair(m1, v1, m2, v2) -> tuple[float, float, float, float]:
    """Validated ``(w1, v1, w2, v2)`` with inverse masses ``w = 1/m`` (0 for a wall)."""
    m1 = _checked_mass("m1", m1)
    m2 = _checked_mass("m2", m2)
    if math.isinf(m1) and math.isinf(m2):
        raise ValueError("two bodies of infinite mass cannot collide: the result is undefined")
    return 1.0 / m1, _checked_velocity("v1", v1), 1.0 / m2, _checked_velocity("v2", v2)


def collision_1d(m1: float, v1: float, m2: float, v2: float, restitution: float) -> tuple[float, float]:
    """Velocities just after a head-on collision with coefficient of restitution e.

    Parameters
    ----------
    m1, m2 : float
        Masses (kg), > 0; ``math.inf`` for one immovable body (a wall), not both.
    v1, v2 : float
        Velocities before the impact (m/s), signed along the line of motion.
    restitution : float
        Coefficient of restitution e in [0, 1] (dimensionless):
        ``v2' - v1' = -e (v2 - v1)``.

    Returns
    -------
    (v1_after, v2_after) : tuple of float
        Velocities just after the impact (m/s).  Momentum is conserved; kinetic energy
        is conserved for e = 1 and lost for e < 1.

    Raises
    ------
    ValueError
        For a mass <= 0 or NaN, two infinite masses, non-finite velocities or e
        outside [0, 1].

    Examples
    --------
    A ball at 3 m/s hits a wall (infinite mass) at rest with e = 0.5:

    >>> collision_1d(0.2, 3.0, math.inf, 0.0, 0.5)
    (-1.5, 0.0)
    """
    raise NotImplementedError("write collision_1d(), then run `grader check momentum`")


def elastic_collision_1d(m1: float, v1: float, m2: float, v2: float) -> tuple[float, float]:
    """Velocities after an elastic head-on collision (e = 1: kinetic energy conserved).

    Solving momentum and energy conservation together gives two roots; one is the
    state before the impact (``v1' = v1``, ``v2' = v2``) and is discarded.  The other is
    ``v1' = ((m1 - m2) v1 + 2 m2 v2) / (m1 + m2)`` and symmetrically for ``v2'``.

    Parameters
    ----------
    m1, m2 : float
        Masses (kg), > 0; ``math.inf`` for one wall.
    v1, v2 : float
        Velocities before the impact (m/s).

    Returns
    -------
    (v1_after, v2_after) : tuple of float
        Velocities just after the impact (m/s).

    Examples
    --------
    Equal masses exchange their velocities:

    >>> elastic_collision_1d(1.0, 2.0, 1.0, -1.0)
    (-1.0, 2.0)
    """
    raise NotImplementedError("write elastic_collision_1d(), then run `grader check momentum`")


def perfectly_inelastic_1d(m1: float, v1: float, m2: float, v2: float) -> float:
    """Common velocity of two bodies that stick together (e = 0).

    Momentum conservation alone gives ``v = (m1 v1 + m2 v2) / (m1 + m2)``, the velocity
    of the centre of mass, which is unchanged by the impact.

    Parameters
    ----------
    m1, m2 : float
        Masses (kg), > 0; ``math.inf`` for one wall (then ``v`` is the wall's velocity).
    v1, v2 : float
        Velocities before the impact (m/s).

    Returns
    -------
    float
        Velocity of both bodies just after the impact (m/s).

    Examples
    --------
    A 5000 kg truck at 80 km/h hits a 1000 kg car at 60 km/h; they stay together
    (any consistent unit of speed works, here km/h):

    >>> round(perfectly_inelastic_1d(5000.0, 80.0, 1000.0, 60.0), 2)
    76.67
    """
    raise NotImplementedError("write perfectly_inelastic_1d(), then run `grader check momentum`")


def momentum(m: float, v):
    """Momentum ``p = m v`` (kg m/s = N s) of a body of finite mass.

    ``v`` may be a scalar (1D) or a vector (array); ``p`` has the direction of ``v``.
    A force changes ``p`` along itself: ``dp = F dt`` (the impulse of ``F``).

    Parameters
    ----------
    m : float
        Mass (kg), finite and >= 0.
    v : float or array_like
        Velocity (m/s).

    Returns
    -------
    float or numpy.ndarray
        Momentum (kg m/s), the same shape as ``v``.

    Examples
    --------
    >>> momentum(0.1, 10.0) + momentum(0.2, -5.0)
    0.0
    """
    m = float(m)
    if not (math.isfinite(m) and m >= 0):
        raise ValueError(f"momentum needs a finite mass >= 0, got {m}")
    if np.ndim(v) == 0:
        return m * float(v)
    return m * np.asarray(v, dtype=float)


def kinetic_energy(m: float, v) -> float:
    """Kinetic energy ``m |v|^2 / 2`` (J) of a body of finite mass.

    Parameters
    ----------
    m : float
        Mass (kg), finite and >= 0.
    v : float or array_like
        Velocity (m/s): a scalar or a vector.

    Returns
    -------
    float
        Kinetic energy (J).

    Examples
    --------
    A 1000 kg car at 60 km/h (16.67 m/s):

    >>> round(kinetic_energy(1000.0, 60.0 / 3.6))
    138889
    """
    m = float(m)
    if not (math.isfinite(m) and m >= 0):
        raise ValueError(f"kinetic_energy needs a finite mass >= 0, got {m}")
    v = np.asarray(v, dtype=float)
    return 0.5 * m * float(np.sum(v * v))
