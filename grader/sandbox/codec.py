"""Plain-data encoding of the values that cross the sandbox boundary.

Only JSON crosses between the trusted grader and the student worker: never pickles,
never objects.  Shapes, bodies and contacts travel as tagged dicts and are rebuilt on
the other side with that side's own classes (the student's ``exercises`` package in
the worker, nothing but numbers in the parent).  Floats keep all their bits (JSON
floats round-trip exactly in Python); NaN and infinities are written as JSON's
``NaN``/``Infinity`` extensions, which Python reads back.

Encoding reads values the way the builtin types store them, never through methods a
student's class could override: a subclass of ``float``, ``int``, ``str``, ``list``,
``tuple`` or ``dict`` (a named tuple, say) is read with the builtin type's own
``float.__float__``, ``tuple.__getitem__``... so a lying ``__float__``, ``__eq__``,
``__index__``, ``__len__`` or ``__iter__`` is never called; numpy scalars and arrays
are read with ``numpy.generic.item`` and ``numpy.ndarray.tolist`` (numeric dtypes
only); any other object is refused with its type's name.  This keeps an honest
worker from being fooled by a returned object.  It is no defence against student
code that patches this module inside its own worker: what the worker sends is
untrusted anyway, and the parent accepts only well-formed plain data
(:func:`plain_data`, run by :mod:`grader.sandbox.process` on every answer) and compares it
itself.

This module is copied into the sandbox next to the worker, so it imports nothing
from the grader or the reference engine (numpy is used only when already imported).
"""
from __future__ import annotations

import json
import math
import re
import sys

SHAPE_TAG = "$shape"
BODY_TAG = "$body"
CONTACT_TAG = "$contact"
PAIRS_TAG = "$pairs"
ARRAY_TAG = "$array"
TAGS = (SHAPE_TAG, BODY_TAG, CONTACT_TAG, PAIRS_TAG, ARRAY_TAG)
#: A request's argument for the worker to keep, ``{KEEP_TAG: key, "value": plain}``, and a
#: later request's reference to it, ``{KEPT_TAG: key}`` (grader.sandbox.kept; requests only).
KEEP_TAG = "$keep"
KEPT_TAG = "$kept"

BODY_FIELDS = ("mass", "angle", "angular_velocity", "restitution", "friction",
               "is_static", "fixed_rotation", "is_bullet")
SHAPE_KINDS = ("Circle", "AABB", "OBB", "ConvexPolygon")
#: Deepest nesting of lists and dicts accepted in either direction.
MAX_DEPTH = 64
#: Contact feature ids (``Contact.feature_ids``, one hashable per point): each id is at
#: most this many tuples deep (``("A", 2, 0, 1)`` is 1 deep, an int or a str 0),
MAX_FEATURE_ID_DEPTH = 4
#: ... holds at most this many ints, floats, bools, Nones and strings in all,
MAX_FEATURE_ID_ITEMS = 16
#: ... and strings of at most this many characters.
MAX_FEATURE_ID_TEXT = 64


class NotPlainData(TypeError):
    """A value that is not the plain data the protocol allows; the message says why."""


# Reading student values without calling their methods ----------------------------------
def _numpy():
    """numpy if this process has imported it (no value can be a numpy object otherwise)."""
    return sys.modules.get("numpy")


def real(value) -> bool | int | float:
    """``value`` as an exact ``bool``, ``int`` or ``float``; NotPlainData otherwise.

    Subclasses are read through the builtin type's own methods; numpy scalars of a
    boolean, integer or floating dtype through ``numpy.generic.item``.
    """
    kind = type(value)
    if kind is float or kind is int or kind is bool:
        return value
    np = _numpy()
    if np is not None and isinstance(value, np.generic):
        if value.dtype.kind not in "biuf":
            raise NotPlainData(f"a numpy {value.dtype} scalar is not a real number")
        item = np.generic.item(value)
        return item if type(item) in (bool, int, float) else float(item)
    if isinstance(value, float):  # a subclass: the stored double, not its __float__
        return float.__float__(value)
    if isinstance(value, int):  # bool cannot be subclassed; int.__index__ gives an exact int
        return int.__index__(value)
    raise NotPlainData(f"expected a number, got a {kind.__name__}")


def floats(values) -> list[float]:
    """A flat sequence of numbers as a list of Python floats."""
    return [float(real(v)) for v in items(values)]


