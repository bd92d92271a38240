"""The bundled example class: every sample scores what its bug deserves, and no more.

The reference and the stubs are graded with every test (public and hidden) in the
sandbox, as ``grader grade`` would: the reference gets full marks, the stubs zero with
every test "not implemented".  Each buggy sample fails exactly the tests its bug should
fail, each losing at least half its points (a systematic bug must, see
:mod:`grader.harness.credit`), except the tests it lists as weak, which lose some but less.

The reference is graded as the probe (:func:`grader.samples.example_class.grade_probe`): the
reference with each exercise function printing its code when it runs, which changes no
answer, graded once per test run and shared by the xdist workers.  Besides full marks
it tells which exercise functions each graded test reaches.  A buggy sample is graded
with the tests that reach the functions it rewrites; every other test runs the
reference's code on the sample, with the same inputs, and so passes there as it does
on the reference.  One test per sample, so pytest-xdist spreads them.
"""
import ast
import fcntl
import filecmp
import json
import os
from pathlib import Path

import pytest

from grader.samples.example_class import (ABOUT_FILE, BUGGY_SAMPLES, ERRATA, EXERCISES_DIR, PACKAGE, PROBE_HELPER,
                                  PROBE_SAMPLE, SOLUTIONS_DIR, BuggySample, ExampleClassError, Replacement,
                                  build_buggy_sample, build_example_class, build_probe, exercise_functions_flat,
                                  find_function, grade_probe, minimum_points_lost, points_lost, reaching_tests,
                                  sample_functions, sample_problems)
from grader.harness.outcome import STATUSES, Outcome
from grader.harness import plugin, spec
from grader.harness.run import run_tests
from grader.harness.spec import EXERCISES
from grader.harness.run import load_spec

#: At least this many buggy samples, covering every exercise.
MIN_SAMPLES = 25


def sandbox_slot() -> int:
    """A sandbox user per xdist worker (gw0 -> 20, gw1 -> 21...), so parallel workers
    do not share one process limit."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "gw0")
    return 20 + int(worker[2:]) if worker[2:].isdigit() else 20


@pytest.fixture(scope="session")
def all_tests():
    return load_spec()


@pytest.fixture(scope="module")
def example_class(tmp_path_factory) -> dict[str, Path]:
    folders = build_example_class(tmp_path_factory.mktemp("example-class"))
    return {folder.name: folder for folder in folders}


@pytest.fixture(scope="session")
def probe(tmp_path_factory, all_tests) -> dict:
    """The probe graded with every test, once per test run: ``{"reached": {test:
    [functions] or None}, "outcomes": {test: [status, score, message]}}``.

    Under xdist the workers share one grading (a file under the run's common temporary
    folder, named after the run's id, written under a lock by the first worker that
    needs it)."""
    def measure() -> dict:
        reached, results = grade_probe(all_tests, tmp_path_factory.mktemp("probe"), slot=sandbox_slot())
        return {"reached": {name: None if found is None else sorted(found) for name, found in reached.items()},
                "outcomes": {r.test.name: [r.outcome.status, r.score, r.outcome.message[:500]] for r in results}}

    run = os.environ.get("PYTEST_XDIST_TESTRUNUID")
    if run is None:
        return measure()
    shared = tmp_path_factory.getbasetemp().parent
    path = shared / f"example-class-probe-{run}.json"
    with open(shared / f"example-class-probe-{run}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not path.is_file():
            path.write_text(json.dumps(measure()))
        return json.loads(path.read_text())


@pytest.fixture(scope="session")
def reached(probe) -> dict[str, frozenset[str] | None]:
    """Which exercise functions each graded test reaches, as the probe saw."""
    return {name: None if found is None else frozenset(found) for name, found in probe["reached"].items()}


def grade(folder: Path, tests) -> dict:
    return {result.test.name: result for result in run_tests(folder, tests, slot=sandbox_slot())}


def describe(results: dict) -> str:
    return "\n".join(f"  {name}: {r.outcome.status} ({r.score:.4g} of {r.test.points:g}): {r.outcome.message[:200]}"
                     for name, r in results.items())


class WithoutProbe(ast.NodeTransformer):
    """A probe module's tree without what the probe adds: the helper and its calls."""

    def visit_Expr(self, node):
        call = node.value
        named = isinstance(call, ast.Call) and isinstance(call.func, ast.Name) and call.func.id == PROBE_HELPER
        return None if named else node

    def visit_FunctionDef(self, node):
        return None if node.name == PROBE_HELPER else self.generic_visit(node)


