"""The bundled example class: sample submissions with the bugs students make.

``grader example-class --out DIR`` writes one folder per sample, each holding an
``exercises`` package that ``grader grade`` accepts like a student's:

- ``reference/``: the reference engine (a copy of ``solutions/``), full marks;
- ``stubs/``: the generated student package (a copy of ``exercises/``), zero;
- ``bug-<name>/``: the reference with one or two exercise functions rewritten the way a
  student would, with one bug: a classic bug of the course notes (errata 5, 7-12, 22
  of COURSE.md) or a common mistake of every exercise (strict comparisons on touching
  shapes, a missing cell or axis, a flipped sign, a wrong combination rule...).

A buggy sample is data, not a committed package: the reference source plus the buggy
functions below.  The builder finds each function by its qualified name with
:mod:`ast` and swaps its source lines for the buggy text, keeping the original
docstring as a student's file would.  Each sample names the exact set of tests its bug
must fail (``expected_failures``, found by grading the sample and each justified in a
comment); the test suite grades every sample and checks that it loses the points of
those tests and of no others, and that each of those tests loses at least half its
points, as a test must when its failures come from one systematic bug
(:mod:`grader.harness.credit`).  Tests known to lose less are named (``weak_tests``): they are
weak graded tests, reported, not hidden.

Grading every sample with every graded test would take minutes, so a sample is graded
with the tests that reach the functions it rewrites.  Which tests reach which exercise
function is measured, not guessed: the probe (:func:`build_probe`) is the reference
with every exercise function announcing itself, graded once (:func:`grade_probe`).
A test that never reaches a rewritten function runs the very same code on the sample
as on the reference (the same seeded inputs, Hypothesis derandomized, and rewritten
functions that keep no state between calls), so it passes there as on the reference.

``grader example-class --out DIR --grade`` also grades the samples that way and prints
the table of what each loses (``--all-tests``: with every graded test).
"""
from __future__ import annotations

import argparse
import ast
import shutil
import string
import sys
import textwrap
from dataclasses import dataclass
from pathlib import Path
from ..sandbox.process import Sandbox
from ..release.exercises import EXERCISES

REPO_ROOT = Path(__file__).resolve().parent.parent.parent
SOLUTIONS_DIR = REPO_ROOT / "solutions"
EXERCISES_DIR = REPO_ROOT / "exercises"
PACKAGE = "exercises"
#: Written into every sample folder: what the sample is.  Its presence also marks a
#: folder as built here, so that rebuilding may replace it.
ABOUT_FILE = "SAMPLE.md"
REFERENCE_SAMPLE = "reference"
STUBS_SAMPLE = "stubs"
#: Errata of the course notes (the table of COURSE.md); ``BuggySample.erratum`` is one of
#: them, or 0 for a common bug.
ERRATA = 26


class ExampleClassError(ValueError):
    """A buggy sample cannot be built; the message names the sample, module and function."""


@dataclass(frozen=True)
class Replacement:
    """One function of the reference swapped for a student's version.

    Attributes
    ----------
    module : str
        Module path inside the package, dotted: ``"narrowphase.projection"``.
    qualname : str
        The function's qualified name: ``"project_vertices"``, ``"Quadtree.split"``.
    source : str
        The student's function, a complete ``def`` (any indentation).  Without a
        docstring, the original docstring is kept.
    imports : tuple of str
        Import lines the student added at the top of the module.
    """

    module: str
    qualname: str
    source: str
    imports: tuple[str, ...] = ()


@dataclass(frozen=True)
class BuggySample:
    """A sample submission: the reference with one bug a student would make.

    Attributes
    ----------
    name : str
        Folder ``bug-<name>``.
    mistake : str
        What the student did wrong, in one sentence.
    erratum : int
        Number of the erratum of the course notes (COURSE.md, 1 to :data:`ERRATA`)
        behind the bug, or 0 for a common bug that is not an erratum of the notes.
    replacements : tuple of Replacement
        The rewritten functions: exercise functions, which hold a solution block.
    expected_failures : frozenset of str
        Exactly the tests this bug fails; every other test passes.  Each of them loses
        at least half its points (all of them unless the test gives partial credit).
    weak_tests : frozenset of str
        Expected failures that lose less than half their points although the failures
        come from this one systematic bug: weak graded tests, each named with its score
        in a comment, kept here so that they are reported rather than hidden.  The test
        suite checks that they still lose some points and still less than half (a test
        made stronger must leave this set).
    status : str
        Outcome status of those tests (``"failed"``: wrong answers, no exception).
    """

    name: str
    mistake: str
    erratum: int
    replacements: tuple[Replacement, ...]
    expected_failures: frozenset[str]
    weak_tests: frozenset[str] = frozenset()
    status: str = "failed"

    @property
    def folder_name(self) -> str:
        return f"bug-{self.name}"

    @property
    def exercise(self) -> str:
        """The exercise (``grader check`` name) of the rewritten functions, from the
        generator's table; several, joined by "+", if they belong to several."""
        return "+".join(dict.fromkeys(exercise_of(r.module, r.qualname) for r in self.replacements))


def exercise_of(module: str, qualname: str) -> str:
    """The exercise a function of the package belongs to (``"?"`` if none).

    Examples
    --------
    >>> exercise_of("narrowphase.polygon_polygon", "reference_face_manifold")
    'contacts'
    """
    entry = EXERCISES.get(module.replace(".", "/") + ".py", "?")
    return entry if isinstance(entry, str) else entry.get(qualname.split(".")[-1], "?")


# --------------------------------------------------------------------------- samples

# momentum (1D collisions) -------------------------------------------------------------

ELASTIC_SWAPPED_MASSES = BuggySample(
    name="elastic-swapped-masses",
    mistake="elastic_collision_1d writes the textbook formula with the masses of the first term swapped: "
            "v1' = ((m2 - m1) v1 + 2 m2 v2) / (m1 + m2), and the same for v2'.",
    erratum=0,
    replacements=(Replacement("response.momentum_1d", "elastic_collision_1d", '''
        def elastic_collision_1d(m1: float, v1: float, m2: float, v2: float) -> tuple[float, float]:
            total = m1 + m2
            v1_after = ((m2 - m1) * v1 + 2 * m2 * v2) / total
            v2_after = ((m1 - m2) * v2 + 2 * m1 * v1) / total
            return v1_after, v2_after
        '''),),
    expected_failures=frozenset({
        # Worked example 2 and 20 random pairs of unequal masses: every case is wrong
        # (only equal masses, which the test never draws, come out right).
        "momentum.elastic",
        # The rewritten function no longer validates its inputs: a mass of 0 gives
        # numbers instead of ValueError.
        "momentum.rejects_bad_input",
        # Not failed: momentum.restitution and momentum.perfectly_inelastic call
        # collision_1d and perfectly_inelastic_1d, the reference's.
    }),
)

RESTITUTION_SIGN = BuggySample(
    name="restitution-sign",
    mistake="collision_1d solves momentum together with v2' - v1' = +e (v2 - v1), losing the minus sign of "
            "the restitution law, so the bodies keep approaching after the impact (right only for e = 0).",
    erratum=0,
    replacements=(Replacement("response.momentum_1d", "collision_1d", '''
        def collision_1d(m1: float, v1: float, m2: float, v2: float, restitution: float) -> tuple[float, float]:
            w1, v1, w2, v2 = _checked_pair(m1, v1, m2, v2)
            e = _checked_restitution(restitution)
            # momentum: v1' / w1 + v2' / w2 = v1 / w1 + v2 / w2; restitution: v2' - v1' = e (v2 - v1)
            v1_after = (w2 * v1 + w1 * v2 - w1 * e * (v2 - v1)) / (w1 + w2)
            v2_after = v1_after + e * (v2 - v1)
            return v1_after, v2_after
        '''),),
    expected_failures=frozenset({
        # Every case with e > 0 is wrong (21 of 22; e = 0 is right).
        "momentum.restitution",
        # elastic_collision_1d is collision_1d with e = 1: the bodies pass through
        # each other instead of bouncing (worked example 2 gives +10, not -10).
        "momentum.elastic",
        # Against a wall too: the ball goes on into the wall (3 of 4 cases; e = 0 is right).
        "momentum.wall",
    }),
)

# grid (uniform grid broad phase) ------------------------------------------------------

GRID_OWN_CELL = BuggySample(
    name="grid-own-cell",
    mistake="pairs_grid_center_cell stores each body in the cell of its centre and then tests it only "
            "against the bodies of that same cell, never the neighbouring cells.",
    erratum=5,
    replacements=(Replacement("broadphase.uniform_grid", "pairs_grid_center_cell", '''
        def pairs_grid_center_cell(aabbs, cell_size: float) -> set[tuple[int, int]]:
            boxes = np.asarray(aabbs, dtype=float).tolist()
            bodies_in_cell = defaultdict(list)
            for i, box in enumerate(boxes):
                centre_x = (box[MIN_X] + box[MAX_X]) / 2
                centre_y = (box[MIN_Y] + box[MAX_Y]) / 2
                bodies_in_cell[cell_index(centre_x, centre_y, cell_size)].append(i)
            pairs = set()
            for members in bodies_in_cell.values():
                for position, i in enumerate(members):
                    for j in members[position + 1:]:
                        if aabbs_overlap(boxes[i], boxes[j]):
                            pairs.add((i, j))
            return pairs
        '''),),
    expected_failures=frozenset({
        # Every centre-cell test has overlapping or touching boxes whose centres lie in
        # neighbouring cells (erratum 5): random and clustered scenes, boxes larger than
        # a cell or several cells long, touching across cell lines (also the special
        # cases and the hard-case batch), boxes in neighbouring negative cells.
        "grid.center_cell_random",
        "grid.center_cell_clustered",
        "grid.center_cell_large_bodies",
        "grid.center_cell_wide_boxes",
        "grid.center_cell_on_cell_lines",
        "grid.center_cell_special_cases",
        "grid.center_cell_negative_cells",
        "grid.center_cell_hard_cases",
        # Not failed: the every-cell tests and grid.speed (pairs_grid_every_cell is the
        # reference's).
    }),
)

GRID_STRICT_TOUCHING = BuggySample(
    name="grid-strict-touching",
    mistake="pairs_grid_every_cell tests the candidates of a cell with its own strict comparisons "
            "(min < other max), so boxes that only touch are not a pair.",
    erratum=0,
    replacements=(Replacement("broadphase.uniform_grid", "pairs_grid_every_cell", '''
        def pairs_grid_every_cell(aabbs, cell_size: float) -> set[tuple[int, int]]:
            boxes = np.asarray(aabbs, dtype=float).tolist()
            bodies_in_cell = defaultdict(list)
            for i, box in enumerate(boxes):
                lo, hi = covered_cells(box, cell_size)
                for cx in range(lo[0], hi[0] + 1):
                    for cy in range(lo[1], hi[1] + 1):
                        bodies_in_cell[cx, cy].append(i)
            pairs = set()
            for members in bodies_in_cell.values():
                for a, i in enumerate(members):
                    for j in members[a + 1:]:
                        p, q = boxes[i], boxes[j]
                        if p[MIN_X] < q[MAX_X] and q[MIN_X] < p[MAX_X] and p[MIN_Y] < q[MAX_Y] and q[MIN_Y] < p[MAX_Y]:
                            pairs.add((i, j))
            return pairs
        '''),),
    expected_failures=frozenset({
        # Boxes touching along a cell line or at a corner (the hand-made scene, the
        # special cases, the category of boxes on cell lines, the lattice scenes of the
        # hard-case batch, 105 of 150 wrong) are never paired.
        "grid.every_cell_touching",
        "grid.every_cell_special_cases",
        "grid.every_cell_on_cell_lines",
        "grid.every_cell_hard_cases",
        # The resting crates among the random scenes (4 of 24 scenes wrong).
        "grid.every_cell_random",
        # Not failed: the negative-cells category (its boxes never touch exactly).
    }),
)

GRID_MISSING_LAST_CELL = BuggySample(
    name="grid-missing-last-cell",
    mistake="pairs_grid_every_cell loops over range(lo, hi) instead of range(lo, hi + 1): each box misses "
            "the last row and column of its cells, and a box inside one cell is stored nowhere.",
    erratum=0,
    replacements=(Replacement("broadphase.uniform_grid", "pairs_grid_every_cell", '''
        def pairs_grid_every_cell(aabbs, cell_size: float) -> set[tuple[int, int]]:
            boxes = np.asarray(aabbs, dtype=float).tolist()
            bodies_in_cell = defaultdict(list)
            for i, box in enumerate(boxes):
                lo, hi = covered_cells(box, cell_size)
                for cx in range(lo[0], hi[0]):
                    for cy in range(lo[1], hi[1]):
                        bodies_in_cell[cx, cy].append(i)
            pairs = set()
            for members in bodies_in_cell.values():
                for a, i in enumerate(members):
                    for j in members[a + 1:]:
                        if aabbs_overlap(boxes[i], boxes[j]):
                            pairs.add((i, j))
            return pairs
        '''),),
    expected_failures=frozenset({
        # A box inside one cell is stored nowhere, so almost every pair is lost: every
        # every-cell test fails, grid.speed too (it checks the 3000-box answer).
        "grid.every_cell_random",
        "grid.every_cell_touching",
        "grid.every_cell_special_cases",
        "grid.every_cell_on_cell_lines",
        "grid.every_cell_negative_cells",
        "grid.every_cell_negative_coordinates",
        "grid.every_cell_hard_cases",
        "grid.speed",
    }),
)

