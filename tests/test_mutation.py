"""Mutation testing of the graded tests (tools/mutation.py): mutants come from the
solution blocks only, are graded like submissions, and the scores leave out the
reviewed equivalent mutants."""
from __future__ import annotations

import tomllib

import pytest

from tools import mutation

pytest.importorskip("cosmic_ray")


def test_solution_lines_are_inside_the_markers():
    path = mutation.SOLUTIONS / "response" / "momentum_1d.py"
    lines = path.read_text().splitlines()
    blocks = mutation.solution_lines(path)
    assert len(blocks) == 3
    for first, last in blocks:
        assert lines[first - 2].strip() == mutation.BEGIN and lines[last].strip() == mutation.END


def test_each_mutated_function_belongs_to_an_exercise():
    assert mutation.exercise_of("narrowphase/polygon_polygon.py", "collide_polygon_polygon") == "contacts"
    assert mutation.exercise_of("narrowphase/polygon_polygon.py", "polygons_overlap") == "sat"
    assert mutation.exercise_of("broadphase/quadtree.py", "Quadtree.split") == "quadtree"


def test_scores_leave_out_equivalent_mutants_and_count_public_kills():
    def mutant(key, killed_by):
        return mutation.Mutant("j", "m.py", "f", "op", 0, 1, "grid", key=key, killed_by=killed_by)

    mutants = [mutant("a", "public"), mutant("b", "hidden"), mutant("c", ""), mutant("d", ""), mutant("e", "none")]
    table = mutation.scores(mutants, {"d": "no input tells it apart"})
    row = table["grid"]
    assert (row["mutants"], row["equivalent"], row["public"], row["all"]) == (4, 1, 1, 2)
    assert row["all_share"] == pytest.approx(2 / 3) and row["public_share"] == pytest.approx(1 / 3)
    assert row["survivors"] == ["c"]


def test_the_equivalent_list_gives_a_reason_for_each_mutant():
    data = tomllib.loads(mutation.EQUIVALENT_FILE.read_text())
    for entry in data.get("mutant", []):
        assert entry["key"] and entry["reason"].strip(), entry


def test_mutants_are_found_in_solution_blocks_and_graded(tmp_path):
    mutants = mutation.find_mutants(tmp_path / "session.sqlite", {"momentum"})
    assert mutants and {m.exercise for m in mutants} == {"momentum"}
    assert all(any(a <= m.line <= b for a, b in mutation.solution_lines(mutation.SOLUTIONS / m.module))
               for m in mutants)
    # A mutant that changes the restitution law is killed by the public tests.
    chosen = next(m for m in mutants if "1.0 + e" in m.diff and m.operator.endswith("ReplaceBinaryOperator_Add_Sub"))
    mutation._start_worker(_Slots())
    graded = mutation.grade_mutant(chosen)
    assert graded.killed_by == "public" and graded.test.startswith("momentum.")


class _Slots:
    def get(self):
        return 30