def test_the_probe_is_the_reference_printing(example_class, tmp_path):
    # Built from the reference sample of the same build, not from solutions/, which may
    # be edited while the tests run.
    reference = example_class["reference"] / PACKAGE
    folder, codes = build_probe(tmp_path, reference)
    assert folder.name == PROBE_SAMPLE and sorted(codes.values()) == sorted(exercise_functions_flat(reference))
    package = folder / PACKAGE
    assert sorted(p.relative_to(package) for p in package.rglob("*")) == \
        sorted(p.relative_to(reference) for p in reference.rglob("*"))
    instrumented = 0
    for path in reference.rglob("*.py"):
        copy = package / path.relative_to(reference)
        if filecmp.cmp(path, copy, shallow=False):
            continue
        instrumented += copy.read_text().count(f"{PROBE_HELPER}(") - 1
        assert ast.dump(WithoutProbe().visit(ast.parse(copy.read_text()))) == ast.dump(ast.parse(path.read_text())), \
            f"{copy}: the probe changes more than its print statements"
    assert instrumented == len(codes), "one print statement per exercise function"


def test_reference_gets_full_marks(probe, all_tests):
    # Graded as the probe: the reference with print statements, nothing else changed
    # (test_the_probe_is_the_reference_printing).
    outcomes = probe["outcomes"]
    assert set(outcomes) == {t.name for t in all_tests}
    not_passed = {name: outcome for name, outcome in outcomes.items() if outcome[0] != "passed"}
    assert not not_passed, "the reference fails:\n" + "\n".join(f"  {name}: {status}: {message[:200]}" for
                                                               name, (status, _, message) in not_passed.items())
    assert sum(score for _, score, _ in outcomes.values()) == pytest.approx(sum(t.points for t in all_tests))


def test_stubs_get_zero_and_every_test_says_not_implemented(example_class, all_tests):
    results = grade(example_class["stubs"], all_tests)
    other = {name: r for name, r in results.items() if r.outcome.status != "not_implemented"}
    assert not other, f"stubs should be 'not_implemented' everywhere:\n{describe(other)}"
    assert sum(r.score for r in results.values()) == 0


def test_the_probe_sees_which_functions_each_test_reaches(reached, all_tests):
    assert set(reached) == {t.name for t in all_tests}
    unexplained = sorted(name for name, functions in reached.items() if functions is None)
    assert not unexplained, f"the probe saw no exercise function run in {unexplained}"
    watched = set(exercise_functions_flat())
    assert set().union(*reached.values()) <= watched
    # Called directly, through other exercise functions, and from the scene the
    # sandbox runs itself (not through a student call).
    assert reached["momentum.perfectly_inelastic"] == {"response.momentum_1d.perfectly_inelastic_1d"}
    assert reached["momentum.elastic"] == {"response.momentum_1d.elastic_collision_1d",
                                           "response.momentum_1d.collision_1d"}
    assert {"response.impulse.resolve_collision", "response.positional_correction.correct_positions"} \
        <= reached["impulse.scene"]
    assert "narrowphase.projection.project_vertices" in reached["sat.polygons_overlap_random"]


@pytest.mark.parametrize("sample", BUGGY_SAMPLES, ids=lambda s: s.name)
def test_buggy_sample_fails_exactly_its_tests(sample: BuggySample, example_class, all_tests, reached):
    graded = reaching_tests(sample, reached)
    unreachable = sample.expected_failures - graded
    assert not unreachable, (f"bug {sample.name!r} expects failures of tests that never reach "
                             f"{sorted(sample_functions(sample))}: {sorted(unreachable)}")
    results = grade(example_class[sample.folder_name], [t for t in all_tests if t.name in graded])
    failed = {name for name, r in results.items() if r.outcome.status != "passed"}
    missed = sample.expected_failures - failed
    extra = failed - sample.expected_failures
    assert not missed, f"bug {sample.name!r} is not caught by {sorted(missed)}"
    assert not extra, (f"bug {sample.name!r} also fails tests it should pass:\n"
                       f"{describe({n: results[n] for n in sorted(extra)})}")
    wrong_status = {n: results[n] for n in sample.expected_failures if results[n].outcome.status != sample.status}
    assert not wrong_status, f"expected status {sample.status!r}:\n{describe(wrong_status)}"
    # Tests it should pass keep every point (those not graded here run the reference's
    # code, see the module docstring).  Each test it fails loses at least half its
    # points: all of them, or at least half where the test gives partial credit, which
    # starts at 90 % right cases; a weak test, named as such, loses some but less.
    weak_but_strong, too_little = [], {}
    for name, result in results.items():
        points, score = result.test.points, result.score
        if name not in sample.expected_failures:
            assert score == points, name
        elif name in sample.weak_tests:
            assert score < points, f"{name} failed but lost no points"
            if points - score >= points / 2:
                weak_but_strong.append(f"{name}: {score:.4g} of {points:g}")
        elif points - score < points / 2 - 1e-9:
            too_little[name] = result
    assert not too_little, (f"bug {sample.name!r} loses less than half the points of (a weak test: name it in "
                            f"weak_tests, with its score, or choose another bug):\n{describe(too_little)}")
    assert not weak_but_strong, (f"bug {sample.name!r}: these weak tests now lose at least half their points, "
                                 f"take them out of weak_tests: {weak_but_strong}")
    lost = sum(r.test.points - r.score for r in results.values())
    assert minimum_points_lost(sample, all_tests) <= lost + 1e-9 <= points_lost(sample, all_tests) + 2e-9


