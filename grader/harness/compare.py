"""Comparisons of what a student's function returned with what was expected.

Every function returns ``None`` when the answer is right, or a sentence saying what
was expected and what came back (never "False is not True").  Values from the student
are plain data from the worker (see :mod:`grader.sandbox.codec`); expected values are
reference-engine objects or numbers.  Tolerances are explicit arguments.
"""
from __future__ import annotations

import math

import numpy as np

from ..sandbox import codec

#: Default absolute tolerance (m, m/s, ...) for values of order 1.
ATOL = 1e-9
#: Default relative tolerance.
RTOL = 1e-9


def show(value) -> str:
    """A short, readable rendering of a plain value."""
    if isinstance(value, float):
        return f"{value:.10g}"
    if isinstance(value, dict) and codec.CONTACT_TAG in value:
        return (f"Contact(normal={show(value.get('normal'))}, depth={show(value.get('depth'))}, "
                f"points={show(value.get('points'))})")
    if isinstance(value, dict) and codec.ARRAY_TAG in value:
        return show(value[codec.ARRAY_TAG])
    if isinstance(value, dict) and codec.PAIRS_TAG in value:
        return "{" + ", ".join(show(tuple(p)) for p in value[codec.PAIRS_TAG][:8]) + (", ...}" if len(value[codec.PAIRS_TAG]) > 8 else "}")
    if isinstance(value, (list, tuple)):
        inner = ", ".join(show(v) for v in list(value)[:8]) + (", ..." if len(value) > 8 else "")
        return f"({inner})" if isinstance(value, tuple) else f"[{inner}]"
    if isinstance(value, np.ndarray):
        return show(value.tolist())
    return repr(value)


def as_number(value):
    """A plain real number, or None if ``value`` is not one (bools are not numbers)."""
    if isinstance(value, dict) and codec.ARRAY_TAG in value and not isinstance(value[codec.ARRAY_TAG], list):
        value = value[codec.ARRAY_TAG]
    return float(value) if codec.is_number(value) else None


def as_vector(value, length: int | None = None):
    """A float numpy vector from a list or tagged array, or None."""
    if isinstance(value, dict) and codec.ARRAY_TAG in value:
        value = value[codec.ARRAY_TAG]
    if not isinstance(value, (list, tuple)) or not all(codec.is_number(v) for v in value):
        return None
    if length is not None and len(value) != length:
        return None
    return np.array(value, dtype=float)


def close(got: float, want: float, rtol: float = RTOL, atol: float = ATOL) -> bool:
    return math.isfinite(got) and abs(got - want) <= atol + rtol * abs(want)


def number(name: str, got, want: float, rtol: float = RTOL, atol: float = ATOL) -> str | None:
    """Compare a scalar."""
    value = as_number(got)
    if value is None:
        return f"{name}: expected a number close to {show(float(want))}, got {show(got)}"
    if not math.isfinite(value):
        return f"{name}: expected {show(float(want))}, got {value} (not a finite number)"
    if not close(value, want, rtol, atol):
        return f"{name}: expected {show(float(want))} (within {atol:g} + {rtol:g} relative), got {show(value)}"
    return None


def vector(name: str, got, want, atol: float = ATOL, rtol: float = RTOL) -> str | None:
    """Compare a vector component by component."""
    want = np.asarray(want, dtype=float)
    value = as_vector(got, len(want))
    if value is None:
        return f"{name}: expected {len(want)} numbers close to {show(want.tolist())}, got {show(got)}"
    if not np.all(np.isfinite(value)):
        return f"{name}: expected {show(want.tolist())}, got {show(value.tolist())} (not finite)"
    if not np.all(np.abs(value - want) <= atol + rtol * np.abs(want)):
        return f"{name}: expected {show(want.tolist())}, got {show(value.tolist())}"
    return None


def boolean(name: str, got, want: bool) -> str | None:
    """Compare a yes/no answer; only a real bool (or numpy bool) counts."""
    if not isinstance(got, bool):
        return f"{name}: expected True or False, got {show(got)}"
    if got != want:
        return f"{name}: expected {want} ({'they collide' if want else 'they are apart'}), got {got}"
    return None