GRID_INT_CENTRE_CELL = BuggySample(
    name="grid-int-centre-cell",
    mistake="pairs_grid_center_cell files each body under int(centre / cell_size), which rounds towards 0, "
            "but searches the cells covered_cells gives (floor): left of or below the origin a centre lands "
            "one cell off, outside the searched window.",
    erratum=0,
    replacements=(Replacement("broadphase.uniform_grid", "pairs_grid_center_cell", '''
        def pairs_grid_center_cell(aabbs, cell_size: float) -> set[tuple[int, int]]:
            boxes = np.asarray(aabbs, dtype=float).tolist()
            bodies_by_centre_cell = defaultdict(list)
            reach_x = reach_y = 0
            for j, box in enumerate(boxes):
                lo, hi = covered_cells(box, cell_size)
                reach_x = max(reach_x, hi[0] - lo[0])
                reach_y = max(reach_y, hi[1] - lo[1])
                centre_x = (box[MIN_X] + box[MAX_X]) / 2
                centre_y = (box[MIN_Y] + box[MAX_Y]) / 2
                bodies_by_centre_cell[int(centre_x / cell_size), int(centre_y / cell_size)].append(j)
            pairs = set()
            for i, box in enumerate(boxes):
                lo, hi = covered_cells(box, cell_size)
                x_range = range(lo[0] - reach_x, hi[0] + reach_x + 1)
                y_range = range(lo[1] - reach_y, hi[1] + reach_y + 1)
                if len(x_range) * len(y_range) <= len(bodies_by_centre_cell):
                    cells = [(cx, cy) for cx in x_range for cy in y_range]
                else:
                    cells = [c for c in bodies_by_centre_cell if c[0] in x_range and c[1] in y_range]
                for cell in cells:
                    for j in bodies_by_centre_cell.get(cell, ()):
                        if j > i and aabbs_overlap(box, boxes[j]):
                            pairs.add((i, j))
            return pairs
        '''),),
    expected_failures=frozenset({
        # Boxes inside one negative cell (no box crossing a cell line, so the search
        # window is the boxes' own cells): a centre at x = -0.5 is filed in cell 0.
        "grid.center_cell_negative_cells",
        # Its negative scenes: 25 of 150 wrong.
        "grid.center_cell_hard_cases",
        # Random boxes around the origin (2 of 20 scenes wrong) and resting crates left
        # of and below it.
        "grid.center_cell_random",
        # A long box below y = 0 and a partner whose centre lies at y = -0.875: filed in
        # cell 0, one row above the window searched for the long box.
        "grid.center_cell_wide_boxes",
        # Not failed: scenes where a body crosses a cell line widen the window by one
        # cell, which covers the off-by-one.
    }),
)

GRID_CENTER_3X3 = BuggySample(
    name="grid-center-3x3",
    mistake="pairs_grid_center_cell searches only the 3 x 3 cells around a body's own centre cell, which "
            "is enough only when no body is larger than a cell.",
    erratum=0,
    replacements=(Replacement("broadphase.uniform_grid", "pairs_grid_center_cell", '''
        def pairs_grid_center_cell(aabbs, cell_size: float) -> set[tuple[int, int]]:
            boxes = np.asarray(aabbs, dtype=float).tolist()
            centre_cells = []
            bodies_by_centre_cell = defaultdict(list)
            for j, box in enumerate(boxes):
                cell = cell_index((box[MIN_X] + box[MAX_X]) / 2, (box[MIN_Y] + box[MAX_Y]) / 2, cell_size)
                centre_cells.append(cell)
                bodies_by_centre_cell[cell].append(j)
            pairs = set()
            for i, (cx, cy) in enumerate(centre_cells):
                for dx in (-1, 0, 1):
                    for dy in (-1, 0, 1):
                        for j in bodies_by_centre_cell.get((cx + dx, cy + dy), ()):
                            if j > i and aabbs_overlap(boxes[i], boxes[j]):
                                pairs.add((i, j))
            return pairs
        '''),),
    expected_failures=frozenset({
        # Bodies larger than a cell (cell sizes of a half or a quarter of the largest
        # box in the random scenes, clustered scenes with small cells, boxes several
        # cells long, lattice boxes up to four cells, a box spanning negative cells)
        # meet partners whose centres are more than one cell away.
        "grid.center_cell_random",
        "grid.center_cell_clustered",
        "grid.center_cell_large_bodies",
        "grid.center_cell_wide_boxes",
        "grid.center_cell_on_cell_lines",
        "grid.center_cell_special_cases",
        "grid.center_cell_negative_cells",
        "grid.center_cell_hard_cases",
    }),
)

# quadtree -----------------------------------------------------------------------------

QUADTREE_DROPS_STRADDLING = BuggySample(
    name="quadtree-drops-straddling",
    mistake="Quadtree.split moves every body that fits in a quarter down and then empties the node, so "
            "bodies lying across a splitting line are lost instead of staying at the inner node.",
    erratum=5,
    replacements=(Replacement("broadphase.quadtree", "Quadtree.split", '''
        def split(self, leaf: QuadtreeNode) -> None:
            to_split = [leaf]
            while to_split:
                node = to_split.pop()
                node.children = [QuadtreeNode(bounds, node.depth + 1) for bounds in node.quarter_bounds()]
                for index in node.bodies:
                    child = self.child_holding(node, self.boxes[index])
                    if child is not None:
                        child.bodies.append(index)
                node.bodies = []   # the bodies now live in the quarters
                to_split.extend(child for child in node.children if self.stopping_rule(child) is None)
        '''),),
    expected_failures=frozenset({
        # Every quadtree test has bodies on or across the splitting lines of a node that
        # splits (the random scenes, the hand-made straddling scene, the special cases,
        # boxes on lines at every depth, copies of one point at the corner of the root,
        # bodies outside the root, which fit no child): they vanish with their pairs.
        "quadtree.random",
        "quadtree.straddling",
        "quadtree.special_cases",
        "quadtree.on_split_lines",
        "quadtree.coincident",
        "quadtree.outside_bounds",
        "quadtree.negative_coordinates",
        "quadtree.many_at_one_point",
        "quadtree.outside_root",
        "quadtree.hard_cases",
        "quadtree.stopping_rules",
        # The trees it builds lose bodies: "bodies [0, 1] are not stored in any node".
        "quadtree.structure",
        "quadtree.structure_large",
    }),
)

QUADTREE_STRADDLER_IN_ONE_CHILD = BuggySample(
    name="quadtree-straddler-in-one-child",
    mistake="Quadtree.child_holding picks the quarter holding the box's centre, so a body across a splitting "
            "line goes down into one child and never meets the bodies on the other side.",
    erratum=5,
    replacements=(Replacement("broadphase.quadtree", "Quadtree.child_holding", '''
        def child_holding(self, node: QuadtreeNode, box) -> QuadtreeNode | None:
            mid_x, mid_y = node.split_point()
            centre_x = (box[MIN_X] + box[MAX_X]) / 2
            centre_y = (box[MIN_Y] + box[MAX_Y]) / 2
            east = 1 if centre_x >= mid_x else 0
            north = 1 if centre_y >= mid_y else 0
            return node.children[2 * north + east]
        '''),),
    expected_failures=frozenset({
        # Every pair test has a body across (or on) a splitting line overlapping a body
        # on the other side, or a body sticking out of the root, which now goes down
        # too: those pairs are in sibling subtrees and never tested.
        "quadtree.random",
        "quadtree.straddling",
        "quadtree.special_cases",
        "quadtree.on_split_lines",
        "quadtree.coincident",
        "quadtree.outside_bounds",
        "quadtree.negative_coordinates",
        "quadtree.many_at_one_point",
        "quadtree.outside_root",
        "quadtree.hard_cases",
        "quadtree.stopping_rules",
        # The trees it builds hold bodies in nodes they do not fit in.
        "quadtree.structure",
        "quadtree.structure_large",
    }),
)

QUADTREE_NO_DESCENDANTS = BuggySample(
    name="quadtree-no-descendants",
    mistake="Quadtree.pairs tests each body only against the other bodies of its own node, never against "
            "the bodies stored below it, as if bodies only collided inside one group.",
    erratum=5,
    replacements=(Replacement("broadphase.quadtree", "Quadtree.pairs", '''
        def pairs(self) -> set[tuple[int, int]]:
            pairs = set()
            for node in self.nodes():
                for position, i in enumerate(node.bodies):
                    for j in node.bodies[position + 1:]:
                        if aabbs_overlap(self.boxes[i], self.boxes[j]):
                            pairs.add((min(i, j), max(i, j)))
            return pairs
        '''),),
    expected_failures=frozenset({
        # Every pair test has a body left at an inner node (across a splitting line,
        # outside the root, or a box whose corner is the point its copies share) that
        # overlaps a body stored below it (erratum 5).
        "quadtree.random",
        "quadtree.straddling",
        "quadtree.special_cases",
        "quadtree.on_split_lines",
        "quadtree.coincident",
        "quadtree.outside_bounds",
        "quadtree.negative_coordinates",
        "quadtree.many_at_one_point",
        "quadtree.outside_root",
        "quadtree.hard_cases",
        "quadtree.stopping_rules",
        # Not failed: quadtree.structure and structure_large (the tree is built right;
        # only pairs() is wrong).
    }),
)

QUADTREE_ON_SPLIT_LINE = BuggySample(
    name="quadtree-on-split-line",
    mistake="Quadtree.child_holding compares with <= and >=, so a box that only touches a splitting line goes "
            "down into the child on its side, and two boxes touching across the line never meet.",
    erratum=0,
    replacements=(Replacement("broadphase.quadtree", "Quadtree.child_holding", '''
        def child_holding(self, node: QuadtreeNode, box) -> QuadtreeNode | None:
            mid_x, mid_y = node.split_point()
            if box[MAX_X] <= mid_x:
                east = 0
            elif box[MIN_X] >= mid_x:
                east = 1
            else:
                return None
            if box[MAX_Y] <= mid_y:
                north = 0
            elif box[MIN_Y] >= mid_y:
                north = 1
            else:
                return None
            child = node.children[2 * north + east]
            return child if box_inside(box, child.bounds) else None
        '''),),
    expected_failures=frozenset({
        # Boxes touching across a splitting line: the special cases (touching along the
        # root's line and at its centre), the categories of boxes on the root's lines
        # (also moved left of the origin, and the half-metre boxes of the outside-root
        # category, which touch on deeper lines), lines at every depth (112 of 140).
        "quadtree.special_cases",
        "quadtree.on_split_lines",
        "quadtree.negative_coordinates",
        "quadtree.outside_bounds",
        "quadtree.hard_cases",
        # A box on the root's splitting line is stored in a quarter: "a box touching or
        # crossing a splitting line has no child, it must stay at that node".
        "quadtree.structure",
        # The resting crates among the random scenes, touching on the root's lines.
        "quadtree.random",
        # Not failed: straddling scenes (no box ends exactly on a line), coincident points,
        # bodies outside the root in the seeded scenes.
    }),
)

# dynamic tree -------------------------------------------------------------------------

SIBLING_ALWAYS_ROOT = BuggySample(
    name="dynamic-tree-sibling-always-root",
    mistake="DynamicTree.best_sibling returns the root, the one candidate that is always possible, so every new "
            "leaf hangs beside the whole tree and only the rotations give the tree a shape.",
    erratum=0,
    replacements=(Replacement("broadphase.dynamic_tree", "DynamicTree.best_sibling", '''
        def best_sibling(self, box) -> TreeNode:
            return self.root
        '''),),
    expected_failures=frozenset({
        # The root is rarely the least-cost node of a random tree.
        "dynamic_tree.best_sibling",
        "dynamic_tree.best_sibling_large",
        # Its trees cost 9 times a median-split tree's (at most 1.5 allowed).
        "dynamic_tree.quality",
        "dynamic_tree.quality_sorted",
        # Their large boxes make each body's search enter most of the tree: pairs reads
        # about 190 node boxes per body and level on 1000 sparse boxes (at most 12).
        "dynamic_tree.random",
        "dynamic_tree.large_random",
        "dynamic_tree.degenerate_scenes",
        # Not failed: the pairs, structures and moves of small scenes are right (the tree
        # is valid, only badly shaped).  A best_sibling that leaves out what the ancestors
        # grow by is a subtler bug, but its trees cost within 7 % of the reference's and only
        # best_sibling and best_sibling_large see it: 3 of best_sibling's 22 points (every
        # test reaches it through insert_leaf), under half, so it is not a sample.
    }),
)

INSERT_WITHOUT_REFIT = BuggySample(
    name="dynamic-tree-insert-no-refit",
    mistake="DynamicTree.insert_leaf gives the new parent its box and height but never walks up to the root: "
            "the ancestors keep boxes that do not hold the new leaf, so a search that skips a box missing it "
            "never finds the leaf.",
    erratum=0,
    replacements=(Replacement("broadphase.dynamic_tree", "DynamicTree.insert_leaf", '''
        def insert_leaf(self, leaf: TreeNode) -> None:
            if self.root is None:
                self.root = leaf
                leaf.parent = None
                return
            sibling = self.best_sibling(leaf.box)
            old_parent = sibling.parent
            parent = TreeNode(union(sibling.box, leaf.box), child1=sibling, child2=leaf, height=sibling.height + 1)
            if old_parent is None:
                self.root = parent
            else:
                old_parent.replace_child(sibling, parent)
            sibling.parent = leaf.parent = parent
        '''),),
    expected_failures=frozenset({
        # The ancestors' boxes miss the leaves inserted below them: "an inner node's box should
        # be the smallest box holding its children's", and pairs whose later body lies outside
        # a stale box are missed in every scene of more than a few boxes.
        "dynamic_tree.structure",
        "dynamic_tree.structure_large",
        "dynamic_tree.random",
        "dynamic_tree.large_random",
        "dynamic_tree.degenerate_scenes",
        "dynamic_tree.moving",
        "dynamic_tree.long_moving",
        # Not failed: best_sibling and its read counts (a least-cost node of the tree as it
        # is), the quality tests (the stale boxes are smaller: the cost comes out lower), the
        # special cases (at most five boxes).
    }),
)

REMOVE_SIBLING_KEEPS_OLD_PARENT = BuggySample(
    name="dynamic-tree-remove-keeps-old-parent",
    mistake="DynamicTree.remove_leaf puts the sibling in the removed parent's place as the grandparent's child, "
            "but the sibling still names the removed parent as its parent, so the walks up from below it (the "
            "next insertion there, refits, rotations) end in a node that is no longer in the tree.",
    erratum=0,
    replacements=(Replacement("broadphase.dynamic_tree", "DynamicTree.remove_leaf", '''
        def remove_leaf(self, leaf: TreeNode) -> None:
            if leaf is self.root:
                self.root = None
                return
            parent = leaf.parent
            sibling = leaf.sibling()
            grandparent = parent.parent
            leaf.parent = None
            if grandparent is None:
                self.root = sibling
                return
            if grandparent.child1 is parent:
                grandparent.child1 = sibling
            else:
                grandparent.child2 = sibling
            node = grandparent
            while node is not None:
                node = self.balance(node)
                self.refit(node)
                node = node.parent
        '''),),
    expected_failures=frozenset({
        # The trees after removals: "node 1 has parent -1", the sibling's parent is a node no
        # longer in the tree.
        "dynamic_tree.structure",
        "dynamic_tree.structure_large",
        # A reinsertion removes a leaf first; later insertions and rotations beside the
        # orphaned sibling work on the removed node, and pairs below it are missed.
        "dynamic_tree.moving",
        "dynamic_tree.long_moving",
        # Not failed: every test that only inserts (pairs, best_sibling, quality).
    }),
)