def test_sample_problems_name_what_is_wrong():
    """The check ``grader example-class --grade`` prints, on made-up results."""
    def result(name, status="failed", fraction=0.0, points=2.0, partial=True):
        # Imported as modules: pytest would take the classes called Test... for test classes.
        test = spec.TestSpec(name, "sat", name, points, "visible", partial_credit=partial)
        return plugin.TestResult(test, Outcome(status, fraction), 0.0)

    sample = BuggySample("made-up", "nothing", 0, (), frozenset({"sat.a", "sat.b", "sat.c", "sat.d", "sat.e"}),
                         weak_tests=frozenset({"sat.c", "sat.d"}))
    # A failed partial-credit test keeps at most half its points (a quarter at 90 % right
    # cases, 0.375 of them at 95 %): a test listed as weak that fails loses at least half.
    assert sample_problems(sample, [result("sat.a"), result("sat.b", fraction=0.9), result("sat.c", fraction=0.95),
                                    result("sat.d", fraction=0.95), result("sat.e", "error")]) == [
        "sat.c is listed as weak but loses at least half its points (0.75 of 2 left): take it out of weak_tests",
        "sat.d is listed as weak but loses at least half its points (0.75 of 2 left): take it out of weak_tests",
        "sat.e ends 'error', not 'failed': "]
    problems = sample_problems(sample, [result("sat.a", "passed"), result("sat.b", fraction=0.95),
                                        result("sat.c", fraction=0.5), result("sat.x")])
    assert problems[0].startswith("expects sat.d to fail, but sat.d was not graded")
    assert problems[1].startswith("expects sat.e to fail, but sat.e was not graded")
    assert problems[2] == "not caught by sat.a (it passed)"
    assert problems[3].startswith("also fails sat.x: failed")
    assert problems[4].startswith("sat.c is listed as weak but loses at least half its points (0 of 2 left)")
    assert len(problems) == 5   # sat.b at 95 % keeps 0.75 of 2: under half, no problem


def test_samples_are_well_formed(all_tests):
    names = {t.name for t in all_tests}
    exercise_functions = set(exercise_functions_flat())
    assert len({s.name for s in BUGGY_SAMPLES}) == len(BUGGY_SAMPLES) >= MIN_SAMPLES
    assert {s.exercise for s in BUGGY_SAMPLES} == set(EXERCISES), "every exercise has buggy samples"
    for sample in BUGGY_SAMPLES:
        assert sample.expected_failures <= names, f"{sample.name}: unknown tests {sample.expected_failures - names}"
        assert sample.expected_failures, sample.name
        assert sample.weak_tests <= sample.expected_failures, sample.name
        assert sample.mistake.strip(), sample.name
        # An erratum of the notes (COURSE.md lists ERRATA of them), or 0 for a common bug.
        assert isinstance(sample.erratum, int) and 0 <= sample.erratum <= ERRATA, sample.name
        assert sample.status in STATUSES, sample.name
        # Only exercise functions (those holding a solution block) are rewritten: the
        # probe watches them, so the tests that can see the bug are known.
        assert sample_functions(sample) <= exercise_functions, (sample.name, sample_functions(sample))
        assert minimum_points_lost(sample, all_tests) > 0, sample.name


