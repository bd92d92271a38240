"""Uniform grid, both variants of the notes, against brute-force pairs of boxes.

Every test also checks that the function does the work of a grid, not of a brute force
(:mod:`grader.oracles.scaling`: its CPU time per box on sparse scenes must not grow with
N).  Every expected set of pairs comes from :mod:`grader.oracles.brute_force` (the closed
box test, touching counts) or is written here as a literal derived by hand.  Cell
sizes follow a simple rule of this file: a cell as large as the largest box (each box
then overlaps at most 2 x 2 cells), or a half, a quarter or twice that.
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st

from grader.harness.compare import pairs as compare_pairs
from grader.harness.compare import show
from grader.harness.credit import fail
from grader.oracles.brute_force import describe_boxes, overlapping_pairs, pairs_figure, smallest_wrong_scene
from grader.oracles.random_cases import clustered_aabbs, random_aabbs, resting_piles
from grader.oracles.scaling import growth_problem
from grader.harness.outcome import StudentCallFailed, StudentCallStopped

MODULE = "broadphase.uniform_grid"
EVERY_CELL = "pairs_grid_every_cell"
CENTER_CELL = "pairs_grid_center_cell"
#: Cell sizes as multiples of the largest box side (see the module docstring).
CELL_FACTORS = (1.0, 0.5, 0.25, 2.0)
#: Cell sizes of the category tests: powers of two, so that k * cell is exact.
CELLS = st.sampled_from([1.0, 0.5, 2.0, 0.25])
#: What each function must do, in the words of the message when it does the work of a
#: brute force instead (:mod:`grader.oracles.scaling`).
ALGORITHMS = {EVERY_CELL: "a grid (each box stored in the cells it overlaps, only boxes sharing a cell tested)",
              CENTER_CELL: "a grid (each box stored in its centre's cell, only the neighbouring cells searched)"}
#: Cell size (m) of the growth measurement: twice the largest box of its sparse scenes.
GROWTH_CELL = 2.0


def check_algorithm(student, function: str) -> None:
    """Fail every test of ``function`` when it does the work of a brute force (measured
    once a session): right pairs from testing every pair are not the exercise."""
    problem = growth_problem(student, MODULE, function, lambda boxes: (boxes, GROWTH_CELL), ALGORITHMS[function])
    if problem is not None:
        fail(problem)


# Comparing and reporting -----------------------------------------------------------------
def largest_side(aabbs) -> float:
    boxes = np.asarray(aabbs, dtype=float)
    return float(np.max(np.maximum(boxes[:, 2] - boxes[:, 0], boxes[:, 3] - boxes[:, 1])))


def pairs_text(pairs, limit: int = 10) -> str:
    pairs = sorted(pairs)
    text = ", ".join(f"({i}, {j})" for i, j in pairs[:limit])
    return "{" + text + (", ..." if len(pairs) > limit else "") + "}"


def wrong_answer(function: str, boxes, cell: float, answer, want=None, title: str = "") -> tuple[str, dict] | None:
    """None if ``answer`` is the right set of pairs (brute force unless ``want``, pairs
    derived by hand), else (message, figure titled ``title``)."""
    want = overlapping_pairs(boxes) if want is None else set(want)
    problem, missed, extra = compare_pairs(answer, want)
    if problem is None:
        return None
    message = (f"{function}(aabbs={describe_boxes(boxes)}, cell_size={cell:g}) should return the pairs "
               f"{pairs_text(want)} (boxes overlapping or touching, i < j), got {show(answer)}: {problem}")
    return message, pairs_figure(boxes, missed, extra, title or f"{function}, cell size {cell:g} m", cell_size=cell)


def check_scene(student, function: str, boxes, cell: float, label: str) -> None:
    """One scene, all or nothing (the category and @given tests)."""
    check_algorithm(student, function)
    boxes = np.asarray(boxes, dtype=float).reshape(-1, 4)
    found = wrong_answer(function, boxes, cell, student.call(MODULE, function, boxes, cell))
    if found is not None:
        fail(f"{label}: {found[0]}", figure=found[1])


def check_scenes(student, function: str, scenes: list[tuple[np.ndarray, float]], label: str) -> None:
    """Seeded scenes in one round trip; fail with the share of right scenes and a
    failing scene cut down to a few boxes."""
    check_algorithm(student, function)
    answers = student.call_many(MODULE, function, [(boxes, cell) for boxes, cell in scenes])
    wrong = [(boxes, cell, found) for (boxes, cell), answer in zip(scenes, answers)
             if (found := wrong_answer(function, boxes, cell, answer)) is not None]
    if not wrong:
        return
    boxes, cell, first = wrong[0]

    def wrong_many(subscenes):
        got = student.call_many(MODULE, function, [(sub, cell) for sub in subscenes])
        return [wrong_answer(function, sub, cell, answer) is not None for sub, answer in zip(subscenes, got)]

    try:
        small = smallest_wrong_scene(boxes, wrong_many)
        found = wrong_answer(function, small, cell, student.call(MODULE, function, small, cell)) or first
    except (StudentCallFailed, StudentCallStopped):
        found = first
    kept = len(found[1]["aabbs"])
    shown = f"Cut down to {kept} boxes: {found[0]}" if kept < len(boxes) else f"The first: {found[0]}"
    fail(f"{label}: {len(wrong)} of {len(scenes)} scenes wrong ({len(boxes)} boxes, cell size {cell:g} m in the "
         f"first). {shown}",
         fraction=1 - len(wrong) / len(scenes), figure=found[1])


def random_scenes(seed: int, count: int = 20, boxes: int = 60) -> list[tuple[np.ndarray, float]]:
    rng = np.random.default_rng(seed)
    scenes = []
    for k in range(count):
        aabbs = random_aabbs(rng, boxes, world=30.0) if k % 5 else clustered_aabbs(rng, boxes)
        scenes.append((aabbs, largest_side(aabbs) * CELL_FACTORS[k % len(CELL_FACTORS)]))
    return scenes


def pile_scenes(seed: int, count: int = 4, boxes: int = 60) -> list[tuple[np.ndarray, float]]:
    """Resting crates (:func:`~grader.oracles.random_cases.resting_piles`: every box touches
    its neighbours exactly), from the origin and left of and below it."""
    rng = np.random.default_rng(seed)
    scenes = []
    for k in range(count):
        aabbs = resting_piles(rng, boxes, origin=rng.integers(-25, 5, 2))
        scenes.append((aabbs, largest_side(aabbs) * CELL_FACTORS[k % len(CELL_FACTORS)]))
    return scenes


def arranged(draw, boxes: list) -> list:
    """The boxes rotated and maybe reversed: any box can be first or last (cheaper to
    draw than a permutation, and it shrinks to the order the scene was built in)."""
    k = draw(st.integers(0, len(boxes) - 1))
    boxes = boxes[k:] + boxes[:k]
    return boxes[::-1] if draw(st.booleans()) else boxes


# Hypothesis strategies: each generates one category only, so a shrunk example stays in it.
def lattice_box(x0: int, y0: int, w: int, h: int, step: float) -> list[float]:
    return [x0 * step, y0 * step, (x0 + w) * step, (y0 + h) * step]


@st.composite
def touching_on_cell_lines(draw, max_cells: int = 3):
    """(boxes, cell): every edge on a cell line, and at least one pair (A, B) that only
    touches: B starts on the cell line where A ends, along an edge or at a corner.
    Sizes 0 (a segment or a point on the lines) to ``max_cells`` cells."""
    cell = draw(CELLS)
    coord, size = st.integers(-4, 4), st.integers(0, max_cells)
    x0, y0, w, h = draw(coord), draw(coord), draw(size), draw(size)
    bw, bh = draw(size), draw(size)
    axis, sign = draw(st.sampled_from("xy")), draw(st.sampled_from((1, -1)))
    if axis == "x":
        bx = x0 + w if sign > 0 else x0 - bw
        by = draw(st.integers(y0 - bh, y0 + h))          # y ranges meet: an edge or a corner
    else:
        by = y0 + h if sign > 0 else y0 - bh
        bx = draw(st.integers(x0 - bw, x0 + w))
    boxes = [lattice_box(x0, y0, w, h, cell), lattice_box(bx, by, bw, bh, cell)]
    others = draw(st.lists(st.tuples(coord, coord, size, size), max_size=5))
    boxes += [lattice_box(*t, cell) for t in others]
    return arranged(draw, boxes), cell


@st.composite
def negative_cells(draw):
    """(boxes, cell): boxes at negative coordinates only.  Most lie inside one cell (1/8
    to 7/8 of it, so boxes sharing a cell overlap at its centre and boxes in different
    cells are apart); the first cell holds at least two.  Up to two boxes span cells.
    No two boxes only touch."""
    cell = draw(CELLS)
    eighth = cell / 8
    where = draw(st.lists(st.tuples(st.integers(-5, -1), st.integers(-5, -1)), min_size=1, max_size=4, unique=True))
    boxes = []
    for k, (cx, cy) in enumerate(where):
        for _ in range(draw(st.integers(2 if k == 0 else 1, 3))):
            # One draw for the four offsets: min_x, min_y in 1..3 and max_x, max_y in 5..7 eighths.
            code = draw(st.integers(0, 80))
            lo_x, lo_y, hi_x, hi_y = 1 + code % 3, 1 + code // 3 % 3, 5 + code // 9 % 3, 5 + code // 27
            boxes.append([(8 * cx + lo_x) * eighth, (8 * cy + lo_y) * eighth,
                          (8 * cx + hi_x) * eighth, (8 * cy + hi_y) * eighth])
    # Boxes spanning cells, in sixteenths: minima 1 and maxima 3 (mod 4), so no edge of
    # one ever lies on an edge of another (the cell boxes' edges are even sixteenths):
    # this category never holds a pair that only touches (other categories test those).
    sixteenth = cell / 16
    for _ in range(draw(st.integers(0, 2))):
        x0, y0 = draw(st.integers(-20, -1)), draw(st.integers(-20, -1))
        x1, y1 = draw(st.integers(x0, -1)), draw(st.integers(y0, -1))
        boxes.append([(4 * x0 + 1) * sixteenth, (4 * y0 + 1) * sixteenth, (4 * x1 + 3) * sixteenth,
                      (4 * y1 + 3) * sixteenth])
    return arranged(draw, boxes), cell


@st.composite
def wide_boxes(draw):
    """(boxes, cell): a box 2 to 6 cells wide (or tall) with a partner overlapping or
    touching its far end, the partner small or wide too; their centres lie at least two
    cells apart, so the partner's centre cell is outside the 3 x 3 cells around the long
    box's centre cell.  Coordinates in quarter cells."""
    cell = draw(st.sampled_from([1.0, 0.5]))
    q = cell / 4
    x0, y0 = draw(st.integers(-12, 12)), draw(st.integers(-12, 12))
    overlap = draw(st.integers(0, 2))                            # 0: touches the far end
    plength, pthick = draw(st.one_of(st.integers(1, 4), st.integers(8, 24))), draw(st.integers(1, 4))
    # Centres (length - 2 overlap + plength) / 2 quarters apart: at least 8 (two cells).
    length, thick = draw(st.integers(max(8, 16 + 2 * overlap - plength), 24)), draw(st.integers(1, 4))
    start = x0 + length - overlap
    py = draw(st.integers(y0 - pthick, y0 + thick))
    a, b = [x0, y0, x0 + length, y0 + thick], [start, py, start + plength, py + pthick]
    if draw(st.booleans()):                                      # the same along y
        a, b = [a[1], a[0], a[3], a[2]], [b[1], b[0], b[3], b[2]]
    boxes = [[v * q for v in a], [v * q for v in b]]
    for _ in range(draw(st.integers(0, 4))):
        fx, fy, fw, fh = (draw(st.integers(-16, 16)), draw(st.integers(-16, 16)),
                          draw(st.integers(0, 24)), draw(st.integers(0, 4)))
        boxes.append([fx * q, fy * q, (fx + fw) * q, (fy + fh) * q])
    return arranged(draw, boxes), cell


