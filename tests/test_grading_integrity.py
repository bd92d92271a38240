"""Issue 24, items 5 and 6: exercises that cannot be bypassed through the library, and
points that follow the harm.

Each test builds a submission the way a determined student would (the reference with
one function rewritten, :mod:`grader.samples.example_class`), grades it with the real
graded tests in a real sandbox, and checks the points and the message.
"""
from __future__ import annotations

import ast
import os
import re
from pathlib import Path

import pytest

from grader.harness.run import load_spec, run_tests
from grader.release.exercises import BEGIN_MARKER
from grader.samples.example_class import (EXERCISES_DIR, SOLUTIONS_DIR, BuggySample, Replacement, build_buggy_sample,
                                          grade_probe)
from grader.samples.shortcuts import BLIND_CALLERS, MANIFOLD_REPEATS_A_POINT, SHORTCUTS


def sandbox_slot() -> int:
    """A sandbox user per xdist worker (30, 31...), apart from the example class's 20s."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "gw0")
    return 30 + int(worker[2:]) if worker[2:].isdigit() else 30


def graded(tmp_path: Path, replacements: tuple[Replacement, ...], names: set[str], base: Path = SOLUTIONS_DIR) -> dict:
    """Results by test name of the tests ``names`` on ``base`` (the reference, or the stubs
    a student starts from: EXERCISES_DIR) with ``replacements``."""
    sample = BuggySample(name="integrity", mistake="a shortcut", erratum=0, replacements=replacements,
                         expected_failures=frozenset())
    folder = build_buggy_sample(sample, tmp_path, base)
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


#: The brute force again, refusing the growth check's scenes (1000 boxes or more) so that
#: the measurement cannot be made.
BRUTE_FORCE_GRID_REFUSING_LARGE = tuple(
    Replacement("broadphase.uniform_grid", name, f'''
        def {name}(aabbs, cell_size: float) -> set[tuple[int, int]]:
            if len(aabbs) >= 1000:
                raise ValueError("too many boxes")
            return pairs_brute_force_numpy(aabbs)
        ''', imports=("from .brute_force import pairs_brute_force_numpy",))
    for name in ("pairs_grid_every_cell", "pairs_grid_center_cell"))


def test_a_grid_failing_only_on_the_measured_scenes_earns_nothing(tmp_path):
    names = {t for t in broadphase_tests("grid.", hidden=False) if "random" in t}
    assert names
    results = graded(tmp_path, BRUTE_FORCE_GRID_REFUSING_LARGE, names)
    for name, result in results.items():
        assert result.score == 0 and "failed on a sparse scene" in result.outcome.message, (
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


#: polygons_overlap in two lines from the helpers of polygon_polygon.py: every face of A,
#: then of B, has the other polygon inside its line.  On main the helpers were library code
#: and a stubs submission with this function earned every polygon SAT point.
SAT_FROM_FACE_SEPARATIONS = (Replacement("narrowphase.polygon_polygon", "polygons_overlap", '''
    def polygons_overlap(a, b) -> bool:
        polygon_a, polygon_b = polygon_faces(a), polygon_faces(b)
        return max_face_separation(*polygon_a, polygon_b[0])[0] <= 0 and max_face_separation(*polygon_b, polygon_a[0])[0] <= 0
    '''),)
#: The public tests that call polygons_overlap and nothing else of the student's.
POLYGON_SAT_TESTS = {"sat.polygons_overlap_random", "sat.far_from_origin"}


def test_the_face_separations_are_an_exercise_not_a_library_shortcut_to_polygon_sat(tmp_path):
    on_stubs = graded(tmp_path / "stubs", SAT_FROM_FACE_SEPARATIONS, POLYGON_SAT_TESTS, base=EXERCISES_DIR)
    for name, result in on_stubs.items():
        assert result.score == 0, (name, result.outcome.message[:500])
        assert "max_face_separation" in result.outcome.message, (name, result.outcome.message[:500])
    # The same two lines are right once max_face_separation is written (the reference's).
    on_reference = graded(tmp_path / "reference", SAT_FROM_FACE_SEPARATIONS, POLYGON_SAT_TESTS)
    assert all(r.outcome.status == "passed" for r in on_reference.values()), \
        {name: r.outcome.message[:300] for name, r in on_reference.items()}


def test_no_library_module_of_the_student_package_chooses_the_reference_face():
    # speculative.py held collide_polygon_polygon's reference-face rule word for word; it
    # now asks the exercise function, so in the student package it is not written yet.
    library = [path for path in EXERCISES_DIR.rglob("*.py")
               if path.read_text(encoding="utf-8").startswith("# Library file")]
    assert any(path.name == "speculative.py" for path in library)
    holding = [str(path.relative_to(EXERCISES_DIR)) for path in library
               if "REFERENCE_FACE_RELATIVE_TOL" in path.read_text(encoding="utf-8")
               or "max_face_separation(" in path.read_text(encoding="utf-8")]
    assert not holding, f"library files holding the reference-face rule: {holding}"
    from exercises.narrowphase.speculative import speculative_polygon_manifold
    from exercises.shapes import AABB
    with pytest.raises(NotImplementedError, match="reference_face_candidates|max_face_separation"):
        speculative_polygon_manifold(AABB((-5.0, -1.0), (5.0, 0.0)), AABB((-0.5, -0.1), (0.5, 0.9)))


def test_a_repeated_contact_point_fails_public_tests_and_is_named(tmp_path):
    # On main only the hidden contacts.degenerate_shapes saw it.
    names = {"contacts.reference_face_manifold", "contacts.polygon_polygon"}
    results = graded(tmp_path, MANIFOLD_REPEATS_A_POINT, names)
    manifold, polygons = results["contacts.reference_face_manifold"], results["contacts.polygon_polygon"]
    assert manifold.score == 0, manifold.outcome.message[:500]
    assert polygons.score <= polygons.test.points / 2, (polygons.score, polygons.outcome.message[:500])
    for result in (manifold, polygons):
        assert "are the same point" in result.outcome.message, result.outcome.message[:1000]


#: The shortcuts of issue 24 (grader/samples/shortcuts.py) and the function each one
#: rewrites, as the probe names it ("module.qualname"); python -m tools.function_losses
#: grades every shortcut and sample.
SYSTEMATIC_BUGS = {name: f"{SHORTCUTS[name][0].module}.{SHORTCUTS[name][0].qualname}"
                   for name in ("manifold-ignores-margin", "manifold-depth-clamped-at-0", "normal-rows-clamped-at-0")}


@pytest.fixture(scope="module")
def reached(tmp_path_factory) -> dict:
    """Which contacts and sequential tests reach which exercise function (the example
    class's probe: the reference, each function printing its name when called)."""
    tests = [t for t in load_spec() if t.exercise in ("contacts", "sequential")]
    found, results = grade_probe(tests, tmp_path_factory.mktemp("probe"), slot=sandbox_slot())
    assert all(r.outcome.status == "passed" for r in results)
    return found


@pytest.mark.parametrize("bug", sorted(SYSTEMATIC_BUGS))
def test_a_systematic_bug_loses_at_least_half_of_its_functions_points(tmp_path, reached, bug):
    # On main a manifold ignoring the margin or clamping its depths lost 1 of 14 points, a
    # row clamped at 0 2 of the 8 of apply_normal_impulse's own tests.
    function, replacements = SYSTEMATIC_BUGS[bug], SHORTCUTS[bug]
    blind = BLIND_CALLERS.get(bug, set())
    names = {name for name, functions in reached.items()
             if functions is None or (function in functions and not functions & blind)}
    results = graded(tmp_path, replacements, names)
    at_stake = sum(r.test.points for r in results.values())
    lost = sum(r.test.points - r.score for r in results.values())
    assert lost >= at_stake / 2, {name: r.score for name, r in results.items()}
    public = [r for r in results.values() if r.test.public and r.score < r.test.points]
    assert public, "a public test must catch it"


# The solver exercise's answers: expressions of at least this many operations in the
# solution blocks of its six functions, compared by shape (every name, attribute or
# subscript the same), so that a vectorised or renamed copy is found too.
SOLVER_ANSWER_OPERATIONS = 5
SOLVER_EXERCISE = {"solver/contact_point.py": ("apply_normal_impulse", "apply_friction_impulse"),
                   "solver/contact_sweeps.py": ("prestep_point", "contact_target", "sweep_contacts", "step_bodies")}
OPERATIONS = (ast.BinOp, ast.Compare, ast.Call, ast.IfExp, ast.UnaryOp)


def expression_shape(node: ast.AST):
    """``node`` with every name, attribute and subscript made the same; constants,
    operators and called names kept."""
    if isinstance(node, (ast.Name, ast.Attribute, ast.Subscript)):
        return "value"
    if isinstance(node, ast.Constant):
        return repr(node.value)
    if isinstance(node, ast.Call):
        called = node.func.id if isinstance(node.func, ast.Name) else "value"
        return ("call", called, *(expression_shape(a) for a in node.args))
    parts = [type(node).__name__]
    for value in ast.iter_fields(node):
        items = value[1] if isinstance(value[1], list) else [value[1]]
        parts += [expression_shape(v) if isinstance(v, ast.expr) else type(v).__name__
                  for v in items if isinstance(v, ast.AST)]
    return tuple(parts)


def answer_shapes(source: str, functions) -> dict:
    """{shape: source text} of the expressions of ``functions``' solution blocks with at
    least :data:`SOLVER_ANSWER_OPERATIONS` operations, but for the normal velocity
    ``v_n`` of ``apply_normal_impulse``: the input of ``contact_target``, which the
    library measures to call it (``closing_speeds``), defined in the docstrings."""
    lines, shapes, contract = source.splitlines(), {}, set()
    for node in ast.walk(ast.parse(source)):
        if not (isinstance(node, ast.FunctionDef) and node.name in functions):
            continue
        begin = next(k for k in range(node.lineno, node.end_lineno) if lines[k].strip() == BEGIN_MARKER)
        for sub in ast.walk(node):
            if isinstance(sub, ast.Assign) and ast.unparse(sub.targets[0]) == "normal_velocity":
                contract |= {expression_shape(e) for e in ast.walk(sub.value) if isinstance(e, OPERATIONS)}
            operations = sum(isinstance(e, OPERATIONS) for e in ast.walk(sub))
            if isinstance(sub, OPERATIONS) and sub.lineno > begin + 1 and operations >= SOLVER_ANSWER_OPERATIONS:
                shapes.setdefault(expression_shape(sub), ast.unparse(sub))
    return {shape: text for shape, text in shapes.items() if shape not in contract}


def holding(source: str, shapes: dict) -> list[str]:
    return [f"line {node.lineno}: {ast.unparse(node)[:80]} (the answer {shapes[expression_shape(node)]})"
            for node in ast.walk(ast.parse(source))
            if isinstance(node, OPERATIONS) and expression_shape(node) in shapes]


def test_no_library_module_of_the_student_package_holds_the_solver_exercises_answers():
    shapes = {}
    for module, functions in SOLVER_EXERCISE.items():
        shapes.update(answer_shapes((SOLUTIONS_DIR / module).read_text(encoding="utf-8"), functions))
    answers = set(shapes.values())
    # The effective mass, the bounce above the threshold, the capped push and the visit.
    assert {"ima + imb + iia * (rn_a * rn_a) + iib * (rn_b * rn_b)",
            "-restitution * normal_velocity if normal_velocity < -restitution_threshold else 0.0",
            "min(bias_factor / dt * max(depth - slop, 0.0), max_push)",
            "mass_normal * mass_scale * (target - normal_velocity) - impulse_scale * normal_total"} <= answers
    # The check finds an answer written another way (the library's vectorised prestep of before).
    assert holding("k_normal = c.ima + c.imb + c.iia * (rn[:, 0] * rn[:, 0]) + c.iib * (rn[:, 1] * rn[:, 1])",
                   shapes)
    library = [path for path in EXERCISES_DIR.rglob("*.py")
               if path.read_text(encoding="utf-8").startswith("# Library file")]
    assert any(path.name == "contact_preparation.py" for path in library)
    found = {str(path.relative_to(EXERCISES_DIR)): holding(path.read_text(encoding="utf-8"), shapes)
             for path in library}
    assert not {path: lines for path, lines in found.items() if lines}, found
    # The visits' docstrings give the contract, not the update.
    from exercises.solver import contact_point
    for function in (contact_point.apply_normal_impulse, contact_point.apply_friction_impulse):
        assert not re.search(r"dP\s*=|dT\s*=|max\(P \+ dP|-m_t v_t|w_B \+=", function.__doc__), function.__name__


def test_the_student_packages_engine_runs_on_the_students_prestep():
    # The library asks the exercise for each contact's rows: until prestep_point is
    # written, a world with a contact cannot step (and it steps on the student's once it is).
    from exercises.body import Body
    from exercises.contact import Contact
    from exercises.response.contact_solver import ContactSolver
    ground = Body.box(10.0, 1.0, position=(0.0, -0.5), is_static=True)
    box = Body.box(1.0, 1.0, position=(0.0, 0.5), velocity=(0.0, -1.0))
    with pytest.raises(NotImplementedError, match="prestep_point"):
        ContactSolver().solve([ground, box], [(0, 1, Contact((0.0, 1.0), 0.0, [(-0.5, 0.0)]))], dt=1 / 60)
