"""Hidden tests of the quadtree: many bodies at one point, bodies outside the root,
seeded batches of the hard cases, the stopping rules, and a scene large enough that a
tree that never splits cannot finish.

Expected pairs come from the brute-force oracle; the helpers are the public tests' own.
"""
from __future__ import annotations

import numpy as np
import pytest

from grader.harness.compare import pairs as compare_pairs
from grader.harness.compare import show
from grader.harness.credit import fail
from grader.oracles.brute_force import describe_boxes, overlapping_pairs, pairs_figure, smallest_wrong_scene
from grader.oracles.random_cases import clustered_aabbs, random_aabbs
from grader.tests.public.test_quadtree import (FUNCTION, MODULE, WHO, call_or_timeout, check_algorithm, check_scenes,
                                               pairs_text, wrong_answer)


# Seeded hard cases -----------------------------------------------------------------------------------
def split_line_scene(rng: np.random.Generator, depth: int, size: float = 16.0) -> tuple[np.ndarray, list, int]:
    """Root (0, 0, size, size); a pair meeting on a splitting line of depth 0..``depth``
    (touching across it, or one box crossing it over the other); fillers make the tree
    split that deep.  Coordinates in units of size / 2**(depth + 2)."""
    unit = size / 2 ** (depth + 2)
    cells = 2 ** (depth + 2)
    level = rng.integers(0, depth + 1)
    line = (2 * rng.integers(0, 2 ** level) + 1) * 2 ** (depth + 1 - level)      # in units
    w, bw = rng.integers(1, min(4, line) + 1), rng.integers(1, min(4, cells - line) + 1)
    h, bh = rng.integers(0, 4, 2)
    y = rng.integers(0, cells - h + 1)
    by = rng.integers(max(0, y - bh), min(cells - bh, y + h) + 1)
    if rng.random() < 0.5:
        pair = [[line - w, y, line, y + h], [line, by, line + bw, by + bh]]
    else:
        a = [line - w, y, line + bw, y + h]
        start = rng.integers(max(0, a[0] - 1), min(cells - 1, a[2]) + 1)
        pair = [a, [start, by, start + 1, by + bh]]
    if rng.random() < 0.5:
        pair = [[p[1], p[0], p[3], p[2]] for p in pair]
    fillers = [[x, y2, x + 1, y2 + 1] for x, y2 in rng.integers(0, cells, (rng.integers(2, 4 * cells), 2))]
    boxes = np.array(pair + fillers, dtype=float)[rng.permutation(len(pair) + len(fillers))] * unit
    return boxes, [0.0, 0.0, size, size], int(rng.integers(1, 3))


def outside_scene(rng: np.random.Generator) -> tuple[np.ndarray, list, int]:
    """Root (0, 0, 8, 8): boxes touching the root's edges from outside, sticking in,
    or lying outside (also both boxes of a pair), with boxes inside."""
    inside = random_aabbs(rng, int(rng.integers(5, 30)), world=7.0, size=1.5, origin=(4.0, 4.0))
    inside = np.clip(inside, 0.0, 8.0)
    outside = []
    for _ in range(rng.integers(1, 6)):
        kind = rng.integers(0, 3)
        y0 = rng.uniform(-1, 8)
        y1 = y0 + rng.uniform(0, 2)
        if kind == 0:     # touches the root's edge x = 0 from outside, and a box on it inside
            outside.append([-rng.uniform(0.1, 2), y0, 0.0, y1])
            outside.append([0.0, y0, rng.uniform(0, 1), y1 + 0.5])
        elif kind == 1:   # sticks in
            outside.append([-rng.uniform(0.1, 3), y0, rng.uniform(0, 6), y1])
        else:             # two overlapping boxes left of the root
            x0 = rng.uniform(-6, -1)
            outside.append([x0, y0, x0 + rng.uniform(0, 1), y1])
            outside.append([x0 + rng.uniform(-1, 0.5), y0 + 0.1, x0 + 0.9, y1 + 1])
    boxes = np.vstack([inside, np.array(outside)])
    boxes[:, [0, 2]] = np.sort(boxes[:, [0, 2]], axis=1)
    turn = rng.integers(0, 4)                  # any side of the root: mirror and swap axes
    if turn & 1:
        boxes = np.column_stack([8 - boxes[:, 2], boxes[:, 1], 8 - boxes[:, 0], boxes[:, 3]])
    if turn & 2:
        boxes = boxes[:, [1, 0, 3, 2]]
    return boxes[rng.permutation(len(boxes))], [0.0, 0.0, 8.0, 8.0], int(rng.integers(1, 4))


