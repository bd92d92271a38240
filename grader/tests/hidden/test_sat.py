"""SAT yes/no tests, hidden side: expected answers from the reference engine.

Shapes are built as plain data (:mod:`grader.oracles.plain`) and rebuilt with the
reference's classes (:func:`grader.sandbox.codec.decode_shape`) for the expected answer, so
the student's code and the reference see the very same numbers.  Pairs that pymunk
finds within 1e-7 m of touching are left out of random batches (rounding decides them).
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest

import solutions.shapes
from solutions.narrowphase.dispatch import shapes_overlap

from grader.sandbox import codec
from grader.harness.credit import check_cases
from grader.oracles import narrowphase_cases as cases
from grader.oracles import plain
from grader.oracles import random_cases as rc
from grader.harness.compare import call_text
from grader.oracles.narrowphase_answers import boolean_problem, pair_figure
from grader.oracles.pymunk_geometry import definite_overlap

POLYGONS = "narrowphase.polygon_polygon"
CIRCLE_POLYGON = "narrowphase.circle_polygon"
CIRCLES = "narrowphase.circle_circle"
AABBS = "narrowphase.aabb_aabb"


def reference(shape: dict):
    return codec.decode_shape(shape, solutions.shapes)


def expected(a: dict, b: dict) -> bool:
    return bool(shapes_overlap(reference(a), reference(b)))


def batch_of(pairs, note: str, skip_near_touching: bool = True) -> list[tuple]:
    """(A, B, reference answer, note); near-touching random pairs left out."""
    return [(a, b, expected(a, b), note) for a, b in pairs
            if not skip_near_touching or definite_overlap(a, b) is not None]


def check_yes_no(student, module: str, function: str, batch: list[tuple], label: str) -> None:
    answers = student.call_many(module, function, [(a, b) for a, b, _, _ in batch])

    def problem_of(case):
        (a, b, want, note), got = case
        problem = boolean_problem(got, want)
        return None if problem is None else f"{problem} [{note}]"

    check_cases(zip(batch, answers), problem_of, label, category=lambda case: case[0][3],
                describe=lambda case: call_text(function, case[0][0], case[0][1]),
                figure_of=lambda case: pair_figure(case[0][0], case[0][1], f"{function}: {case[0][3]}"))


@pytest.mark.points(2)
@pytest.mark.visibility("after_due_date")
def test_obb_negative_coordinates(student):
    """SAT: boxes left of the origin (FLT_MIN)"""
    rng = np.random.default_rng(311)
    # Erratum 7: with max starting at FLT_MIN, every interval left of the origin reaches 0.
    pairs = [(plain.obb((-5, 0), (0.5, 0.5), 0.0), plain.obb((-2, 0), (0.5, 0.5), 0.0)),
             (plain.obb((-9, -7), (1, 0.5), 0.3), plain.obb((-5, -7), (1, 0.5), -0.2)),
             (plain.obb((-4, -4), (0.5, 1), 0.0), plain.obb((-4, -1), (0.5, 1), 0.0)),
             # overlapping ones, so that "always apart" fails too
             (plain.obb((-5, -3), (1, 1), 0.0), plain.obb((-4.2, -2.5), (1, 0.5), 0.4)),
             (plain.obb((-9, -7), (1, 0.5), 0.3), plain.obb((-7.5, -7), (1, 0.5), -0.2))]
    pairs += [tuple(cases.translated(s, (-12, -9)) for s in (rc.random_obb(rng, 1.5), rc.random_obb(rng, 1.5))) for _ in range(30)]
    pairs += [cases.random_one_side(rng, offset=(-10, -10)) for _ in range(6)]
    batch = batch_of(pairs, "boxes left of the origin")
    batch += [(a, b, True, "touching exactly, left of the origin")
              for a, b, _ in (cases.touching_boxes_pair((-6, -4), (1, 0.5), (0.5, 0.5), side, 0.25) for side in range(4))]
    polygons = [(plain.polygon(plain.vertices(a)), plain.polygon(plain.vertices(b)), want, note)
                for a, b, want, note in batch[:12]]
    check_yes_no(student, POLYGONS, "polygons_overlap", batch + polygons, "boxes left of the origin")
    check_yes_no(student, POLYGONS, "obbs_overlap", batch, "boxes left of the origin")


@pytest.mark.points(2)
@pytest.mark.visibility("after_due_date")
def test_circle_polygon_opposite_sides(student):
    """SAT: circle and box on opposite sides of the origin (abs)"""
    # Erratum 10: abs() folds projections around the origin.
    pairs = [(plain.circle((-10, 0), 1), plain.aabb((8, -2), (12, 2))),
             (plain.circle((0, -7), 1.5), plain.obb((0, 6), (1, 1), 0.4)),
             (plain.circle((-3, -3), 0.5), plain.aabb((2, 2), (4, 4))),
             (plain.circle((10, 0), 1), plain.aabb((-12, -2), (-8, 2))),
             (plain.circle((3, 4), 1), plain.obb((-3, -4), (1.5, 1), 1.0)),
             # overlapping, on the negative side: folded, the circle would jump across
             (plain.circle((-10, 0), 1), plain.aabb((-12, -2), (-8, 2))),
             (plain.circle((-6.5, -6.5), 1), plain.obb((-5, -5), (1, 1), 0.785)),
             (plain.circle((0, -7), 1.5), plain.obb((0.5, -5), (1, 1), 0.4)),
             # straddling the origin
             (plain.circle((0.5, 0), 1), plain.aabb((-3, -1), (-0.4, 1))),
             (plain.circle((-0.5, 0), 1), plain.aabb((0.6, -1), (3, 1)))]
    rng = np.random.default_rng(312)
    for _ in range(20):
        circle, box = rc.random_circle(rng, 1.0), rc.random_obb(rng, 1.0)
        side = rng.choice([-1.0, 1.0])
        pairs.append((cases.translated(circle, (side * 6, side * 4)), cases.translated(box, (side * 6 + rng.uniform(-2, 2), side * 4))))
        pairs.append((cases.translated(circle, (side * 6, side * 4)), cases.translated(box, (-side * 6, -side * 4))))
    batch = batch_of(pairs, "circle and box on opposite sides of the origin, or both on its negative side")
    check_yes_no(student, CIRCLE_POLYGON, "circle_polygon_overlap", batch, "circles and boxes around the origin")


def kind_pairs(rng, kind: str, count: int, offset) -> list[tuple]:
    def shape(k):
        if k == "circle":
            return rc.random_circle(rng)
        if k == "aabb":
            return plain.aabb_from_center(rng.uniform(-2, 2, 2), rng.uniform(0.1, 1.5, 2))
        if k == "obb":
            return rc.random_obb(rng)
        return rc.random_polygon(rng, rng.uniform(-2, 2, 2), float(rng.uniform(0.3, 1.5)))

    a_kind, b_kind = kind.split("-")
    return [(cases.translated(shape(a_kind), offset), cases.translated(shape(b_kind), offset)) for _ in range(count)]


@lru_cache(maxsize=1)
def random_batches() -> dict:
    """(module, function) -> [(A, B, expected, note)]: the same for every submission,
    so built (with the reference's answers) once per grading process."""
    rng = np.random.default_rng(313)
    offsets = [(0, 0), (-40, -25), (35, 50), (-100, 100)]
    batches = {
        (AABBS, "aabbs_overlap"): ["aabb-aabb"],
        (POLYGONS, "obbs_overlap"): ["obb-obb", "aabb-obb", "obb-aabb"],
        (POLYGONS, "polygons_overlap"): ["poly-poly", "obb-poly", "poly-obb", "aabb-poly"],
        (CIRCLE_POLYGON, "circle_polygon_overlap"): ["circle-obb", "circle-poly", "circle-aabb"],
        (CIRCLES, "circles_overlap"): ["circle-circle"],
    }
    out = {}
    for (module, function), kinds in batches.items():
        pairs = [p for kind in kinds for offset in offsets for p in kind_pairs(rng, kind, 20, offset)]
        if function in ("obbs_overlap", "polygons_overlap"):
            pairs += [cases.random_one_side(rng, offset=offsets[k % 4]) for k in range(30)]
            pairs += [(b, a) for a, b in pairs[-30:]]
        if function == "polygons_overlap":
            pairs += [cases.random_close_apart(rng, offset=offsets[k % 4]) for k in range(60)]
        if function == "circle_polygon_overlap":
            pairs += [cases.random_corner_circle(rng, apart=k % 2 == 0, offset=offsets[k % 4]) for k in range(60)]
        out[(module, function)] = batch_of(pairs, "random pair")
    return out


@pytest.mark.points(2)
@pytest.mark.partial_credit
@pytest.mark.visibility("after_due_date")
def test_random_against_reference(student):
    """SAT: many random pairs of every kind, near and far from the origin"""
    everything = []
    for (module, function), batch in random_batches().items():
        answers = student.call_many(module, function, [(a, b) for a, b, _, _ in batch])
        everything += [(function, case, got) for case, got in zip(batch, answers)]

    def problem_of(item):
        function, (a, b, want, note), got = item
        return boolean_problem(got, want)

    check_cases(everything, problem_of, "random pairs of every kind", category=lambda item: item[0],
                describe=lambda item: call_text(item[0], item[1][0], item[1][1]),
                figure_of=lambda item: pair_figure(item[1][0], item[1][1], f"{item[0]}: random pair"))


@pytest.mark.points(1)
@pytest.mark.visibility("after_due_date")
def test_degenerate_shapes(student):
    """SAT: shapes of zero size (points, segments) get a defined answer"""
    point = lambda x, y: plain.circle((x, y), 0.0)  # noqa: E731
    segment = plain.obb((1, 1), (1.5, 0.0), 0.6)    # a box of zero height: a segment
    flat = plain.aabb((-1, 2), (3, 2))             # an AABB of zero height
    groups = {
        (CIRCLES, "circles_overlap"): [(point(1, 2), point(1, 2)), (point(1, 2), point(1, 2.5)),
                                       (point(0, 0), plain.circle((0.75, 1.0), 1.25)), (point(0, 0), plain.circle((0.75, 1.0), 1.2))],
        (CIRCLE_POLYGON, "circle_polygon_overlap"): [
            (point(0.5, 0.5), plain.aabb((0, 0), (1, 1))), (point(1.5, 0.5), plain.aabb((0, 0), (1, 1))),
            (point(1, 0.5), plain.aabb((0, 0), (1, 1))), (point(1, 1), plain.aabb((0, 0), (1, 1))),
            (plain.circle((1, 1), 0.5), plain.aabb((0, 0), (1, 1))),  # centre on the vertex
            (plain.circle((1, 1.2), 0.3), segment), (plain.circle((1, 1.6), 0.3), segment),
            (plain.circle((1, 2.2), 0.3), flat), (plain.circle((1, 2.4), 0.3), flat)],
        (POLYGONS, "obbs_overlap"): [(segment, plain.obb((1, 1), (0.3, 0.3), 0.0)), (segment, plain.obb((1, 2), (0.3, 0.3), 0.0)),
                                     (segment, segment), (flat, plain.obb((0, 2.5), (0.5, 0.5), 0.0)),
                                     (flat, plain.obb((0, 3.0), (0.5, 0.4), 0.0)),
                                     (plain.obb((0, 0), (0.0, 0.0), 0.3), plain.obb((0, 0), (1, 1), 0.2))],
        (AABBS, "aabbs_overlap"): [(flat, plain.aabb((0, 1), (1, 2))), (flat, plain.aabb((0, 2.1), (1, 3))),
                                   (plain.aabb((1, 1), (1, 1)), plain.aabb((0, 0), (1, 1))),
                                   (plain.aabb((1, 1), (1, 1)), plain.aabb((1, 1), (1, 1)))],
    }
    everything = []
    for (module, function), pairs in groups.items():
        answers = student.call_many(module, function, pairs)
        everything += [(function, a, b, expected(a, b), got) for (a, b), got in zip(pairs, answers)]
    check_cases(everything, lambda item: boolean_problem(item[4], item[3]), "shapes of zero size",
                describe=lambda item: call_text(item[0], item[1], item[2]),
                figure_of=lambda item: pair_figure(item[1], item[2], f"{item[0]}: shapes of zero size"))
