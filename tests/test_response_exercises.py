"""The student copy of solutions/response, built with the project's generator.

grader/release/exercises.py turns each ``### BEGIN SOLUTION`` ... ``### END SOLUTION``
block into ``raise NotImplementedError``; tests/test_generate_exercises.py checks the
markers and stubs of the whole package.  Here: exactly the response and solver
exercises are stubbed, and what students are given unmarked (helpers, the
ContactSolver that a world steps with) works in their copy: its readable sweeps call
the sequential-impulse exercise (and say so until it is written), its compiled twin
needs nothing of theirs.
"""
import importlib
import sys

import numpy as np
import pytest

from grader.release import exercises as gen

STUBBED = {
    "exercises.response.momentum_1d": {"collision_1d", "elastic_collision_1d", "perfectly_inelastic_1d"},
    "exercises.response.impulse": {"relative_normal_velocity", "effective_mass_inverse", "normal_impulse_magnitude",
                                   "apply_impulse", "resolve_collision"},
    "exercises.response.positional_correction": {"correct_positions"},
    "exercises.solver.contact_point": {"apply_normal_impulse", "apply_friction_impulse"},
    "exercises.solver.contact_sweeps": {"prestep_point", "contact_target", "sweep_contacts", "step_bodies"},
}


@pytest.fixture(scope="module")
def student_package(tmp_path_factory):
    """The generated package written to a temporary folder and put on sys.path."""
    files, stubs = gen.generate(gen.REPO_ROOT / gen.SOURCE_PACKAGE)
    root = tmp_path_factory.mktemp("student")
    gen.write(files, root / gen.TARGET_PACKAGE)
    stale = {name: sys.modules.pop(name) for name in list(sys.modules)
             if name == gen.TARGET_PACKAGE or name.startswith(gen.TARGET_PACKAGE + ".")}
    sys.path.insert(0, str(root))
    try:
        yield stubs
    finally:
        sys.path.remove(str(root))
        for name in [n for n in sys.modules if n == gen.TARGET_PACKAGE or n.startswith(gen.TARGET_PACKAGE + ".")]:
            del sys.modules[name]
        sys.modules.update(stale)


def test_exactly_the_response_exercises_are_stubbed(student_package):
    made = {}
    for stub in student_package:
        if stub.module.startswith(("exercises.response.", "exercises.solver.")):
            made.setdefault(stub.module, set()).add(stub.qualname)
    assert made == STUBBED  # ContactSolver and the helpers stay whole


def test_student_copy_raises_in_exercises_and_has_no_compiled_solver(student_package):
    body = importlib.import_module("exercises.body").Body
    contact = importlib.import_module("exercises.contact").Contact
    momentum_1d = importlib.import_module("exercises.response.momentum_1d")
    impulse = importlib.import_module("exercises.response.impulse")
    correction = importlib.import_module("exercises.response.positional_correction")
    contact_solver = importlib.import_module("exercises.response.contact_solver")
    ground = body.box(10.0, 1.0, position=(0.0, -0.5), is_static=True)
    ball = body.circle(0.5, position=(0.0, 0.5), velocity=(0.0, -1.0))
    touching = contact((0.0, 1.0), 0.0, [(0.0, 0.0)])
    for call in (lambda: momentum_1d.collision_1d(1.0, 1.0, 1.0, -1.0, 0.5),
                 lambda: impulse.normal_impulse_magnitude(ground, ball, (0.0, 0.0), (0.0, 1.0), 0.5),
                 lambda: impulse.resolve_collision(ground, ball, touching),
                 lambda: correction.correct_positions(ground, ball, (0.0, 1.0), 0.1)):
        with pytest.raises(NotImplementedError):
            call()
    assert momentum_1d.kinetic_energy(2.0, 3.0) == 9.0
    assert impulse.solve_small_lcp(np.array([[2.0]]), np.array([1.0])).tolist() == [0.5]
    with pytest.raises(NotImplementedError, match="grader check sequential"):
        contact_solver.ContactSolver().solve([ground, ball], [(0, 1, touching)], 1 / 60)
    # The compiled kernel would solve without the student's code: it is not in the copy.
    with pytest.raises(ValueError, match="student edition does not include"):
        contact_solver.ContactSolver(backend="numba")
