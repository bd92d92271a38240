"""Hidden tests of the dynamic tree: larger and harder scenes of the public kinds (many
equal boxes, bodies all at one point, long moving runs with teleports, many removals),
sibling choices in larger trees, and tree quality for sorted insertion orders.

Expected answers come from the brute-force and tree oracles; the helpers are the public tests'.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from grader.oracles.random_cases import clustered_aabbs, random_aabbs, resting_piles
from grader.tests.public.test_dynamic_tree import (MARGIN, check_moving, check_pair_scenes, check_quality,
                                                   check_siblings, check_structures, moving_scene)


@pytest.mark.points(2)
@pytest.mark.visibility("after_due_date")
@pytest.mark.title("Dynamic tree: long moving runs")
def test_long_moving(student):
    rng = np.random.default_rng(403)
    scenes = [(moving_scene(rng, 120, 25, 20.0, step), margin) for step, margin in ((0.02, 0.1), (0.15, 0.05))]
    check_moving(student, scenes, "120 boxes over 25 frames")


@pytest.mark.points(2)
@pytest.mark.visibility("after_due_date")
@pytest.mark.title("Dynamic tree: structure after many removals and moves")
def test_structure_large(student):
    rng = np.random.default_rng(404)
    cases = []
    for k in range(3):
        boxes = random_aabbs(rng, 300, world=40.0) if k != 1 else clustered_aabbs(rng, 300)
        removed = rng.choice(300, 150 if k else 299, replace=False).tolist()
        moves = boxes + np.tile(rng.uniform(-0.5, 0.5, (300, 2)), 2)
        cases.append((boxes, MARGIN, removed, moves))
    check_structures(student, cases, "300 boxes")


@pytest.mark.points(1)
@pytest.mark.visibility("after_due_date")
@pytest.mark.title("Dynamic tree: best_sibling in larger trees")
def test_best_sibling_large(student):
    rng = np.random.default_rng(405)
    cases = []
    for _ in range(10):
        boxes = clustered_aabbs(rng, 300) if rng.random() < 0.5 else random_aabbs(rng, 300, world=40.0)
        centre, half = rng.uniform(-25, 25, 2), rng.uniform(0.0, 6.0, 2)
        cases.append((boxes, [*(centre - half), *(centre + half)], MARGIN))
    check_siblings(student, cases, "300 boxes")


@pytest.mark.points(1)
@pytest.mark.visibility("after_due_date")
@pytest.mark.title("Dynamic tree: quality for sorted insertion orders")
def test_quality_sorted(student):
    rng = np.random.default_rng(406)
    boxes = random_aabbs(rng, 800, world=2 * math.sqrt(800))
    check_quality(student, [(boxes[np.argsort(boxes[:, 0])], "sorted by min_x"),
                            (boxes[np.argsort(-boxes[:, 1])], "sorted by min_y, descending")], "tree quality")


@pytest.mark.points(2)
@pytest.mark.visibility("after_due_date")
@pytest.mark.title("Dynamic tree: many equal boxes, points and lines")
def test_degenerate_scenes(student):
    rng = np.random.default_rng(401)
    scenes = [(np.tile([[2.0, 2.0, 3.0, 3.0]], (30, 1)), MARGIN),
              (np.tile([[-1.5, 4.0, -1.5, 4.0]], (25, 1)), 0.0),
              (np.vstack([np.tile([[0.0, 0.0, 0.0, 0.0]], (10, 1)), random_aabbs(rng, 20, world=4.0)]), MARGIN)]
    for _ in range(4):
        ys = np.sort(rng.integers(0, 20, (15, 2)), axis=1) / 2          # on one vertical line
        scenes.append((np.column_stack([np.full(15, 1.5), ys[:, 0], np.full(15, 1.5), ys[:, 1]]), MARGIN))
        grid = rng.integers(0, 6, (30, 2)).astype(float)                 # unit boxes on integer corners: touching
        scenes.append((np.hstack([grid, grid + 1]), 0.0))
    check_pair_scenes(student, scenes, "degenerate scenes")


@pytest.mark.points(2)
@pytest.mark.visibility("after_due_date")
@pytest.mark.partial_credit
@pytest.mark.title("Dynamic tree: larger random scenes")
def test_large_random(student):
    rng = np.random.default_rng(402)
    scenes = [(random_aabbs(rng, 600, world=50.0) if k % 2 else clustered_aabbs(rng, 600), MARGIN) for k in range(6)]
    piles = np.random.default_rng(407)       # resting crates, touching exactly
    scenes += [(resting_piles(piles, 300, origin=piles.integers(-25, 5, 2)), margin) for margin in (MARGIN, 0.0)]
    check_pair_scenes(student, scenes, "600 random boxes, 300 resting crates")