# Special cases, with the pairs derived by hand (index pairs i < j).
NEXT_AFTER_ONE = float(np.nextafter(1.0, 2.0))
SPECIAL_CASES = [
    ("one box", [[0.2, 0.3, 0.7, 0.9]], []),
    ("one box on cell lines", [[1, 1, 2, 2]], []),
    ("two boxes in one cell, apart", [[0.1, 0.1, 0.4, 0.4], [0.5, 0.1, 0.9, 0.4]], []),
    # B starts one float after A ends at x = 1: a gap of 2.2e-16 m.
    ("two boxes apart by the smallest gap across a cell line", [[0, 0, 1, 1], [NEXT_AFTER_ONE, 0, 2, 1]], []),
    ("16 boxes, one per cell, no pairs", [[i + 0.1, j + 0.1, i + 0.9, j + 0.9] for i in range(4) for j in range(4)],
     []),
    ("two boxes touching along a cell line", [[0, 0, 1, 1], [1, 0, 2, 1]], [(0, 1)]),
    ("two boxes touching at a corner on cell lines", [[0, 0, 1, 1], [1, 1, 2, 2]], [(0, 1)]),
    ("three coincident boxes", [[0.25, 0.25, 0.75, 0.75]] * 3, [(0, 1), (0, 2), (1, 2)]),
    ("two coincident points on a cell corner", [[1, 1, 1, 1], [1, 1, 1, 1]], [(0, 1)]),
    # The point (1, 0.5) lies on the shared edge x = 1 of boxes 1 and 2; box 3 is apart.
    ("a point on a cell line between two touching boxes", [[1, 0.5, 1, 0.5], [0, 0, 1, 1], [1, 0, 2, 1],
                                                            [2.5, 2.5, 3, 3]], [(0, 1), (0, 2), (1, 2)]),
    ("a small box inside a large one", [[0, 0, 10, 10], [4, 4, 5, 5]], [(0, 1)]),
    # Cells of 1 m: box 0 is one cell, box 1 touches it at x = 1 and its centre (2, 0.5)
    # lies on the cell line x = 2, two cells from box 0's centre cell.
    ("a box as large as a cell touching one whose centre is on a cell line",
     [[0, 0, 1, 1], [1, 0, 3, 1]], [(0, 1)]),
    # Box 1 touches box 0 along x = -2; the centres (-1, -1) and (-3, 0) lie on cell lines.
    ("boxes at negative coordinates with centres on cell lines", [[-2, -2, 0, 0], [-4, -1, -2, 1]], [(0, 1)]),
    # Cells of 1 m: box 1 spans the cells x = 0 to 2 and touches box 0 (all in cell (0, 0))
    # at x = 0.5; box 1's centre (1.625, 0.5) is in cell (1, 0), which box 0 does not overlap.
    ("a small box at the origin touching one two cells long", [[0, 0, 0.5, 0.5], [0.5, 0.25, 2.75, 0.75]],
     [(0, 1)]),
    # Box 0 is 8 m long: its centre (4, 0.25) is about four cells from box 1's (8.25, 1.125).
    ("a long thin box meeting a small one at its far end", [[0, 0, 8, 0.5], [7.5, 0.25, 9, 2], [3, 3, 4, 4]],
     [(0, 1)]),
    # Box 1 lies inside box 0; box 2 touches box 0 at the corner (0, 0) only.
    ("boxes at negative coordinates", [[-1, -1, 0, 0], [-0.5, -0.5, -0.25, -0.25], [0, 0, 1, 1]], [(0, 1), (0, 2)]),
]
SPECIAL_CELLS = (1.0, 0.5, 3.0)


