"""Checks of the boolean SAT tests and their building blocks.

Each classic bug of the notes meets a case where it gives the wrong answer: FLT_MIN as
the start of a maximum (all projections negative), min/max not reset per axis (random
pairs), abs() of projections (shapes on opposite sides of the origin), the circle's
diameter instead of its radius, and an unnormalised centre-to-vertex axis (circles
near a corner).
"""
from __future__ import annotations

import math

import numpy as np
from hypothesis import strategies as st

from solutions.narrowphase.projection import intervals_overlap, project_circle, project_vertices
from solutions.shapes import AABB, OBB, Circle, polygon_vertices

from ..compare import boolean, number, show
from ..outcome import Outcome
from . import check
from .cases import circles, obbs, random_circle, random_obb, random_polygon, unit_vector
from .geometry import definite_overlap, shapes_figure
from .shrink import smallest_failure


def compare_overlaps(student, module: str, function: str, pairs: list, label: str, strategy=None) -> Outcome:
    """Yes/no answers on unambiguous pairs against the reference; shrink a failure."""
    cases = [(a, b, definite_overlap(a, b)) for a, b in pairs]
    cases = [(a, b, want) for a, b, want in cases if want is not None]
    answers = student.call_many(module, function, [(a, b) for a, b, _ in cases])
    wrong = [(a, b, want, got) for (a, b, want), got in zip(cases, answers)
             if boolean("", got, want) is not None]
    if not wrong:
        return Outcome.passed(f"{len(cases)} pairs agree with the reference")
    a, b, want, got = wrong[0]
    message = boolean(f"{function}({a!r}, {b!r})", got, want)
    if strategy is not None:
        def is_wrong(pair):
            expected = definite_overlap(*pair)
            return expected is not None and boolean("", student.call(module, function, *pair), expected) is not None

        small = smallest_failure(strategy, is_wrong)
        if small is not None:
            a, b = small
            want = definite_overlap(a, b)
            message = boolean(f"{function}({a!r}, {b!r})", student.call(module, function, a, b), want)
    right = len(cases) - len(wrong)
    return Outcome.failed(f"{label}: {len(wrong)} of {len(cases)} pairs wrong, e.g. {message}",
                          shapes_figure(a, b, f"{function}: {label}"), fraction=right / len(cases))


@check("sat.project_vertices")
def check_project_vertices(student):
    rng = np.random.default_rng(301)
    cases = []
    for k in range(40):
        # Half the polygons lie where every projection is negative (the FLT_MIN trap).
        center = rng.uniform(-20, -8, 2) if k % 2 else rng.uniform(-3, 3, 2)
        cases.append((random_polygon(rng, center, float(rng.uniform(0.5, 2))).vertices, unit_vector(rng)))
    cases.append((np.array([[-6.0, -1.0], [-4.0, -1.0], [-4.0, 1.0], [-6.0, 1.0]]), np.array([1.0, 0.0])))
    answers = student.call_many("narrowphase.projection", "project_vertices", cases)
    for (vertices, axis), got in zip(cases, answers):
        lo, hi = project_vertices(vertices, axis)
        if not isinstance(got, list) or len(got) != 2:
            return Outcome.failed(f"project_vertices must return (min, max), got {show(got)}")
        problem = number("min", got[0], lo) or number("max", got[1], hi)
        if problem:
            return Outcome.failed(f"projecting {show(np.round(vertices, 3).tolist())} on axis "
                                  f"{show(np.round(axis, 4).tolist())}: {problem} (expected ({lo:.6g}, {hi:.6g}))")
    return Outcome.passed(f"{len(cases)} projections agree")


@check("sat.project_circle")
def check_project_circle(student):
    rng = np.random.default_rng(302)
    cases = [(rng.uniform(-10, 10, 2), float(rng.uniform(0.1, 3)), unit_vector(rng)) for _ in range(30)]
    answers = student.call_many("narrowphase.projection", "project_circle", cases)
    for (center, radius, axis), got in zip(cases, answers):
        lo, hi = project_circle(center, radius, axis)
        if not isinstance(got, list) or len(got) != 2:
            return Outcome.failed(f"project_circle must return (min, max), got {show(got)}")
        problem = number("min", got[0], lo) or number("max", got[1], hi)
        if problem:
            return Outcome.failed(f"circle at {show(np.round(center, 3).tolist())} with radius {radius:.4g} on axis "
                                  f"{show(np.round(axis, 4).tolist())}: {problem}; the interval is centre +- radius")
    return Outcome.passed(f"{len(cases)} projections agree")


@check("sat.intervals_overlap")
def check_intervals(student):
    cases = [((0.0, 1.0), (1.0, 2.0)), ((0.0, 1.0), (1.5, 2.0)), ((-6.0, -4.0), (-3.0, -1.0)), ((2.0, 3.0), (0.0, 5.0)),
             ((-1.0, 1.0), (-1.0, 1.0)), ((3.0, 4.0), (0.0, 2.999)), ((-2.0, -1.0), (-1.0, 0.0)), ((5.0, 5.0), (5.0, 5.0))]
    answers = student.call_many("narrowphase.projection", "intervals_overlap", cases)
    for (a, b), got in zip(cases, answers):
        message = boolean(f"intervals_overlap({a}, {b})", got, intervals_overlap(a, b))
        if message:
            return Outcome.failed(message + " (sharing an end point counts as overlapping)")
    return Outcome.passed(f"{len(cases)} interval pairs agree")