MOVE_REINSERTS_EVERY_FRAME = BuggySample(
    name="dynamic-tree-move-every-frame",
    mistake="DynamicTree.move reinserts a body whenever its box changed, ignoring the fat box: the margin saves "
            "no work and every moving body is reinserted every frame.",
    erratum=0,
    replacements=(Replacement("broadphase.dynamic_tree", "DynamicTree.move", '''
        def move(self, body: int, box) -> bool:
            tight = tuple(float(v) for v in box)
            leaf = self.leaves[body]
            if tight == self.tight[body]:
                return False
            self.tight[body] = tight
            self.remove_leaf(leaf)
            leaf.box = fattened(tight, self.margin)
            self.insert_leaf(leaf)
            return True
        '''),),
    expected_failures=frozenset({
        # Every drifting body is reinserted: "move should reinsert exactly the bodies whose
        # tight box left their fat box ... but reinserted [0, 1, 2, ...]".
        "dynamic_tree.moving",
        "dynamic_tree.long_moving",
        # Moved inside their fat boxes, the bodies get new fat boxes, not the ones they kept.
        "dynamic_tree.structure",
        "dynamic_tree.structure_large",
        # Not failed: every test without moves.
    }),
)

MOVE_NEVER_REINSERTS = BuggySample(
    name="dynamic-tree-move-never",
    mistake="DynamicTree.move records the new tight box but never reinserts the leaf: its fat box stays where "
            "the body was inserted, and a body that left it is searched for in the wrong place.",
    erratum=0,
    replacements=(Replacement("broadphase.dynamic_tree", "DynamicTree.move", '''
        def move(self, body: int, box) -> bool:
            self.tight[body] = tuple(float(v) for v in box)
            return False
        '''),),
    expected_failures=frozenset({
        # A body that jumped (5 % a frame) or drifted out of its fat box is searched for where
        # it was: its pairs are missed, and the list of reinserted bodies is empty.
        "dynamic_tree.moving",
        "dynamic_tree.long_moving",
        # Moved out of their fat boxes: "the fat box ... does not hold its tight box".
        "dynamic_tree.structure",
        "dynamic_tree.structure_large",
        # Not failed: every test without moves.
    }),
)

#: DynamicTree.pairs as a student writes it, with three places to change: HELPER (a
#: line of its own, for a function the student defines first), OVERLAP (the box test, a
#: function of two boxes) and KEEP (which partner j of body i to report).
TREE_PAIRS = '''
    def pairs(self) -> set[tuple[int, int]]:
        HELPER
        pairs = set()
        if self.root is None:
            return pairs
        for i, box in self.tight.items():
            stack = [self.root]
            while stack:
                node = stack.pop()
                if not OVERLAP(box, node.box):
                    continue
                if node.is_leaf:
                    j = node.body
                    if KEEP and OVERLAP(box, self.tight[j]):
                        pairs.add((i, j))
                else:
                    stack.append(node.child1)
                    stack.append(node.child2)
        return pairs
    '''


def tree_pairs(overlap: str = "aabbs_overlap", keep: str = "i < j", helper: str = "") -> tuple[Replacement, ...]:
    """DynamicTree.pairs rewritten: the reference's, with the three places given."""
    helper = textwrap.indent(textwrap.dedent(helper).strip(), " " * 8) + "\n\n" if helper.strip() else ""
    source = TREE_PAIRS.replace("        HELPER\n", helper)
    return (Replacement("broadphase.dynamic_tree", "DynamicTree.pairs",
                        source.replace("OVERLAP", overlap).replace("KEEP", keep)),)


TREE_PAIRS_STRICT_TOUCHING = BuggySample(
    name="dynamic-tree-strict-touching",
    mistake="DynamicTree.pairs tests boxes with strict comparisons (< instead of <=), so two bodies whose tight "
            "boxes only touch are not a pair.",
    erratum=0,
    replacements=tree_pairs(overlap="overlap", helper="""
        def overlap(a, b):
            return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]
        """),
    expected_failures=frozenset({
        # Boxes touching along an edge or at a corner, zero-size boxes at one point or on an
        # edge; the degenerate scenes: copies of one point, boxes on one line, unit boxes on
        # integer corners.
        "dynamic_tree.special_cases",
        "dynamic_tree.degenerate_scenes",
        # The resting crates among the random scenes (4 of 22; 2 of 8 hidden), all touching.
        "dynamic_tree.random",
        "dynamic_tree.large_random",
        # Not failed: the moving scenes (no two boxes there end exactly on one line).
    }),
)

TREE_PAIRS_BOTH_ORDERS = BuggySample(
    name="dynamic-tree-pairs-both-orders",
    mistake="DynamicTree.pairs keeps every partner j != i of each body i, so each pair is reported twice, as "
            "(i, j) and as (j, i).",
    erratum=0,
    replacements=tree_pairs(keep="j != i"),
    expected_failures=frozenset({
        # Every scene with a pair: "each pair must be written (i, j) with i < j, found (1, 0)".
        "dynamic_tree.special_cases",
        "dynamic_tree.random",
        "dynamic_tree.large_random",
        "dynamic_tree.degenerate_scenes",
        "dynamic_tree.moving",
        "dynamic_tree.long_moving",
        # Not failed: the tree tests (structure, best_sibling, quality), which list no pairs.
    }),
)

# sat (separating axis tests) ----------------------------------------------------------

FLT_MIN = BuggySample(
    name="flt-min",
    mistake="project_vertices starts the running maximum at FLT_MIN (sys.float_info.min), the smallest "
            "positive float, instead of -infinity, so an interval lying left of the origin ends at 0.",
    erratum=7,
    replacements=(Replacement("narrowphase.projection", "project_vertices", '''
        def project_vertices(vertices, axis) -> tuple[float, float]:
            lowest = sys.float_info.max     # FLT_MAX
            highest = sys.float_info.min    # FLT_MIN, as in the notes
            for vertex in np.asarray(vertices, dtype=float).reshape(-1, 2):
                along = float(vertex[0] * axis[0] + vertex[1] * axis[1])
                if along < lowest:
                    lowest = along
                if along > highest:
                    highest = along
            return lowest, highest
        ''', imports=("import sys",)),),
    expected_failures=frozenset({
        # Half of its polygons lie where every projection is negative (23 of 49 wrong).
        "sat.project_vertices",
        # Boxes at x = -5 and -2: both intervals stretch to 0 and overlap (erratum 7).
        "sat.obb_negative_coordinates",
        # The categories of shapes left of the origin (polygons_overlap, obbs_overlap,
        # far_from_origin), and pairs whose projections on a turned axis are all
        # negative (the one-side category, the random pairs).
        "sat.polygons_overlap_random",
        "sat.obbs_overlap_random",
        "sat.far_from_origin",
        "sat.one_side_separates",
        # circle_polygon_overlap projects the box with project_vertices: a box whose
        # projection on its own turned axis is negative grows to 0 and meets a circle
        # it does not touch (1 of 49 pairs; the test gives no partial credit).
        "sat.circle_polygon_opposite_sides",
        # 4 of its 185 circle-box pairs are wrong, all in one category (boxes far left
        # of the origin): the worst category's share gives 1.5 of 3 points.
        "sat.circle_polygon_random",
        # 176 of 2160 pairs wrong, concentrated in polygons_overlap and obbs_overlap:
        # scored by the worst function's share, no points.
        "sat.random_against_reference",
    }),
)

NO_RESET = BuggySample(
    name="no-reset",
    mistake="polygons_overlap sets the min/max of both shapes once, before the loop over the axes, so every "
            "axis compares the union of the intervals of all axes so far.",
    erratum=8,
    replacements=(Replacement("narrowphase.polygon_polygon", "polygons_overlap", '''
        def polygons_overlap(a: AABB | OBB | ConvexPolygon, b: AABB | OBB | ConvexPolygon) -> bool:
            vertices_a = polygon_vertices(a)
            vertices_b = polygon_vertices(b)
            min_a, max_a = np.inf, -np.inf
            min_b, max_b = np.inf, -np.inf
            for axis in [*separating_axis_candidates(a), *separating_axis_candidates(b)]:
                for vertex in vertices_a:
                    along = float(vertex @ axis)
                    min_a = min(min_a, along)
                    max_a = max(max_a, along)
                for vertex in vertices_b:
                    along = float(vertex @ axis)
                    min_b = min(min_b, along)
                    max_b = max(max_b, along)
                if max_a < min_b or max_b < min_a:
                    return False
            return True
        '''),),
    expected_failures=frozenset({
        # The notes' 8 259 wrong pairs out of 20 000: random pairs apart on a later axis
        # look overlapping because the earlier axes' intervals leak in (112 of 293).
        "sat.polygons_overlap_random",
        # Its third pair is apart along y only; y is tested after x, whose interval
        # [-4.5, -3.5] is added to both y intervals ([-5, -3] and [-2, 0]).
        "sat.obb_negative_coordinates",
        # Pairs apart along a later axis: shapes far from the origin (whose intervals
        # on x and y are far apart), pairs only B's normals separate, random pairs
        # (260 of 2160 wrong, 88 %).
        "sat.far_from_origin",
        "sat.one_side_separates",
        "sat.random_against_reference",
        # Not failed: obbs_overlap and circle_polygon_overlap are the reference's.
    }),
)

ABS_PROJECTION = BuggySample(
    name="abs-projection",
    mistake="circle_polygon_overlap projects the circle's centre with abs(Dot(c, axis)), folding it onto the "
            "positive side of the origin.",
    erratum=10,
    replacements=(Replacement("narrowphase.circle_polygon", "circle_polygon_overlap", '''
        def circle_polygon_overlap(circle: Circle, polygon: Polygonal) -> bool:
            vertices = polygon_vertices(polygon)
            axes = list(separating_axis_candidates(polygon))
            offsets = vertices - circle.center
            nearest_vertex = vertices[int(np.argmin(np.einsum("kd,kd->k", offsets, offsets)))]
            vertex_axis = normalize(nearest_vertex - circle.center)
            if vertex_axis is not None:
                axes.append(vertex_axis)
            for axis in axes:
                centre = abs(float(np.dot(circle.center, axis)))
                polygon_min, polygon_max = project_vertices(vertices, axis)
                if centre + circle.radius < polygon_min or centre - circle.radius > polygon_max:
                    return False
            return True
        '''),),
    expected_failures=frozenset({
        # Box x in [8, 12] against a circle at (-10, 0): folded to +10, it overlaps (erratum 10).
        "sat.circle_polygon_opposite_sides",
        # Any centre with a negative projection is mirrored, which turns separated
        # pairs into overlapping ones and back: random circles around the origin (79
        # of 185), circles off a corner, circles far left of the origin, a point on a
        # box's edge.
        "sat.circle_polygon_random",
        "sat.circle_off_corner",
        "sat.far_from_origin",
        "sat.degenerate_shapes",
        # 200 of 2160 pairs wrong; scored by the worst function's share: no points.
        "sat.random_against_reference",
    }),
)

DIAMETER = BuggySample(
    name="diameter",
    mistake="The circle is projected as centre +- diameter, and two circles are said to meet when their "
            "centres are closer than the sum of the diameters.",
    erratum=9,
    replacements=(
        Replacement("narrowphase.projection", "project_circle", '''
            def project_circle(center, radius: float, axis) -> tuple[float, float]:
                along = float(center[0]) * float(axis[0]) + float(center[1]) * float(axis[1])
                diameter = 2.0 * radius
                return along - diameter, along + diameter
            '''),
        Replacement("narrowphase.circle_circle", "circles_overlap", '''
            def circles_overlap(a: Circle, b: Circle) -> bool:
                dx = float(b.center[0] - a.center[0])
                dy = float(b.center[1] - a.center[1])
                reach = 2.0 * a.radius + 2.0 * b.radius
                return dx * dx + dy * dy <= reach * reach
            '''),
    ),
    expected_failures=frozenset({
        # The interval is twice too wide (erratum 9).
        "sat.project_circle",
        # Circles of radius 1 at distance 2.5 are said to overlap (35 of 94 wrong).
        "sat.circles_overlap",
        # Circles 2-30 % of a radius off a box are reported as overlapping: random
        # pairs (66 of 185), circles off a corner, left of the origin, the circle at
        # (-6.5, -6.5) off a box at (-5, -5), a point 1 m from a circle of radius 1.2.
        "sat.circle_polygon_random",
        "sat.circle_off_corner",
        "sat.far_from_origin",
        "sat.circle_polygon_opposite_sides",
        "sat.degenerate_shapes",
        "sat.random_against_reference",
        # Not failed: the contact tests (collide_* compute the depth with the radius
        # themselves).
    }),
)

UNNORMALISED_AXIS = BuggySample(
    name="unnormalised-axis",
    mistake="circle_polygon_overlap uses the centre-to-nearest-vertex axis without normalising it, so the "
            "centre's projection is scaled by the axis length but the radius is not.",
    erratum=11,
    replacements=(Replacement("narrowphase.circle_polygon", "circle_polygon_overlap", '''
        def circle_polygon_overlap(circle: Circle, polygon: Polygonal) -> bool:
            vertices = polygon_vertices(polygon)
            axes = list(separating_axis_candidates(polygon))
            offsets = vertices - circle.center
            nearest_vertex = vertices[int(np.argmin(np.einsum("kd,kd->k", offsets, offsets)))]
            axes.append(nearest_vertex - circle.center)
            for axis in axes:
                circle_interval = project_circle(circle.center, circle.radius, axis)
                if not intervals_overlap(circle_interval, project_vertices(vertices, axis)):
                    return False
            return True
        '''),),
    expected_failures=frozenset({
        # Circles just off a corner are separated by the vertex axis only; on the
        # unnormalised axis the radius is too short or too long compared with the gap.
        "sat.circle_off_corner",
        # One circle overlapping a corner by less than the error (no partial credit).
        "sat.circle_polygon_opposite_sides",
        # 16 of 185 pairs wrong, all circles off a corner: that category's share
        # gives no points.
        "sat.circle_polygon_random",
        # 23 of 2160 pairs wrong, 98.9 % right, spread over the circle-polygon
        # function's random pairs: 0.97 of 2 points (a failed test keeps at most half).
        "sat.random_against_reference",
    }),
)

