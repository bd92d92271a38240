"""Every broad phase against the brute-force oracle, plus invariants and bad input.

One parametrised suite runs each implementation (several cell sizes and quadtree
settings) on seeded random scenes and on hand-made hard cases, and compares the pair
set with :func:`pairs_brute_force`.  The oracle itself is checked on cases whose
answer is known by hand.
"""
from __future__ import annotations

import functools
import importlib
import shutil
import sys
import tracemalloc
import uuid
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from solutions.broadphase import sorted_grid_numpy
from solutions.broadphase.aabb_array import aabb_array, validate_aabbs
from solutions.broadphase.brute_force import aabbs_overlap, pairs_brute_force, pairs_brute_force_numpy
from solutions.broadphase.quadtree import (
    RULE_MAX_DEPTH,
    RULE_MIN_AREA,
    Quadtree,
    pairs_quadtree,
    scene_bounds,
)
from solutions.broadphase.sorted_grid_numpy import pairs_as_set, pairs_grid_numpy
from solutions.broadphase.uniform_grid import pairs_uniform_grid, suggest_cell_size
from solutions.shapes import AABB, OBB, Circle, ConvexPolygon

SOLUTIONS_DIR = Path(__file__).resolve().parents[1] / "solutions"
BROADPHASE_DIR = SOLUTIONS_DIR / "broadphase"


# --------------------------------------------------------------------------- scenes
def boxes_around(centres, sizes) -> np.ndarray:
    """(N, 4) boxes with the given centres and full sizes (width, height)."""
    centres = np.asarray(centres, dtype=float)
    half = np.asarray(sizes, dtype=float) / 2
    return np.hstack([centres - half, centres + half])


def scene_uniform(rng):
    return boxes_around(rng.uniform(0, 30, (300, 2)), rng.uniform(0.5, 2.5, (300, 2)))


def scene_clustered(rng):
    cluster_centres = rng.uniform(0, 60, (5, 2))
    centres = cluster_centres[rng.integers(0, 5, 300)] + rng.normal(0, 2.0, (300, 2))
    return boxes_around(centres, rng.uniform(0.3, 1.5, (300, 2)))


def scene_mixed_sizes(rng):
    return boxes_around(rng.uniform(0, 40, (300, 2)), rng.lognormal(0.0, 1.0, (300, 2)))


def scene_few_huge_bodies(rng):
    small = boxes_around(rng.uniform(0, 40, (250, 2)), rng.uniform(0.5, 1.5, (250, 2)))
    huge = boxes_around(rng.uniform(0, 40, (3, 2)), [[30, 4], [5, 25], [20, 20]])
    return np.vstack([small[:100], huge[:1], small[100:200], huge[1:], small[200:]])


def scene_negative_coordinates(rng):
    return boxes_around(rng.uniform(-25, 5, (300, 2)), rng.uniform(0.5, 2.5, (300, 2)))


def scene_far_from_origin(rng):
    return boxes_around(rng.uniform(1e5, 1e5 + 30, (300, 2)) * [1, -1], rng.uniform(0.5, 2.5, (300, 2)))


def scene_integer_touching(rng):
    """Integer corners and sizes 0..3: many boxes touch exactly, along edges and corners."""
    corners = rng.integers(-8, 8, (250, 2)).astype(float)
    return np.hstack([corners, corners + rng.integers(0, 4, (250, 2))])


SEEDED_SCENES = {
    "uniform": scene_uniform,
    "clustered": scene_clustered,
    "mixed_sizes": scene_mixed_sizes,
    "few_huge_bodies": scene_few_huge_bodies,
    "negative_coordinates": scene_negative_coordinates,
    "far_from_origin": scene_far_from_origin,
    "integer_touching": scene_integer_touching,
}


