"""A shrunk example stays in its test's category.

The graded tests draw their cases from one Hypothesis strategy per category ("boxes
touching on cell lines", "boxes at negative coordinates"...), and when a student's
answer is wrong the example shown is the one Hypothesis shrinks to
(:func:`grader.harness.shrink.smallest_failure`).  A message that says "touching on a cell line"
must then show boxes touching on a cell line.  Each strategy is checked here against
its own category, written independently of how it is built: on many drawn examples,
and on the examples the grader's own shrinking returns for several kinds of wrong
answer (the smallest example of all, one with many boxes, one with a touching pair).
"""
from __future__ import annotations

import itertools

import pytest
from hypothesis import HealthCheck, given, settings

from grader.harness.shrink import smallest_failure
from grader.tests.public import test_grid as grid_tests
from grader.tests.public import test_quadtree as quadtree_tests


def meet(a, b) -> bool:
    """The closed boxes a and b share at least a point."""
    return a[0] <= b[2] and b[0] <= a[2] and a[1] <= b[3] and b[1] <= a[3]


def only_touch(a, b) -> bool:
    """a and b meet, and on one axis only at an edge (no overlap of positive width there)."""
    return meet(a, b) and (a[2] == b[0] or b[2] == a[0] or a[3] == b[1] or b[3] == a[1])


def on_lines(value: float, step: float) -> bool:
    return (value / step).is_integer()


def touching_on_cell_lines(example) -> bool:
    boxes, cell = example
    return (all(on_lines(v, cell) for box in boxes for v in box)
            and any(only_touch(a, b) for a, b in itertools.combinations(boxes, 2)))


def at_negative_coordinates(example) -> bool:
    """Boxes at negative coordinates, none of them only touching another."""
    boxes, _ = example
    return (bool(boxes) and all(v < 0 for box in boxes for v in box)
            and not any(only_touch(a, b) and not overlap_area(a, b) for a, b in itertools.combinations(boxes, 2)))


def overlap_area(a, b) -> bool:
    return min(a[2], b[2]) > max(a[0], b[0]) and min(a[3], b[3]) > max(a[1], b[1])


def wide_box_with_a_far_partner(example) -> bool:
    boxes, cell = example
    for a, b in itertools.permutations(boxes, 2):
        for axis in (0, 1):
            length = a[axis + 2] - a[axis]
            apart = abs((a[axis] + a[axis + 2]) - (b[axis] + b[axis + 2])) / 2
            if length >= 2 * cell and apart >= 2 * cell and meet(a, b):
                return True
    return False


def pair_on_a_splitting_line(offset: float):
    lines = [v * quadtree_tests.HALF + offset for v in quadtree_tests.LINES]

    def category(example) -> bool:
        boxes, _, _ = example
        for a, b in itertools.combinations(boxes, 2):
            if not meet(a, b):
                continue
            for box in (a, b):
                for axis in (0, 1):
                    if any(box[axis] <= line <= box[axis + 2] for line in lines):
                        return True
        return False
    return category


def coincident(example) -> bool:
    boxes, _, _ = example
    return any(a == b for a, b in itertools.combinations(boxes, 2))


def a_box_outside_the_root(example) -> bool:
    boxes, bounds, _ = example
    x0, y0, x1, y1 = bounds
    outside = [box for box in boxes if not (x0 <= box[0] and box[2] <= x1 and y0 <= box[1] and box[3] <= y1)]
    return any(meet(a, b) for a in outside for b in boxes if b is not a)


CATEGORIES = {
    "grid: touching on cell lines": (grid_tests.touching_on_cell_lines(), touching_on_cell_lines),
    "grid: touching on cell lines (centre cell)": (grid_tests.touching_on_cell_lines(max_cells=4),
                                                   touching_on_cell_lines),
    "grid: negative coordinates": (grid_tests.negative_cells(), at_negative_coordinates),
    "grid: wide boxes": (grid_tests.wide_boxes(), wide_box_with_a_far_partner),
    "quadtree: on splitting lines": (quadtree_tests.on_split_lines(), pair_on_a_splitting_line(0.0)),
    "quadtree: negative coordinates": (quadtree_tests.on_split_lines(offset=-16.0), pair_on_a_splitting_line(-16.0)),
    "quadtree: coincident boxes": (quadtree_tests.coincident_boxes(), coincident),
    "quadtree: outside the root": (quadtree_tests.outside_bounds(), a_box_outside_the_root),
}


@pytest.mark.parametrize("name", CATEGORIES)
def test_every_drawn_example_is_in_its_category(name):
    strategy, category = CATEGORIES[name]

    @settings(max_examples=300, database=None, derandomize=True, deadline=None,
              suppress_health_check=list(HealthCheck))
    @given(strategy)
    def check(example):
        assert category(example), f"{name}: {example}"

    check()


#: Kinds of wrong answer whose shrunk example is checked: the smallest example of all,
#: one with many boxes, and one holding a pair that only touches.
WRONG_ANSWERS = {
    "any case": lambda example: True,
    "cases with five boxes or more": lambda example: len(example[0]) >= 5,
    "cases with a pair that only touches": lambda example: any(
        only_touch(a, b) for a, b in itertools.combinations(example[0], 2)),
}


@pytest.mark.parametrize("wrong", WRONG_ANSWERS)
@pytest.mark.parametrize("name", CATEGORIES)
def test_the_shrunk_example_stays_in_its_category(name, wrong):
    strategy, category = CATEGORIES[name]
    example = smallest_failure(strategy, WRONG_ANSWERS[wrong])
    if example is None:
        assert wrong != "any case", f"{name}: no example at all"
        return
    assert WRONG_ANSWERS[wrong](example)
    assert category(example), f"{name}, shrunk for {wrong}: {example} is not in the category"
