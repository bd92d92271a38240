"""The student package is generated from solutions/ and committed in sync, and the
generator never erases a student's work: it refuses to overwrite edits unless forced,
and then keeps a backup."""
import hashlib
import importlib
import inspect
import json
import re
import shutil
import textwrap

import pytest

from grader.release import exercises as gen

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
    problems = gen.check(files, gen.REPO_ROOT / gen.TARGET_PACKAGE)
    assert not problems, "run `python -m grader.release.exercises` (it refuses to overwrite edits):\n" + \
        "\n".join(problems)


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
        with pytest.raises(NotImplementedError) as info:
            _call_with_placeholders(target)
        # The message names the function to write (a method, not its caller) and its check.
        assert f"write {stub.qualname}()" in str(info.value), stub
        assert f"`grader check {stub.exercise}`" in str(info.value), stub


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


# Every stub belongs to an exercise; headers and messages say how to check it -----------
def test_every_stub_of_the_course_names_its_exercise(generated):
    from grader.harness.spec import EXERCISES  # the names `grader check` takes

    _, stubs = generated
    unnamed = [f"{s.module}.{s.qualname}" for s in stubs if s.exercise not in EXERCISES]
    assert not unnamed, f"add these stubs to grader/release/exercises.py EXERCISES: {unnamed}"
    by_name = {(s.module, s.qualname): s.exercise for s in stubs}
    assert by_name["exercises.broadphase.quadtree", "Quadtree.insert"] == "quadtree"
    assert by_name["exercises.narrowphase.aabb_aabb", "aabbs_overlap"] == "sat"
    assert by_name["exercises.narrowphase.aabb_aabb", "collide_aabb_aabb"] == "contacts"
    assert by_name["exercises.response.positional_correction", "correct_positions"] == "impulse"


def _header(text: str) -> str:
    """The comment lines a student file starts with."""
    lines = text.splitlines(keepends=True)
    return "".join(lines[: next(i for i, line in enumerate(lines) if not line.startswith("#"))])


def test_headers_say_what_the_file_is_and_how_to_check_it(generated):
    files, stubs = generated
    for name, text in files.items():
        head = _header(text)
        assert len(head.splitlines()) >= 2, name
        assert "generate_exercises" not in head and "python -m" not in head, name  # never "regenerate"
        module = ".".join(["exercises", *name.removesuffix(".py").split("/")]).removesuffix(".__init__")
        mine = [s for s in stubs if s.module == module]
        if mine:
            assert head.startswith("# Exercise file of the collision course"), name
            assert "NotImplementedError" in head, name
            for stub in mine:
                assert f"`grader check {stub.exercise}`" in head, (name, stub)
        else:
            assert head.startswith("# Library file of the collision course (you do not need to edit it)"), name
    two = files["narrowphase/polygon_polygon.py"]
    assert "`grader check sat` (polygons_overlap, obbs_overlap)" in two
    assert ("`grader check contacts` (max_face_separation, reference_face_candidates, clip_segment_to_half_plane"
            in " ".join(two.replace("\n# ", " ").split()))


def test_a_stub_outside_the_table_points_at_every_exercise():
    source = "def f():\n    ### BEGIN SOLUTION\n    return 1\n    ### END SOLUTION\n"
    student, _ = gen.strip_solutions(source)
    assert 'raise NotImplementedError("write f(), then run `grader check`")' in student


# The generator refuses to overwrite edits -------------------------------------------------
@pytest.fixture
def course(tmp_path):
    """Copies of the repository's solutions/ and exercises/ (never the real tree)."""
    source, target = tmp_path / "solutions", tmp_path / "exercises"
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc")
    shutil.copytree(gen.REPO_ROOT / gen.SOURCE_PACKAGE, source, ignore=ignore)
    shutil.copytree(gen.REPO_ROOT / gen.TARGET_PACKAGE, target, ignore=ignore)
    assert (target / gen.MANIFEST).is_file()

    def run(*options):
        return gen.main(["--source", str(source), "--target", str(target), *options])

    return source, target, run