def test_buggy_samples_differ_from_the_reference_only_in_their_functions(example_class):
    # Compared with the reference sample of the same build, not with solutions/, which
    # may be edited while the tests run.
    reference = example_class["reference"] / PACKAGE
    for sample in BUGGY_SAMPLES:
        package = example_class[sample.folder_name] / PACKAGE
        assert sorted(p.relative_to(package) for p in package.rglob("*")) == \
            sorted(p.relative_to(reference) for p in reference.rglob("*"))
        changed = {r.module for r in sample.replacements}
        for path in reference.rglob("*.py"):
            module = ".".join(path.relative_to(reference).with_suffix("").parts)
            copy = package / path.relative_to(reference)
            if module not in changed:
                assert filecmp.cmp(path, copy, shallow=False), f"{sample.name}: {module} should be the reference's"
                continue
            original, buggy = ast.parse(path.read_text()), ast.parse(copy.read_text())
            for replacement in (r for r in sample.replacements if r.module == module):
                old = find_function(original, replacement.qualname)
                new = find_function(buggy, replacement.qualname)
                assert ast.dump(old) != ast.dump(new), f"{sample.name}: {replacement.qualname} is unchanged"
                assert ast.get_docstring(new) == ast.get_docstring(old), "the given docstring is kept"
                assert "BEGIN SOLUTION" not in ast.get_source_segment(copy.read_text(), new)
            text = copy.read_text()
            assert text.count("### BEGIN SOLUTION") == text.count("### END SOLUTION"), "markers stay paired"
        assert (example_class[sample.folder_name] / ABOUT_FILE).is_file()


def test_copies_of_reference_and_stubs(example_class):
    for name, source in (("reference", SOLUTIONS_DIR), ("stubs", EXERCISES_DIR)):
        copy = example_class[name] / PACKAGE
        files = {p.relative_to(source) for p in source.rglob("*.py")}
        assert {p.relative_to(copy) for p in copy.rglob("*.py")} == files
        assert not list(copy.rglob("__pycache__"))


def test_builder_refuses_an_unknown_function(tmp_path):
    bogus = BuggySample("bogus", "nothing", 7, (Replacement("narrowphase.projection", "project_vertexes",
                                                            "def project_vertexes(vertices, axis):\n    pass\n"),),
                        frozenset({"sat.project_vertices"}))
    with pytest.raises(ExampleClassError, match=r"bogus.*no function 'project_vertexes'.*narrowphase.projection"):
        build_buggy_sample(bogus, tmp_path)
    assert not list(tmp_path.iterdir()), "nothing is written for a sample that cannot be built"


@pytest.mark.parametrize("replacement, message", [
    (Replacement("narrowphase.projection", "project_vertices", "def project_vertices(vertices, axis):\n  return (\n"),
     "does not parse"),
    (Replacement("narrowphase.projection", "project_vertices", "def project_circle(vertices, axis):\n    pass\n"),
     "exactly one function called 'project_vertices'"),
    (Replacement("narrowphase.projection", "project_vertices", "def project_vertices(points, axis):\n    pass\n"),
     "keeps the given signature"),
    (Replacement("narrowphase.no_such_module", "f", "def f():\n    pass\n"), "no file"),
    (Replacement("broadphase.quadtree", "Quadtree.no_such_method", "def no_such_method(self):\n    pass\n"),
     "no function 'Quadtree.no_such_method'"),
])
def test_builder_explains_a_broken_sample(tmp_path, replacement, message):
    sample = BuggySample("broken", "nothing", 7, (replacement,), frozenset())
    with pytest.raises(ExampleClassError, match=message):
        build_buggy_sample(sample, tmp_path)


def test_builder_never_deletes_a_folder_it_did_not_write(tmp_path):
    (tmp_path / "reference").mkdir()
    (tmp_path / "reference" / "notes.txt").write_text("mine")
    with pytest.raises(ExampleClassError, match="not a sample written by"):
        build_example_class(tmp_path, samples=())
    assert (tmp_path / "reference" / "notes.txt").read_text() == "mine"


def test_rebuilding_replaces_the_samples(tmp_path):
    first = build_example_class(tmp_path, samples=BUGGY_SAMPLES[:1])
    (first[-1] / PACKAGE / "stale.py").write_text("")
    second = build_example_class(tmp_path, samples=BUGGY_SAMPLES[:1])
    assert [f.name for f in first] == [f.name for f in second] == ["reference", "stubs", BUGGY_SAMPLES[0].folder_name]
    assert not (second[-1] / PACKAGE / "stale.py").exists()