@pytest.mark.points(2)
@pytest.mark.visibility("hidden")
@pytest.mark.title("Quadtree: many bodies at one point terminate")
def test_many_at_one_point(student):
    check_algorithm(student)
    # 40 identical boxes: no split can separate them.  Copies of one point: only the
    # depth rule stops the splitting (with bounds None the point is the root's corner,
    # and halving reaches nodes one float wide that keep it).
    cases = [
        ("40 boxes at one point", np.vstack([np.tile([[3.0, 3.0, 3.5, 3.5]], (40, 1)), [[0, 0, 1, 1], [9, 9, 10, 10]]]),
         [0.0, 0.0, 10.0, 10.0], 2),
        ("5 copies of the point (0.3, 0.3)", np.tile([[0.3, 0.3, 0.3, 0.3]], (5, 1)), None, 1),
        ("40 copies of the point (123.456, 123.456)", np.tile([[123.456, 123.456, 123.456, 123.456]], (40, 1)), None, 2),
        ("3 copies of the point (-0.3, -0.3)", np.tile([[-0.3, -0.3, -0.3, -0.3]], (3, 1)), None, 1),
        ("3 copies of the point (1.3, 1.3) and a box", np.vstack([np.tile([[1.3, 1.3, 1.3, 1.3]], (3, 1)),
                                                                 [[1.3, 1.3, 2.3, 2.3]]]), None, 1),
        ("30 copies of the point (2.7, 4.1) in a root (0, 0, 10, 10)",
         np.tile([[2.7, 4.1, 2.7, 4.1]], (30, 1)), [0.0, 0.0, 10.0, 10.0], 1),
    ]
    for label, boxes, bounds, max_bodies in cases:
        answer = call_or_timeout(student, boxes, bounds, max_bodies, label)
        found = wrong_answer(boxes, bounds, max_bodies, answer)
        if found is not None:
            fail(f"{WHO}, {label}: {found[0]}", figure=found[1])


@pytest.mark.points(2)
@pytest.mark.visibility("after_due_date")
@pytest.mark.title("Quadtree: bodies outside the root bounds")
def test_outside_root(student):
    rng = np.random.default_rng(204)
    inside = random_aabbs(rng, 30, world=8.0, origin=(5.0, 5.0))
    outside = np.array([[-3, 4, -0.5, 6], [9.5, 9.5, 12, 12], [4, -2, 6, 0.2], [20, 20, 21, 21]], dtype=float)
    scenes = [(np.vstack([inside, outside]), [0.0, 0.0, 10.0, 10.0], 2)]
    scenes += [outside_scene(rng) for _ in range(30)]
    check_scenes(student, scenes, "bodies outside the root's bounds")


@pytest.mark.points(2)
@pytest.mark.visibility("after_due_date")
@pytest.mark.partial_credit
@pytest.mark.title("Quadtree: hard cases (splitting lines at every depth, negative and far coordinates)")
def test_hard_cases(student):
    rng = np.random.default_rng(205)
    scenes = []
    for depth in (0, 1, 2, 3):
        scenes += [split_line_scene(rng, depth) for _ in range(25)]
    for shift in (-16.0, -1e6, 1e6):           # exact shifts: the lines stay where the boxes meet
        for _ in range(10):
            boxes, bounds, max_bodies = split_line_scene(rng, 2)
            scenes.append((boxes + shift, [b + shift for b in bounds], max_bodies))
    # Bounds None on degenerate data: every box on one vertical line, or one horizontal line.
    for _ in range(5):
        ys = np.sort(rng.integers(0, 20, (8, 2)), axis=1) / 2
        scenes.append((np.column_stack([np.full(8, 1.5), ys[:, 0], np.full(8, 1.5), ys[:, 1]]), None, 1))
        scenes.append((np.column_stack([ys[:, 0], np.full(8, -2.0), ys[:, 1], np.full(8, -2.0)]), None, 2))
    check_scenes(student, scenes, "hard cases")