def check_special_cases(student, function: str) -> None:
    check_algorithm(student, function)
    cases = [(name, np.array(boxes, dtype=float), want, cell)
             for name, boxes, want in SPECIAL_CASES for cell in SPECIAL_CELLS]
    answers = student.call_many(MODULE, function, [(boxes, cell) for _, boxes, _, cell in cases])
    wrong = [(name, found) for (name, boxes, want, cell), answer in zip(cases, answers)
             if (found := wrong_answer(function, boxes, cell, answer, want, f"{function}: {name}")) is not None]
    if wrong:
        name, (message, figure) = wrong[0]
        fail(f"{len(wrong)} of {len(cases)} special cases wrong, e.g. {name}: {message}", figure=figure)


# Insert in every cell -----------------------------------------------------------------------
@pytest.mark.points(3)
@pytest.mark.partial_credit
@pytest.mark.title("Grid, insert in every cell: random boxes and resting crates")
def test_every_cell_random(student):
    check_scenes(student, EVERY_CELL, random_scenes(101) + pile_scenes(104), "random boxes and resting crates")


@pytest.mark.points(1)
@pytest.mark.title("Grid, insert in every cell: boxes touching on cell lines")
def test_every_cell_touching(student):
    # Boxes 0-1 share the edge x = 1, 1-2 the corner (2, 1), 0-3 the corner (0, 0) and
    # 4-5 the corner (5, 5); every edge lies on a cell line for cells of 1 and 0.5 m,
    # also after moving the scene by (-3, -3).
    check_algorithm(student, EVERY_CELL)
    boxes = np.array([[0, 0, 1, 1], [1, 0, 2, 1], [2, 1, 3, 2], [-1, -1, 0, 0], [5, 5, 6, 6], [4, 4, 5, 5]], float)
    want = {(0, 1), (1, 2), (0, 3), (4, 5)}
    scenes = [(shifted, cell) for shifted in (boxes, boxes - 3.0) for cell in (1.0, 0.5)]
    for (shifted, cell), answer in zip(scenes, student.call_many(MODULE, EVERY_CELL, scenes)):
        found = wrong_answer(EVERY_CELL, shifted, cell, answer, want, f"{EVERY_CELL}: touching on cell lines")
        if found is not None:
            fail(found[0], figure=found[1])


