"""Issue 24, items 5 and 6: exercises that cannot be bypassed through the library, and
points that follow the harm.

Each test builds a submission the way a determined student would (the reference with
one function rewritten, :mod:`grader.samples.example_class`), grades it with the real
graded tests in a real sandbox, and checks the points and the message.
"""
from __future__ import annotations

import os
from pathlib import Path

import pytest

from grader.harness.run import load_spec, run_tests
from grader.samples.example_class import SOLUTIONS_DIR, BuggySample, Replacement, build_buggy_sample


def sandbox_slot() -> int:
    """A sandbox user per xdist worker (30, 31...), apart from the example class's 20s."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "gw0")
    return 30 + int(worker[2:]) if worker[2:].isdigit() else 30


def graded(tmp_path: Path, replacements: tuple[Replacement, ...], names: set[str]) -> dict:
    """Results by test name of the tests ``names`` on the reference with ``replacements``."""
    sample = BuggySample(name="integrity", mistake="a shortcut", erratum=0, replacements=replacements,
                         expected_failures=frozenset())
    folder = build_buggy_sample(sample, tmp_path, SOLUTIONS_DIR)
    tests = [t for t in load_spec() if t.name in names]
    assert {t.name for t in tests} == names, "a test named here is not in the spec"
    return {r.test.name: r for r in run_tests(folder, tests, slot=sandbox_slot())}


REFUSE_EVERYTHING = tuple(
    Replacement("response.momentum_1d", name, f'''
        def {name}({args}):
            raise ValueError("refused")
        ''') for name, args in (("collision_1d", "m1, v1, m2, v2, restitution"),
                                ("elastic_collision_1d", "m1, v1, m2, v2"),
                                ("perfectly_inelastic_1d", "m1, v1, m2, v2")))


def test_refusing_every_input_does_not_pass_the_test_of_refusals(tmp_path):
    results = graded(tmp_path, REFUSE_EVERYTHING, {"momentum.rejects_bad_input"})
    result = results["momentum.rejects_bad_input"]
    assert result.score == 0, result.outcome.message
    assert "allowed input" in result.outcome.message and "ValueError" in result.outcome.message


BRUTE_FORCE_GRID = tuple(
    Replacement("broadphase.uniform_grid", name, f'''
        def {name}(aabbs, cell_size: float) -> set[tuple[int, int]]:
            return pairs_brute_force_numpy(aabbs)
        ''', imports=("from .brute_force import pairs_brute_force_numpy",))
    for name in ("pairs_grid_every_cell", "pairs_grid_center_cell"))

#: Quadtree.pairs testing every pair of the tree's bodies with numpy (the tree is built).
BRUTE_FORCE_QUADTREE = (Replacement("broadphase.quadtree", "Quadtree.pairs", '''
    def pairs(self) -> set[tuple[int, int]]:
        import numpy as np
        indices = sorted(self.boxes)
        if len(indices) < 2:
            return set()
        boxes = np.array([self.boxes[i] for i in indices], dtype=float)
        hit = ((boxes[:, None, 0] <= boxes[None, :, 2]) & (boxes[None, :, 0] <= boxes[:, None, 2])
               & (boxes[:, None, 1] <= boxes[None, :, 3]) & (boxes[None, :, 1] <= boxes[:, None, 3]))
        first, second = np.nonzero(np.triu(hit, 1))
        return {(indices[a], indices[b]) for a, b in zip(first.tolist(), second.tolist())}
    '''),)


def broadphase_tests(prefix: str, hidden: bool) -> set[str]:
    return {t.name for t in load_spec() if t.name.startswith(prefix) and (hidden or t.public)}


def test_a_grid_that_returns_the_brute_force_earns_nothing_and_is_told_why(tmp_path):
    # On main both functions returning the library's brute force earned 26/26.
    names = broadphase_tests("grid.", hidden=True)
    results = graded(tmp_path, BRUTE_FORCE_GRID, names)
    kept = {name: r.score for name, r in results.items() if r.score}
    assert not kept, kept
    for name, result in results.items():
        assert "brute force" in result.outcome.message and "per box" in result.outcome.message, (
            name, result.outcome.message[:500])


def test_a_quadtree_whose_pairs_test_every_pair_fails_the_pairs_tests(tmp_path):
    names = broadphase_tests("quadtree.", hidden=True)
    results = graded(tmp_path, BRUTE_FORCE_QUADTREE, names)
    structure = {"quadtree.structure", "quadtree.structure_large"}
    assert structure <= set(results)
    for name, result in results.items():
        if name in structure:  # the tree itself is the reference's
            assert result.outcome.status == "passed", (name, result.outcome.message[:500])
        else:
            assert result.score == 0 and "brute force" in result.outcome.message, (name, result.outcome.message[:500])


def test_the_reference_broad_phases_pass_the_algorithm_checks(tmp_path):
    results = graded(tmp_path, (), broadphase_tests("grid.", hidden=False) | broadphase_tests("quadtree.", False))
    failed = {name: r.outcome.message[:300] for name, r in results.items() if r.outcome.status != "passed"}
    assert not failed, failed