SAT_ONLY_A_AXES = BuggySample(
    name="sat-only-a-axes",
    mistake="polygons_overlap tests the edge normals of A only, so pairs that only B's normals separate "
            "(a corner of A next to a face of B) are reported as overlapping.",
    erratum=0,
    replacements=(Replacement("narrowphase.polygon_polygon", "polygons_overlap", '''
        def polygons_overlap(a: AABB | OBB | ConvexPolygon, b: AABB | OBB | ConvexPolygon) -> bool:
            vertices_a = polygon_vertices(a)
            vertices_b = polygon_vertices(b)
            for axis in separating_axis_candidates(a):
                if not intervals_overlap(project_vertices(vertices_a, axis), project_vertices(vertices_b, axis)):
                    return False
            return True
        '''),),
    expected_failures=frozenset({
        # Pairs only B's normals separate: the one-side category (all or nothing), and
        # its 50 pairs in the random batch (47 of 293 wrong, 84 %), its pairs left of
        # the origin, boxes far from the origin, random pairs.
        "sat.one_side_separates",
        "sat.polygons_overlap_random",
        "sat.obb_negative_coordinates",
        "sat.far_from_origin",
        # Its pairs in the random batch against the reference (20 per kind and
        # offset): that function's share of right pairs is below 90 %, no points.
        "sat.random_against_reference",
        # Not failed: the obbs_overlap tests (obbs_overlap is the reference's).
    }),
)

SAT_EDGE_DIRECTIONS = BuggySample(
    name="sat-edge-directions",
    mistake="polygons_overlap projects on the edge directions instead of the edge normals; for boxes these "
            "are the normals of the next edges, so only polygons other than rectangles go wrong.",
    erratum=0,
    replacements=(Replacement("narrowphase.polygon_polygon", "polygons_overlap", '''
        def polygons_overlap(a: AABB | OBB | ConvexPolygon, b: AABB | OBB | ConvexPolygon) -> bool:
            vertices_a = polygon_vertices(a)
            vertices_b = polygon_vertices(b)
            axes = []
            for vertices in (vertices_a, vertices_b):
                for k in range(len(vertices)):
                    edge = vertices[(k + 1) % len(vertices)] - vertices[k]
                    length = float(np.hypot(edge[0], edge[1]))
                    if length > 0.0:
                        axes.append(edge / length)
            for axis in axes:
                if not intervals_overlap(project_vertices(vertices_a, axis), project_vertices(vertices_b, axis)):
                    return False
            return True
        '''),),
    expected_failures=frozenset({
        # Its polygons just apart, which only a face normal separates (36 of 293 wrong).
        "sat.polygons_overlap_random",
        # Its pairs in the random batch against the reference (20 per kind and
        # offset): that function's share of right pairs is below 90 %, no points.
        "sat.random_against_reference",
        # Not failed: every other polygons_overlap test uses boxes only, whose edge
        # directions are their normals.
    }),
)

CIRCLE_NO_VERTEX_AXIS = BuggySample(
    name="circle-no-vertex-axis",
    mistake="circle_polygon_overlap tests the polygon's edge normals only, without the axis from the centre "
            "to the nearest vertex, so circles just off a corner are reported as overlapping.",
    erratum=0,
    replacements=(Replacement("narrowphase.circle_polygon", "circle_polygon_overlap", '''
        def circle_polygon_overlap(circle: Circle, polygon: Polygonal) -> bool:
            vertices = polygon_vertices(polygon)
            for axis in separating_axis_candidates(polygon):
                circle_interval = project_circle(circle.center, circle.radius, axis)
                if not intervals_overlap(circle_interval, project_vertices(vertices, axis)):
                    return False
            return True
        '''),),
    expected_failures=frozenset({
        # Circles off a corner, apart: only the vertex axis separates them (the
        # category test, and 31 of the 185 random pairs).
        "sat.circle_off_corner",
        "sat.circle_polygon_random",
        # Its pairs in the random batch against the reference (20 per kind and
        # offset): that function's share of right pairs is below 90 %, no points.
        "sat.random_against_reference",
    }),
)

INTERVALS_STRICT = BuggySample(
    name="intervals-strict",
    mistake="intervals_overlap compares with strict < (a_min < b_max and b_min < a_max), so intervals that "
            "share an end point do not overlap and touching shapes are reported apart.",
    erratum=0,
    replacements=(Replacement("narrowphase.projection", "intervals_overlap", '''
        def intervals_overlap(a, b) -> bool:
            a_min, a_max = a
            b_min, b_max = b
            return bool(a_min < b_max and b_min < a_max)
        '''),),
    expected_failures=frozenset({
        # Intervals sharing an end point (7 of 19 pairs).
        "sat.intervals_overlap",
        # Every SAT test with shapes built to touch exactly: boxes, polygons, circles
        # against boxes, boxes left of the origin, a point on a box's edge.
        "sat.polygons_overlap_random",
        "sat.obbs_overlap_random",
        "sat.circle_polygon_random",
        "sat.obb_negative_coordinates",
        "sat.degenerate_shapes",
        # Not failed: circles_overlap and aabbs_overlap do not use intervals_overlap;
        # the category tests and random pairs hold no exact touching.
    }),
)

# contacts (normal, depth, points) -----------------------------------------------------

NORMAL_NOT_FLIPPED = BuggySample(
    name="normal-not-flipped",
    mistake="collide_polygon_polygon returns the reference face's normal as it is, also when the reference "
            "face belongs to B: the normal then points from B to A.",
    erratum=0,
    replacements=(Replacement("narrowphase.polygon_polygon", "collide_polygon_polygon", '''
        def collide_polygon_polygon(a: AABB | OBB | ConvexPolygon, b: AABB | OBB | ConvexPolygon) -> Contact | None:
            polygon_a, polygon_b = polygon_faces(a), polygon_faces(b)
            candidates = reference_face_candidates(polygon_a, polygon_b)
            if not candidates:
                return None
            scale = tolerance_scale(polygon_a[0], polygon_b[0])
            for ref_name, separation, face, (ref_vertices, ref_normals, ref_faces), incident in candidates:
                ref_normal = ref_normals[int(np.flatnonzero(ref_faces == face)[0])]
                points, depths, ids = reference_face_manifold(ref_vertices, ref_normal, face, *incident, ref_name,
                                                              scale)
                if max(depths, default=-np.inf) >= -separation - KEEP_POINT_TOL * scale:
                    break
            depth = -separation
            if not points:
                k = int(np.argmin(incident[0] @ ref_normal))
                points, depths, ids = [incident[0][k] + 0.5 * depth * ref_normal], [depth], [(ref_name, face, k, k)]
            return Contact(ref_normal, max(depth, *depths), np.array(points), np.array(depths), tuple(ids))
        '''),),
    expected_failures=frozenset({
        # Pairs where B's face is clearly the least penetrated (39 of 141 random boxes
        # and polygons, 182 of 1398 random pairs of every kind).
        "contacts.polygon_polygon",
        "contacts.random_against_reference",
        # The hand-worked pairs whose reference face is B's: the 2 % rule when A's side
        # planes cut off B's deepest vertex, and the pair A's manifold misses entirely.
        "contacts.reference_face_rules",
        "contacts.reference_face_edge_cases",
        # The feature-id pair whose reference face is B's (the steep box): its normal is wrong.
        "contacts.feature_ids",
        # Not failed: the face-to-face tests, whose reference face is A's.
    }),
)

AABB_DEPTH_MAX = BuggySample(
    name="aabb-depth-max",
    mistake="collide_aabb_aabb takes the face of A with the largest penetration instead of the smallest, so "
            "the depth is the longest way out and the normal points along it.",
    erratum=0,
    replacements=(Replacement("narrowphase.aabb_aabb", "collide_aabb_aabb", '''
        def collide_aabb_aabb(a: AABB, b: AABB) -> Contact | None:
            (a_x0, a_y0), (a_x1, a_y1) = a.min_corner.tolist(), a.max_corner.tolist()
            (b_x0, b_y0), (b_x1, b_y1) = b.min_corner.tolist(), b.max_corner.tolist()
            penetrations = [b_y1 - a_y0, a_x1 - b_x0, a_y1 - b_y0, b_x1 - a_x0]
            face = max(range(4), key=penetrations.__getitem__)   # the deepest overlap
            depth = penetrations[face]
            if min(penetrations) < 0.0:
                return None
            normal_along_y = face in (0, 2)
            if normal_along_y:
                level = (a_y0 + b_y1) / 2 if face == 0 else (a_y1 + b_y0) / 2
                a_lo, a_hi, b_lo, b_hi = a_x0, a_x1, b_x0, b_x1
            else:
                level = (a_x1 + b_x0) / 2 if face == 1 else (a_x0 + b_x1) / 2
                a_lo, a_hi, b_lo, b_hi = a_y0, a_y1, b_y0, b_y1
            incident = (face + 2) % 4
            next_is_high = face in (0, 1)
            ends = []
            for b_vertex, at_high in ((incident, next_is_high), ((incident + 1) % 4, not next_is_high)):
                along = min(a_hi, b_hi) if at_high else max(a_lo, b_lo)
                ends.append((along, ("A", face, incident, b_vertex)))
            if ends[0][0] == ends[1][0]:
                ends = ends[:1]
            points = [(along, level) if normal_along_y else (level, along) for along, _ in ends]
            return Contact(FACE_NORMALS[face], depth, points, [depth] * len(points), tuple(f for _, f in ends))
        '''),),
    expected_failures=frozenset({
        # Every overlapping pair (and pairs apart on one axis but deep on another).
        "contacts.aabb_contacts",
        "contacts.aabb_aabb",
        # The hand-worked feature-id pairs: the deepest face, so normal, points and ids are wrong.
        "contacts.feature_ids",
    }),
)

ONE_POINT_MANIFOLD = BuggySample(
    name="one-point-manifold",
    mistake="reference_face_manifold keeps only the deepest clipped point, so boxes face to face get one "
            "contact point instead of two (the notes: the choice of point is 'not critical').",
    erratum=12,
    replacements=(Replacement("narrowphase.polygon_polygon", "reference_face_manifold", '''
        def reference_face_manifold(ref_vertices: np.ndarray, ref_normal: np.ndarray, ref_face: int,
                                    inc_vertices: np.ndarray, inc_normals: np.ndarray, inc_faces: np.ndarray,
                                    ref_name: str, scale: float, margin: float = 0.0) -> tuple[list, list, list]:
            n = ref_normal
            tangent = np.array([-n[1], n[0]])
            v1, v2 = ref_vertices[ref_face], ref_vertices[(ref_face + 1) % len(ref_vertices)]
            j = incident_face(inc_normals, inc_faces, n)
            j2 = (j + 1) % len(inc_vertices)
            segment = [(inc_vertices[j], (ref_name, ref_face, j, j)),
                       (inc_vertices[j2], (ref_name, ref_face, j, j2))]
            roundoff = KEEP_POINT_TOL * scale
            segment = clip_segment_to_half_plane(segment, tangent, float(tangent @ v2), roundoff)
            segment = clip_segment_to_half_plane(segment, -tangent, float(-tangent @ v1), roundoff)
            best = None
            for point, feature in segment:
                separation = float(n @ (point - v1))
                if separation <= margin + roundoff and (best is None or separation < best[0]):
                    best = (separation, point, feature)
            if best is None:
                return [], [], []
            separation, point, feature = best   # one contact point: the deepest
            return [point - 0.5 * separation * n], [-separation], [feature]
        '''),),
    expected_failures=frozenset({
        # Boxes face to face (erratum 12), in the hand-made cases, the category and the
        # random batches (90 of 141, 347 of 1398), and a box on a segment.
        "contacts.face_face",
        "contacts.face_face_boxes",
        "contacts.polygon_polygon",
        "contacts.random_against_reference",
        "contacts.degenerate_shapes",
        # reference_face_manifold called directly (a crate face to face with the floor),
        # and the hand-worked pairs with two points (a tilted box's face on a box's corners,
        # a crate on a very wide ground).
        "contacts.reference_face_manifold",
        "contacts.reference_face_rules",
        "contacts.reference_face_edge_cases",
        # The same with a margin (a crate hovering above the floor keeps one corner), and the
        # crate landing in the soft step, which then rests on one corner.
        "contacts.reference_face_manifold_margin",
        "contacts.landing_crate",
        # The feature-id pairs of polygons face to face get one point (and one id) instead of two.
        "contacts.feature_ids",
    }),
)

CONTACT_POINT_ON_POLYGON = BuggySample(
    name="contact-point-on-polygon",
    mistake="collide_circle_polygon reports the polygon's point closest to the centre as the contact point, "
            "instead of the midpoint between it and the circle's deepest point.",
    erratum=0,
    replacements=(Replacement("narrowphase.circle_polygon", "collide_circle_polygon", '''
        def collide_circle_polygon(circle: Circle, polygon: Polygonal) -> Contact | None:
            vertices, normals, faces = polygon_faces(polygon)
            center, radius = circle.center, circle.radius
            count = len(vertices)
            center_separations = np.einsum("kd,kd->k", center - vertices[faces], normals)
            best = int(np.argmax(center_separations))
            if center_separations[best] <= 0.0:
                outward = normals[best]
                on_polygon = center - center_separations[best] * outward
                depth = radius - float(center_separations[best])
                feature = ("face", int(faces[best]))
            else:
                closest_distance, on_polygon, outward, feature = np.inf, None, None, None
                facing = center_separations >= 0.0
                for face, face_normal in zip(faces[facing], normals[facing]):
                    start, end = vertices[face], vertices[(face + 1) % count]
                    edge = end - start
                    length2 = float(edge @ edge)
                    along = 0.0 if length2 == 0.0 else min(max(float((center - start) @ edge) / length2, 0.0), 1.0)
                    point = start + along * edge
                    distance = float(np.hypot(*(center - point)))
                    if distance < closest_distance:
                        closest_distance, on_polygon = distance, point
                        if 0.0 < along < 1.0:
                            outward, feature = face_normal, ("face", int(face))
                        else:
                            vertex = int(face) if along == 0.0 else (int(face) + 1) % count
                            direction = normalize(center - point)
                            outward = face_normal if direction is None else direction
                            feature = ("vertex", vertex)
                if closest_distance > radius:
                    return None
                depth = radius - closest_distance
            return Contact(0.0 - outward, depth, [on_polygon], feature_ids=(feature,))   # the point on the polygon
        '''),),
    expected_failures=frozenset({
        # Every circle-polygon contact of positive depth: the random batch (110 of 140),
        # centres inside a box, the random pairs, a point inside a box.
        "contacts.circle_polygon",
        "contacts.centre_inside",
        "contacts.random_against_reference",
        "contacts.degenerate_shapes",
        # The hand-worked circle-and-box pairs of the feature-id test: their points are wrong.
        "contacts.feature_ids",
    }),
)