def items(values) -> list:
    """The elements of a list, tuple or 1-D array, read without calling overridden methods."""
    if isinstance(values, list):
        return [list.__getitem__(values, i) for i in range(list.__len__(values))]
    if isinstance(values, tuple):
        return [tuple.__getitem__(values, i) for i in range(tuple.__len__(values))]
    np = _numpy()
    if np is not None and isinstance(values, np.ndarray):
        return list(np.ndarray.tolist(values)) if values.ndim else [np.ndarray.tolist(values)]
    raise NotPlainData(f"expected a sequence of numbers, got a {type(values).__name__}")


def _rows(array) -> list:
    rows = items(array)
    if rows and not isinstance(rows[0], (list, tuple)) and not _is_array(rows[0]):
        return [rows]
    return rows


def _is_array(value) -> bool:
    np = _numpy()
    return np is not None and isinstance(value, np.ndarray)


# Shapes, bodies, contacts ------------------------------------------------------------------
def encode_shape(shape) -> dict:
    """A shape as a tagged dict, read through its public attributes."""
    kind = type(shape).__name__
    if kind == "Circle":
        return {SHAPE_TAG: kind, "center": floats(shape.center), "radius": float(real(shape.radius))}
    if kind == "AABB":
        return {SHAPE_TAG: kind, "min_corner": floats(shape.min_corner), "max_corner": floats(shape.max_corner)}
    if kind == "OBB":
        return {SHAPE_TAG: kind, "center": floats(shape.center), "half_extents": floats(shape.half_extents),
                "angle": float(real(shape.angle))}
    if kind == "ConvexPolygon":
        return {SHAPE_TAG: kind, "vertices": [floats(v) for v in _rows(shape.vertices)]}
    raise NotPlainData(f"cannot encode a {kind} as a shape")


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
        value = real(getattr(body, name))
        out[name] = bool(value) if type(value) is bool or name.startswith(("is_", "fixed")) else float(value)
    return out


def decode_body(data: dict, shapes_module, body_module):
    """Rebuild a tagged body with the classes of the given modules."""
    fields = {k: v for k, v in data.items() if k not in (BODY_TAG, "shape")}
    return body_module.Body(decode_shape(data["shape"], shapes_module), **fields)


def encode_contact(contact) -> dict | None:
    """A contact (anything with normal, depth, points) as plain numbers; None stays None.

    ``depths`` and ``feature_ids`` are sent when the contact has them (not None); the
    ids as :func:`encode_feature_ids` writes them.
    """
    if contact is None:
        return None
    points = [floats(p) for p in _rows(contact.points)]
    out = {CONTACT_TAG: True, "normal": floats(contact.normal), "depth": float(real(contact.depth)), "points": points}
    depths = getattr(contact, "depths", None)
    if depths is not None:
        out["depths"] = floats(depths)
    feature_ids = getattr(contact, "feature_ids", None)
    if feature_ids is not None:
        out["feature_ids"] = encode_feature_ids(feature_ids, len(points))
    return out


def decode_contact(data: dict, contact_module):
    """Rebuild a tagged contact with ``contact_module.Contact`` (feature ids as tuples)."""
    fields = {k: v for k, v in data.items() if k != CONTACT_TAG}
    if "feature_ids" in fields:
        fields["feature_ids"] = decode_feature_ids(fields["feature_ids"])
    return contact_module.Contact(**fields)


# Feature ids ---------------------------------------------------------------------------------
# A contact's feature ids travel as a JSON list, one entry per contact point; an entry is
# an id written as JSON: an int, float, bool, None or string as itself, a tuple as a
# JSON list of its entries (``("A", 2, 0, 1)`` -> ``["A", 2, 0, 1]``).  A list inside
# the ids always stands for a tuple, never for a list: an id is a dict key (hashable),
# so no id is a list, and :func:`decode_feature_ids` gives every one back as a tuple.
# Either side refuses anything else (lists, sets, arrays, objects in an id) and ids
# larger than MAX_FEATURE_ID_DEPTH / _ITEMS / _TEXT, and a count other than the number
# of points.
def encode_feature_ids(ids, count: int) -> list:
    """``Contact.feature_ids`` (a tuple or list of ``count`` hashable ids) as JSON data."""
    if isinstance(ids, tuple):
        size = tuple.__len__(ids)
    elif isinstance(ids, list):
        size = list.__len__(ids)
    elif _is_array(ids):
        ids = items(ids)    # its own tolist(), never a subclass's size or __len__
        size = len(ids)
    else:
        raise NotPlainData(f"feature_ids must be a tuple of ids, one per contact point, got a {type(ids).__name__}")
    if size != count:
        raise NotPlainData(f"a contact with {count} point(s) has {size} feature id(s): it needs one per point")
    return [_encode_feature_id(v, 0, [0]) for v in items(ids)]


