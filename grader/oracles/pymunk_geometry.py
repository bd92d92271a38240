"""pymunk (Chipmunk2D 7) as an oracle for the narrow phase: overlap yes/no and contacts.

Shapes come in and contacts go out as the plain tagged dicts of :mod:`.plain`, so
the public graded tests can use this module without the reference engine.  The
adapter irons out pymunk's quirks (measured on pymunk 7.3.1):

- every shape hangs on a ``pymunk.Body`` (a body-less shape crashes in
  ``cache_bb``), and the body is kept alive with the shape (a shape holds only a weak
  reference to its body);
- ``cache_bb()`` is called before ``shapes_collide``, as the shapes were never
  stepped in a space;
- for shapes that do not touch, ``shapes_collide`` raises AssertionError or returns a
  ContactPointSet without points: both mean "apart";
- for the polygon-circle order the reported ``distance`` has the wrong sign, so the
  depth of each point is recomputed as ``-Dot(point_b - point_a, normal)``;
- pymunk polygons get radius 0 (no rounded corners).

Conventions of the course (:mod:`solutions`, stated in the exercises' docstrings):
the normal points from A to B (as pymunk's), depth >= 0 with ``distance = -depth``,
and each contact point is the midpoint between the two surfaces (pymunk gives one
point on each surface: ``point_a`` on A, ``point_b`` on B, so the course's point is
their midpoint).  Units: m.
"""
from __future__ import annotations

import copy
import json

import numpy as np
import pymunk

from . import plain
from ..sandbox.codec import SHAPE_TAG

#: Shapes closer than this (m) to touching get no yes/no answer here: the answer there
#: depends on rounding, not on the method (see :func:`definite_overlap`).
AMBIGUITY = 1e-7


def to_pymunk(shape: dict, grow: float = 0.0) -> pymunk.Shape:
    """A pymunk shape for a plain shape, made larger by ``grow`` (m) all around.

    A polygon grows by pymunk's rounding radius, a circle by its radius.
    """
    body = pymunk.Body(body_type=pymunk.Body.STATIC)
    if shape[SHAPE_TAG] == "Circle":
        pm = pymunk.Circle(body, float(shape["radius"]) + grow, offset=tuple(float(v) for v in shape["center"]))
    else:
        pm = pymunk.Poly(body, [tuple(float(x) for x in v) for v in plain.vertices(shape)], radius=grow)
    pm.cache_bb()
    pm._oracle_body = body  # the shape only holds a weak reference to its body
    return pm


def _collide(pm_a: pymunk.Shape, pm_b: pymunk.Shape):
    try:
        result = pm_a.shapes_collide(pm_b)
    except AssertionError:
        return None
    return result if result.points else None


#: pymunk's answers already found, by question and the two shapes' JSON text: the graded
#: tests draw their cases from fixed seeds, so every submission of a batch brings the same
#: ones, and an answer is a function of the two shapes alone.  Only the trusted process
#: that computed an answer reads it; the student's code never reaches this dictionary.
_ANSWERS: dict[tuple[str, str], object] = {}
#: Answers kept at most (then the dictionary starts again empty).
ANSWERS_KEPT = 50_000


def _remembered(question, a: dict, b: dict):
    """``question(a, b)``, computed once per pair of shapes (a copy of the answer each time)."""
    try:
        key = (question.__name__, json.dumps([a, b], sort_keys=True))  # floats as repr: exact
    except (TypeError, ValueError):   # numpy arrays and the like: not remembered
        return question(a, b)
    if key not in _ANSWERS:
        if len(_ANSWERS) >= ANSWERS_KEPT:
            _ANSWERS.clear()
        _ANSWERS[key] = question(a, b)
    return copy.deepcopy(_ANSWERS[key])


def pymunk_contact(a: dict, b: dict) -> dict | None:
    """pymunk's contact between plain shapes A and B in the course's conventions, or None.

    Returns a plain contact (:func:`.plain.contact`): pymunk's normal (A to B), the
    depth of the deepest point and one midpoint per pymunk point, plus ``"depths"``,
    the depth at each point (m).
    """
    return _remembered(_contact, a, b)


def _contact(a: dict, b: dict) -> dict | None:
    result = _collide(to_pymunk(a), to_pymunk(b))
    if result is None:
        return None
    normal = np.array(result.normal, dtype=float)
    points, depths = [], []
    for p in result.points:
        point_a, point_b = np.array(p.point_a, dtype=float), np.array(p.point_b, dtype=float)
        points.append((point_a + point_b) / 2)
        depths.append(-float((point_b - point_a) @ normal))
    contact = plain.contact(normal, max(0.0, max(depths)), points)
    contact["depths"] = [max(0.0, d) for d in depths]
    return contact


def pymunk_overlap(a: dict, b: dict) -> bool:
    """pymunk's yes/no answer: do the shapes overlap (or touch, up to its rounding)?"""
    return _collide(to_pymunk(a), to_pymunk(b)) is not None


def definite_overlap(a: dict, b: dict) -> bool | None:
    """pymunk's yes/no answer, or None when the shapes are within :data:`AMBIGUITY` of
    touching (apart by less, or overlapping by less)."""
    return _remembered(_definite_overlap, a, b)


def _definite_overlap(a: dict, b: dict) -> bool | None:
    contact = pymunk_contact(a, b)
    if contact is not None:
        return True if contact["depth"] > AMBIGUITY else None
    # Apart: still apart when A is grown by AMBIGUITY all around?
    return False if _collide(to_pymunk(a, AMBIGUITY), to_pymunk(b)) is None else None