# impulse (collision response) ---------------------------------------------------------

SEPARATE_IMPULSES = BuggySample(
    name="separate-impulses",
    mistake="resolve_collision computes one impulse for A with A's mass and inertia only, then 'repeats the "
            "computation for B' with B's terms only, instead of one impulse with r = r_A + r_B.",
    erratum=22,
    replacements=(Replacement("response.impulse", "resolve_collision", '''
        def resolve_collision(body_a: Body, body_b: Body, contact: Contact,
                              restitution: float | None = None,
                              friction: float | None = None) -> tuple[np.ndarray, np.ndarray]:
            e = body_a.restitution * body_b.restitution if restitution is None else restitution
            mu = body_a.friction * body_b.friction if friction is None else friction
            n = np.asarray(contact.normal, dtype=float)
            tangent = np.array([n[1], -n[0]])
            points = contact.points
            normal_impulses = np.zeros(len(points))
            tangent_impulses = np.zeros(len(points))
            for i, point in enumerate(points):
                v_n = relative_normal_velocity(body_a, body_b, point, n)
                if v_n >= 0.0:
                    continue
                # The impulse for A as if B could not move, then the same for B.
                for body, sign in ((body_a, -1.0), (body_b, 1.0)):
                    if body.is_static:
                        continue
                    rn = float(cross(point - body.position, n))
                    j = -(1.0 + e) * v_n / (body.inverse_mass + body.inverse_inertia * rn * rn)
                    body.velocity = body.velocity + sign * body.inverse_mass * j * n
                    body.angular_velocity += sign * body.inverse_inertia * rn * j
                    normal_impulses[i] = j
            for i, point in enumerate(points):
                k_t = effective_mass_inverse(body_a, body_b, point, tangent)
                if normal_impulses[i] <= 0.0 or mu == 0.0 or k_t == 0.0:
                    continue
                v_t = relative_normal_velocity(body_a, body_b, point, tangent)
                limit = mu * normal_impulses[i]
                tangent_impulses[i] = float(np.clip(-v_t / k_t, -limit, limit))
                apply_impulse(body_a, body_b, point, tangent_impulses[i] * tangent)
            return normal_impulses, tangent_impulses
        '''),),
    expected_failures=frozenset({
        # Pairs of dynamic bodies leave with velocities unlike sympy's (20 of 39).
        "impulse.resolve_collision",
        "impulse.resolve_any_case",
        # Two different impulses: momentum is not conserved, energy grows (erratum 22).
        "impulse.resolve_conserves_momentum",
        # Ball-ball contacts of the scene go wrong (ball-wall ones are right: a static
        # body adds nothing to r), so the balls end far from the reference.
        "impulse.scene",
        # Not failed: the building blocks it calls (magnitude, apply_impulse...) are the
        # reference's.
    }),
)

NORMAL_B_TO_A = BuggySample(
    name="normal-b-to-a",
    mistake="relative_normal_velocity takes the normal as pointing from B to A: v_n = (v_A(p) - v_B(p)) . n, "
            "so approaching contacts look separating and the other way round.",
    erratum=0,
    replacements=(Replacement("response.impulse", "relative_normal_velocity", '''
        def relative_normal_velocity(body_a: Body, body_b: Body, point, normal) -> float:
            n = _unit_normal(normal)
            return float((body_a.velocity_at(point) - body_b.velocity_at(point)) @ n)
        '''),),
    expected_failures=frozenset({
        # v_n has the wrong sign in every case but v_n = 0.
        "impulse.relative_normal_velocity",
        "impulse.closed_forms_any_case",
        # Approaching contacts get j = 0, separating ones an impulse.
        "impulse.magnitude",
        "impulse.resolve_collision",
        "impulse.resolve_any_case",
        "impulse.scene",
        # Its contacts all approach, so this resolver does nothing: momentum is kept,
        # but a contact closing in must be pushed.
        "impulse.resolve_conserves_momentum",
        # The hand-worked landings get no impulse, the separating ones one (10 of 19).
        "impulse.limits",
    }),
)

IMPULSE_ON_SEPARATING = BuggySample(
    name="impulse-on-separating",
    mistake="normal_impulse_magnitude returns -(1 + e) v_n / k also for a separating contact (v_n > 0): a "
            "negative impulse that pulls the bodies together.",
    erratum=0,
    replacements=(Replacement("response.impulse", "normal_impulse_magnitude", '''
        def normal_impulse_magnitude(body_a: Body, body_b: Body, point, normal, restitution: float) -> float:
            e = _checked_coefficient("restitution", restitution, 1.0)
            normal_velocity = relative_normal_velocity(body_a, body_b, point, normal)
            k = effective_mass_inverse(body_a, body_b, point, normal)
            if k == 0.0:
                return 0.0
            return -(1.0 + e) * normal_velocity / k
        '''),),
    expected_failures=frozenset({
        # Separating contacts get a negative j (8 of 34, and Hypothesis draws one).
        "impulse.magnitude",
        "impulse.closed_forms_any_case",
        # Not failed: resolve_collision solves its own impulses (it does not call
        # normal_impulse_magnitude).
    }),
)

NO_ANGULAR_MASS = BuggySample(
    name="no-angular-mass",
    mistake="effective_mass_inverse keeps only the linear terms 1/m_A + 1/m_B and drops (r x n)^2 / I, as if "
            "every contact pushed through both centres of mass.",
    erratum=0,
    replacements=(Replacement("response.impulse", "effective_mass_inverse", '''
        def effective_mass_inverse(body_a: Body, body_b: Body, point, normal) -> float:
            _unit_normal(normal)
            return float(body_a.inverse_mass + body_b.inverse_mass)
        '''),),
    expected_failures=frozenset({
        # Every contact point off the line of centres (18 of 29).
        "impulse.effective_mass",
        "impulse.closed_forms_any_case",
        "impulse.magnitude",
        # resolve_collision computes k_t for friction with effective_mass_inverse: the
        # friction impulses of turning bodies are wrong, in the scene too.
        "impulse.resolve_collision",
        "impulse.resolve_any_case",
        "impulse.scene",
        # The rolling disc with mu = inf: k_t = 1 instead of 3 (2 of 19).
        "impulse.limits",
    }),
)

RESTITUTION_MAX = BuggySample(
    name="restitution-max",
    mistake="resolve_collision combines the bodies' restitutions with max(e_A, e_B) instead of the course's "
            "product e_A e_B (friction is still the product).",
    erratum=0,
    replacements=(Replacement("response.impulse", "resolve_collision", '''
        def resolve_collision(body_a: Body, body_b: Body, contact: Contact,
                              restitution: float | None = None,
                              friction: float | None = None) -> tuple[np.ndarray, np.ndarray]:
            e = max(body_a.restitution, body_b.restitution) if restitution is None else restitution
            mu = body_a.friction * body_b.friction if friction is None else friction
            e = _checked_coefficient("restitution", e, 1.0)
            mu = _checked_coefficient("friction", mu, np.inf)
            n = _unit_normal(contact.normal)
            tangent = np.array([n[1], -n[0]])
            points = contact.points
            rn_a = cross(points - body_a.position, n)
            rn_b = cross(points - body_b.position, n)
            unit_response = (body_a.inverse_mass + body_b.inverse_mass
                             + body_a.inverse_inertia * np.outer(rn_a, rn_a)
                             + body_b.inverse_inertia * np.outer(rn_b, rn_b))
            normal_velocity = np.array([relative_normal_velocity(body_a, body_b, p, n) for p in points])
            target = np.where(normal_velocity < 0.0, -e * normal_velocity, 0.0)
            normal_impulses = solve_small_lcp(unit_response, target - normal_velocity)
            for point, j in zip(points, normal_impulses):
                if j > 0.0:
                    apply_impulse(body_a, body_b, point, j * n)
            tangent_impulses = np.zeros(len(points))
            for i, (point, j) in enumerate(zip(points, normal_impulses)):
                k_t = effective_mass_inverse(body_a, body_b, point, tangent)
                if j <= 0.0 or mu == 0.0 or k_t == 0.0:
                    continue
                tangent_velocity = relative_normal_velocity(body_a, body_b, point, tangent)
                tangent_impulses[i] = float(np.clip(-tangent_velocity / k_t, -mu * j, mu * j))
                apply_impulse(body_a, body_b, point, tangent_impulses[i] * tangent)
            return normal_impulses, tangent_impulses
        '''),),
    expected_failures=frozenset({
        # Every case with default materials and two different restitutions.
        "impulse.resolve_collision",
        "impulse.resolve_any_case",
        # The balls (e = 0.5) bounce off the walls (e = 1) with e = 1.
        "impulse.scene",
        # Not failed: the conservation test (any e <= 1 keeps momentum and energy).
    }),
)

IMPULSE_TO_BOTH = BuggySample(
    name="impulse-to-both",
    mistake="apply_impulse adds +P to both bodies instead of +P to B and -P to A, so A is pushed into B.",
    erratum=0,
    replacements=(Replacement("response.impulse", "apply_impulse", '''
        def apply_impulse(body_a: Body, body_b: Body, point, impulse_vector) -> None:
            impulse_vector = np.asarray(impulse_vector, dtype=float).reshape(2)
            point = np.asarray(point, dtype=float)
            for body in (body_a, body_b):
                if body.is_static:
                    continue
                body.velocity = body.velocity + body.inverse_mass * impulse_vector
                body.angular_velocity += float(body.inverse_inertia * cross(point - body.position, impulse_vector))
        '''),),
    expected_failures=frozenset({
        "impulse.apply_impulse",
        # Everything applying an impulse: momentum is not conserved, the scene explodes.
        "impulse.resolve_collision",
        "impulse.resolve_any_case",
        "impulse.resolve_conserves_momentum",
        "impulse.scene",
        # The box landing on static ground B: A, the dynamic one, is pushed down (1 of 19).
        "impulse.limits",
    }),
)

CORRECTION_NO_SLOP = BuggySample(
    name="correction-no-slop",
    mistake="correct_positions removes percent of the whole depth, ignoring the slop that should be left.",
    erratum=0,
    replacements=(Replacement("response.positional_correction", "correct_positions", '''
        def correct_positions(body_a: Body, body_b: Body, normal, depth: float,
                              percent: float = 0.8, slop: float = 0.01) -> tuple[np.ndarray, np.ndarray]:
            normal = np.asarray(normal, dtype=float).reshape(2)
            inverse_mass_sum = body_a.inverse_mass + body_b.inverse_mass
            if inverse_mass_sum == 0.0 or depth <= 0.0:
                return np.zeros(2), np.zeros(2)
            correction = percent * depth / inverse_mass_sum * normal
            displacement_a = -body_a.inverse_mass * correction
            displacement_b = body_b.inverse_mass * correction
            if not body_a.is_static:
                body_a.position = body_a.position + displacement_a
            if not body_b.is_static:
                body_b.position = body_b.position + displacement_b
            return displacement_a, displacement_b
        '''),),
    expected_failures=frozenset({
        # Every case with a slop > 0 and a depth beyond it (13 of 19).
        "impulse.correct_positions",
        "impulse.correct_positions_any_case",
        # The scene corrects with slop 0.01 m.
        "impulse.scene",
        # Every correction case with a slop > 0 (5 of 19).
        "impulse.limits",
    }),
)

FRICTION_CLAMP_SIGN = BuggySample(
    name="friction-clamp-sign",
    mistake="resolve_collision clamps a too large friction impulse to +mu j whatever its sign, so a body "
            "sliding one way is pushed along instead of braked.",
    erratum=0,
    replacements=(Replacement("response.impulse", "resolve_collision", '''
        def resolve_collision(body_a: Body, body_b: Body, contact: Contact,
                              restitution: float | None = None,
                              friction: float | None = None) -> tuple[np.ndarray, np.ndarray]:
            e = body_a.restitution * body_b.restitution if restitution is None else restitution
            mu = body_a.friction * body_b.friction if friction is None else friction
            e = _checked_coefficient("restitution", e, 1.0)
            mu = _checked_coefficient("friction", mu, np.inf)
            n = _unit_normal(contact.normal)
            tangent = np.array([n[1], -n[0]])
            points = contact.points
            rn_a = cross(points - body_a.position, n)
            rn_b = cross(points - body_b.position, n)
            unit_response = (body_a.inverse_mass + body_b.inverse_mass
                             + body_a.inverse_inertia * np.outer(rn_a, rn_a)
                             + body_b.inverse_inertia * np.outer(rn_b, rn_b))
            normal_velocity = np.array([relative_normal_velocity(body_a, body_b, p, n) for p in points])
            target = np.where(normal_velocity < 0.0, -e * normal_velocity, 0.0)
            normal_impulses = solve_small_lcp(unit_response, target - normal_velocity)
            for point, j in zip(points, normal_impulses):
                if j > 0.0:
                    apply_impulse(body_a, body_b, point, j * n)
            tangent_impulses = np.zeros(len(points))
            for i, (point, j) in enumerate(zip(points, normal_impulses)):
                k_t = effective_mass_inverse(body_a, body_b, point, tangent)
                if j <= 0.0 or mu == 0.0 or k_t == 0.0:
                    continue
                tangent_velocity = relative_normal_velocity(body_a, body_b, point, tangent)
                impulse = -tangent_velocity / k_t
                if abs(impulse) > mu * j:
                    impulse = mu * j   # Coulomb: at most mu j
                tangent_impulses[i] = impulse
                apply_impulse(body_a, body_b, point, impulse * tangent)
            return normal_impulses, tangent_impulses
        '''),),
    expected_failures=frozenset({
        # Sliding with t . v_t > 0 beyond the Coulomb limit (10 of 39).
        "impulse.resolve_collision",
        # Friction pushes along the sliding: kinetic energy grows (4 of 20).
        "impulse.resolve_conserves_momentum",
        # The balls sliding on the floor.
        "impulse.scene",
        # The box sliding at 6 m/s beyond the Coulomb limit 2.25 N s (1 of 19).
        "impulse.limits",
        # Not failed: impulse.resolve_any_case, whose 30 Hypothesis examples hold no
        # case sliding the wrong way beyond the limit (with 60 examples it failed).
    }),
)


