# Exercise file of the collision course: write the functions that raise NotImplementedError, then
# check them with `grader check sat` (circles_overlap) and `grader check contacts`
# (collide_circle_circle).
# Handed out with the course; generated from solutions/narrowphase/circle_circle.py on the
# instructor's side.
"""Circle against circle: the simplest SAT case, with one axis (centre to centre).

Two discs overlap or touch when the distance between their centres is at most the sum
of their radii.  A radius of 0 makes a circle a point.  When the centres coincide the
centre-to-centre direction is undefined; the normal is then
:data:`COINCIDENT_CENTRES_NORMAL` (pymunk uses (1, 0) there; either choice is a
convention, what matters is that it is a unit vector and never NaN).
"""
from __future__ import annotations

import math

import numpy as np

from ..contact import Contact
from ..shapes import Circle

#: Normal (A to B) reported when the two centres coincide: push B up (+y).
COINCIDENT_CENTRES_NORMAL = (0.0, 1.0)

#: Centres closer than this (m) are treated as coincident: below it the direction of
#: the centre offset is not a number we can normalise (subnormal lengths).
COINCIDENT_CENTRES_ATOL = 1e-300


def circles_overlap(a: Circle, b: Circle) -> bool:
    """Whether two circles overlap or touch: ``|c_b - c_a| <= r_a + r_b``.

    Compared squared, so no square root is needed.

    Examples
    --------
    >>> circles_overlap(Circle((0.0, 0.0), 1.0), Circle((2.0, 0.0), 1.0))
    True
    >>> circles_overlap(Circle((0.0, 0.0), 1.0), Circle((2.5, 0.0), 1.0))
    False
    """
    raise NotImplementedError("write circles_overlap(), then run `grader check sat`")


def collide_circle_circle(a: Circle, b: Circle) -> Contact | None:
    """Contact between two circles, or None if they are apart.

    ``normal`` is the unit vector from A's centre to B's centre
    (:data:`COINCIDENT_CENTRES_NORMAL` if the centres coincide), ``depth`` is
    ``r_a + r_b - |c_b - c_a|`` (m, >= 0) and the single contact point is the midpoint
    between A's deepest point ``c_a + r_a n`` and B's deepest point ``c_b - r_b n``.

    Examples
    --------
    >>> contact = collide_circle_circle(Circle((0.0, 0.0), 1.0), Circle((1.5, 0.0), 1.0))
    >>> contact.normal.tolist(), contact.depth, contact.points.tolist()
    ([1.0, 0.0], 0.5, [[0.75, 0.0]])
    """
    raise NotImplementedError("write collide_circle_circle(), then run `grader check contacts`")