def hand_scenes() -> dict[str, np.ndarray]:
    rng = np.random.default_rng(7)
    one_point = np.tile([0.3, 0.3, 0.3, 0.3], (120, 1))
    on_split_point = np.tile([5.0, 5.0, 5.0, 5.0], (40, 1))
    points = rng.integers(0, 6, (60, 2)).astype(float)
    return {
        "empty": np.empty((0, 4)),
        "one_body": np.array([[0.0, 0.0, 1.0, 1.0]]),
        "touching_at_an_edge": np.array([[0.0, 0.0, 1.0, 1.0], [1.0, 0.0, 2.0, 1.0]]),
        "touching_at_a_corner": np.array([[0.0, 0.0, 1.0, 1.0], [1.0, 1.0, 2.0, 2.0]]),
        "separated_by_one_ulp": np.array([[0.0, 0.0, 1.0, 1.0], [np.nextafter(1.0, 2.0), 0.0, 2.0, 1.0]]),
        "touching_on_negative_side": np.array([[-2.0, -2.0, -1.0, -1.0], [-1.0, -3.0, 0.0, -2.0]]),
        "identical_boxes": np.tile([2.0, 3.0, 4.0, 5.0], (6, 1)),
        "many_bodies_at_one_point": np.vstack([one_point, [[0.0, 0.0, 1.0, 1.0], [2.0, 2.0, 3.0, 3.0]]]),
        "many_points_on_a_splitting_line": np.vstack([on_split_point, [[0.0, 0.0, 10.0, 10.0]]]),
        "zero_size_points": np.hstack([points, points]),
        "body_bigger_than_a_cell": np.vstack([
            [[-50.0, -50.0, 50.0, 50.0]],
            boxes_around(rng.uniform(-60, 60, (40, 2)), np.full((40, 2), 1.0)),
        ]),
        "thin_segments": np.array([[0.0, 0.0, 5.0, 0.0], [2.0, -1.0, 2.0, 3.0], [5.0, 0.0, 6.0, 0.0], [7.0, 0.0, 8.0, 0.0]]),
    }


HAND_SCENES = hand_scenes()


@functools.cache
def scene(name: str) -> np.ndarray:
    if name in HAND_SCENES:
        boxes = HAND_SCENES[name]
    else:
        seed = sorted(SEEDED_SCENES).index(name) + 1000
        boxes = SEEDED_SCENES[name](np.random.default_rng(seed))
    boxes.setflags(write=False)
    return boxes


@functools.cache
def oracle(name: str) -> frozenset:
    return frozenset(pairs_brute_force(scene(name)))


# ------------------------------------------------------------------ implementations
def grid(method: str, factor: float):
    return lambda boxes: pairs_uniform_grid(boxes, suggest_cell_size(boxes) * factor, method)


def quadtree_inside_half_bounds(boxes):
    """Root bounds = the central half of the scene, so many bodies stick out of the root."""
    lo_x, lo_y, hi_x, hi_y = scene_bounds(boxes)
    w, h = hi_x - lo_x, hi_y - lo_y
    bounds = (lo_x + w / 4, lo_y + h / 4, hi_x - w / 4, hi_y - h / 4)
    return pairs_quadtree(boxes, bounds=bounds, max_bodies_per_node=2)


def numpy_grid(**options):
    def run(boxes):
        pairs = pairs_grid_numpy(boxes, **options)
        assert pairs.dtype == np.int64 and pairs.ndim == 2 and pairs.shape[1] == 2
        keys = pairs[:, 0] * max(len(boxes), 1) + pairs[:, 1]
        assert np.all(np.diff(keys) > 0), "rows must be sorted and unique"
        return pairs_as_set(pairs)
    return run


def numpy_grid_factor(factor: float, **options):
    def run(boxes):
        return numpy_grid(cell_size=suggest_cell_size(boxes) * factor, **options)(boxes)
    return run