#: Every buggy sample, by exercise.
# sequential impulses -------------------------------------------------------------------
INCREMENT_CLAMP = BuggySample(
    name="increment-clamp",
    mistake="apply_normal_impulse clamps each increment to >= 0 instead of the accumulated impulse, so a "
            "visit can never take back what an earlier one overdid (the classic sequential-impulse bug).",
    erratum=0,
    replacements=(Replacement("solver.contact_point", "apply_normal_impulse", '''
        def apply_normal_impulse(velocity_a, velocity_b, point: ContactPoint, normal_total: float,
                                 target: float = 0.0, mass_scale: float = 1.0, impulse_scale: float = 0.0):
            vxa, vya, wa = velocity_a
            vxb, vyb, wb = velocity_b
            nx, ny, rn_a, rn_b, _, _, ima, imb, iia, iib, mass_normal, _, _, lower = point
            normal_velocity = (vxb - vxa) * nx + (vyb - vya) * ny + wb * rn_b - wa * rn_a
            change = mass_normal * mass_scale * (target - normal_velocity) - impulse_scale * normal_total
            change = max(change, lower)
            new_total = normal_total + change
            return ((vxa - ima * change * nx, vya - ima * change * ny, wa - iia * rn_a * change),
                    (vxb + imb * change * nx, vyb + imb * change * ny, wb + iib * rn_b * change),
                    new_total)
        '''),),
    expected_failures=frozenset({
        # The hand-worked visits that take impulse back (2 of 9) and the soft one, whose
        # -impulse_scale P term is clamped away.
        "sequential.normal_worked_examples",
        # Random visits with an accumulated impulse to take back.
        "sequential.normal_random",
        # Not failed: sequential.visits_converge (the box's two corners only ever need
        # more impulse: pushing one corner presses the other down, so no visit overdoes).
        "sequential.random_against_reference",
        # The stack's warm-started impulses only grow: the loads overshoot.
        "sequential.stack_of_ten",
        # The sweeps call this visit: the warm-started random manifolds have impulse to
        # take back (20 of 31 cases, and 23 of 30 of the hidden ones).
        "sequential.sweep_contacts",
        "sequential.prestep_and_sweeps_against_reference",
        # Warm started, each step's remembered impulses can only grow: the stacks'
        # loads climb (contact 2 carries 4.7 N s for 1.3 N s), the 4-sweep stack flies
        # apart (13.6 m/s), the pyramid's boxes move 0.4 m.
        "sequential.stack_loads",
        "sequential.warm_started_stack",
        "sequential.pyramid_stands",
        # The sliding box is pressed ever harder and its friction overshoots: it turns
        # and stops after 0.34 m instead of 0.89 m.
        "sequential.sliding_box_stops",
        # The tall box's first corner takes the whole landing and nothing gives it
        # back: it turns on the first step (angle -0.0030 rad for -0.0016).
        "sequential.tall_box_landing",
        # The step calls these sweeps: 18 of 30 steps; the ball dropped onto the ground
        # is pushed ever harder and rests 48 mm deep.
        "sequential.step_bodies",
        "sequential.step_rests_within_the_slop",
        # The box dropped onto the ground leaves the exact path as it settles (step 74),
        # the kicked ball bounces too low, the bouncing world's bodies leave the
        # reference's paths.
        "sequential.step_drops_bounce",
        "sequential.kicked_ball_rises",
        "sequential.bouncing_bodies",
    }),
)


LEVER_ARM_BACKWARDS = BuggySample(
    name="lever-arm-backwards",
    mistake="prestep_point crosses the normal with the lever arm (n x r) instead of r x n, and t x r for the "
            "tangent: every lever-arm term has the wrong sign, so impulses turn the bodies the wrong way.",
    erratum=0,
    replacements=(Replacement("solver.contact_sweeps", "prestep_point", '''
        def prestep_point(point, normal, centre_a, centre_b, ima: float, imb: float, iia: float, iib: float,
                          friction: float) -> ContactPoint:
            (px, py), (nx, ny) = point, normal
            rax, ray = px - centre_a[0], py - centre_a[1]
            rbx, rby = px - centre_b[0], py - centre_b[1]
            rn_a, rn_b = nx * ray - ny * rax, nx * rby - ny * rbx
            rt_a, rt_b = ny * ray + nx * rax, ny * rby + nx * rbx
            k_normal = ima + imb + iia * rn_a * rn_a + iib * rn_b * rn_b
            k_tangent = ima + imb + iia * rt_a * rt_a + iib * rt_b * rt_b
            return ContactPoint(nx, ny, rn_a, rn_b, rt_a, rt_b, ima, imb, iia, iib,
                                1.0 / k_normal if k_normal > 0.0 else 0.0, 1.0 / k_tangent if k_tangent > 0.0 else 0.0,
                                friction, 0.0)
        '''),),
    expected_failures=frozenset({
        # Every point off the line of centres (34 of 34 public, 44 of 44 hidden).
        "sequential.prestep_point",
        "sequential.prestep_and_sweeps_against_reference",
        # Friction's torque turns the box the wrong way: it tips and slides 1.16 m, not
        # 0.89 m; the tall box turns the other way (+0.0016 rad for -0.0016); the
        # pyramid's boxes move 0.46 m.
        "sequential.sliding_box_stops",
        "sequential.tall_box_landing",
        "sequential.pyramid_stands",
        # The step calls this prestep (22 of 30 steps wrong).
        "sequential.step_bodies",
        # The tilted box dropped in the bouncing world turns the wrong way.
        "sequential.bouncing_bodies",
        # Not failed: the stacks' boxes do not turn and the discs touch below their
        # centres (r x n = 0), so the sign is never seen there.
    }),
)

PRESTEP_NO_ANGULAR_MASS = BuggySample(
    name="prestep-no-angular-mass",
    mistake="prestep_point's effective masses keep only 1/m_A + 1/m_B and drop the (r x n)^2 / I terms, as if "
            "every contact pushed through both centres of mass.",
    erratum=0,
    replacements=(Replacement("solver.contact_sweeps", "prestep_point", '''
        def prestep_point(point, normal, centre_a, centre_b, ima: float, imb: float, iia: float, iib: float,
                          friction: float) -> ContactPoint:
            (px, py), (nx, ny) = point, normal
            rax, ray = px - centre_a[0], py - centre_a[1]
            rbx, rby = px - centre_b[0], py - centre_b[1]
            rn_a, rn_b = rax * ny - ray * nx, rbx * ny - rby * nx
            rt_a, rt_b = -(rax * nx + ray * ny), -(rbx * nx + rby * ny)
            k = ima + imb
            mass = 1.0 / k if k > 0.0 else 0.0
            return ContactPoint(nx, ny, rn_a, rn_b, rt_a, rt_b, ima, imb, iia, iib, mass, mass, friction, 0.0)
        '''),),
    expected_failures=frozenset({
        # Every point of a turning body off the line of centres (32 of 34, 42 of 44).
        "sequential.prestep_point",
        "sequential.prestep_and_sweeps_against_reference",
        # Friction at the box's corners over-stops it (0.73 m for 0.89 m); the tall
        # box and the pyramid's boxes get too large impulses at their corners.
        "sequential.sliding_box_stops",
        "sequential.tall_box_landing",
        "sequential.pyramid_stands",
        # The step calls this prestep (13 of 30 steps wrong).
        "sequential.step_bodies",
        # The tilted box dropped in the bouncing world lands with too large impulses.
        "sequential.bouncing_bodies",
        # Not failed: the stacks' boxes do not turn and a disc's normal passes through
        # its centre, where the dropped terms are 0.
    }),
)

THRESHOLD_IGNORED = BuggySample(
    name="threshold-ignored",
    mistake="contact_target bounces every closing point (v_n < 0) at e times its speed, however slowly it "
            "closes: the restitution threshold is ignored, so a resting contact bounces on gravity's step.",
    erratum=0,
    replacements=(Replacement("solver.contact_sweeps", "contact_target", '''
        def contact_target(normal_velocity: float, restitution: float, depth: float, dt: float,
                           restitution_threshold: float = 1.0, bias_factor: float = 0.0, slop: float = 0.005,
                           max_push: float = 3.0) -> float:
            bounce = -restitution * normal_velocity if normal_velocity < 0.0 else 0.0
            push = min(bias_factor / dt * max(depth - slop, 0.0), max_push)
            return max(bounce, push)
        '''),),
    expected_failures=frozenset({
        # The slow impacts below the threshold (3 of 51; 1 of 60 hidden).
        "sequential.contact_target",
        "sequential.prestep_and_sweeps_against_reference",
        # The sweeps set their targets with it: random manifolds closing below the
        # threshold (7 of 31 sweeps, 9 of 30 steps).
        "sequential.sweep_contacts",
        "sequential.step_bodies",
        # The dropped box bounces again on landings below the threshold (step 73).
        "sequential.step_drops_bounce",
        # The resting ball with e = 0.5 hops by 2 mm on gravity's 0.16 m/s a step; so do
        # the resting bodies (the box with e = 1 at 0.16 m/s on the first step), the ball
        # landing at 0.9 m/s (it leaves at 0.72 m/s), the one landing again below the
        # threshold after its bounce, the balls either side of a 0.5 m/s threshold and the
        # box pushed out of the ground once it closes slowly (step 28).
        "sequential.resting_ball_stays",
        "sequential.resting_bodies_stay",
        "sequential.slow_landing_stays",
        "sequential.landing_above_threshold_bounces",
        "sequential.landings_either_side_of_the_threshold",
        "sequential.sunk_box_pushed_out",
        # Not failed: the stacks, the sliding box, the tall box and the pyramid have
        # e = 0; the kicked ball, the 5 m/s bounce and the bouncing world's bodies land
        # faster than the threshold.
    }),
)

PUSH_ON_SEPARATION = BuggySample(
    name="push-on-separation",
    mistake="contact_target reads depth as box2d-lite's separation (positive apart): it pushes apart points "
            "that are apart and never pushes an overlap out.",
    erratum=0,
    replacements=(Replacement("solver.contact_sweeps", "contact_target", '''
        def contact_target(normal_velocity: float, restitution: float, depth: float, dt: float,
                           restitution_threshold: float = 1.0, bias_factor: float = 0.0, slop: float = 0.005,
                           max_push: float = 3.0) -> float:
            bounce = -restitution * normal_velocity if normal_velocity < -restitution_threshold else 0.0
            separation = depth
            push = min(-bias_factor / dt * min(separation + slop, 0.0), max_push)
            return max(bounce, push)
        '''),),
    expected_failures=frozenset({
        # Every overlap beyond the slop with a bias factor (32 of 51; 39 of 60 hidden).
        "sequential.contact_target",
        "sequential.prestep_and_sweeps_against_reference",
        # The sweeps set their targets with it: the overlaps of the pushed manifolds (10
        # of 31 sweeps, 7 of 30 steps); the ball dropped onto the ground stays 17.8 mm deep.
        "sequential.sweep_contacts",
        "sequential.step_bodies",
        "sequential.step_rests_within_the_slop",
        "sequential.step_drops_bounce",
        # Nothing pushes the overlaps out: the box sunk 30 cm stays there, the bodies
        # spawned 1 to 4 cm deep and the balls landing up to 25 mm deep stay as deep.
        "sequential.sunk_box_pushed_out",
        "sequential.resting_bodies_stay",
        "sequential.slow_landing_stays",
        "sequential.landing_above_threshold_bounces",
        "sequential.landings_either_side_of_the_threshold",
        # Not failed: the stacks run without a push (bias factor 0) and the other upright
        # bodies never sink past the slop (the sweeps stop them where they touch); the
        # engine's worlds correct positions in another stage (split impulses).
    }),
)

NO_WARM_START = BuggySample(
    name="no-warm-start",
    mistake="sweep_contacts skips the warm start: the sweeps start from zero impulses and last step's are "
            "forgotten, so a stack needs many more sweeps to stand.",
    erratum=0,
    replacements=(Replacement("solver.contact_sweeps", "sweep_contacts", '''
        def sweep_contacts(velocity, manifolds, settings: StepSettings):
            dt, iterations, threshold, bias_factor, slop, max_push = settings
            velocity = [tuple(v) for v in velocity]
            normal = [[0.0] * len(m[2]) for m in manifolds]
            tangent = [[0.0] * len(m[2]) for m in manifolds]
            targets = []
            for a, b, points, restitution, depths, _, _ in manifolds:
                (vxa, vya, wa), (vxb, vyb, wb) = velocity[a], velocity[b]
                targets.append([contact_target((vxb - vxa) * p[0] + (vyb - vya) * p[1] + wb * p[3] - wa * p[2],
                                               restitution, depth, dt, threshold, bias_factor, slop, max_push)
                                for p, depth in zip(points, depths)])
            for _ in range(iterations):
                for m, (a, b, points, _, _, _, _) in enumerate(manifolds):
                    for k, point in enumerate(points):
                        velocity[a], velocity[b], tangent[m][k] = apply_friction_impulse(
                            velocity[a], velocity[b], point, normal[m][k], tangent[m][k])
                    for k, point in enumerate(points):
                        velocity[a], velocity[b], normal[m][k] = apply_normal_impulse(
                            velocity[a], velocity[b], point, normal[m][k], targets[m][k])
            return velocity, normal, tangent
        '''),),
    expected_failures=frozenset({
        # The cases with remembered impulses (23 of 31; 28 of 30 hidden).
        "sequential.sweep_contacts",
        "sequential.prestep_and_sweeps_against_reference",
        # The step calls these sweeps (21 of 30 steps wrong).
        "sequential.step_bodies",
        # Without last step's impulses the box resting under the ball leaves the
        # reference's path.
        "sequential.bouncing_bodies",
        # Cold, 10 sweeps a step leave the ten-box stack's loads 0.14 % off the LCP
        # answer after 1 s (the bound is 0.1 %); with 4 sweeps the top box sinks 3.3 m.
        "sequential.stack_loads",
        "sequential.warm_started_stack",
        # Without last step's friction the sliding box stops 2 mm late and keeps
        # 0.09 mm/s; the tall box leaves the reference's path by step 25.
        "sequential.sliding_box_stops",
        "sequential.tall_box_landing",
    }),
)