def pairs(got, want: set[tuple[int, int]]) -> tuple[str | None, set, set]:
    """Compare a set of pairs (i, j), i < j.  Returns (message, missed, extra)."""
    if isinstance(got, dict) and codec.PAIRS_TAG in got:
        items = got[codec.PAIRS_TAG]
    elif isinstance(got, dict) and codec.ARRAY_TAG in got:
        items = got[codec.ARRAY_TAG]
    elif isinstance(got, list):
        items = got
    else:
        return f"expected a set of pairs (i, j) with i < j, got {show(got)}", set(want), set()
    found = set()
    for item in items:
        if (not isinstance(item, list) or len(item) != 2 or not all(isinstance(k, int) and not isinstance(k, bool)
                                                                      for k in item)):
            return f"expected pairs of two body indices, found {show(item)}", set(want), set()
        i, j = item
        if not i < j:
            return f"each pair must be written (i, j) with i < j, found {show(tuple(item))}", set(want), set()
        if (i, j) in found:
            return f"the pair {(i, j)} is listed twice", set(), set()
        found.add((i, j))
    missed, extra = want - found, found - want
    if not missed and not extra:
        return None, missed, extra
    parts = []
    if missed:
        parts.append(f"missed {len(missed)} of {len(want)} overlapping pairs, e.g. {sorted(missed)[:3]}")
    if extra:
        parts.append(f"returned {len(extra)} pairs whose boxes do not overlap, e.g. {sorted(extra)[:3]}")
    return "; ".join(parts), missed, extra


def contact(got, want, atol: float = 1e-7) -> str | None:
    """Compare a contact (normal A to B, depth >= 0, points) or None.

    Points are compared as a set (order free).  ``want`` is a reference Contact or None.
    """
    if want is None:
        if got is None:
            return None
        return f"expected None (the shapes are apart), got {show(got)}"
    if got is None:
        return (f"expected a contact with normal {show(want.normal.tolist())} and depth {show(want.depth)}, "
                "got None (your function says they do not touch)")
    if not isinstance(got, dict) or codec.CONTACT_TAG not in got:
        return f"expected a Contact or None, got {show(got)}"
    normal = as_vector(got.get("normal"), 2)
    if normal is None or not np.all(np.isfinite(normal)):
        return f"the normal must be two finite numbers, got {show(got.get('normal'))}"
    if abs(float(np.hypot(*normal)) - 1.0) > 1e-9:
        return f"the normal must have length 1, got {show(normal.tolist())} (length {np.hypot(*normal):.6g})"
    problem = vector("normal (from A to B)", normal.tolist(), want.normal, atol=atol)
    if problem and np.allclose(normal, -want.normal, atol=atol):
        return f"the normal points from B to A: expected {show(want.normal.tolist())}, got {show(normal.tolist())}"
    if problem:
        return problem
    problem = number("depth", got.get("depth"), want.depth, rtol=0, atol=atol)
    if problem:
        return problem
    points = got.get("points")
    rows = points if isinstance(points, list) else None
    if rows is None or not all(as_vector(p, 2) is not None for p in rows):
        return f"points must be a list of (x, y), got {show(points)}"
    if len(rows) != len(want.points):
        return (f"expected {len(want.points)} contact point(s) {show(want.points.tolist())}, "
                f"got {len(rows)}: {show(rows)}")
    remaining = [np.asarray(p, dtype=float) for p in want.points]
    for p in rows:
        p = np.asarray(p, dtype=float)
        distances = [float(np.hypot(*(p - q))) for q in remaining]
        k = int(np.argmin(distances))
        if distances[k] > atol:
            return f"contact points: expected {show(want.points.tolist())}, got {show(rows)}"
        remaining.pop(k)
    return None


# Values as a student reads them in messages ----------------------------------------------------
def number_text(value: float) -> str:
    return f"{value:.10g}"


def shape_text(shape: dict) -> str:
    """A plain shape as the constructor call that rebuilds it (m, rad)."""
    kind = shape.get(codec.SHAPE_TAG)

    def xy(v):
        return "(" + ", ".join(number_text(float(x)) for x in v) + ")"

    if kind == "Circle":
        return f"Circle(center={xy(shape['center'])}, radius={number_text(shape['radius'])})"
    if kind == "AABB":
        return f"AABB(min_corner={xy(shape['min_corner'])}, max_corner={xy(shape['max_corner'])})"
    if kind == "OBB":
        return (f"OBB(center={xy(shape['center'])}, half_extents={xy(shape['half_extents'])}, "
                f"angle={number_text(shape['angle'])})")
    if kind == "ConvexPolygon":
        return "ConvexPolygon([" + ", ".join(xy(v) for v in shape["vertices"]) + "])"
    return show(shape)


def call_text(function: str, *args) -> str:
    """``function(A, B)`` with the shapes written out, for failure messages."""
    return f"{function}(" + ", ".join(shape_text(a) if isinstance(a, dict) and codec.SHAPE_TAG in a else show(a)
                                      for a in args) + ")"