def snapshot(folder):
    """Every file under ``folder`` and its bytes."""
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def edit_a_stub(target):
    path = target / "broadphase" / "quadtree.py"
    text = path.read_text()
    stub = 'raise NotImplementedError("write Quadtree.insert(), then run `grader check quadtree`")'
    assert stub in text
    path.write_text(text.replace(stub, "self.root.bodies.append(index)  # my work"))
    return "exercises/broadphase/quadtree.py"


def add_a_file(target):
    (target / "my_helpers.py").write_text("def mine():\n    return 42\n")
    return "exercises/my_helpers.py"


def delete_a_file(target):
    (target / "vector.py").unlink()
    return "exercises/vector.py"


@pytest.mark.parametrize("change, kind", [(edit_a_stub, "edited"), (add_a_file, "added"),
                                          (delete_a_file, "deleted")])
def test_edits_are_refused_named_and_left_alone(course, capsys, change, kind):
    source, target, run = course
    named = change(target)
    before, beside = snapshot(target), sorted(p.name for p in target.parent.iterdir())
    solutions_before = snapshot(source)
    capsys.readouterr()
    assert run() == gen.REFUSED
    err = capsys.readouterr().err
    assert f"{kind}: {named}" in err
    assert "student" in err and "--force" in err and "Nothing was written" in err
    assert snapshot(target) == before  # byte for byte
    assert sorted(p.name for p in target.parent.iterdir()) == beside  # no backup, no leftovers
    assert snapshot(source) == solutions_before


def test_force_keeps_a_backup_of_the_edited_tree_then_writes_fresh_stubs(course, capsys):
    source, target, run = course
    edit_a_stub(target)
    add_a_file(target)
    edited = snapshot(target)
    capsys.readouterr()
    assert run("--force") == 0
    out = capsys.readouterr().out
    backups = [p for p in target.parent.iterdir() if p.name.startswith("exercises.backup-")]
    assert len(backups) == 1 and re.fullmatch(r"exercises\.backup-\d{8}-\d{6}", backups[0].name)
    assert str(backups[0]) in out
    assert snapshot(backups[0]) == edited
    files, _ = gen.generate(source)
    assert gen.check(files, target) == []
    assert "my work" not in (target / "broadphase" / "quadtree.py").read_text()
    assert not (target / "my_helpers.py").exists()
    assert run() == 0  # the fresh tree is the generator's again: no refusal, no backup
    assert len([p for p in target.parent.iterdir() if p.name.startswith("exercises.backup-")]) == 1


def test_an_unedited_tree_is_rewritten_without_a_backup(course, capsys):
    source, target, run = course
    (target / "__pycache__").mkdir(exist_ok=True)
    (target / "__pycache__" / "vector.cpython-311.pyc").write_bytes(b"cache")  # no one's work
    assert run() == 0 and run("--force") == 0
    assert sorted(p.name for p in target.parent.iterdir()) == ["exercises", "solutions"]


def test_without_a_record_the_tree_must_equal_the_generated_one(course, capsys):
    source, target, run = course
    (target / gen.MANIFEST).unlink()
    assert run() == 0  # a tree from before the record: equal, so the record is written
    assert (target / gen.MANIFEST).is_file()
    (target / gen.MANIFEST).unlink()
    named = edit_a_stub(target)
    before = snapshot(target)
    capsys.readouterr()
    assert run() == gen.REFUSED
    err = capsys.readouterr().err
    assert f"differs: {named}" in err and "no record" in err
    assert snapshot(target) == before


def test_an_unreadable_record_counts_as_none(course):
    source, target, run = course
    (target / gen.MANIFEST).write_text("{not json")
    assert run() == 0
    edit_a_stub(target)
    (target / gen.MANIFEST).write_text("[]")
    assert run() == gen.REFUSED


