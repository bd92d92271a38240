"""Hidden sequential-impulse tests: random visits against the reference, and a stack of
ten boxes stepped with the student's sweeps against the complementarity answer.

Instructor's side only (it imports ``solutions``).  The stack runs
:func:`grader.sandbox.scene_driver.stack_of_boxes` in the student's sandbox: a resting stack's
contact k, counted from the bottom, carries the weight of the ``count - k`` boxes
above it, ``(count - k) m g dt`` per step (the solution of the LCP of the book's first
chapter); the student's impulses must reach it and the boxes stay at rest.
"""
from __future__ import annotations

import numpy as np
import pytest

from grader.harness.credit import check_cases, fail
from grader.tests.public.test_sequential import answer_problem, describe, random_cases
from solutions.solver.contact_point import apply_friction_impulse, apply_normal_impulse

MODULE = "solver.contact_point"
BOXES, STEPS, DT, G = 10, 60, 1 / 60, 9.81
#: 20 sweeps a step, warm started, leave the loads within 0.1 % of the answer after 1 s
#: (measured on the reference: 0.03 %) and the boxes within 2 mm/s of rest (0.7).
LOAD_TOLERANCE, SPEED_TOLERANCE = 1e-3, 2e-3


def against_reference(student, function: str, reference_function, cases) -> None:
    answers = student.call_many(MODULE, function, [list(args) for args, _ in cases])

    def problem_of(case_answer):
        (args, note), got = case_answer
        want = reference_function(*args)
        problem = answer_problem(got, [list(want[0]), list(want[1]), want[2]], function)
        return None if problem is None else f"{problem} [{note}]"

    check_cases(list(zip(cases, answers)), problem_of, f"random {function} visits",
                describe=lambda ca: describe(function, ca[0]), category=lambda ca: ca[0][1])


@pytest.mark.points(1)
@pytest.mark.visibility("hidden")
@pytest.mark.title("Sequential impulses: random visits against the reference (normal and friction)")
def test_random_against_reference(student):
    against_reference(student, "apply_normal_impulse", apply_normal_impulse, random_cases(901, 40, friction=False))
    against_reference(student, "apply_friction_impulse", apply_friction_impulse, random_cases(902, 40, friction=True))


@pytest.mark.points(2)
@pytest.mark.visibility("hidden")
@pytest.mark.title("Sequential impulses: a stack of ten boxes rests on the complementarity answer")
def test_stack_of_ten(student):
    result = student.sandbox.call("scene_driver", "stack_of_boxes", [STEPS, BOXES, DT], timeout=60.0)
    data = student.value_of(result, "the stack of ten boxes with your sweeps")
    try:
        trajectory = np.array(data["trajectory"], dtype=float)
        impulses = np.array(data["impulses"], dtype=float)
    except (KeyError, TypeError, ValueError):
        fail("the stack of ten boxes returned no trajectory and impulses")
    if trajectory.shape != (STEPS, BOXES, 2) or impulses.shape != (STEPS, BOXES):
        fail(f"the stack of ten boxes returned {trajectory.shape} states and {impulses.shape} impulses, "
             f"not {(STEPS, BOXES, 2)} and {(STEPS, BOXES)}")
    if not (np.all(np.isfinite(trajectory)) and np.all(np.isfinite(impulses))):
        fail("the stack of ten boxes produced non-finite positions, velocities or impulses")
    want = np.array([(BOXES - k) * G * DT for k in range(BOXES)])       # N s per step, bottom contact first
    worst = int(np.argmax(np.abs(impulses[-1] - want)))
    if abs(impulses[-1, worst] - want[worst]) > LOAD_TOLERANCE * want[worst]:
        fail(f"after {STEPS} steps contact {worst} (counted from the ground) carries {impulses[-1, worst]:.6g} N s "
             f"per step; a resting stack puts the weight of the {BOXES - worst} boxes above it there, "
             f"{want[worst]:.6g} N s (all contacts: {np.round(impulses[-1], 6).tolist()})")
    sinking = float(np.abs(trajectory[-1, :, 1]).max())
    if sinking > SPEED_TOLERANCE:
        fail(f"after {STEPS} steps a box still moves at {sinking:.3g} m/s: the stack does not rest")
