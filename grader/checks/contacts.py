"""Checks of contact generation: normal from A to B, depth, contact point(s)."""
from __future__ import annotations

import numpy as np
from hypothesis import strategies as st

from solutions.narrowphase.dispatch import collide
from solutions.shapes import AABB, OBB, Circle

from ..compare import contact as compare_contact
from ..outcome import Outcome
from . import check
from .cases import circles, obbs, random_circle, random_obb, random_polygon
from .geometry import AMBIGUITY, definite_overlap, shapes_figure
from .shrink import smallest_failure

#: Contacts match within this (m): both sides compute the same closed forms in doubles.
CONTACT_ATOL = 1e-7


def same_contact(c1, c2) -> bool:
    if c1 is None or c2 is None:
        return c1 is None and c2 is None
    return (np.allclose(c1.normal, c2.normal, atol=1e-9) and abs(c1.depth - c2.depth) < 1e-9
            and len(c1.points) == len(c2.points))


def unambiguous(a, b):
    """The reference contact, or False when the case is a matter of rounding or of a
    free choice (touching, or two reference faces equally good)."""
    if definite_overlap(a, b) is None:
        return False
    want = collide(a, b)
    if want is not None and want.depth < AMBIGUITY:
        return False
    swapped = collide(b, a)
    if not same_contact(want, swapped.flipped() if swapped is not None else None):
        return False
    return want


def compare_contacts(student, module: str, function: str, pairs: list, label: str, strategy=None) -> Outcome:
    cases = [(a, b, unambiguous(a, b)) for a, b in pairs]
    cases = [(a, b, want) for a, b, want in cases if want is not False]
    answers = student.call_many(module, function, [(a, b) for a, b, _ in cases])
    wrong = [(a, b, want, got) for (a, b, want), got in zip(cases, answers)
             if compare_contact(got, want, CONTACT_ATOL) is not None]
    if not wrong:
        return Outcome.passed(f"{len(cases)} contacts agree with the reference")
    a, b, want, got = wrong[0]
    message = compare_contact(got, want, CONTACT_ATOL)
    if strategy is not None:
        def is_wrong(pair):
            expected = unambiguous(*pair)
            return expected is not False and compare_contact(student.call(module, function, *pair), expected,
                                                             CONTACT_ATOL) is not None

        small = smallest_failure(strategy, is_wrong)
        if small is not None:
            a, b = small
            want = unambiguous(a, b)
            got = student.call(module, function, a, b)
            message = compare_contact(got, want, CONTACT_ATOL)
    right = len(cases) - len(wrong)
    return Outcome.failed(f"{label}: {len(wrong)} of {len(cases)} contacts wrong, e.g. {function}({a!r}, {b!r}): "
                          f"{message}", shapes_figure(a, b, f"{function}: {label}", want, got),
                          fraction=right / len(cases))


@check("contacts.circle_circle")
def circle_circle(student):
    rng = np.random.default_rng(401)
    pairs = [(random_circle(rng, 1.0), random_circle(rng, 1.0)) for _ in range(80)]
    return compare_contacts(student, "narrowphase.circle_circle", "collide_circle_circle", pairs, "random circles",
                            st.tuples(circles, circles))


@check("contacts.circle_polygon")
def circle_polygon(student):
    rng = np.random.default_rng(402)
    pairs = [(random_circle(rng, 1.2), random_obb(rng, 1.2)) for _ in range(80)]
    pairs += [(Circle((0.1, 0.2), 0.3), OBB((0, 0), (1, 1), 0.0))]  # centre inside the box
    return compare_contacts(student, "narrowphase.circle_polygon", "collide_circle_polygon", pairs,
                            "random circles and boxes", st.tuples(circles, obbs))


@check("contacts.polygon_polygon")
def polygon_polygon(student):
    rng = np.random.default_rng(403)
    pairs = [(random_obb(rng, 1.2), random_obb(rng, 1.2)) for _ in range(100)]
    pairs += [(random_polygon(rng, rng.uniform(-1, 1, 2), 1.0), random_polygon(rng, rng.uniform(-1, 1, 2), 1.0))
              for _ in range(60)]
    return compare_contacts(student, "narrowphase.polygon_polygon", "collide_polygon_polygon", pairs,
                            "random boxes and polygons", st.tuples(obbs, obbs))


@check("contacts.face_face")
def face_face(student):
    # Resting boxes: parallel faces give a two-point manifold (erratum 12).
    pairs = [(OBB((0, 0), (1, 0.5), 0.0), OBB((0.3, 0.95), (0.5, 0.5), 0.0)),
             (OBB((0, 0), (2, 0.5), 0.3), OBB(np.array((0, 0)) + 0.98 * np.array((-np.sin(0.3), np.cos(0.3))),
                                              (0.5, 0.5), 0.3)),
             (OBB((0, 0), (0.5, 0.5), 0.0), OBB((0.9, 0.2), (0.5, 0.5), 0.0))]
    return compare_contacts(student, "narrowphase.polygon_polygon", "collide_polygon_polygon", pairs,
                            "boxes resting face to face")


@check("contacts.aabb_aabb")
def aabb_aabb(student):
    rng = np.random.default_rng(405)
    pairs = [(AABB.from_center(rng.uniform(-1, 1, 2), rng.uniform(0.3, 1, 2)),
              AABB.from_center(rng.uniform(-1, 1, 2), rng.uniform(0.3, 1, 2))) for _ in range(60)]
    return compare_contacts(student, "narrowphase.aabb_aabb", "collide_aabb_aabb", pairs, "axis-aligned boxes")
