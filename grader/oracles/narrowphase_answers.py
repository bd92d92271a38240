"""Reading the narrow phase's answers: yes/no and contacts compared with expected ones.

Expected contacts are plain dicts (:func:`.plain.contact`, from pymunk or literals) or
None.  Every returned field is compared: the normal (finite, unit length, within the
tolerance of the expected one, with a word when it points the wrong way), the depth,
the number of points and each point; each point's depth and feature id when the
expected contact lists them (:func:`with_feature_ids`: pymunk gives no feature ids, so
only contacts worked out by hand, and the reference's on the hidden side, have them).
A NaN or infinite value is never "within the tolerance": every comparison is written
so that NaN fails (``not |x - y| <= tol``) after an explicit finiteness test.  Each
function returns None for a right answer, else a sentence saying what was expected and
what came back.
"""
from __future__ import annotations

import math

import numpy as np

from ..sandbox.codec import CONTACT_TAG, NotPlainData, check_feature_ids, decode_feature_ids
from ..harness.compare import as_number, as_vector, boolean, number_text, show

#: Contacts match within this (m): the oracle and a right answer compute the same
#: closed forms in doubles (they agree to about 1e-15 m on shapes of about 1 m), while a
#: wrong feature, sign or clipping is off by far more than 1e-7 m.
CONTACT_ATOL = 1e-7
#: A normal must have length 1 within this (a normalised double is within 1e-15).
UNIT_ATOL = 1e-9


def contact_text(contact: dict | None) -> str:
    if contact is None:
        return "None"
    ids = contact.get("feature_ids")
    return (f"Contact(normal={show([float(v) for v in contact['normal']])}, depth={number_text(contact['depth'])}, "
            f"points={show([[float(x) for x in p] for p in contact['points']])}"
            + ("" if ids is None else f", feature_ids={ids_text(ids)}") + ")")


def with_feature_ids(contact: dict, feature_ids) -> dict:
    """An expected plain contact that also names each point's feature id (in the order
    of its points): ids are compared exactly, each with the one of its point."""
    if len(feature_ids) != len(contact["points"]):
        raise ValueError("one feature id per expected contact point (a problem of the test)")
    return dict(contact, feature_ids=[_plain_id(v) for v in feature_ids])


def without_feature_ids(contact: dict | None) -> dict | None:
    """The contact without its feature ids (they are then not compared)."""
    if not isinstance(contact, dict) or "feature_ids" not in contact:
        return contact
    return {k: v for k, v in contact.items() if k != "feature_ids"}


def _plain_id(value):
    return [_plain_id(v) for v in value] if isinstance(value, (list, tuple)) else value


def id_text(value) -> str:
    """A feature id as Python writes it: tuples in parentheses, strings quoted."""
    if isinstance(value, (list, tuple)):
        inner = ", ".join(id_text(v) for v in value)
        return f"({inner},)" if len(value) == 1 else f"({inner})"
    return repr(value)


def ids_text(ids) -> str:
    return "(" + ", ".join(id_text(v) for v in list(ids)[:8]) + (", ..." if len(ids) > 8 else "") + (
        ",)" if len(ids) == 1 else ")")


def boolean_problem(got, want: bool) -> str | None:
    """A yes/no answer compared with the expected one (only a real bool counts)."""
    problem = boolean("answer", got, want)
    return None if problem is None else problem[len("answer: "):]


def _finite_vector(value, length: int = 2):
    vector = as_vector(value, length)
    if vector is None or not np.all(np.isfinite(vector)):
        return None
    return vector


