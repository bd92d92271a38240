"""Mutation testing of the graded tests (tools/mutation.py): mutants come from the
solution blocks only, are graded like submissions, and the scores leave out the
reviewed equivalent mutants."""
from __future__ import annotations

import multiprocessing.util
import tempfile
import tomllib

import pytest

from grader.harness.spec import TestSpec as GradedTest
from tools import mutation, mutation_scope

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


def test_mutants_are_found_in_solution_blocks_graded_and_an_interrupted_run_leaves_nothing(tmp_path, monkeypatch):
    session, temporary = tmp_path / "session", tmp_path / "temporary"
    session.mkdir()
    temporary.mkdir()
    mutants = mutation.find_mutants(session / "session.sqlite", {"momentum"})
    assert mutants and {m.exercise for m in mutants} == {"momentum"}
    assert all(any(a <= m.line <= b for a, b in mutation.solution_lines(mutation.SOLUTIONS / m.module))
               for m in mutants)
    # A mutant that changes the restitution law is killed by the public tests; the run is
    # interrupted (Ctrl-C) while the worker grades the next one: its folders are gone.
    chosen = next(m for m in mutants if "1.0 + e" in m.diff and m.operator.endswith("ReplaceBinaryOperator_Add_Sub"))
    graded = []

    def interrupt(mutant, done, total):
        graded.append(mutant)
        assert any(temporary.iterdir())  # the workers' copies are there while it runs
        raise KeyboardInterrupt

    multiprocessing.util.get_temp_dir()  # the process's own (its forkserver's socket), removed at its exit
    monkeypatch.setattr(tempfile, "tempdir", str(temporary))
    with pytest.raises(KeyboardInterrupt):
        mutation.run_mutants([chosen, mutants[-1]], 1, interrupt)
    assert graded[0].killed_by == "public" and graded[0].test.startswith("momentum.")
    assert list(temporary.iterdir()) == []


def test_a_module_is_seen_by_the_test_files_naming_what_imports_it():
    public, hidden = mutation_scope.GRADER / "tests" / "public", mutation_scope.GRADER / "tests" / "hidden"
    assert mutation_scope.module_name("broadphase/dynamic_tree.py") == "broadphase.dynamic_tree"
    assert mutation_scope.module_name("broadphase/__init__.py") == "broadphase"
    graph = mutation_scope.import_graph()
    assert {"broadphase", "broadphase.aabb_array", "broadphase.brute_force"} <= graph["broadphase.dynamic_tree"]
    # The hidden file names the module through the public one it imports.
    assert mutation_scope.sees(hidden / "test_dynamic_tree.py", "broadphase.dynamic_tree")
    # polygon_polygon imports projection: the contacts tests can run a mutant of it.
    assert mutation_scope.sees(public / "test_contacts.py", "narrowphase.projection")
    assert not mutation_scope.sees(public / "test_momentum.py", "broadphase.dynamic_tree")
    assert not mutation_scope.sees(public / "test_dynamic_tree.py", "solver.contact_point")


def test_a_mutant_is_graded_by_its_exercise_then_the_tests_seeing_it():
    def spec(name, path, visibility="visible"):
        folder = "public" if visibility == "visible" else "hidden"
        return GradedTest(name, name.split(".")[0], name, 1.0, visibility,
                        path=str(mutation_scope.GRADER / "tests" / folder / path))

    tests = [spec("sat.a", "test_sat.py"), spec("contacts.b", "test_contacts.py"),
             spec("momentum.c", "test_momentum.py"), spec("sat.d", "test_sat.py", "hidden"),
             spec("contacts.e", "test_contacts.py", "hidden")]
    groups = mutation_scope.tests_seeing("narrowphase/projection.py", "sat", tests)
    assert [(suite, [t.name for t in chosen]) for suite, chosen in groups] == [
        ("public", ["sat.a"]), ("public", ["contacts.b"]), ("hidden", ["sat.d"]), ("hidden", ["contacts.e"])]
    every = mutation_scope.tests_seeing("narrowphase/projection.py", "sat", tests, every=True)
    assert [t.name for _, chosen in every for t in chosen] == ["sat.a", "contacts.b", "momentum.c", "sat.d",
                                                               "contacts.e"]


def test_only_a_test_that_ran_and_did_not_pass_kills_a_mutant():
    from types import SimpleNamespace as Result

    tests = [Result(name=name) for name in "abc"]
    calls = []

    def run_tests(workspace, chosen, limits, **options):
        """a passes; the budget leaves b and c unstarted, then b passes and c fails."""
        calls.append([t.name for t in chosen])
        status = {"a": "passed", "b": "not_run" if len(calls) == 1 else "passed",
                  "c": "not_run" if len(calls) == 1 else "failed"}
        return [Result(test=t, outcome=Result(status=status[t.name])) for t in chosen]

    failing = mutation._first_failure(run_tests, tests, None)
    assert failing.test.name == "c" and failing.outcome.status == "failed"
    assert calls == [["a", "b", "c"], ["b", "c"]]
    assert mutation._first_failure(lambda *a, **k: [Result(test=t, outcome=Result(status="passed"))
                                                    for t in a[1]], tests, None) is None