RETARGET_EACH_VISIT = BuggySample(
    name="retarget-each-visit",
    mistake="sweep_contacts measures each point's target at every visit, from the velocities the sweeps have "
            "already changed, instead of once before the warm start: a bounce sees the bounce it made and takes "
            "it back (the fourth classic bug of the sequential-impulse chapter).",
    erratum=0,
    replacements=(Replacement("solver.contact_sweeps", "sweep_contacts", '''
        def sweep_contacts(velocity, manifolds, settings: StepSettings):
            dt, iterations, threshold, bias_factor, slop, max_push = settings
            velocity = [tuple(v) for v in velocity]
            normal = [list(m[5]) for m in manifolds]
            tangent = [list(m[6]) for m in manifolds]
            for m, (a, b, points, _, _, _, _) in enumerate(manifolds):
                for k, point in enumerate(points):
                    nx, ny, rn_a, rn_b, rt_a, rt_b, ima, imb, iia, iib = point[:10]
                    pn, pt = normal[m][k], tangent[m][k]
                    px, py = pn * nx + pt * ny, pn * ny - pt * nx
                    vxa, vya, wa = velocity[a]
                    vxb, vyb, wb = velocity[b]
                    velocity[a] = (vxa - ima * px, vya - ima * py, wa - iia * (rn_a * pn + rt_a * pt))
                    velocity[b] = (vxb + imb * px, vyb + imb * py, wb + iib * (rn_b * pn + rt_b * pt))
            for _ in range(iterations):
                for m, (a, b, points, restitution, depths, _, _) in enumerate(manifolds):
                    for k, point in enumerate(points):
                        velocity[a], velocity[b], tangent[m][k] = apply_friction_impulse(
                            velocity[a], velocity[b], point, normal[m][k], tangent[m][k])
                    for k, point in enumerate(points):
                        (vxa, vya, wa), (vxb, vyb, wb) = velocity[a], velocity[b]
                        closing = (vxb - vxa) * point[0] + (vyb - vya) * point[1] + wb * point[3] - wa * point[2]
                        target = contact_target(closing, restitution, depths[k], dt, threshold, bias_factor, slop,
                                                max_push)
                        velocity[a], velocity[b], normal[m][k] = apply_normal_impulse(
                            velocity[a], velocity[b], point, normal[m][k], target)
            return velocity, normal, tangent
        '''),),
    expected_failures=frozenset({
        # The bounces of two sweeps or more: the second visit finds the point leaving and
        # aims at no bounce (10 of 31 sweeps, 10 of 30 steps); the ball hitting the
        # ground at 5 m/s leaves at 0 m/s after 2 sweeps, not 4 m/s.
        "sequential.sweep_contacts",
        "sequential.step_bodies",
        "sequential.bounce_whatever_the_sweeps",
        "sequential.prestep_and_sweeps_against_reference",
        # Every other bounce: the dropped balls and box and the kicked ball landing
        # again do not bounce (0.22 m expected), nor do the bouncing world's bodies.
        "sequential.step_drops_bounce",
        "sequential.kicked_ball_rises",
        "sequential.bouncing_bodies",
        # Not failed: the stacks, the sliding box, the tall box and the pyramid have e = 0
        # and push with split impulses or not at all, where a target measured again is
        # the same.
    }),
)

POSITIONS_BEFORE_SWEEPS = BuggySample(
    name="positions-before-sweeps",
    mistake="step_bodies moves the bodies right after gravity, with velocities the contacts have not corrected "
            "yet, and solves the contacts after: a resting body sinks by g h^2 every step (the fifth classic bug "
            "of the sequential-impulse chapter).",
    erratum=0,
    replacements=(Replacement("solver.contact_sweeps", "step_bodies", '''
        def step_bodies(bodies, pairs, gravity, settings: StepSettings):
            dt = settings[0]
            gx, gy = gravity
            velocity = [(vx + dt * gx, vy + dt * gy, w) if ima > 0.0 else (vx, vy, w)
                        for _, _, _, vx, vy, w, ima, _ in bodies]
            poses = [(x + dt * vx, y + dt * vy, angle + dt * w)
                     for (x, y, angle, *_), (vx, vy, w) in zip(bodies, velocity)]
            manifolds = []
            for a, b, normal, points, depths, friction, restitution, normal_total, tangent_total in pairs:
                xa, ya, _, _, _, _, ima, iia = bodies[a]
                xb, yb, _, _, _, _, imb, iib = bodies[b]
                rows = [prestep_point(point, normal, (xa, ya), (xb, yb), ima, imb, iia, iib, friction)
                        for point in points]
                manifolds.append(ManifoldRows(a, b, rows, restitution, depths, normal_total, tangent_total))
            velocity, normal, tangent = sweep_contacts(velocity, manifolds, settings)
            return [(*pose, *v) for pose, v in zip(poses, velocity)], normal, tangent
        '''),),
    expected_failures=frozenset({
        # Every step with a body that gravity moves (26 of 30); the resting box and the
        # ball dropped onto the ground rest 18.6 mm deep, where the push balances g h^2.
        "sequential.step_bodies",
        "sequential.step_rests_within_the_slop",
        "sequential.step_drops_bounce",
        "sequential.prestep_and_sweeps_against_reference",
        # The worlds that step with step_bodies: the tall box and the bouncing bodies
        # leave the reference's paths, the pyramid sinks.
        "sequential.tall_box_landing",
        "sequential.pyramid_stands",
        "sequential.bouncing_bodies",
        # Not failed: the scenes stepped around prestep_point and sweep_contacts.
    }),
)

BUGGY_SAMPLES: tuple[BuggySample, ...] = (
    ELASTIC_SWAPPED_MASSES, RESTITUTION_SIGN,
    GRID_OWN_CELL, GRID_STRICT_TOUCHING, GRID_MISSING_LAST_CELL, GRID_INT_CENTRE_CELL, GRID_CENTER_3X3,
    QUADTREE_DROPS_STRADDLING, QUADTREE_STRADDLER_IN_ONE_CHILD, QUADTREE_NO_DESCENDANTS, QUADTREE_ON_SPLIT_LINE,
    SIBLING_ALWAYS_ROOT, INSERT_WITHOUT_REFIT, REMOVE_SIBLING_KEEPS_OLD_PARENT,
    MOVE_REINSERTS_EVERY_FRAME, MOVE_NEVER_REINSERTS, TREE_PAIRS_STRICT_TOUCHING, TREE_PAIRS_BOTH_ORDERS,
    FLT_MIN, NO_RESET, ABS_PROJECTION, DIAMETER, UNNORMALISED_AXIS, SAT_ONLY_A_AXES, SAT_EDGE_DIRECTIONS,
    CIRCLE_NO_VERTEX_AXIS, INTERVALS_STRICT,
    NORMAL_NOT_FLIPPED, AABB_DEPTH_MAX, ONE_POINT_MANIFOLD, CONTACT_POINT_ON_POLYGON,
    SEPARATE_IMPULSES, NORMAL_B_TO_A, IMPULSE_ON_SEPARATING, NO_ANGULAR_MASS, RESTITUTION_MAX, IMPULSE_TO_BOTH,
    CORRECTION_NO_SLOP, FRICTION_CLAMP_SIGN, INCREMENT_CLAMP, LEVER_ARM_BACKWARDS, PRESTEP_NO_ANGULAR_MASS,
    THRESHOLD_IGNORED, PUSH_ON_SEPARATION, NO_WARM_START, RETARGET_EACH_VISIT, POSITIONS_BEFORE_SWEEPS,
)


# --------------------------------------------------------------------------- building

def find_function(tree: ast.Module, qualname: str) -> ast.FunctionDef | ast.AsyncFunctionDef | None:
    """The function or method called ``qualname`` ("f", "Class.method") in ``tree``, or None.

    Examples
    --------
    >>> tree = ast.parse("class A:\\n    def f(self):\\n        pass\\n")
    >>> find_function(tree, "A.f").lineno
    2
    """
    scope: list[ast.stmt] = tree.body
    *outer, last = qualname.split(".")
    for name in outer:
        classes = [n for n in scope if isinstance(n, ast.ClassDef) and n.name == name]
        if not classes:
            return None
        scope = classes[-1].body
    functions = [n for n in scope if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)) and n.name == last]
    return functions[-1] if functions else None


def docstring_lines(lines: list[str], function: ast.FunctionDef) -> list[str] | None:
    """The source lines of ``function``'s docstring, or None if it has none."""
    if ast.get_docstring(function, clean=False) is None:
        return None
    node = function.body[0]
    return lines[node.lineno - 1:node.end_lineno]


def parameter_names(function: ast.FunctionDef) -> list[str]:
    arguments = function.args
    names = [a.arg for a in (*arguments.posonlyargs, *arguments.args, *arguments.kwonlyargs)]
    names += [f"*{a.arg}" for a in (arguments.vararg, arguments.kwarg) if a is not None]
    return names


def student_function(original_lines: list[str], original: ast.FunctionDef, replacement: Replacement,
                     where: str) -> list[str]:
    """The replacement's lines, indented like ``original``, with its docstring kept."""
    source = textwrap.dedent(replacement.source).strip("\n") + "\n"
    try:
        parsed = ast.parse(source)
    except SyntaxError as exc:
        raise ExampleClassError(f"{where}: the buggy source does not parse: {exc}") from None
    name = replacement.qualname.split(".")[-1]
    if len(parsed.body) != 1 or not isinstance(parsed.body[0], (ast.FunctionDef, ast.AsyncFunctionDef)) \
            or parsed.body[0].name != name:
        raise ExampleClassError(f"{where}: the buggy source must be exactly one function called {name!r}")
    new = parsed.body[0]
    if parameter_names(new) != parameter_names(original):
        raise ExampleClassError(f"{where}: the buggy function takes {parameter_names(new)}, the original "
                                f"{parameter_names(original)}; a student keeps the given signature")
    lines = source.splitlines(keepends=True)
    kept_doc = docstring_lines(original_lines, original)
    if kept_doc is not None and ast.get_docstring(new, clean=False) is None:
        if new.body[0].lineno == new.lineno:
            raise ExampleClassError(f"{where}: write the buggy function's body on the lines below its `def`")
        # The original docstring, moved from the original body's indentation to the new one's.
        old_indent, new_indent = original.body[0].col_offset, new.body[0].col_offset
        moved = []
        for line in kept_doc:
            text = line[old_indent:] if line[:old_indent].strip() == "" else line.lstrip()
            moved.append(" " * new_indent + text if text.strip() else "\n")
        first_body_line = new.body[0].lineno - 1
        lines = lines[:first_body_line] + moved + lines[first_body_line:]
    indent = " " * original.col_offset
    return [indent + line if line.strip() else line for line in lines]


def replace_functions(source: str, replacements: list[Replacement], where: str) -> str:
    """``source`` with each replacement's function swapped for its buggy text.

    Raises
    ------
    ExampleClassError
        When a function is not found, a buggy text does not parse, or the result does
        not parse or lacks the function.
    """
    lines = source.splitlines(keepends=True)
    tree = ast.parse(source)
    located = []
    for replacement in replacements:
        here = f"{where}, {replacement.qualname}"
        function = find_function(tree, replacement.qualname)
        if function is None:
            raise ExampleClassError(f"{here}: no function {replacement.qualname!r} in module {replacement.module!r}")
        first = min([function.lineno, *(d.lineno for d in function.decorator_list)])
        last = function.end_lineno
        # Comments right after the last statement, indented as the body, belong to it
        # (the "### END SOLUTION" marker).
        while last < len(lines) and lines[last].lstrip().startswith("#") \
                and len(lines[last]) - len(lines[last].lstrip()) > function.col_offset:
            last += 1
        located.append((first, last, function, replacement, here))
    located.sort(key=lambda item: item[0], reverse=True)  # bottom up: earlier line numbers stay valid
    for first, last, function, replacement, here in located:
        lines[first - 1:last] = student_function(lines, function, replacement, here)

    imports = [line for r in replacements for line in r.imports]
    if imports:
        tree = ast.parse("".join(lines))
        top_imports = [n for n in tree.body if isinstance(n, (ast.Import, ast.ImportFrom))]
        after = top_imports[-1].end_lineno if top_imports else 0
        present = {line.strip() for line in lines}
        lines[after:after] = [line + "\n" for line in dict.fromkeys(imports) if line not in present]

    result = "".join(lines)
    try:
        tree = ast.parse(result)
    except SyntaxError as exc:
        raise ExampleClassError(f"{where}: the module with the buggy functions does not parse: {exc}") from None
    for replacement in replacements:
        if find_function(tree, replacement.qualname) is None:
            raise ExampleClassError(f"{where}: {replacement.qualname!r} is missing after the replacement")
    return result


def module_path(package_dir: Path, module: str) -> Path:
    return package_dir.joinpath(*module.split(".")).with_suffix(".py")


def copy_package(source: Path, destination: Path) -> None:
    shutil.copytree(source, destination, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))


def prepare_folder(folder: Path) -> None:
    """Make ``folder`` empty; refuse to delete a folder this module did not write."""
    if folder.exists():
        if not (folder / ABOUT_FILE).is_file():
            raise ExampleClassError(f"{folder} exists and is not a sample written by `grader example-class`; "
                                    "choose another --out folder")
        shutil.rmtree(folder)
    folder.mkdir(parents=True)


def build_buggy_sample(sample: BuggySample, out_dir: Path, reference_dir: Path = SOLUTIONS_DIR) -> Path:
    """Write ``out_dir/bug-<name>/exercises``: the reference with the sample's bug.

    The modules are rewritten in memory first, so a sample that cannot be built
    (:class:`ExampleClassError`) leaves nothing behind.
    """
    by_module: dict[str, list[Replacement]] = {}
    for replacement in sample.replacements:
        by_module.setdefault(replacement.module, []).append(replacement)
    rewritten = {}
    for module, replacements in by_module.items():
        path = module_path(reference_dir, module)
        where = f"sample {sample.name!r}, module {module!r}"
        if not path.is_file():
            raise ExampleClassError(f"{where}: no file {path}")
        rewritten[module] = replace_functions(path.read_text(encoding="utf-8"), replacements, where)
    folder = Path(out_dir) / sample.folder_name
    prepare_folder(folder)
    copy_package(reference_dir, folder / PACKAGE)
    for module, text in rewritten.items():
        module_path(folder / PACKAGE, module).write_text(text, encoding="utf-8")
    functions = ", ".join(f"`{r.module}.{r.qualname}`" for r in sample.replacements)
    failures = "\n".join(f"- `{name}`" for name in sorted(sample.expected_failures))
    origin = f"erratum {sample.erratum} of the notes" if sample.erratum else "a common bug"
    weak = "".join(f"\n`{name}` is a weak test: it loses less than half its points to this bug.\n"
                   for name in sorted(sample.weak_tests))
    (folder / ABOUT_FILE).write_text(
        f"# Sample `{sample.folder_name}` ({sample.exercise}, {origin})\n\n{sample.mistake}\n\n"
        f"Rewritten: {functions}; everything else is the reference.\n\nTests it should fail:\n\n{failures}\n"
        f"{weak}", encoding="utf-8")
    return folder