def contact_problem(got, want: dict | None, atol: float = CONTACT_ATOL) -> str | None:
    """A returned contact (plain data) against the expected plain contact or None.

    Points are compared as a set (order free), each within ``atol`` (m).
    """
    if want is None:
        if got is None:
            return None
        return f"expected None (the shapes are apart), got {show(got)}"
    if got is None:
        return f"expected {contact_text(want)}, got None (your function says they do not touch)"
    if not isinstance(got, dict) or CONTACT_TAG not in got:
        return f"expected a Contact or None, got {show(got)}"
    want_normal = np.asarray(want["normal"], dtype=float)
    normal = _finite_vector(got.get("normal"))
    if normal is None:
        return f"the normal must be two finite numbers, got {show(got.get('normal'))} (expected {show(want_normal.tolist())})"
    length = math.hypot(*normal)
    if not abs(length - 1.0) <= UNIT_ATOL:
        return (f"the normal must be a unit vector, got {show(normal.tolist())} of length {length:.10g} "
                f"(expected {show(want_normal.tolist())})")
    if not np.all(np.abs(normal - want_normal) <= atol):
        if np.all(np.abs(normal + want_normal) <= atol):
            return (f"the normal points from B to A: expected {show(want_normal.tolist())} (from A to B), "
                    f"got {show(normal.tolist())}")
        return f"normal (from A to B): expected {show(want_normal.tolist())}, got {show(normal.tolist())}"
    depth = as_number(got.get("depth"))
    if depth is None or not math.isfinite(depth):
        return f"depth: expected the finite number {number_text(want['depth'])}, got {show(got.get('depth'))}"
    if not abs(depth - want["depth"]) <= atol:
        hint = " (depth is >= 0: how far the shapes overlap)" if depth < 0 else ""
        return f"depth: expected {number_text(want['depth'])} (within {atol:g} m), got {number_text(depth)}{hint}"
    rows = got.get("points")
    want_points = [np.asarray(p, dtype=float) for p in want["points"]]
    if not isinstance(rows, list) or not all(as_vector(p, 2) is not None for p in rows):
        return f"points must be a list of (x, y), got {show(rows)}"
    points = [as_vector(p, 2) for p in rows]
    if not all(np.all(np.isfinite(p)) for p in points):
        return f"contact points must be finite, got {show(rows)}"
    if len(points) != len(want_points):
        return (f"expected {len(want_points)} contact point(s) {show([p.tolist() for p in want_points])}, "
                f"got {len(points)}: {show(rows)}{repeated_point_text(points, atol)}")
    remaining = list(range(len(want_points)))
    matched = []
    for p in points:
        distances = [float(np.hypot(*(p - want_points[j]))) for j in remaining]
        k = int(np.argmin(distances))
        if not distances[k] <= atol:
            return (f"contact points: expected {show([q.tolist() for q in want_points])} (each the midpoint "
                    f"between the two surfaces), got {show(rows)}")
        matched.append(remaining.pop(k))
    return _depths_problem(got, want, points, matched, atol) or _feature_ids_problem(got, want, points, matched)


#: Most points scanned for a repeated one (see repeated_point_text).
REPEAT_SCAN_POINTS = 8


def repeated_point_text(points: list, atol: float = CONTACT_ATOL) -> str:
    """``": points i and j are the same point, ..."`` when two of ``points`` (arrays, m) lie
    within ``atol`` of each other, else ``""``: the end of a message about the number of points.
    Only a handful of points are compared (a 2D manifold holds at most two): an answer of
    thousands is wrong for its count alone, and must not cost the trusted side a pair scan."""
    if len(points) > REPEAT_SCAN_POINTS:
        return ""
    for i in range(len(points)):
        for j in range(i + 1, len(points)):
            if float(np.hypot(*(points[i] - points[j]))) <= atol:
                return (f": points {i} and {j} are the same point, and a manifold never holds a point twice "
                        f"(the two ends of a zero-size incident face give one contact point)")
    return ""


def _depths_problem(got: dict, want: dict, points: list, matched: list, atol: float) -> str | None:
    """Each point's own depth (``depths``), when the expected contact lists them."""
    if "depths" not in want or "depths" not in got:
        return None
    depths = as_vector(got["depths"], len(points))
    if depths is None or not np.all(np.isfinite(depths)):
        return f"depths must be one finite number per contact point, got {show(got['depths'])}"
    for point, depth, j in zip(points, depths, matched):
        wanted = float(want["depths"][j])
        if not abs(depth - wanted) <= atol:
            return (f"the depth at contact point {show(point.tolist())}: expected {number_text(wanted)}, got "
                    f"{number_text(depth)} (each point has its own depth, how far it is below the reference face; "
                    f"depths = {show(got['depths'])})")
    return None


def _feature_ids_problem(got: dict, want: dict, points: list, matched: list) -> str | None:
    """Each point's feature id, when the expected contact lists them: equal as dict keys
    (what warm starting matches them by), tuples however they were sent."""
    if want.get("feature_ids") is None:
        return None
    want_ids = decode_feature_ids(want["feature_ids"])
    data = got.get("feature_ids")
    if data is None:
        return (f"feature_ids: expected {ids_text(want_ids)} (one id per contact point, naming the features that "
                f"touch there, as the docstring says), got None")
    try:
        check_feature_ids(data, len(points))
    except NotPlainData:
        return f"feature_ids must hold one id (an int, a str or a tuple of them) per contact point, got {show(data)}"
    got_ids = decode_feature_ids(data)
    for point, feature, j in zip(points, got_ids, matched):
        if not feature == want_ids[j]:
            return (f"the feature id of the contact point {show(point.tolist())}: expected {id_text(want_ids[j])}, "
                    f"got {id_text(feature)} (feature_ids = {ids_text(got_ids)})")
    return None


def pair_figure(a: dict, b: dict, title: str, want: dict | None = None, got=None) -> dict:
    """Plain data for a picture of two shapes and the expected and returned contacts
    (see :mod:`grader.harness.figures`, kind "shapes")."""
    figure = {"kind": "shapes", "title": title, "shapes": [a, b]}
    if want is not None:
        figure["expected"] = {k: want[k] for k in (CONTACT_TAG, "normal", "depth", "points")}
    if isinstance(got, dict) and CONTACT_TAG in got:
        figure["got"] = without_feature_ids(got)   # not drawn
    return figure