IMPLEMENTATIONS = {
    "brute_numpy": pairs_brute_force_numpy,
    "brute_numpy_tiny_blocks": lambda boxes: pairs_brute_force_numpy(boxes, block_elements=7),
    "grid_every_cell_x0.3": grid("every_cell", 0.3),
    "grid_every_cell_x1": grid("every_cell", 1.0),
    "grid_every_cell_x3.7": grid("every_cell", 3.7),
    "grid_center_cell_x0.3": grid("center_cell", 0.3),
    "grid_center_cell_x1": grid("center_cell", 1.0),
    "grid_center_cell_x3.7": grid("center_cell", 3.7),
    "quadtree_default": pairs_quadtree,
    "quadtree_1_per_node": lambda boxes: pairs_quadtree(boxes, max_bodies_per_node=1),
    "quadtree_max_depth_3": lambda boxes: pairs_quadtree(boxes, max_bodies_per_node=2, max_depth=3),
    "quadtree_min_area": lambda boxes: pairs_quadtree(
        boxes, max_bodies_per_node=1, min_node_area=4 * suggest_cell_size(boxes) ** 2),
    "quadtree_root_smaller_than_scene": quadtree_inside_half_bounds,
    "numpy_grid_default": numpy_grid(),
    "numpy_grid_x0.3": numpy_grid_factor(0.3),
    "numpy_grid_x3.7": numpy_grid_factor(3.7),
    "numpy_grid_one_strip_per_body": numpy_grid(max_strips_per_body=1),
    "numpy_grid_chunks_of_5": numpy_grid(max_candidates_per_chunk=5),
    "numpy_grid_one_strip": numpy_grid(cell_size=1e7),
}

ALL_SCENES = sorted(SEEDED_SCENES) + sorted(HAND_SCENES)


@pytest.mark.parametrize("scene_name", ALL_SCENES)
@pytest.mark.parametrize("implementation", sorted(IMPLEMENTATIONS))
def test_matches_brute_force(implementation, scene_name):
    got = IMPLEMENTATIONS[implementation](scene(scene_name))
    want = oracle(scene_name)
    assert all(type(i) is int and type(j) is int and i < j for i, j in got)
    assert got == want, (f"missing {sorted(want - got)[:5]}, extra {sorted(got - want)[:5]} "
                         f"({len(got)} pairs, want {len(want)})")


def test_scenes_are_not_trivial():
    # The seeded scenes must exercise the code: pairs exist but are a small fraction.
    for name in SEEDED_SCENES:
        n = len(scene(name))
        assert 50 < len(oracle(name)) < n * (n - 1) / 20, name
    touching = scene("integer_touching")
    exact_touches = sum(
        1 for i, j in oracle("integer_touching")
        if touching[i, 2] == touching[j, 0] or touching[j, 2] == touching[i, 0]
        or touching[i, 3] == touching[j, 1] or touching[j, 3] == touching[i, 1])
    assert exact_touches > 50


# ------------------------------------------------------------------------- the oracle
@pytest.mark.parametrize("name, want", [
    ("empty", set()),
    ("one_body", set()),
    ("touching_at_an_edge", {(0, 1)}),
    ("touching_at_a_corner", {(0, 1)}),
    ("separated_by_one_ulp", set()),
    ("touching_on_negative_side", {(0, 1)}),
    ("identical_boxes", {(i, j) for i in range(6) for j in range(i + 1, 6)}),
    ("thin_segments", {(0, 1), (0, 2)}),
])
def test_oracle_on_cases_known_by_hand(name, want):
    assert pairs_brute_force(scene(name)) == want


def test_aabbs_overlap_is_symmetric_and_closed():
    a, b = [0.0, 0.0, 1.0, 1.0], [1.0, -1.0, 2.0, 0.0]   # share the corner (1, 0)
    assert aabbs_overlap(a, b) and aabbs_overlap(b, a)
    assert not aabbs_overlap(a, [1.0, -1.0, 2.0, -1e-12])


def test_many_points_at_one_place_are_all_pairs():
    pairs = pairs_brute_force(scene("many_bodies_at_one_point"))
    assert len(pairs) == 120 * 119 // 2 + 120   # the points, and each point inside box 120