def _encode_feature_id(value, depth: int, used: list):
    """One id as JSON (read as :func:`real` and :func:`items` read values); ``used[0]``
    counts its numbers and strings."""
    if isinstance(value, tuple):
        if depth >= MAX_FEATURE_ID_DEPTH:
            raise NotPlainData(f"a feature id is nested more than {MAX_FEATURE_ID_DEPTH} tuples deep")
        if tuple.__len__(value) > MAX_FEATURE_ID_ITEMS:
            raise NotPlainData(f"a feature id holds more than {MAX_FEATURE_ID_ITEMS} values")
        return [_encode_feature_id(v, depth + 1, used) for v in items(value)]
    used[0] += 1
    if used[0] > MAX_FEATURE_ID_ITEMS:
        raise NotPlainData(f"a feature id holds more than {MAX_FEATURE_ID_ITEMS} values")
    if value is None:
        return None
    if isinstance(value, str):
        if str.__len__(value) > MAX_FEATURE_ID_TEXT:
            raise NotPlainData(f"a feature id holds a string longer than {MAX_FEATURE_ID_TEXT} characters")
        return value if type(value) is str else str.__str__(value)
    np = _numpy()
    if isinstance(value, (int, float)) or (np is not None and isinstance(value, np.generic)
                                           and not isinstance(value, np.str_)):
        return real(value)
    raise NotPlainData(f"a feature id must be an int, a str or a tuple of them (hashable), not a "
                       f"{type(value).__name__}")


def check_feature_ids(data, count: int) -> None:
    """NotPlainData unless ``data`` is None or well-formed ids (JSON) for ``count`` points."""
    if data is None:
        return
    if type(data) is not list:
        raise NotPlainData(f"{CONTACT_TAG} value: feature_ids must be a list, one id per point")
    if len(data) != count:
        raise NotPlainData(f"{CONTACT_TAG} value: {count} point(s) but {len(data)} feature id(s)")
    for value in data:
        _check_feature_id(value, 0, [0])


def _check_feature_id(value, depth: int, used: list) -> None:
    kind = type(value)
    if kind is list:
        if depth >= MAX_FEATURE_ID_DEPTH:
            raise NotPlainData(f"a feature id is nested more than {MAX_FEATURE_ID_DEPTH} tuples deep")
        if len(value) > MAX_FEATURE_ID_ITEMS:
            raise NotPlainData(f"a feature id holds more than {MAX_FEATURE_ID_ITEMS} values")
        for v in value:
            _check_feature_id(v, depth + 1, used)
        return
    used[0] += 1
    if used[0] > MAX_FEATURE_ID_ITEMS:
        raise NotPlainData(f"a feature id holds more than {MAX_FEATURE_ID_ITEMS} values")
    if kind is str:
        if len(value) > MAX_FEATURE_ID_TEXT:
            raise NotPlainData(f"a feature id holds a string longer than {MAX_FEATURE_ID_TEXT} characters")
    elif value is not None and kind not in (bool, int, float):
        raise NotPlainData(f"a feature id must be an int, a str or a tuple of them, not a {kind.__name__}")


def decode_feature_ids(data) -> tuple | None:
    """Feature ids as JSON (or already decoded) back as a tuple of hashable ids: every
    list (or tuple) becomes a tuple.  Call :func:`check_feature_ids` first on data not
    yet checked by :func:`plain_data`."""
    if data is None:
        return None
    return tuple(_decode_feature_id(v) for v in data)


def _decode_feature_id(value):
    if isinstance(value, (list, tuple)):
        return tuple(_decode_feature_id(v) for v in value)
    return value