def test_the_record_holds_hashes_of_the_stub_files_only(course, generated):
    source, target, _ = course
    files, _ = generated
    text = (target / gen.MANIFEST).read_text()
    record = json.loads(text)
    assert set(record) == {"about", "sha256"}
    assert record["sha256"] == {name: hashlib.sha256(body.encode()).hexdigest() for name, body in files.items()}
    assert all(re.fullmatch(r"[0-9a-f]{64}", value) for value in record["sha256"].values())
    # Nothing of a solution block, not even the hash of a solution file, is in the record.
    solution_lines = set()
    for path in source.rglob("*.py"):
        inside = False
        for line in path.read_text().splitlines():
            if line.strip() == gen.BEGIN_MARKER:
                inside = True
            elif line.strip() == gen.END_MARKER:
                inside = False
            elif inside and len(line.strip()) >= 8:
                solution_lines.add(line.strip())
        assert hashlib.sha256(path.read_bytes()).hexdigest() not in text
    assert solution_lines
    assert not [line for line in solution_lines if line in text]


def test_check_names_the_edits_and_never_suggests_erasing_them(course, capsys):
    source, target, run = course
    assert run("--check") == 0
    named = edit_a_stub(target)
    before = snapshot(target)
    capsys.readouterr()
    assert run("--check") == 1
    err = capsys.readouterr().err
    assert named.removeprefix("exercises/") in err and "perhaps a student's work" in err
    assert "refuses" in err and "--force only if those edits are not wanted" in err
    assert snapshot(target) == before


def test_check_reports_a_missing_record_and_files_that_are_not_python(course):
    source, target, run = course
    (target / "notes.txt").write_text("my notes\n")
    assert run("--check") == 1
    (target / "notes.txt").unlink()
    (target / gen.MANIFEST).unlink()
    assert run("--check") == 1


def test_no_reference_package_writes_nothing(tmp_path, course, capsys):
    _, target, _ = course
    before = snapshot(target)
    assert gen.main(["--source", str(tmp_path / "nowhere"), "--target", str(target)]) == 2
    assert "grader check" in capsys.readouterr().err
    assert gen.main(["--source", str(tmp_path / "nowhere"), "--target", str(target), "--force"]) == 2
    assert snapshot(target) == before


def test_instructor_only_modules_are_left_out(generated, tmp_path):
    files, _ = generated
    marked = [p.relative_to(gen.REPO_ROOT / gen.SOURCE_PACKAGE).as_posix()
              for p in (gen.REPO_ROOT / gen.SOURCE_PACKAGE).rglob("*.py")
              if gen.is_instructor_only(p.read_text(encoding="utf-8"))]
    assert "solver/kernel_numba.py" in marked and "narrowphase/speculative_batch.py" in marked
    assert not set(marked) & set(files)
    assert "solver/kernel.py" in files and "twins.py" in files
    # The marker must start a line: a mention inside a string or a docstring does not count.
    source = tmp_path / "package"
    source.mkdir()
    (source / "twin.py").write_text('"""A twin."""\n### INSTRUCTOR ONLY: computes an answer.\nx = 1\n')
    (source / "mentions.py").write_text('"""Says ### INSTRUCTOR ONLY inline."""\ny = 2\n')
    made, _ = gen.generate(source)
    assert sorted(made) == ["mentions.py"]


def test_cross_references_name_the_student_package_where_it_holds_the_module(generated):
    """Docstrings of the student edition point at its own modules (``exercises.shapes``),
    and never at a module of ``solutions``: the twins it does not hold are named as the
    instructor's files."""
    files, _ = generated
    named = [(name, m.group(0)) for name, text in files.items()
             for m in re.finditer(r"(?<![\w/.])solutions(?:\.\w+)+", text)]
    assert not named, named
    assert any("exercises.shapes" in text for text in files.values())
    twins = [p.relative_to(gen.REPO_ROOT / gen.SOURCE_PACKAGE).as_posix()
             for p in (gen.REPO_ROOT / gen.SOURCE_PACKAGE).rglob("*.py")
             if gen.is_instructor_only(p.read_text(encoding="utf-8"))]
    mentioned = {twin for twin in twins for text in files.values() if f"``{twin}`` of the instructor's edition" in text}
    assert "solver/kernel_numba.py" in mentioned, mentioned