# -------------------------------------------------------------- numpy output format
def test_numpy_grid_output_is_sorted_unique_and_ordered():
    boxes = scene("integer_touching")
    pairs = pairs_grid_numpy(boxes, 1.0)
    assert pairs.dtype == np.int64 and pairs.shape == (len(oracle("integer_touching")), 2)
    assert np.all(pairs[:, 0] < pairs[:, 1])
    keys = pairs[:, 0] * len(boxes) + pairs[:, 1]
    assert np.all(np.diff(keys) > 0)   # strictly increasing: sorted lexicographically, no duplicates


@pytest.mark.parametrize("n", [0, 1])
def test_numpy_grid_empty_results_have_shape_0_2(n):
    pairs = pairs_grid_numpy(np.tile([0.0, 0.0, 1.0, 1.0], (n, 1)))
    assert pairs.shape == (0, 2) and pairs.dtype == np.int64


def test_numpy_grid_ranked_strips(monkeypatch):
    # Strip indices ~1e12 apart, then a tiny key limit: strips numbered by rank.
    rng = np.random.default_rng(3)
    corners = rng.integers(-10, 10, (200, 2)).astype(float) * 1e11
    sizes = rng.integers(0, 4, (200, 2)).astype(float)
    sizes[::3] *= 1e11
    boxes = np.hstack([corners, corners + sizes])
    want = pairs_brute_force(boxes)
    assert len(want) > 20
    assert pairs_as_set(pairs_grid_numpy(boxes, 1.0)) == want
    monkeypatch.setattr(sorted_grid_numpy, "KEY_LIMIT", 1)
    assert pairs_as_set(pairs_grid_numpy(boxes, 1.0)) == want
    assert pairs_as_set(pairs_grid_numpy(scene("integer_touching"), 1.0)) == oracle("integer_touching")


def test_pairs_as_set():
    assert pairs_as_set(np.array([[0, 3], [1, 2]])) == {(0, 3), (1, 2)}
    assert pairs_as_set(np.empty((0, 2), dtype=np.int64)) == set()


# ------------------------------------------------------------------ memory bounds
def peak_bytes(function, *args, **kwargs) -> int:
    tracemalloc.start()
    try:
        function(*args, **kwargs)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_brute_force_numpy_memory_is_blocked():
    boxes = scene_uniform(np.random.default_rng(5))
    boxes = np.vstack([boxes + [k * 40, 0, k * 40, 0] for k in range(10)])   # 3000 boxes
    # A full N x N boolean matrix would be 9 MB; blocks of 2**16 comparisons stay tiny.
    assert peak_bytes(pairs_brute_force_numpy, boxes, block_elements=2**16) < 2_000_000


def test_numpy_grid_memory_is_chunked_when_everything_shares_a_strip():
    boxes = boxes_around(np.random.default_rng(6).uniform(0, 1, (3000, 2)) * [0.001, 1], np.full((3000, 2), 0.01))
    # 3000 bodies in one strip, all overlapping along x: 4.5 million candidates
    # (over 100 MB if materialised at once).
    peak = peak_bytes(pairs_grid_numpy, boxes, cell_size=100.0)
    assert peak < 15_000_000
    assert pairs_as_set(pairs_grid_numpy(boxes, cell_size=100.0)) == pairs_brute_force_numpy(boxes)


# ------------------------------------------------------------------ hypothesis
coordinate = st.integers(-6, 6).map(lambda v: v / 2)
extent = st.integers(0, 8).map(lambda v: v / 2)
small_boxes = st.lists(st.tuples(coordinate, coordinate, extent, extent), max_size=30).map(
    lambda rows: np.array([[x, y, x + w, y + h] for x, y, w, h in rows], dtype=float).reshape(-1, 4))


@settings(max_examples=60, deadline=None)
@given(boxes=small_boxes, cell_size=st.sampled_from([0.5, 1.0, 1.5, 4.0]),
       max_bodies=st.integers(1, 4), max_depth=st.integers(0, 6), max_strips=st.integers(1, 9))
