"""Checks of the quadtree against brute force, on the cases the notes worry about."""
from __future__ import annotations

import numpy as np
from hypothesis import strategies as st

from solutions.broadphase.brute_force import pairs_brute_force

from ..compare import pairs as compare_pairs
from ..outcome import Outcome
from . import check
from .cases import clustered_aabbs, random_aabbs
from .grid import pairs_figure
from .shrink import smallest_failure

MODULE = "broadphase.quadtree"
FUNCTION = "pairs_quadtree"

small_scenes = st.lists(
    st.tuples(st.integers(-8, 7), st.integers(-8, 7), st.integers(1, 8), st.integers(1, 8)).map(
        lambda t: [t[0] / 2, t[1] / 2, t[0] / 2 + t[2] / 4, t[1] / 2 + t[3] / 4]),
    min_size=2, max_size=10)


def compare_quadtree(student, scenes: list[tuple[np.ndarray, dict]], label: str) -> Outcome:
    """Run pairs_quadtree(aabbs, **options) on each scene; shrink the first failure."""
    answers = [student.call(MODULE, FUNCTION, aabbs, options.get("bounds"), options.get("max_bodies_per_node", 2))
               for aabbs, options in scenes]
    wrong = [(aabbs, options) for (aabbs, options), answer in zip(scenes, answers)
             if compare_pairs(answer, pairs_brute_force(aabbs))[0] is not None]
    if not wrong:
        return Outcome.passed(f"{len(scenes)} scenes agree with brute force")
    aabbs, options = wrong[0]
    bounds = options.get("bounds")
    message, missed, extra = compare_pairs(
        student.call(MODULE, FUNCTION, aabbs, bounds, options.get("max_bodies_per_node", 2)), pairs_brute_force(aabbs))

    def is_wrong(boxes):
        boxes = np.array(boxes, dtype=float)
        got = student.call(MODULE, FUNCTION, boxes, bounds, 1)
        return compare_pairs(got, pairs_brute_force(boxes))[0] is not None

    small = smallest_failure(small_scenes, is_wrong)
    if small is not None:
        aabbs = np.array(small, dtype=float)
        message, missed, extra = compare_pairs(student.call(MODULE, FUNCTION, aabbs, bounds, 1),
                                               pairs_brute_force(aabbs))
    figure = pairs_figure(aabbs, missed, extra, 0.0, f"{FUNCTION}: {label}")
    figure["bounds"] = bounds
    return Outcome.failed(f"{label}: {len(wrong)} of {len(scenes)} scenes wrong, e.g. ({len(aabbs)} boxes) {message}",
                          figure, fraction=1 - len(wrong) / len(scenes))


@check("quadtree.random")
def random_scenes(student):
    rng = np.random.default_rng(201)
    scenes = [(random_aabbs(rng, 80, world=30.0), {"max_bodies_per_node": 2}) for _ in range(3)]
    scenes += [(clustered_aabbs(rng, 80), {"max_bodies_per_node": 4})]
    return compare_quadtree(student, scenes, "random boxes")


@check("quadtree.straddling")
def straddling(student):
    # Bodies lying across the root's and the quarters' splitting lines stay at inner
    # nodes and must still meet the bodies below them (erratum 5).
    bounds = (0.0, 0.0, 16.0, 16.0)
    boxes = [[7.5, 2, 8.5, 3], [7.0, 2.2, 7.6, 2.8], [8.4, 2.4, 9.0, 2.6], [2, 7.5, 3, 8.5], [2.2, 8.4, 2.8, 9.5],
             [7.6, 7.6, 8.4, 8.4], [7.0, 7.0, 7.7, 7.7], [8.3, 8.3, 9.0, 9.0], [3.5, 3.5, 4.5, 4.5], [4.4, 3.0, 5.0, 3.8],
             [11.5, 11.5, 12.5, 12.5], [12.4, 12.4, 13.0, 13.0], [1, 1, 1.5, 1.5], [14, 14, 14.5, 14.5]]
    return compare_quadtree(student, [(np.array(boxes), {"bounds": bounds, "max_bodies_per_node": 1})],
                            "bodies across splitting lines")


@check("quadtree.many_at_one_point")
def many_at_one_point(student):
    # 40 identical boxes: no split can separate them; a stopping rule must end the splitting.
    boxes = np.tile([[3.0, 3.0, 3.5, 3.5]], (40, 1))
    boxes = np.vstack([boxes, [[0, 0, 1, 1], [9, 9, 10, 10]]])
    return compare_quadtree(student, [(boxes, {"bounds": (0.0, 0.0, 10.0, 10.0), "max_bodies_per_node": 2})],
                            "40 boxes at one point")


@check("quadtree.outside_root")
def outside_root(student):
    rng = np.random.default_rng(204)
    inside = random_aabbs(rng, 30, world=8.0, origin=(5.0, 5.0))
    outside = np.array([[-3, 4, -0.5, 6], [9.5, 9.5, 12, 12], [4, -2, 6, 0.2], [20, 20, 21, 21]], dtype=float)
    boxes = np.vstack([inside, outside])
    return compare_quadtree(student, [(boxes, {"bounds": (0.0, 0.0, 10.0, 10.0), "max_bodies_per_node": 2})],
                            "bodies outside the root's bounds")
