"""Shared pieces of the SAT and contact checks: unambiguous random pairs, pictures."""
from __future__ import annotations

import numpy as np

from solutions.narrowphase.dispatch import shapes_overlap
from solutions.shapes import AABB, OBB, Circle, ConvexPolygon, polygon_centroid

from .. import codec

#: Shapes closer than this to touching (m) are left out of yes/no comparisons: the
#: answer there depends on rounding, not on the method.
AMBIGUITY = 1e-7


def grown(shape, amount: float):
    """The shape made larger by ``amount`` (m) (smaller for a negative amount)."""
    if isinstance(shape, Circle):
        return Circle(shape.center, max(shape.radius + amount, 0.0))
    if isinstance(shape, OBB):
        return OBB(shape.center, np.maximum(shape.half_extents + amount, 0.0), shape.angle)
    if isinstance(shape, AABB):
        return AABB.from_center(shape.center, np.maximum(shape.half_extents + amount, 0.0))
    c = polygon_centroid(shape.vertices)
    radius = float(np.max(np.hypot(*(shape.vertices - c).T)))
    return ConvexPolygon(c + (shape.vertices - c) * (1 + amount / radius))


def definite_overlap(a, b) -> bool | None:
    """The reference yes/no answer, or None when within AMBIGUITY of touching."""
    bigger = shapes_overlap(grown(a, AMBIGUITY), b)
    smaller = shapes_overlap(grown(a, -AMBIGUITY), b)
    return bigger if bigger == smaller else None


def shapes_figure(a, b, title: str, expected=None, got=None) -> dict:
    """Plain data for a picture of two shapes and the expected and returned contacts."""
    figure = {"kind": "shapes", "title": title, "shapes": [codec.encode_shape(a), codec.encode_shape(b)]}
    if expected is not None:
        figure["expected"] = codec.encode_contact(expected)
    if isinstance(got, dict) and codec.CONTACT_TAG in got:
        figure["got"] = got
    return figure