def test_property_every_broad_phase_equals_brute_force(boxes, cell_size, max_bodies, max_depth, max_strips):
    want = pairs_brute_force(boxes)
    assert pairs_brute_force_numpy(boxes, block_elements=17) == want
    assert pairs_uniform_grid(boxes, cell_size, "every_cell") == want
    assert pairs_uniform_grid(boxes, cell_size, "center_cell") == want
    tree = Quadtree.from_aabbs(boxes, max_bodies_per_node=max_bodies, max_depth=max_depth)
    tree.check_invariants()
    assert tree.pairs() == want
    assert pairs_quadtree(boxes, bounds=(-1, -1, 2, 2), max_bodies_per_node=max_bodies) == want
    assert pairs_as_set(pairs_grid_numpy(boxes, cell_size, max_strips_per_body=max_strips,
                                         max_candidates_per_chunk=3)) == want


@settings(max_examples=40, deadline=None)
@given(boxes=small_boxes, shift_x=st.integers(-10**4, 10**4), shift_y=st.integers(-10**4, 10**4))
def test_property_translating_the_scene_changes_nothing(boxes, shift_x, shift_y):
    # Shifts by whole metres of half-integer boxes are exact in float64.
    moved = boxes + [shift_x, shift_y, shift_x, shift_y]
    want = pairs_brute_force(boxes)
    assert pairs_brute_force(moved) == want
    assert pairs_uniform_grid(moved, 1.0, "every_cell") == want
    assert pairs_uniform_grid(moved, 1.0, "center_cell") == want
    assert pairs_quadtree(moved, max_bodies_per_node=1) == want
    assert pairs_as_set(pairs_grid_numpy(moved)) == want


@settings(max_examples=30, deadline=None)
@given(boxes=small_boxes, data=st.data())
def test_property_renumbering_bodies_renumbers_pairs(boxes, data):
    order = data.draw(st.permutations(range(len(boxes))))
    renumbered = boxes[list(order)] if len(boxes) else boxes
    new_index = {old: new for new, old in enumerate(order)}
    want = {tuple(sorted((new_index[i], new_index[j]))) for i, j in pairs_brute_force(boxes)}
    assert pairs_as_set(pairs_grid_numpy(renumbered)) == want
    assert pairs_quadtree(renumbered, max_bodies_per_node=1) == want
    assert pairs_uniform_grid(renumbered, 1.0, "center_cell") == want


# ------------------------------------------------------------ quadtree invariants
@pytest.mark.parametrize("scene_name", ALL_SCENES)
@pytest.mark.parametrize("rules", [
    {}, {"max_bodies_per_node": 1}, {"max_bodies_per_node": 2, "max_depth": 3},
    {"max_bodies_per_node": 1, "min_node_area": 20.0},
])
def test_quadtree_invariants_hold(scene_name, rules):
    boxes = scene(scene_name)
    tree = Quadtree.from_aabbs(boxes, **rules)
    tree.check_invariants()
    stored = sorted(index for _, index in tree.stored_bodies())
    assert stored == list(range(len(boxes)))


def test_quadtree_many_bodies_at_one_point_stop_at_max_depth():
    tree = Quadtree((0, 0, 1, 1), max_bodies_per_node=4, max_depth=6)
    for index in range(500):
        tree.insert(index, (0.3, 0.3, 0.3, 0.3))
    tree.check_invariants()
    full_leaf = next(node for node in tree.nodes() if node.bodies)
    assert full_leaf.depth == 6 and len(full_leaf.bodies) == 500
    assert max(node.depth for node in tree.nodes()) == 6
    assert tree.stopping_rule(full_leaf) == RULE_MAX_DEPTH


def test_quadtree_many_bodies_at_one_point_stop_at_min_area():
    tree = Quadtree((0, 0, 1, 1), max_bodies_per_node=4, min_node_area=0.01)
    for index in range(500):
        tree.insert(index, (0.3, 0.3, 0.3, 0.3))
    tree.check_invariants()
    full_leaf = next(node for node in tree.nodes() if node.bodies)
    assert full_leaf.depth == 3   # areas 1, 1/4, 1/16, 1/64; the next would be < 0.01
    assert tree.stopping_rule(full_leaf) == RULE_MIN_AREA


