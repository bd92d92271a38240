# Exercise file of the collision course: write the functions that raise NotImplementedError, then
# check them with `grader check impulse`.
# Handed out with the course; generated from solutions/response/positional_correction.py on the
# instructor's side.
"""Removing overlap by moving positions: linear projection.

Detection is discrete (a posteriori), so bodies are usually found already overlapping
by ``depth`` (m) along the contact normal ``n`` (from A to B).  An impulse fixes the
velocities but not that overlap; linear projection moves the bodies apart along ``n``,
each in proportion to its inverse mass, so that a light body moves more than a heavy
one and a static body (inverse mass 0) not at all::

    C = percent * max(depth - slop, 0) / (1/m_A + 1/m_B)     (kg m)
    x_A -= C / m_A * n,        x_B += C / m_B * n

The two moves add up to ``percent * max(depth - slop, 0)`` and leave the centre of
mass where it was.  Correcting only ``percent`` < 1 of the overlap per step, and
leaving a ``slop`` of it, avoids the jitter of bodies pushed apart and falling back
every step.  Projection changes positions only, never velocities, so it adds no
kinetic energy, but it ignores rotation; velocity-based correction (Baumgarte bias,
split impulses) and non-linear projection are the alternatives, see
:mod:`.contact_solver`.
"""
from __future__ import annotations

import numpy as np

from ..body import Body


def correct_positions(body_a: Body, body_b: Body, normal, depth: float,
                      percent: float = 0.8, slop: float = 0.01) -> tuple[np.ndarray, np.ndarray]:
    """Push two overlapping bodies apart along ``normal``, split by inverse mass.

    Parameters
    ----------
    body_a, body_b : Body
        The two bodies; their ``position`` arrays are replaced (static bodies are
        left alone).
    normal : array_like, shape (2,)
        Unit contact normal, pointing from A to B.
    depth : float
        Overlap along ``normal`` (m); values <= ``slop`` (or negative) move nothing.
    percent : float, optional
        Fraction in [0, 1] of the overlap beyond ``slop`` removed by this call
        (dimensionless).
    slop : float, optional
        Overlap (m) allowed to remain, >= 0.  The default 0.01 m suits bodies of about
        1 m; scale it with the scene.

    Returns
    -------
    (displacement_a, displacement_b) : tuple of numpy.ndarray, shape (2,)
        How far each body was moved (m); ``m_A d_A + m_B d_B = 0``.

    Examples
    --------
    A 1 kg and a 3 kg disc overlap by 0.11 m along x: the light one takes 3/4 of
    the 0.08 m correction (80 % of 0.11 - 0.01):

    >>> a = Body.circle(0.5, mass=1.0, position=(0.0, 0.0))
    >>> b = Body.circle(0.5, mass=3.0, position=(0.89, 0.0))
    >>> moved_a, moved_b = correct_positions(a, b, (1.0, 0.0), 0.11)
    >>> [round(float(x), 12) for x in (moved_a[0], moved_b[0], a.position[0], b.position[0])]
    [-0.06, 0.02, -0.06, 0.91]
    """
    raise NotImplementedError("write correct_positions(), then run `grader check impulse`")
