# Exercise file of the collision course: write the functions that raise NotImplementedError, then
# check them with `grader check impulse`.
# Handed out with the course; generated from solutions/response/impulse.py on the instructor's side.
"""One impulse at one contact point between two rigid bodies.

Symbols (as in the book): ``n`` the unit contact normal, pointing from body A to body
B; ``p`` the contact point (world, m); ``r_A = p - x_A`` and ``r_B = p - x_B`` the
lever arms from each body's CENTRE OF MASS ``x`` (not from some other body origin);
``m`` mass (kg), ``I`` moment of inertia about the centre of mass (kg m^2).  In 2D the
cross product of two vectors is the scalar ``a x b = a_x b_y - a_y b_x`` and a scalar
angular velocity turns a lever arm into a velocity ``w x r = (-w r_y, w r_x)``.

- Velocity of the material point of a body at ``p``: ``v + w x r``.
- Relative normal velocity ``v_n = (v_B(p) - v_A(p)) . n``: negative while the bodies
  approach (the closing speed is ``-v_n``), positive while they separate.
- An impulse ``P`` (N s) at ``p`` given to B and ``-P`` to A changes
  ``v_B += P / m_B``, ``w_B += (r_B x P) / I_B``, ``v_A -= P / m_A``,
  ``w_A -= (r_A x P) / I_A``.  Both bodies receive the same impulse with opposite
  signs: total linear momentum and angular momentum about any point are conserved.
- A unit impulse along ``n`` changes ``v_n`` by the inverse effective mass
  ``k = 1/m_A + 1/m_B + (r_A x n)^2 / I_A + (r_B x n)^2 / I_B`` (a scalar, m/s per N s).
- Restitution ``v_n' = -e v_n`` then needs ``j = -(1 + e) v_n / k``.

A static body has ``1/m = 1/I = 0``; a body with fixed rotation has ``1/I = 0``.
"""
from __future__ import annotations

from itertools import combinations

import numpy as np

from ..body import Body
from ..contact import Contact
from ..vector import cross


def _unit_normal(normal) -> np.ndarray:
    normal = np.asarray(normal, dtype=float).reshape(2)
    length = float(np.hypot(normal[0], normal[1]))
    if not abs(length - 1.0) <= 1e-9:
        raise ValueError(f"the contact normal must be a unit vector, got {normal.tolist()} (length {length})")
    return normal


def _checked_coefficient(name: str, value: float, upper: float) -> float:
    value = float(value)
    if not 0.0 <= value <= upper:  # also rejects NaN
        raise ValueError(f"{name} must be in [0, {upper}], got {value}")
    return value


def solve_small_lcp(matrix: np.ndarray, wanted_change: np.ndarray) -> np.ndarray:
    """Impulses ``j >= 0`` with ``matrix @ j >= wanted_change``, complementary.

    Solves the linear complementarity problem of k simultaneous contact points
    (k = 1 or 2 in practice) by trying the active sets from small to large: for a
    set S, ``matrix[S, S] j_S = wanted_change[S]`` and ``j = 0`` outside S; the set is
    accepted when ``j_S >= 0`` and every point outside S already gets at least its
    wanted change.  ``matrix`` is the symmetric positive semi-definite matrix of
    unit-impulse responses (m/s per N s); ``wanted_change`` is ``target - v_n`` (m/s).
    If no set fits (a degenerate matrix), 50 sweeps of projected Gauss-Seidel give
    the answer instead.

    Examples
    --------
    Two independent points: each gets its own ``wanted / k``; a point that already
    separates fast enough gets nothing:

    >>> solve_small_lcp(np.array([[2.0, 0.0], [0.0, 4.0]]), np.array([1.0, -1.0])).tolist()
    [0.5, 0.0]
    """
    matrix = np.asarray(matrix, dtype=float)
    wanted_change = np.asarray(wanted_change, dtype=float)
    count = len(wanted_change)
    tolerance = 1e-12 * (1.0 + float(np.max(np.abs(wanted_change), initial=0.0)))
    impulses = np.zeros(count)
    if not np.any(wanted_change > tolerance):
        return impulses
    for size in range(1, count + 1):
        for active in map(list, combinations(range(count), size)):
            block = matrix[np.ix_(active, active)]
            try:
                impulses_active = np.linalg.solve(block, wanted_change[active])
            except np.linalg.LinAlgError:
                continue
            trial = np.zeros(count)
            trial[active] = impulses_active
            slack = matrix @ trial - wanted_change
            scale = tolerance * (1.0 + float(np.max(np.abs(trial))) * float(np.max(np.abs(matrix))))
            if np.all(trial >= -scale) and np.all(np.abs(slack[active]) <= scale) and np.all(slack >= -scale):
                return np.maximum(trial, 0.0)
    for _ in range(50):
        for i in range(count):
            if matrix[i, i] > 0.0:
                change = (wanted_change[i] - matrix[i] @ impulses) / matrix[i, i]
                impulses[i] = max(impulses[i] + change, 0.0)
    return impulses