def test_quadtree_of_points_on_a_vertical_line_goes_down():
    # Zero-width data: the root is widened on one side only, so the points do not lie
    # on the root's splitting line and can go down the tree.
    points = np.array([[2.0, y, 2.0, y] for y in np.linspace(0.0, 10.0, 64)])
    assert scene_bounds(points) == (2.0, 0.0, 12.0, 10.0)
    tree = Quadtree.from_aabbs(points, max_bodies_per_node=4)
    tree.check_invariants()
    assert max(node.depth for node, _ in tree.stored_bodies()) >= 3
    assert len(tree.root.bodies) <= 4
    assert tree.pairs() == pairs_brute_force(points) == set()


def test_quadtree_straddling_body_stays_at_inner_node():
    tree = Quadtree((0, 0, 8, 8), max_bodies_per_node=1)
    for index, box in enumerate([(1, 1, 2, 2), (5, 5, 6, 6), (3, 3, 5, 5), (1, 1, 4, 1.5)]):
        tree.insert(index, box)
    tree.check_invariants()
    where = {index: node for node, index in tree.stored_bodies()}
    assert where[2] is tree.root                       # crosses both splitting lines
    assert where[3] is tree.root                       # touches mid_x = 4
    assert where[0].depth == 1 and where[1].depth == 1
    assert tree.pairs() == pairs_brute_force(list(tree.boxes.values())) == {(0, 3), (1, 2)}


def test_quadtree_body_outside_root_bounds_is_kept_at_root_and_tested():
    boxes = np.array([[1, 1, 2, 2], [20, 20, 21, 21], [20.5, 20.5, 22, 22], [-3, 1, 1, 1.5], [7, 7, 8, 8]], float)
    tree = Quadtree.from_aabbs(boxes, bounds=(0, 0, 10, 10), max_bodies_per_node=1)
    tree.check_invariants()
    where = {index: node for node, index in tree.stored_bodies()}
    assert where[1] is tree.root and where[2] is tree.root and where[3] is tree.root
    assert tree.pairs() == pairs_brute_force(boxes) == {(0, 3), (1, 2)}


def broken(mutate):
    tree = Quadtree.from_aabbs(scene("uniform"), max_bodies_per_node=2)
    tree.check_invariants()
    mutate(tree)
    return tree


def move_first_deep_body_to_a_sibling(tree):
    parent = next(node for node in tree.nodes() if node.children and any(c.bodies for c in node.children))
    source = next(child for child in parent.children if child.bodies)
    target = next(child for child in parent.children if child is not source)
    target.bodies.append(source.bodies.pop())


def overfill_a_leaf(tree):
    leaf = next(node for node in tree.nodes() if node.is_leaf and node.bodies and node.depth < tree.max_depth)
    index = leaf.bodies[0]
    for extra in range(1000, 1005):
        tree.boxes[extra] = tree.boxes[index]
        leaf.bodies.append(extra)


def store_a_body_twice(tree):
    node = next(node for node in tree.nodes() if node.bodies)
    node.bodies.append(node.bodies[0])


def keep_a_fitting_body_at_the_root(tree):
    node, index = next((n, i) for n, i in tree.stored_bodies() if n.depth >= 2)
    node.bodies.remove(index)
    tree.root.bodies.append(index)


@pytest.mark.parametrize("mutate, message", [
    (store_a_body_twice, "stored twice"),
    (move_first_deep_body_to_a_sibling, "not inside"),
    (overfill_a_leaf, "no stopping rule"),
    (keep_a_fitting_body_at_the_root, "fits in a child"),
    (lambda tree: tree.root.children.pop(), "children"),
    (lambda tree: tree.boxes.__setitem__(10**6, (0.0, 0.0, 1.0, 1.0)), "not stored"),
])
def test_quadtree_invariant_check_catches_broken_trees(mutate, message):
    with pytest.raises(AssertionError, match=message):
        broken(mutate).check_invariants()


