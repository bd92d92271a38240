"""Checks of the uniform grid: both variants of the notes against brute force."""
from __future__ import annotations

import numpy as np
from hypothesis import strategies as st

from solutions.broadphase.brute_force import pairs_brute_force
from solutions.broadphase.uniform_grid import suggest_cell_size

from ..compare import pairs as compare_pairs
from ..outcome import Outcome
from . import check
from .cases import clustered_aabbs, random_aabbs
from .shrink import smallest_failure

MODULE = "broadphase.uniform_grid"
EVERY_CELL = "pairs_grid_every_cell"
TIMED_REPEATS = 3
CENTER_CELL = "pairs_grid_center_cell"

small_scenes = st.lists(
    st.tuples(st.integers(-6, 6), st.integers(-6, 6), st.integers(1, 6), st.integers(1, 6)).map(
        lambda t: [t[0] / 2, t[1] / 2, t[0] / 2 + t[2] / 2, t[1] / 2 + t[3] / 2]),
    min_size=2, max_size=8)


def pairs_figure(aabbs: np.ndarray, missed: set, extra: set, cell_size: float, title: str) -> dict:
    return {"kind": "pairs", "title": title, "aabbs": np.asarray(aabbs).tolist(), "cell_size": cell_size,
            "missed": sorted(missed), "extra": sorted(extra)}


def compare_on_scenes(student, function: str, scenes: list[tuple[np.ndarray, float]], label: str) -> Outcome:
    """Run ``function`` on every (aabbs, cell_size) scene; shrink the first failure."""
    answers = student.call_many(MODULE, function, [(aabbs, cell) for aabbs, cell in scenes])
    wrong = [(aabbs, cell) for (aabbs, cell), answer in zip(scenes, answers)
             if compare_pairs(answer, pairs_brute_force(aabbs))[0] is not None]
    if not wrong:
        return Outcome.passed(f"{len(scenes)} scenes agree with brute force")
    aabbs, cell = wrong[0]
    message, missed, extra = compare_pairs(student.call(MODULE, function, aabbs, cell), pairs_brute_force(aabbs))

    def is_wrong(boxes):
        boxes = np.array(boxes, dtype=float)
        return compare_pairs(student.call(MODULE, function, boxes, cell), pairs_brute_force(boxes))[0] is not None

    small = smallest_failure(small_scenes, is_wrong)
    if small is not None:
        small = np.array(small, dtype=float)
        message, missed, extra = compare_pairs(student.call(MODULE, function, small, cell), pairs_brute_force(small))
        aabbs = small
    where = f"{len(aabbs)} boxes, cell size {cell:g} m"
    return Outcome.failed(f"{label}: {len(wrong)} of {len(scenes)} scenes wrong, e.g. ({where}) {message}",
                          pairs_figure(aabbs, missed, extra, cell, f"{function}: {label}"),
                          fraction=1 - len(wrong) / len(scenes))


def uniform_scenes(seed: int, count: int = 60, scenes: int = 5) -> list[tuple[np.ndarray, float]]:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(scenes):
        aabbs = random_aabbs(rng, count, world=30.0)
        out.append((aabbs, suggest_cell_size(aabbs)))
    return out


@check("grid.every_cell.random")
def every_cell_random(student):
    return compare_on_scenes(student, EVERY_CELL, uniform_scenes(101), "random boxes")


@check("grid.every_cell.negative_coordinates")
def every_cell_negative(student):
    rng = np.random.default_rng(102)
    scenes = [(random_aabbs(rng, 50, world=20.0, origin=(-40.0, -25.0)), 2.0) for _ in range(3)]
    return compare_on_scenes(student, EVERY_CELL, scenes, "boxes at negative coordinates")


@check("grid.every_cell.touching")
def every_cell_touching(student):
    # Boxes whose edges lie exactly on cell lines and touch their neighbours.
    boxes = np.array([[0, 0, 1, 1], [1, 0, 2, 1], [2, 1, 3, 2], [-1, -1, 0, 0], [5, 5, 6, 6], [4, 4, 5, 5]], dtype=float)
    return compare_on_scenes(student, EVERY_CELL, [(boxes, 1.0)], "boxes touching exactly on cell lines")


@check("grid.center_cell.random")
def center_cell_random(student):
    return compare_on_scenes(student, CENTER_CELL, uniform_scenes(103), "random boxes")


@check("grid.center_cell.large_bodies")
def center_cell_large(student):
    # Boxes up to three cells wide: partners sit several cells away from a centre.
    rng = np.random.default_rng(104)
    scenes = []
    for _ in range(4):
        aabbs = random_aabbs(rng, 40, world=20.0, size=6.0)
        scenes.append((aabbs, 2.0))
    return compare_on_scenes(student, CENTER_CELL, scenes, "boxes larger than a cell")


@check("grid.center_cell.clustered")
def center_cell_clustered(student):
    rng = np.random.default_rng(105)
    scenes = [(clustered_aabbs(rng, 80), 1.5) for _ in range(3)]
    return compare_on_scenes(student, CENTER_CELL, scenes, "clustered boxes")


@check("grid.speed")
def grid_speed(student, reference=None):
    """Time on a 3000-box scene, against the reference in the same run (leaderboard).

    Both sides first run a tiny scene untimed (imports and first-call costs), then the
    timed call repeats the work ``TIMED_REPEATS`` times inside the worker.
    """
    rng = np.random.default_rng(106)
    aabbs = random_aabbs(rng, 3000, world=150.0)
    cell = suggest_cell_size(aabbs)
    warm_up = aabbs[:10]
    student.value_of(student.raw(MODULE, EVERY_CELL, warm_up, cell), f"{MODULE}.{EVERY_CELL}")
    result = student.raw(MODULE, EVERY_CELL, aabbs, cell, timeout=30.0, repeat=TIMED_REPEATS)
    value = student.value_of(result, f"{MODULE}.{EVERY_CELL}")
    message, missed, extra = compare_pairs(value, pairs_brute_force(aabbs))
    metrics = {"seconds": result.elapsed / TIMED_REPEATS, "missed_pairs": len(missed), "extra_pairs": len(extra)}
    if reference is not None:
        reference.raw(MODULE, EVERY_CELL, warm_up, cell)
        ref = reference.raw(MODULE, EVERY_CELL, aabbs, cell, timeout=30.0, repeat=TIMED_REPEATS)
        metrics["reference_seconds"] = ref.elapsed / TIMED_REPEATS
    if message:
        return Outcome.failed(f"3000 random boxes: {message}", **metrics)
    return Outcome.passed(f"3000 boxes in {metrics['seconds'] * 1e3:.1f} ms", **metrics)