def relative_normal_velocity(body_a: Body, body_b: Body, point, normal) -> float:
    """Relative velocity of the two bodies' material points at ``point``, along ``normal``.

    ``v_n = (v_B + w_B x r_B - v_A - w_A x r_A) . n`` with ``r`` measured from each
    body's centre of mass.  This is the closing velocity of the contact, not the rate
    at which the centres approach.

    Parameters
    ----------
    body_a, body_b : Body
        The two bodies; ``normal`` points from A to B.
    point : array_like, shape (2,)
        Contact point in world coordinates (m).
    normal : array_like, shape (2,)
        Unit contact normal from A to B.

    Returns
    -------
    float
        ``v_n`` (m/s): negative when the bodies approach at the point, positive when
        they separate.

    Examples
    --------
    A ball falling at 2 m/s onto static ground (normal from ground A to ball B is +y):

    >>> ground = Body.box(10.0, 1.0, is_static=True)
    >>> ball = Body.circle(0.5, position=(0.0, 1.0), velocity=(0.0, -2.0))
    >>> relative_normal_velocity(ground, ball, (0.0, 0.5), (0.0, 1.0))
    -2.0
    """
    raise NotImplementedError("write relative_normal_velocity(), then run `grader check impulse`")


def effective_mass_inverse(body_a: Body, body_b: Body, point, normal) -> float:
    """Change of ``v_n`` per unit impulse along ``normal`` at ``point`` (m/s per N s).

    ``k = 1/m_A + 1/m_B + (r_A x n)^2 / I_A + (r_B x n)^2 / I_B``; the terms of a static
    body, and the angular term of a body with fixed rotation, are 0.  ``1/k`` is the
    effective mass of the contact (kg).

    Parameters
    ----------
    body_a, body_b : Body
        The two bodies.
    point : array_like, shape (2,)
        Contact point in world coordinates (m).
    normal : array_like, shape (2,)
        Unit contact normal from A to B.

    Returns
    -------
    float
        ``k`` >= 0 (1/kg); 0 only when both bodies are static.

    Examples
    --------
    A 2 kg disc hit through its centre by an impulse from static ground: no
    angular term, ``k = 1/m``:

    >>> ground = Body.box(10.0, 1.0, is_static=True)
    >>> ball = Body.circle(0.5, mass=2.0, position=(0.0, 1.0))
    >>> effective_mass_inverse(ground, ball, (0.0, 0.5), (0.0, 1.0))
    0.5
    """
    raise NotImplementedError("write effective_mass_inverse(), then run `grader check impulse`")


def normal_impulse_magnitude(body_a: Body, body_b: Body, point, normal, restitution: float) -> float:
    """Magnitude ``j`` (N s) of the normal impulse that makes ``v_n' = -e v_n``.

    ``j = -(1 + e) v_n / k`` with ``k`` from :func:`effective_mass_inverse`.  The impulse
    ``j n`` is given to B and ``-j n`` to A (see :func:`apply_impulse`).  A contact
    that is separating (``v_n >= 0``) or between two static bodies gets ``j = 0``: a
    contact can push, never pull.

    Parameters
    ----------
    body_a, body_b : Body
        The two bodies; ``normal`` points from A to B.
    point : array_like, shape (2,)
        Contact point in world coordinates (m).
    normal : array_like, shape (2,)
        Unit contact normal from A to B.
    restitution : float
        Coefficient of restitution e in [0, 1].

    Returns
    -------
    float
        ``j >= 0`` (N s).

    Examples
    --------
    A 2 kg ball hits static ground at 3 m/s with e = 0.5: ``j = 1.5 * 3 * 2``:

    >>> ground = Body.box(10.0, 1.0, is_static=True)
    >>> ball = Body.circle(0.5, mass=2.0, position=(0.0, 1.0), velocity=(0.0, -3.0))
    >>> normal_impulse_magnitude(ground, ball, (0.0, 0.5), (0.0, 1.0), 0.5)
    9.0
    """
    raise NotImplementedError("write normal_impulse_magnitude(), then run `grader check impulse`")