# ------------------------------------------------------------------ aabb_array
def test_aabb_array_of_world_shapes():
    half_diagonal = np.sqrt(2.0)
    shapes = [
        Circle((1.0, 2.0), 0.5),
        AABB((-1.0, -2.0), (3.0, 0.0)),
        OBB((10.0, 0.0), (1.0, 1.0), np.pi / 4),
        ConvexPolygon([[0.0, 0.0], [4.0, 1.0], [1.0, 3.0]]),
    ]
    want = np.array([
        [0.5, 1.5, 1.5, 2.5],
        [-1.0, -2.0, 3.0, 0.0],
        [10 - half_diagonal, -half_diagonal, 10 + half_diagonal, half_diagonal],
        [0.0, 0.0, 4.0, 3.0],
    ])
    # rtol 0, atol 1e-12: only the rotated box involves rounding (cos and sin of 45 deg).
    np.testing.assert_allclose(aabb_array(shapes), want, rtol=0, atol=1e-12)
    assert aabb_array([]).shape == (0, 4)


# ----------------------------------------------------------------- bad input
BAD_ARRAYS = {
    "three_columns": [[0.0, 0.0, 1.0]],
    "flat_row": [0.0, 0.0, 1.0, 1.0],
    "nan": [[0.0, np.nan, 1.0, 1.0]],
    "infinite": [[0.0, 0.0, np.inf, 1.0]],
    "min_x_above_max_x": [[0.0, 0.0, 1.0, 1.0], [2.0, 0.0, 1.0, 1.0]],
    "min_y_above_max_y": [[0.0, 3.0, 1.0, 1.0]],
    "not_numbers": [["a", "b", "c", "d"]],
}
ENTRY_POINTS = {
    "validate_aabbs": validate_aabbs,
    "pairs_brute_force": pairs_brute_force,
    "pairs_brute_force_numpy": pairs_brute_force_numpy,
    "pairs_uniform_grid_every_cell": lambda boxes: pairs_uniform_grid(boxes, 1.0, "every_cell"),
    "pairs_uniform_grid_center_cell": lambda boxes: pairs_uniform_grid(boxes, 1.0, "center_cell"),
    "suggest_cell_size": suggest_cell_size,
    "pairs_quadtree": pairs_quadtree,
    "pairs_grid_numpy": pairs_grid_numpy,
}


@pytest.mark.parametrize("bad", sorted(BAD_ARRAYS))
@pytest.mark.parametrize("entry_point", sorted(ENTRY_POINTS))
def test_bad_aabb_arrays_raise_value_error(entry_point, bad):
    with pytest.raises(ValueError, match="aabbs"):
        ENTRY_POINTS[entry_point](BAD_ARRAYS[bad])


def test_bad_row_is_named():
    with pytest.raises(ValueError, match="row 1 has min_x > max_x"):
        validate_aabbs(BAD_ARRAYS["min_x_above_max_x"])


@pytest.mark.parametrize("cell_size", [0.0, -1.0, np.nan, np.inf])
def test_bad_cell_size_raises_value_error(cell_size):
    boxes = scene("touching_at_an_edge")
    for method in ("every_cell", "center_cell"):
        with pytest.raises(ValueError, match="cell_size"):
            pairs_uniform_grid(boxes, cell_size, method)
    with pytest.raises(ValueError, match="cell_size"):
        pairs_grid_numpy(boxes, cell_size)


def test_unknown_grid_method_raises_value_error():
    with pytest.raises(ValueError, match="method"):
        pairs_uniform_grid(scene("one_body"), 1.0, "leaves_only")


def test_cell_size_too_small_for_coordinates_raises_value_error():
    with pytest.raises(ValueError, match="too small"):
        pairs_grid_numpy([[1e6, 1e6, 1e6 + 1, 1e6 + 1], [0, 0, 1, 1]], 1e-12)