@check("sat.aabbs_overlap")
def check_aabbs(student):
    rng = np.random.default_rng(303)
    pairs = []
    for _ in range(60):
        a = AABB.from_center(rng.uniform(-3, 3, 2), rng.uniform(0.2, 1.5, 2))
        b = AABB.from_center(rng.uniform(-3, 3, 2), rng.uniform(0.2, 1.5, 2))
        pairs.append((a, b))
    pairs += [(AABB((-6, -1), (-4, 1)), AABB((-3, -1), (-1, 1))), (AABB((0, 0), (1, 1)), AABB((1, 0), (2, 1)))]
    return compare_overlaps(student, "narrowphase.aabb_aabb", "aabbs_overlap", pairs, "axis-aligned boxes")


@check("sat.obb_negative_coordinates")
def check_negative_boxes(student):
    # Erratum 7: with max starting at FLT_MIN, boxes left of the origin look colliding.
    pairs = [(OBB((-5, 0), (0.5, 0.5), 0.0), OBB((-2, 0), (0.5, 0.5), 0.0)),
             (OBB((-9, -7), (1, 0.5), 0.3), OBB((-5, -7), (1, 0.5), -0.2)),
             (OBB((-4, -4), (0.5, 1), 0.0), OBB((-4, -1), (0.5, 1), 0.0))]
    return compare_overlaps(student, "narrowphase.polygon_polygon", "polygons_overlap", pairs,
                            "boxes at negative coordinates")


@check("sat.polygons_overlap.random")
def check_polygons_random(student):
    rng = np.random.default_rng(304)
    pairs = [(random_obb(rng), random_obb(rng)) for _ in range(150)]
    pairs += [(random_polygon(rng, rng.uniform(-2, 2, 2), 1.2), random_polygon(rng, rng.uniform(-2, 2, 2), 1.2))
              for _ in range(100)]
    return compare_overlaps(student, "narrowphase.polygon_polygon", "polygons_overlap", pairs,
                            "random boxes and polygons", st.tuples(obbs, obbs))


@check("sat.obbs_overlap.random")
def check_obbs_random(student):
    # The two-axes-per-box test: random boxes, boxes left of the origin (erratum 7) and
    # boxes touching along an edge (touching counts).
    rng = np.random.default_rng(305)
    pairs = [(random_obb(rng), random_obb(rng)) for _ in range(150)]
    pairs += [(OBB((-9, -7), (1, 0.5), 0.3), OBB((-5, -7), (1, 0.5), -0.2)),
              (OBB((-5, 0), (0.5, 0.5), 0.0), OBB((-2, 0), (0.5, 0.5), 0.0)),
              (OBB((0, 0), (1, 1), 0.0), OBB((2, 0), (1, 1), 0.0))]
    return compare_overlaps(student, "narrowphase.polygon_polygon", "obbs_overlap", pairs,
                            "random oriented boxes", st.tuples(obbs, obbs))


@check("sat.circle_polygon.opposite_sides")
def check_circle_opposite(student):
    # Erratum 10: abs() folds projections around the origin.
    pairs = [(Circle((-10, 0), 1), AABB((8, -2), (12, 2))), (Circle((0, -7), 1.5), OBB((0, 6), (1, 1), 0.4)),
             (Circle((-3, -3), 0.5), AABB((2, 2), (4, 4)))]
    return compare_overlaps(student, "narrowphase.circle_polygon", "circle_polygon_overlap", pairs,
                            "circle and box on opposite sides of the origin")


@check("sat.circle_polygon.random")
def check_circle_random(student):
    rng = np.random.default_rng(305)
    pairs = [(random_circle(rng), random_obb(rng)) for _ in range(150)]
    # Circles in a corner's region, just apart: only the normalised vertex axis separates them.
    for _ in range(60):
        box = random_obb(rng, 0.5)
        corner = polygon_vertices(box)[rng.integers(4)]
        outward = corner - box.center
        outward /= np.linalg.norm(outward)
        radius = float(rng.uniform(0.3, 1.0))
        pairs.append((Circle(corner + outward * radius * rng.uniform(1.02, 1.3), radius), box))
    return compare_overlaps(student, "narrowphase.circle_polygon", "circle_polygon_overlap", pairs,
                            "random circles and boxes", st.tuples(circles, obbs))


@check("sat.circles_overlap")
def check_circles(student):
    rng = np.random.default_rng(306)
    pairs = [(random_circle(rng), random_circle(rng)) for _ in range(80)]
    pairs.append((Circle((0, 0), 1), Circle((2.5, 0), 1)))  # diameter would say they touch
    return compare_overlaps(student, "narrowphase.circle_circle", "circles_overlap", pairs, "random circles",
                            st.tuples(circles, circles))