def apply_impulse(body_a: Body, body_b: Body, point, impulse_vector) -> None:
    """Apply ONE impulse at ``point``: ``+P`` to body B and ``-P`` to body A.

    ``v_B += P / m_B``, ``w_B += (r_B x P) / I_B``, ``v_A -= P / m_A``,
    ``w_A -= (r_A x P) / I_A``, lever arms from the centres of mass.  Static bodies
    and the rotation of fixed-rotation bodies do not change.  The bodies' ``velocity``
    arrays are replaced by new arrays (arrays held elsewhere are not modified).

    Computing a separate impulse for each body, as if the other were immovable, is
    wrong: it ignores that both bodies give way and overshoots the velocity change.

    Parameters
    ----------
    body_a, body_b : Body
        The two bodies (modified in place).
    point : array_like, shape (2,)
        Point of application in world coordinates (m).
    impulse_vector : array_like, shape (2,)
        ``P`` (N s), the impulse given to B; for a normal impulse ``P = j n``.

    Examples
    --------
    Two 1 kg discs; an impulse of 1 N s along +x through both centres:

    >>> a = Body.circle(0.5, position=(0.0, 0.0))
    >>> b = Body.circle(0.5, position=(1.0, 0.0))
    >>> apply_impulse(a, b, (0.5, 0.0), (1.0, 0.0))
    >>> a.velocity.tolist(), b.velocity.tolist()
    ([-1.0, 0.0], [1.0, 0.0])
    """
    raise NotImplementedError("write apply_impulse(), then run `grader check impulse`")


def resolve_collision(body_a: Body, body_b: Body, contact: Contact,
                      restitution: float | None = None,
                      friction: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Single-shot collision response of one contact manifold, with Coulomb friction.

    1. Normal impulses ``j_i >= 0`` at the manifold's points, solved simultaneously so
       that every approaching point leaves with ``v_n' = -e v_n`` and no point is left
       approaching: for one point this is :func:`normal_impulse_magnitude`; for a
       2-point manifold (a face resting on a face) it is a 2x2 linear system, and a
       point whose impulse would have to pull (``j_i < 0``) is dropped from it.
       Solving the points one after the other instead would spin a box that lands flat.
    2. Friction, one pass over the points: the impulse ``j_t`` along the tangent
       ``t = (n_y, -n_x)`` that would stop the sliding at the point, clamped to
       ``|j_t| <= mu j_i`` (Coulomb).

    Friction changes the normal velocity too (through rotation), so after one pass
    the normal condition holds only approximately; the iterative
    :class:`~.contact_solver.ContactSolver` repeats the passes until both hold.
    Positions are not touched (see :mod:`.positional_correction`).

    Parameters
    ----------
    body_a, body_b : Body
        The two bodies (velocities modified in place).
    contact : Contact
        Manifold with ``normal`` from A to B and ``points`` (k, 2) in world coordinates (m).
    restitution : float, optional
        e in [0, 1]; by default ``body_a.restitution * body_b.restitution``.
    friction : float, optional
        mu >= 0; by default ``body_a.friction * body_b.friction``.

    Returns
    -------
    (normal_impulses, tangent_impulses) : tuple of numpy.ndarray, shape (k,)
        ``j_i`` (N s, >= 0) and ``j_t`` (N s, signed along ``t``) at each point; the
        impulse given to B at point i is ``j_i n + j_t t`` (and its opposite to A).

    Examples
    --------
    A 1 kg box landing flat at 2 m/s on static ground with e = 0.5 bounces at 1 m/s
    without spinning; each of the two corners takes half of the 3 N s:

    >>> ground = Body.box(10.0, 1.0, is_static=True)
    >>> box = Body.box(1.0, 1.0, position=(0.0, 1.0), velocity=(0.0, -2.0))
    >>> corners = Contact((0.0, 1.0), 0.0, [(-0.5, 0.5), (0.5, 0.5)])
    >>> normal_impulses, _ = resolve_collision(ground, box, corners, restitution=0.5)
    >>> normal_impulses.round(12).tolist(), box.velocity.round(12).tolist(), round(box.angular_velocity, 12)
    ([1.5, 1.5], [0.0, 1.0], 0.0)
    """
    raise NotImplementedError("write resolve_collision(), then run `grader check impulse`")