@pytest.mark.points(1)
@pytest.mark.title("Grid, insert in every cell: special cases (one box, no pairs, coincident boxes, "
                   "the smallest gap)")
def test_every_cell_special_cases(student):
    check_special_cases(student, EVERY_CELL)


@pytest.mark.points(1)
@pytest.mark.title("Grid, insert in every cell: any boxes on cell lines, some only touching")
@given(scene=touching_on_cell_lines())
def test_every_cell_on_cell_lines(student, scene):
    boxes, cell = scene
    check_scene(student, EVERY_CELL, boxes, cell, "boxes with every edge on a cell line")


@pytest.mark.points(1)
@pytest.mark.title("Grid, insert in every cell: boxes at negative coordinates")
@given(scene=negative_cells())
def test_every_cell_negative_cells(student, scene):
    boxes, cell = scene
    check_scene(student, EVERY_CELL, boxes, cell, "boxes at negative coordinates (x = -0.5 is in cell -1)")


# Centre cell and neighbours -------------------------------------------------------------------
@pytest.mark.points(3)
@pytest.mark.partial_credit
@pytest.mark.title("Grid, centre cell and neighbours: random boxes and resting crates")
def test_center_cell_random(student):
    check_scenes(student, CENTER_CELL, random_scenes(103) + pile_scenes(105), "random boxes and resting crates")