# Any return value ----------------------------------------------------------------------------
def encode_value(value, depth: int = 0):
    """Any return value of an exercise as plain JSON data.

    Recognised: None, bool, int, float, str (and subclasses, read as the builtin
    value), shapes, bodies, contacts (by class name), sets of pairs, tuples/lists,
    dicts, numpy arrays and scalars of numeric dtypes.  Anything else raises
    :class:`NotPlainData` (a TypeError) with the type's name.
    """
    if depth > MAX_DEPTH:
        raise NotPlainData(f"the value is nested more than {MAX_DEPTH} levels deep")
    if value is None:
        return None
    kind = type(value)
    if kind in EXACT_SCALARS:
        return value
    if (kind is list or kind is tuple) and all(type(v) in EXACT_SCALARS for v in value):
        return list(value)   # a list or tuple itself, of builtin scalars: nothing overridden to call
    if isinstance(value, str):
        return str.__str__(value)
    np = _numpy()
    if isinstance(value, (int, float)) or (np is not None and isinstance(value, np.generic)):
        return real(value)
    name = kind.__name__
    if name in SHAPE_KINDS:
        return encode_shape(value)
    if name == "Body":
        return encode_body(value)
    if name == "Contact":
        return encode_contact(value)
    if isinstance(value, (set, frozenset)):
        elements = list(set.__iter__(value) if isinstance(value, set) else frozenset.__iter__(value))
        return {PAIRS_TAG: sorted([encode_value(v, depth + 1) for v in elements], key=repr)}
    if isinstance(value, (list, tuple)):
        return [encode_value(v, depth + 1) for v in items(value)]
    if isinstance(value, dict):
        return {_key(k): encode_value(v, depth + 1) for k, v in dict.items(value)}
    if np is not None and isinstance(value, np.ndarray):
        if value.dtype.kind in "biuf":
            data = np.ndarray.tolist(value)
            return data if value.ndim == 0 else {ARRAY_TAG: data}
        if value.dtype.kind == "O":
            data = np.ndarray.tolist(value)
            return encode_value(data, depth + 1) if value.ndim == 0 else {ARRAY_TAG: _nested(data, depth + 1)}
        raise NotPlainData(f"an exercise returned a numpy array of {value.dtype}, which the grader cannot read")
    raise NotPlainData(f"an exercise returned a {name}, which the grader cannot read")


def _nested(data, depth: int):
    """The elements of an object array's ``tolist()``: nested lists of real numbers."""
    if depth > MAX_DEPTH:
        raise NotPlainData(f"the value is nested more than {MAX_DEPTH} levels deep")
    if type(data) is list:
        return [_nested(v, depth + 1) for v in data]
    return real(data)


def _key(key) -> str:
    if type(key) is str:
        return key
    if isinstance(key, str):
        return str.__str__(key)
    if type(key) in (bool, int, float) or key is None:
        return str(key)
    raise NotPlainData(f"a dict key of type {type(key).__name__} cannot be sent")


# Checking what arrives (the parent's side) -------------------------------------------------------
#: Builtin scalars (exact types, never subclasses) that are plain data as they are.
EXACT_SCALARS = frozenset({bool, int, float, str, type(None)})
#: Integers below this size are plain data as they are (a float holds far larger).
FLOAT_INT_LIMIT = 2 ** 1000
#: Digits of the longest integer the parent reads from an answer: every number of the
#: course is a float, and a float holds at most 309 digits before the decimal point.
MAX_INT_DIGITS = 309


class TooLargeInt:
    """An integer of an answer too long to be a number of the course (what
    :func:`parse_json_int` gives instead of converting it; :func:`plain_data` refuses it)."""

    def __init__(self, digits: int):
        self.digits = digits


#: A run of digits longer than any integer the parent reads (only then does json.loads
#: need :func:`parse_json_int`, a Python call per integer).
LONG_DIGITS = re.compile(rb"\d{%d}" % (MAX_INT_DIGITS + 1))


def loads_answer(line: bytes):
    """``json.loads`` of one answer line, integers past ``MAX_INT_DIGITS`` digits read as
    :class:`TooLargeInt` (the C parser alone when the line holds no such run of digits)."""
    if LONG_DIGITS.search(line):
        return json.loads(line, parse_int=parse_json_int)
    return json.loads(line)


def parse_json_int(text: str) -> int | TooLargeInt:
    """``json.loads``'s ``parse_int``: the integer, or a TooLargeInt past ``MAX_INT_DIGITS``
    digits (converting it would take time quadratic in its length, and Python refuses
    past 4300 digits: the answer would be lost, not judged)."""
    digits = len(text) - text.startswith("-")
    return int(text) if digits <= MAX_INT_DIGITS else TooLargeInt(digits)