@pytest.mark.points(1)
@pytest.mark.visibility("after_due_date")
@pytest.mark.title("Quadtree: every stopping rule gives the same pairs")
def test_stopping_rules(student):
    """max_depth 0, 1, 2 and a large min_node_area keep bodies in few, crowded nodes."""
    check_algorithm(student)
    rng = np.random.default_rng(206)
    rules = [(1, 0.0, 0), (1, 0.0, 1), (1, 0.0, 2), (2, 0.0, 3), (1, 50.0, 16), (3, 400.0, 16)]
    cases = []
    for max_bodies, min_area, max_depth in rules:
        for _ in range(4):
            boxes = random_aabbs(rng, 60, world=30.0) if rng.random() < 0.5 else clustered_aabbs(rng, 60)
            bounds = None if rng.random() < 0.5 else [-40.0, -40.0, 40.0, 40.0]
            cases.append((boxes, bounds, max_bodies, min_area, max_depth))
    answers = student.call_many(MODULE, FUNCTION, cases)
    wrong = [case for case, answer in zip(cases, answers) if compare_pairs(answer, overlapping_pairs(case[0]))[0]]
    if not wrong:
        return
    boxes, bounds, *rules = wrong[0]

    def wrong_many(subscenes):
        got = student.call_many(MODULE, FUNCTION, [(sub, bounds, *rules) for sub in subscenes])
        return [compare_pairs(answer, overlapping_pairs(sub))[0] is not None for sub, answer in zip(subscenes, got)]

    small = smallest_wrong_scene(boxes, wrong_many)
    answer = student.call(MODULE, FUNCTION, small, bounds, *rules)
    want = overlapping_pairs(small)
    problem, missed, extra = compare_pairs(answer, want)
    max_bodies, min_area, max_depth = rules
    fail(f"{WHO}: {len(wrong)} of {len(cases)} scenes wrong. Cut down to {len(small)} boxes: "
         f"{FUNCTION}(aabbs={describe_boxes(small)}, bounds={show(bounds)}, max_bodies_per_node={max_bodies}, "
         f"min_node_area={min_area:g}, max_depth={max_depth}) should return {pairs_text(want)}, got {show(answer)}: "
         f"{problem}", figure=pairs_figure(small, missed, extra, f"{FUNCTION}, max_depth {max_depth}, "
                                                                f"min_node_area {min_area:g}", bounds=bounds))


@pytest.mark.points(1)
@pytest.mark.visibility("after_due_date")
def test_structure_large(student):
    """Quadtree: 3 000 bodies, the tree keeps every invariant (it splits, and only when full)"""
    from grader.oracles.quadtree_shape import structure_problem
    from grader.tests.public.test_quadtree import STRUCTURE, structure_call

    rng = np.random.default_rng(207)
    cases = [(random_aabbs(rng, 3000, world=200.0), None, 8, 0.0, 16, "3 000 random boxes"),
             (clustered_aabbs(rng, 2000), None, 4, 0.0, 10, "2 000 clustered boxes, max_depth 10"),
             (random_aabbs(rng, 1000, world=40.0), [-10.0, -10.0, 10.0, 10.0], 6, 0.5, 16,
              "1 000 boxes, many outside the root, min_node_area 0.5")]
    for boxes, bounds, max_bodies, min_area, max_depth, note in cases:
        answer = student.call(MODULE, STRUCTURE, boxes, bounds, max_bodies, min_area, max_depth, timeout=30.0)
        problem = structure_problem(answer, boxes, max_bodies, min_area, max_depth, bounds)
        if problem is not None:
            fail(f"{structure_call(boxes, bounds, max_bodies, min_area, max_depth)} [{note}]: {problem}")