@pytest.mark.points(1)
@pytest.mark.title("Grid, centre cell and neighbours: special cases (one box, no pairs, coincident boxes, "
                   "the smallest gap)")
def test_center_cell_special_cases(student):
    check_special_cases(student, CENTER_CELL)


@pytest.mark.points(1)
@pytest.mark.title("Grid, centre cell and neighbours: boxes on cell lines, centres on cell lines")
@given(scene=touching_on_cell_lines(max_cells=4))
def test_center_cell_on_cell_lines(student, scene):
    boxes, cell = scene
    check_scene(student, CENTER_CELL, boxes, cell, "boxes with every edge on a cell line")


@pytest.mark.points(1)
@pytest.mark.title("Grid, centre cell and neighbours: boxes at negative coordinates")
@given(scene=negative_cells())
def test_center_cell_negative_cells(student, scene):
    boxes, cell = scene
    check_scene(student, CENTER_CELL, boxes, cell, "boxes at negative coordinates (x = -0.5 is in cell -1)")


@pytest.mark.points(1)
@pytest.mark.title("Grid, centre cell and neighbours: boxes several cells long")
# Tried first, every run: a long box below y = 0 whose partner's centre lies in a
# negative cell (where int() and floor() part), touching at a corner.
@example(scene=([[0.0, -2.25, 3.75, -1.25], [3.75, -1.25, 4.0, -0.5]], 1.0))
@given(scene=wide_boxes())
def test_center_cell_wide_boxes(student, scene):
    boxes, cell = scene
    check_scene(student, CENTER_CELL, boxes, cell, "a box several cells long meets a partner at its far end")
