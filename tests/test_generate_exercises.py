"""The student package is generated from solutions/ and committed in sync."""
import importlib
import re
import inspect
import textwrap

import pytest

from tools import generate_exercises as gen

#: The exercises the course promises students (module, qualname), at least.
REQUIRED_STUBS = {
    ("exercises.broadphase.uniform_grid", "pairs_grid_every_cell"),
    ("exercises.broadphase.uniform_grid", "pairs_grid_center_cell"),
    ("exercises.narrowphase.projection", "project_vertices"),
    ("exercises.narrowphase.aabb_aabb", "aabbs_overlap"),
    ("exercises.narrowphase.polygon_polygon", "polygons_overlap"),
    ("exercises.narrowphase.circle_polygon", "circle_polygon_overlap"),
    ("exercises.narrowphase.circle_circle", "circles_overlap"),
    ("exercises.narrowphase.polygon_polygon", "collide_polygon_polygon"),
    ("exercises.narrowphase.circle_polygon", "collide_circle_polygon"),
    ("exercises.response.momentum_1d", "collision_1d"),
    ("exercises.response.momentum_1d", "elastic_collision_1d"),
    ("exercises.response.momentum_1d", "perfectly_inelastic_1d"),
    ("exercises.response.impulse", "normal_impulse_magnitude"),
    ("exercises.response.impulse", "apply_impulse"),
    ("exercises.response.positional_correction", "correct_positions"),
}


@pytest.fixture(scope="module")
def generated():
    return gen.generate(gen.REPO_ROOT / gen.SOURCE_PACKAGE)


def test_committed_exercises_match_the_generator(generated):
    files, _ = generated
    problems = gen.differences(files, gen.existing_files(gen.REPO_ROOT / gen.TARGET_PACKAGE))
    assert not problems, "run `python -m tools.generate_exercises`:\n" + "\n".join(problems)


def test_required_exercises_are_stubbed(generated):
    _, stubs = generated
    made = {(s.module, s.qualname) for s in stubs}
    assert REQUIRED_STUBS <= made, f"missing stubs: {sorted(REQUIRED_STUBS - made)}"
    quadtree_stubs = {q for m, q in made if m == "exercises.broadphase.quadtree"}
    assert any("insert" in q for q in quadtree_stubs) and len(quadtree_stubs) >= 2


def _call_with_placeholders(function):
    parameters = [p for p in inspect.signature(function).parameters.values()
                  if p.default is inspect.Parameter.empty
                  and p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
    return function(*[None] * len(parameters))


def test_every_stub_imports_and_raises_not_implemented(generated):
    _, stubs = generated
    assert stubs
    for stub in stubs:
        module = importlib.import_module(stub.module)
        owner, *rest = stub.qualname.split(".")
        target = getattr(module, owner)
        if rest:
            instance = object.__new__(target)
            target = getattr(instance, rest[-1])
        with pytest.raises(NotImplementedError):
            _call_with_placeholders(target)


def test_student_modules_never_import_the_reference(generated):
    files, _ = generated
    importing = re.compile(r"^\s*(>>>\s+|\.\.\.\s+)?(from|import)\s+solutions\b", re.MULTILINE)
    for name, text in files.items():
        assert not importing.search(text), name


def test_docstring_kept_and_block_replaced():
    source = textwrap.dedent('''\
        def speed(p, m):
            """Speed (m/s) from momentum p (kg m/s) and mass m (kg)."""
            ### BEGIN SOLUTION
            return p / m
            ### END SOLUTION
        ''')
    student, stubbed = gen.strip_solutions(source)
    assert stubbed == ["speed"]
    assert '"""Speed (m/s)' in student and "return p / m" not in student
    namespace = {}
    exec(student, namespace)
    with pytest.raises(NotImplementedError):
        namespace["speed"](1.0, 2.0)


def test_methods_are_named_by_qualname():
    source = textwrap.dedent('''\
        class Tree:
            def insert(self, item):
                ### BEGIN SOLUTION
                self.items.append(item)
                ### END SOLUTION
        ''')
    assert gen.strip_solutions(source)[1] == ["Tree.insert"]


@pytest.mark.parametrize("source, message", [
    ("def f():\n    ### BEGIN SOLUTION\n    ### BEGIN SOLUTION\n    return 1\n    ### END SOLUTION\n", "nested"),
    ("def f():\n    ### BEGIN SOLUTION\n    return 1\n", "never closed"),
    ("def f():\n    return 1\n    ### END SOLUTION\n", "without a matching"),
    ("### BEGIN SOLUTION\nx = 1\n### END SOLUTION\n", "outside a function"),
    ("def f():\n    pass\n    ### BEGIN SOLUTION\n    # nothing\n    ### END SOLUTION\n", "empty solution block"),
    ("from solutions.shapes import Circle\n", "absolute import"),
    ("def f():\n    x = 1  ### BEGIN SOLUTION\n    return x\n", "stand alone"),
    ("def f(:\n    pass\n", "does not parse"),
])
def test_bad_markers_are_refused_with_file_and_line(source, message):
    with pytest.raises(gen.MarkerError, match=message) as info:
        gen.strip_solutions(source, "solutions/bad.py")
    assert "solutions/bad.py:" in str(info.value)


def test_a_marker_error_writes_nothing(tmp_path, capsys):
    source = tmp_path / "solutions"
    source.mkdir()
    (source / "good.py").write_text("def f():\n    ### BEGIN SOLUTION\n    return 1\n    ### END SOLUTION\n")
    target = tmp_path / "exercises"
    assert gen.main(["--source", str(source), "--target", str(target)]) == 0
    before = (target / "good.py").read_text()
    (source / "bad.py").write_text("def g():\n    ### BEGIN SOLUTION\n    return 2\n")
    assert gen.main(["--source", str(source), "--target", str(target)]) == 2
    assert "bad.py:2" in capsys.readouterr().err
    assert (target / "good.py").read_text() == before
    assert not (target / "bad.py").exists()


def test_check_reports_stale_and_missing_files(tmp_path):
    source = tmp_path / "solutions"
    source.mkdir()
    (source / "a.py").write_text("x = 1\n")
    target = tmp_path / "exercises"
    assert gen.main(["--source", str(source), "--target", str(target)]) == 0
    assert gen.main(["--check", "--source", str(source), "--target", str(target)]) == 0
    (target / "orphan.py").write_text("y = 2\n")
    (target / "a.py").write_text("x = 3\n")
    assert gen.main(["--check", "--source", str(source), "--target", str(target)]) == 1


def test_doctest_imports_point_at_the_student_package():
    source = 'def f():\n    """\n    >>> from solutions.shapes import Circle\n    """\n'
    assert ">>> from exercises.shapes import Circle" in gen.strip_solutions(source)[0]
