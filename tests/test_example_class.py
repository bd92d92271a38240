"""The bundled example class: every sample scores what its bug deserves, and no more.

Each sample is graded with every test (public and hidden) in the sandbox, as
``grader grade`` would: the reference gets full marks, the stubs zero with every test
"not implemented", and each buggy sample fails exactly the tests its bug should fail,
so it loses exactly their points.  One test per sample, so pytest-xdist spreads them.
"""
import ast
import filecmp
import os
from pathlib import Path

import pytest

from grader.example_class import (ABOUT_FILE, BUGGY_SAMPLES, EXERCISES_DIR, PACKAGE, SOLUTIONS_DIR, BuggySample,
                                  ExampleClassError, Replacement, build_buggy_sample, build_example_class,
                                  find_function, points_lost)
from grader.run import run_tests
from grader.spec import load_spec


def sandbox_slot() -> int:
    """A sandbox user per xdist worker (gw0 -> 20, gw1 -> 21...), so parallel workers
    do not share one process limit."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "gw0")
    return 20 + int(worker[2:]) if worker[2:].isdigit() else 20


@pytest.fixture(scope="module")
def all_tests():
    return load_spec()


@pytest.fixture(scope="module")
def example_class(tmp_path_factory) -> dict[str, Path]:
    folders = build_example_class(tmp_path_factory.mktemp("example-class"))
    return {folder.name: folder for folder in folders}


def grade(folder: Path, tests) -> dict:
    return {result.test.name: result for result in run_tests(folder, tests, slot=sandbox_slot())}


def describe(results: dict) -> str:
    return "\n".join(f"  {name}: {r.outcome.status}: {r.outcome.message[:200]}" for name, r in results.items())


def test_reference_gets_full_marks(example_class, all_tests):
    results = grade(example_class["reference"], all_tests)
    not_passed = {name: r for name, r in results.items() if r.outcome.status != "passed"}
    assert not not_passed, f"the reference fails:\n{describe(not_passed)}"
    assert sum(r.score for r in results.values()) == pytest.approx(sum(t.points for t in all_tests))


def test_stubs_get_zero_and_every_test_says_not_implemented(example_class, all_tests):
    results = grade(example_class["stubs"], all_tests)
    other = {name: r for name, r in results.items() if r.outcome.status != "not_implemented"}
    assert not other, f"stubs should be 'not_implemented' everywhere:\n{describe(other)}"
    assert sum(r.score for r in results.values()) == 0


@pytest.mark.parametrize("sample", BUGGY_SAMPLES, ids=lambda s: s.name)
def test_buggy_sample_fails_exactly_its_tests(sample: BuggySample, example_class, all_tests):
    results = grade(example_class[sample.folder_name], all_tests)
    failed = {name for name, r in results.items() if r.outcome.status != "passed"}
    missed = sample.expected_failures - failed
    extra = failed - sample.expected_failures
    assert not missed, f"bug {sample.name!r} is not caught by {sorted(missed)}"
    assert not extra, (f"bug {sample.name!r} also fails tests it should pass:\n"
                       f"{describe({n: results[n] for n in sorted(extra)})}")
    wrong_status = {n: results[n] for n in sample.expected_failures if results[n].outcome.status != sample.status}
    assert not wrong_status, f"expected status {sample.status!r}:\n{describe(wrong_status)}"
    # Tests it should pass keep every point; each test it fails loses points (all of
    # them, or the share of wrong cases where the spec gives partial credit).
    points = {t.name: t.points for t in all_tests}
    for name, result in results.items():
        if name in sample.expected_failures:
            assert result.score < points[name], f"{name} failed but lost no points"
        else:
            assert result.score == points[name], name
    assert points_lost(sample, all_tests) > 0


def test_samples_are_well_formed(all_tests):
    names = {t.name for t in all_tests}
    assert len({s.name for s in BUGGY_SAMPLES}) == len(BUGGY_SAMPLES)
    for sample in BUGGY_SAMPLES:
        assert sample.expected_failures <= names, f"{sample.name}: unknown tests {sample.expected_failures - names}"
        assert sample.expected_failures, sample.name
        assert sample.mistake.strip() and sample.erratum > 0


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