def build_copy_sample(name: str, source: Path, about: str, out_dir: Path) -> Path:
    folder = Path(out_dir) / name
    prepare_folder(folder)
    copy_package(source, folder / PACKAGE)
    (folder / ABOUT_FILE).write_text(f"# Sample `{name}`\n\n{about}\n", encoding="utf-8")
    return folder


def build_example_class(out_dir: Path, samples: tuple[BuggySample, ...] = BUGGY_SAMPLES) -> list[Path]:
    """Write the example class into ``out_dir``: one folder per sample submission.

    Returns the folders: ``reference``, ``stubs``, then ``bug-<name>`` per sample.
    Folders of an earlier build are replaced; other folders are never touched.

    Raises
    ------
    ExampleClassError
        When a buggy sample cannot be built (unknown module or function, buggy source
        that does not parse), or a sample folder exists and was not written here.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    folders = [
        build_copy_sample(REFERENCE_SAMPLE, SOLUTIONS_DIR, "The reference engine (`solutions/`): full marks.", out_dir),
        build_copy_sample(STUBS_SAMPLE, EXERCISES_DIR, "The student package as handed out (`exercises/`): every "
                          "exercise raises NotImplementedError, zero marks.", out_dir),
    ]
    folders += [build_buggy_sample(sample, out_dir) for sample in samples]
    return folders


def points_lost(sample: BuggySample, tests) -> float:
    """Points at stake: those of the tests in ``tests`` (TestSpec list) that ``sample``
    should fail (it loses all of them, or a share where a test gives partial credit)."""
    return sum(t.points for t in tests if t.name in sample.expected_failures)


def minimum_points_lost(sample: BuggySample, tests) -> float:
    """The least ``sample`` may lose: every point of an expected failure without partial
    credit, at least half of one with partial credit, and something of a weak test."""
    return sum(t.points / 2 if t.partial_credit else t.points for t in tests
               if t.name in sample.expected_failures - sample.weak_tests)


def loses_enough(points: float, score: float) -> bool:
    """Whether a failed test scoring ``score`` of ``points`` lost at least half of them."""
    return points - score >= points / 2 - 1e-9


def sample_problems(sample: BuggySample, results) -> list[str]:
    """What is wrong with ``sample``'s graded ``results`` (TestResult list, the tests that
    reach its functions), one sentence each; empty when all is as expected."""
    by_name = {r.test.name: r for r in results}
    failed = {name for name, r in by_name.items() if r.outcome.status != "passed"}
    problems = [f"expects {name} to fail, but {name} was not graded (it does not reach the functions rewritten)"
                for name in sorted(sample.expected_failures - set(by_name))]
    problems += [f"not caught by {name} (it passed)" for name in sorted((sample.expected_failures & set(by_name))
                                                                          - failed)]
    problems += [f"also fails {name}: {by_name[name].outcome.status}: {by_name[name].outcome.message[:300]}"
                 for name in sorted(failed - sample.expected_failures)]
    for name in sorted(sample.expected_failures & failed):
        result = by_name[name]
        points, score = result.test.points, result.score
        if result.outcome.status != sample.status:
            problems.append(f"{name} ends {result.outcome.status!r}, not {sample.status!r}: "
                            f"{result.outcome.message[:300]}")
        if name in sample.weak_tests and loses_enough(points, score):
            problems.append(f"{name} is listed as weak but loses at least half its points ({score:.4g} of "
                            f"{points:g} left): take it out of weak_tests")
        elif name not in sample.weak_tests and not loses_enough(points, score):
            problems.append(f"{name} keeps {score:.4g} of {points:g} points ({result.outcome.fraction:.1%} of its "
                            "cases right): a systematic bug must lose at least half of them (a weak test?)")
    return problems


# --------------------------------------------------------------------------- the probe

#: The folder of the probe: the reference with every exercise function announcing itself.
PROBE_SAMPLE = "probe"
#: The line opening a solution block (grader/release/exercises.py): the functions holding
#: one are the exercises, the only functions a sample rewrites.
BEGIN_MARKER = "### BEGIN SOLUTION"
#: The probe's exercise functions print this mark followed by their one-character code.
PROBE_MARK = "\u00a7"
PROBE_CODES = string.ascii_uppercase + string.ascii_lowercase + string.digits
PROBE_HELPER = "_example_class_probe"
PROBE_HELPER_SOURCE = f'''


def {PROBE_HELPER}(code, _seen={{}}):
    """Print the probe's mark and ``code``, once per call into the grader's worker
    (the worker captures each call's printed text in a fresh ``sys.stdout``)."""
    import sys
    if _seen.get(None) is not sys.stdout:
        _seen.clear()
        _seen[None] = sys.stdout
    if code not in _seen:
        _seen[code] = True
        sys.stdout.write({PROBE_MARK!r} + code)
'''


def top_level_functions(tree: ast.Module):
    """``(qualname, node)`` of the module's functions and of its classes' methods."""
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            yield node.name, node
        elif isinstance(node, ast.ClassDef):
            for member in node.body:
                if isinstance(member, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    yield f"{node.name}.{member.name}", member


def exercise_functions(package_dir: Path = SOLUTIONS_DIR) -> dict[str, list[str]]:
    """``{module: [qualname, ...]}`` of every function holding a solution block.

    Examples
    --------
    >>> exercise_functions()["broadphase.quadtree"]
    ['Quadtree.child_holding', 'Quadtree.insert', 'Quadtree.split', 'Quadtree.pairs']
    """
    found: dict[str, list[str]] = {}
    for path in sorted(Path(package_dir).rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        if "__pycache__" in path.parts or BEGIN_MARKER not in text:
            continue
        module = ".".join(path.relative_to(package_dir).with_suffix("").parts)
        lines = text.splitlines()
        for qualname, function in top_level_functions(ast.parse(text)):
            if any(line.strip() == BEGIN_MARKER for line in lines[function.lineno - 1:function.end_lineno]):
                found.setdefault(module, []).append(qualname)
    return found


def exercise_functions_flat(package_dir: Path = SOLUTIONS_DIR) -> list[str]:
    """``"module.qualname"`` of every exercise function of the package."""
    return [f"{module}.{qualname}" for module, qualnames in exercise_functions(package_dir).items()
            for qualname in qualnames]


def sample_functions(sample: BuggySample) -> frozenset[str]:
    """``"module.qualname"`` of the functions ``sample`` rewrites."""
    return frozenset(f"{r.module}.{r.qualname}" for r in sample.replacements)


def build_probe(out_dir: Path, reference_dir: Path = SOLUTIONS_DIR) -> tuple[Path, dict[str, str]]:
    """Write ``out_dir/probe/exercises``: the reference, each exercise function printing
    :data:`PROBE_MARK` and its code when called (once per call into the worker).

    Graded like a submission, the probe tells which exercise functions each graded test
    reaches (:func:`grade_probe`).  A test that never reaches the functions a
    sample rewrites runs the very same code on the sample as on the reference: the
    same inputs (seeded; Hypothesis derandomized), the same answers, the same outcome.

    Returns the folder and ``{code: "module.qualname"}``.
    """
    reference_dir = Path(reference_dir)
    functions = exercise_functions(reference_dir)
    names = [f"{module}.{qualname}" for module, qualnames in functions.items() for qualname in qualnames]
    if len(names) > len(PROBE_CODES):
        raise ExampleClassError(f"the probe has codes for {len(PROBE_CODES)} exercise functions, not {len(names)}")
    codes = dict(zip(PROBE_CODES, names))
    code_of = {name: code for code, name in codes.items()}
    folder = Path(out_dir) / PROBE_SAMPLE
    prepare_folder(folder)
    copy_package(reference_dir, folder / PACKAGE)
    for module, qualnames in functions.items():
        path = module_path(folder / PACKAGE, module)
        text = path.read_text(encoding="utf-8")
        lines = text.splitlines(keepends=True)
        inserts = []
        for qualname, function in top_level_functions(ast.parse(text)):
            if qualname not in qualnames:
                continue
            for number in range(function.lineno - 1, function.end_lineno):
                if lines[number].strip() == BEGIN_MARKER:
                    indent = lines[number][:len(lines[number]) - len(lines[number].lstrip())]
                    inserts.append((number + 1, f"{indent}{PROBE_HELPER}({code_of[f'{module}.{qualname}']!r})\n"))
        for number, line in sorted(inserts, reverse=True):
            lines.insert(number, line)
        path.write_text("".join(lines) + PROBE_HELPER_SOURCE, encoding="utf-8")
    (folder / ABOUT_FILE).write_text(f"# Sample `{PROBE_SAMPLE}`\n\nThe reference engine, each exercise function "
                                     f"printing {PROBE_MARK}<code> when called: it shows which exercise functions "
                                     "each graded test reaches.\n", encoding="utf-8")
    return folder, codes


def grade_probe(tests, out_dir: Path, slot: int = 0,
                isolation: str = "auto") -> tuple[dict[str, frozenset[str] | None], list]:
    """Grade the probe with ``tests``: ``({test: the exercise functions it reaches},
    the TestResult list)``.

    Every call into the probe's worker, whatever path the test takes to it (a student
    call, a batch, or a program of calls of a scene), brings back what the
    code printed: the codes of the exercise functions it reached.  A test that seems to
    reach none is not believed: it gets None (it may reach any).  Tests run one after
    the other, so what is printed between two tests' ends belongs to the later one.
    The results are the reference's own (the probe only prints): every test passes.
    """
    from ..harness.run import run_tests  # deferred: pytest, heavy to import

    folder, codes = build_probe(out_dir)
    printed: list[str] = []
    reached: dict[str, frozenset[str] | None] = {}

    def call(self, *args, **kwargs):
        result = original(self, *args, **kwargs)
        printed.append(result.output or "")
        return result

    def progress(result) -> None:
        text = "".join(printed)
        printed.clear()
        found = frozenset(codes[text[k + 1]] for k in range(len(text) - 1)
                          if text[k] == PROBE_MARK and text[k + 1] in codes)
        reached[result.test.name] = found or None

    original = Sandbox.call
    Sandbox.call = call
    try:
        results = run_tests(folder, list(tests), slot=slot, isolation=isolation, progress=progress)
    finally:
        Sandbox.call = original
    return reached, results


def reaching_tests(sample: BuggySample, reached: dict[str, frozenset[str] | None]) -> set[str]:
    """The tests that may see ``sample``'s bug: those reaching a function it rewrites
    (all tests if it rewrites a function the probe does not watch)."""
    rewritten = sample_functions(sample)
    if not rewritten <= set(exercise_functions_flat()):
        return set(reached)
    return {name for name, found in reached.items() if found is None or found & rewritten}


# --------------------------------------------------------------------------- command line

def add_example_class_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", type=Path, required=True, metavar="DIR",
                        help="folder to write the sample submissions into (one subfolder each)")
    parser.add_argument("--grade", action="store_true",
                        help="also grade each buggy sample with the tests that reach the functions it rewrites "
                             "and print what it loses (exit status 1 if a sample does not lose what it should)")
    parser.add_argument("--all-tests", action="store_true",
                        help="with --grade: grade each sample with every graded test (minutes)")


def main_example_class(args: argparse.Namespace) -> int:
    from ..harness.run import load_spec  # deferred: pytest, heavy to import

    tests = load_spec()
    total = sum(t.points for t in tests)
    try:
        folders = build_example_class(args.out)
    except ExampleClassError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    expected = {REFERENCE_SAMPLE: f"{total:g} of {total:g}", STUBS_SAMPLE: f"0 of {total:g}"}
    for sample in BUGGY_SAMPLES:
        low, high = total - points_lost(sample, tests), total - minimum_points_lost(sample, tests)
        expected[sample.folder_name] = f"{low:g} of {total:g}" if low == high else f"{low:g} to {high:g} of {total:g}"
    width = max(len(f.name) for f in folders)
    print(f"wrote {len(folders)} sample submissions to {args.out}:")
    for folder in folders:
        print(f"  {folder.name:{width}s}  expected {expected[folder.name]}")
    print(f"grade them with: grader grade {args.out}/* --out REPORTS_DIR")
    if not getattr(args, "grade", False):
        return 0
    return grade_table(tests, {f.name: f for f in folders}, all_tests=getattr(args, "all_tests", False))


def grade_table(tests, folders: dict[str, Path], all_tests: bool = False, slot: int = 0) -> int:
    """Grade every buggy sample and print what it fails and loses; 1 if any sample does
    not lose what its data says."""
    import tempfile
    import time

    from ..harness.run import run_tests  # deferred: pytest, heavy to import

    total = sum(t.points for t in tests)
    reached = None
    if not all_tests:
        started = time.perf_counter()
        with tempfile.TemporaryDirectory() as probe_dir:
            reached, results = grade_probe(tests, Path(probe_dir), slot=slot)
        print(f"\nprobe: the reference, printing which exercise functions each test reaches "
              f"({time.perf_counter() - started:.1f} s)")
        wrong = [r for r in results if r.outcome.status != "passed"]
        for result in wrong:
            print(f"  PROBLEM: the reference fails {result.test.name}: {result.outcome.message[:300]}")
        if wrong:
            return 1
    status = 0
    for sample in BUGGY_SAMPLES:
        names = set(t.name for t in tests) if reached is None else reaching_tests(sample, reached)
        started = time.perf_counter()
        results = run_tests(folders[sample.folder_name], [t for t in tests if t.name in names], slot=slot)
        seconds = time.perf_counter() - started
        failed = [r for r in results if r.outcome.status != "passed"]
        lost = sum(r.test.points - r.score for r in failed)
        origin = f"erratum {sample.erratum}" if sample.erratum else "a common bug"
        print(f"\n{sample.folder_name} ({sample.exercise}, {origin}): fails {len(failed)} of the {len(results)} "
              f"tests graded ({seconds:.1f} s), loses {lost:.4g} of {total:g} points")
        for result in failed:
            share = (f"{result.outcome.fraction:6.1%} of its cases right" if result.test.partial_credit
                     else "no partial credit")
            weak = "" if loses_enough(result.test.points, result.score) else "  (loses less than half: weak)"
            print(f"    {result.test.name:40s} {result.score:7.4g} / {result.test.points:g}  {share}{weak}")
        problems = sample_problems(sample, results)
        for problem in problems:
            print(f"  PROBLEM: {problem}")
        status = status or int(bool(problems))
    return status