def plain_data(value, depth: int = 0):
    """A copy of decoded JSON ``value`` checked to be well-formed protocol data.

    Strings are made valid Unicode (a lone surrogate, which JSON can carry but no file
    can hold, becomes ``?``).  Tagged dicts must have their tag's layout: arrays of
    numbers, lists of pairs, shapes, bodies and contacts of numbers.  Raises
    :class:`NotPlainData` saying what is wrong.
    """
    if depth > MAX_DEPTH:
        raise NotPlainData(f"the answer is nested more than {MAX_DEPTH} levels deep")
    kind = type(value)
    if kind is int and abs(value) > sys.float_info.max:
        raise NotPlainData(f"an integer of about {int(value.bit_length() * math.log10(2)) + 1} digits is not a "
                           "number of the course "
                           "(a float holds at most about 1.8e308)")
    if value is None or kind in (bool, int, float):
        return value
    if kind is TooLargeInt:
        raise NotPlainData(f"an integer of {value.digits} digits is not a number of the course "
                           "(a float holds at most about 1.8e308)")
    if kind is str:
        return clean_text(value)
    if kind is list:
        if _plain_numbers(value):
            return value[:]
        return [plain_data(v, depth + 1) for v in value]
    if kind is not dict:
        raise NotPlainData(f"a {kind.__name__} is not JSON data")
    tags = [t for t in TAGS if t in value]
    if len(tags) > 1:
        raise NotPlainData(f"a value carries two tags {tags}")
    if tags:
        _check_tagged(tags[0], value, depth)
    return {clean_text(k): plain_data(v, depth + 1) for k, v in value.items()}


def _plain_numbers(values: list) -> bool:
    """True when every element is a float, or an int a float holds (no call per element)."""
    for v in values:
        kind = type(v)
        if kind is not float and not (kind is int and -FLOAT_INT_LIMIT < v < FLOAT_INT_LIMIT):
            return False
    return True


def _check_tagged(tag: str, value: dict, depth: int) -> None:
    def numbers(name, data, nesting=1):
        ok = type(data) is list and all(
            is_number(v) if nesting == 1 else type(v) is list and all(is_number(w) for w in v) for v in data)
        if not ok:
            raise NotPlainData(f"{tag} value: {name} must be a list of numbers")

    if tag == ARRAY_TAG:
        _check_array(value[ARRAY_TAG], depth)
    elif tag == PAIRS_TAG:
        if type(value[PAIRS_TAG]) is not list:
            raise NotPlainData("a set of pairs must be a list")
    elif tag == SHAPE_TAG:
        if value[SHAPE_TAG] not in SHAPE_KINDS:
            raise NotPlainData(f"unknown shape {str(value[SHAPE_TAG])[:40]!r}")
        for name, field in value.items():
            if name != SHAPE_TAG and not is_number(field):
                numbers(name, field, 2 if name == "vertices" else 1)
    elif tag == CONTACT_TAG:
        numbers("normal", value.get("normal"))
        numbers("points", value.get("points"), 2)
        if not is_number(value.get("depth")):
            raise NotPlainData(f"{tag} value: depth must be a number")
        if "depths" in value:
            numbers("depths", value["depths"])
        if "feature_ids" in value:
            check_feature_ids(value["feature_ids"], len(value["points"]))
    elif tag == BODY_TAG:
        shape = value.get("shape")
        if type(shape) is not dict or SHAPE_TAG not in shape:
            raise NotPlainData("a body needs a shape")
        _check_tagged(SHAPE_TAG, shape, depth + 1)
        numbers("position", value.get("position"))
        numbers("velocity", value.get("velocity"))
        for name in BODY_FIELDS:
            if name in value and type(value[name]) not in (bool, int, float):
                raise NotPlainData(f"{tag} value: {name} must be a number or a bool")


def _check_array(data, depth: int) -> None:
    if depth > MAX_DEPTH:
        raise NotPlainData(f"the answer is nested more than {MAX_DEPTH} levels deep")
    if type(data) is list:
        for v in data:
            _check_array(v, depth + 1)
    elif type(data) not in (bool, int, float):
        raise NotPlainData("an array must hold numbers only")


def clean_text(text: str) -> str:
    """``text`` as valid Unicode: lone surrogates (from JSON escapes) become ``?``."""
    try:
        text.encode("utf-8")
        return text
    except UnicodeEncodeError:
        return text.encode("utf-8", "replace").decode("utf-8")


def is_number(value) -> bool:
    """True for a real int or float (bools excluded)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def finite(value) -> bool:
    """True for a finite real number."""
    return is_number(value) and math.isfinite(value)
