"""Plain-data encoding of the values that cross the sandbox boundary.

Only JSON crosses between the trusted grader and the student worker: never pickles,
never objects.  Shapes, bodies and contacts travel as tagged dicts and are rebuilt on
the other side with that side's own classes (the student's ``exercises`` package in
the worker, nothing but numbers in the parent).  Floats keep all their bits (JSON
floats round-trip exactly in Python); NaN and infinities are written as JSON's
``NaN``/``Infinity`` extensions, which Python reads back.

This module is copied into the sandbox next to the worker, so it imports nothing
from the grader or the reference engine.
"""
from __future__ import annotations

import math

SHAPE_TAG = "$shape"
BODY_TAG = "$body"
CONTACT_TAG = "$contact"
PAIRS_TAG = "$pairs"
ARRAY_TAG = "$array"

BODY_FIELDS = ("mass", "angle", "angular_velocity", "restitution", "friction",
               "is_static", "fixed_rotation", "is_bullet")


def encode_shape(shape) -> dict:
    """A shape as a tagged dict, read through its public attributes."""
    kind = type(shape).__name__
    if kind == "Circle":
        return {SHAPE_TAG: kind, "center": floats(shape.center), "radius": float(shape.radius)}
    if kind == "AABB":
        return {SHAPE_TAG: kind, "min_corner": floats(shape.min_corner), "max_corner": floats(shape.max_corner)}
    if kind == "OBB":
        return {SHAPE_TAG: kind, "center": floats(shape.center), "half_extents": floats(shape.half_extents),
                "angle": float(shape.angle)}
    if kind == "ConvexPolygon":
        return {SHAPE_TAG: kind, "vertices": [floats(v) for v in shape.vertices]}
    raise TypeError(f"cannot encode a {kind} as a shape")


def decode_shape(data: dict, shapes_module):
    """Rebuild a tagged shape with the classes of ``shapes_module``."""
    kind = data[SHAPE_TAG]
    cls = getattr(shapes_module, kind)
    fields = {k: v for k, v in data.items() if k != SHAPE_TAG}
    return cls(**fields)


def encode_body(body) -> dict:
    """A body's shape, state and material as a tagged dict."""
    out = {BODY_TAG: True, "shape": encode_shape(body.shape), "position": floats(body.position),
           "velocity": floats(body.velocity)}
    for name in BODY_FIELDS:
        value = getattr(body, name)
        out[name] = bool(value) if isinstance(value, bool) or name.startswith(("is_", "fixed")) else float(value)
    return out


def decode_body(data: dict, shapes_module, body_module):
    """Rebuild a tagged body with the classes of the given modules."""
    fields = {k: v for k, v in data.items() if k not in (BODY_TAG, "shape")}
    return body_module.Body(decode_shape(data["shape"], shapes_module), **fields)


def encode_contact(contact) -> dict | None:
    """A contact (anything with normal, depth, points) as plain numbers; None stays None."""
    if contact is None:
        return None
    points = [floats(p) for p in _rows(contact.points)]
    out = {CONTACT_TAG: True, "normal": floats(contact.normal), "depth": float(contact.depth), "points": points}
    depths = getattr(contact, "depths", None)
    if depths is not None:
        out["depths"] = floats(depths)
    return out


def decode_contact(data: dict, contact_module):
    """Rebuild a tagged contact with ``contact_module.Contact``."""
    fields = {k: v for k, v in data.items() if k != CONTACT_TAG}
    return contact_module.Contact(**fields)


def floats(values) -> list[float]:
    """A flat sequence as a list of Python floats."""
    return [float(v) for v in values]


def _rows(array) -> list:
    rows = list(array)
    if rows and not hasattr(rows[0], "__len__"):
        return [rows]
    return rows


def encode_value(value):
    """Any return value of an exercise as plain JSON data.

    Recognised: None, bool, int, float, str, shapes, bodies, contacts, sets of pairs,
    tuples/lists, dicts with string keys, numpy arrays and scalars (by duck typing:
    ``tolist``).  Anything else raises TypeError with the type's name.
    """
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, int):
        return int(value)
    if isinstance(value, float):
        return float(value)
    kind = type(value).__name__
    if kind in ("Circle", "AABB", "OBB", "ConvexPolygon"):
        return encode_shape(value)
    if kind == "Body":
        return encode_body(value)
    if kind == "Contact":
        return encode_contact(value)
    if isinstance(value, (set, frozenset)):
        return {PAIRS_TAG: sorted([encode_value(v) for v in value], key=repr)}
    if isinstance(value, (list, tuple)):
        return [encode_value(v) for v in value]
    if isinstance(value, dict):
        return {str(k): encode_value(v) for k, v in value.items()}
    if hasattr(value, "tolist") and hasattr(value, "dtype"):
        if getattr(value, "ndim", 1) == 0:
            return _plain(value.tolist())
        return {ARRAY_TAG: _plain(value.tolist())}
    raise TypeError(f"an exercise returned a {kind}, which the grader cannot read")


def _plain(value):
    if isinstance(value, list):
        return [_plain(v) for v in value]
    if isinstance(value, bool):
        return value
    if isinstance(value, (int, float)):
        return value
    return float(value)


def is_number(value) -> bool:
    """True for a real int or float (bools excluded)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def finite(value) -> bool:
    """True for a finite real number."""
    return is_number(value) and math.isfinite(value)