@pytest.mark.parametrize("options", [
    {"bounds": (0, 0, 0, 1)}, {"bounds": (0, 0, np.nan, 1)}, {"bounds": (0, 0, 1)},
    {"max_bodies_per_node": 0}, {"max_bodies_per_node": 1.5}, {"min_node_area": -1.0},
    {"min_node_area": np.inf}, {"max_depth": -1},
])
def test_bad_quadtree_settings_raise_value_error(options):
    with pytest.raises(ValueError):
        pairs_quadtree(scene("touching_at_an_edge"), **{"bounds": (0, 0, 2, 2), **options})


def test_quadtree_rejects_a_reused_index_and_a_bad_box():
    tree = Quadtree((0, 0, 1, 1))
    tree.insert(0, (0.1, 0.1, 0.2, 0.2))
    with pytest.raises(ValueError, match="already"):
        tree.insert(0, (0.5, 0.5, 0.6, 0.6))
    with pytest.raises(ValueError, match="min_x > max_x"):
        tree.insert(1, (0.6, 0.5, 0.5, 0.6))


@pytest.mark.parametrize("boxes", [np.empty((0, 4)), [[1, 1, 1, 1]], [[1, 1, 1, 1]] * 5, [[0, 0, 0, 0], [3, 4, 3, 4]]])
def test_suggest_cell_size_is_always_usable(boxes):
    size = suggest_cell_size(boxes)
    assert np.isfinite(size) and size > 0


# ----------------------------------------------------- student copy (exercises)
EXPECTED_STUBS = {
    "uniform_grid.py": ["pairs_grid_every_cell", "pairs_grid_center_cell"],
    "quadtree.py": ["Quadtree.child_holding", "Quadtree.insert", "Quadtree.split", "Quadtree.pairs"],
    "dynamic_tree.py": ["DynamicTree.best_sibling", "DynamicTree.insert_leaf", "DynamicTree.remove_leaf",
                        "DynamicTree.move", "DynamicTree.pairs"],
}


def test_solution_markers_are_where_expected():
    generator = pytest.importorskip("grader.release.exercises")
    for path in sorted(BROADPHASE_DIR.glob("*.py")):
        _, stubbed = generator.strip_solutions(path.read_text(), f"solutions/broadphase/{path.name}")
        assert stubbed == EXPECTED_STUBS.get(path.name, []), path.name


def test_student_copy_imports_and_raises_not_implemented(tmp_path):
    generator = pytest.importorskip("grader.release.exercises")
    package = f"exercises_probe_{uuid.uuid4().hex[:8]}"
    shutil.copytree(SOLUTIONS_DIR, tmp_path / package, ignore=shutil.ignore_patterns("__pycache__"))
    for path in (tmp_path / package / "broadphase").glob("*.py"):
        path.write_text(generator.strip_solutions(path.read_text())[0])
    sys.path.insert(0, str(tmp_path))
    try:
        student = importlib.import_module(f"{package}.broadphase")
        boxes = scene("touching_at_an_edge")
        tree = student.Quadtree((0, 0, 1, 1), max_bodies_per_node=2)
        for marked in (lambda: student.pairs_uniform_grid(boxes, 1.0, "every_cell"),
                       lambda: student.pairs_uniform_grid(boxes, 1.0, "center_cell"),
                       lambda: student.pairs_quadtree(boxes),
                       lambda: tree.insert(0, (0.1, 0.1, 0.2, 0.2)),
                       lambda: tree.split(tree.root),
                       lambda: tree.child_holding(tree.root, (0.1, 0.1, 0.2, 0.2)),
                       lambda: tree.pairs()):
            with pytest.raises(NotImplementedError):
                marked()
        # The unmarked parts still work in the student copy.
        assert tree.root.is_leaf and tree.stopping_rule(tree.root) == "few_bodies"
        assert student.pairs_brute_force(boxes) == {(0, 1)}
        assert student.pairs_as_set(student.pairs_grid_numpy(boxes)) == {(0, 1)}
        with pytest.raises(ValueError):
            student.pairs_uniform_grid(boxes, 0.0)
    finally:
        sys.path.remove(str(tmp_path))
        for name in [m for m in sys.modules if m.startswith(package)]:
            del sys.modules[name]
