"""Hidden sequential-impulse tests: random visits against the reference (joint rows
among them), and a stack of ten boxes with a chain of three hanging beside it, stepped
with the student's sweeps, against the complementarity answer.

Instructor's side only (it imports ``solutions``).  The stack is stepped here, in the
trusted process, with the reference's contact solver whose row visits are the
student's ``apply_normal_impulse`` and ``apply_friction_impulse``: each step's sweeps
go to the student's sandbox as one program of calls (:meth:`StudentCode.run_program`)
and their answers are wired back here, so nothing but those two functions runs on the
student's side.  A resting stack's contact k, counted from the bottom, carries the
weight of the ``count - k`` boxes above it, ``(count - k) m g dt`` per step (the
solution of the LCP of the book's first chapter); the student's impulses must reach it
and the boxes stay at rest.  The chain's rigid distance joints are rows of the same
kernel with ``lower = -inf``: joint k, counted from the ceiling, pulls with the weight
of the ``chain - k`` boxes below it, ``-(chain - k) m g dt`` per step (an impulse along
the joint's direction, ceiling to box, is negative when it pulls).

The prestep, sweeps and step (``solver/contact_sweeps.py``) are compared with the
reference on random cases, and two worlds, a tall box landing and a pyramid, are
stepped here by :class:`~solutions.response.sweep_solver.SweepWorld`, whose step after
the contact search is the student's ``step_bodies`` called through the sandbox.
"""
from __future__ import annotations

import numpy as np
import pytest

from grader.harness.compare import show
from grader.harness.credit import check_cases, fail
from grader.harness.student_code import register
from grader.oracles import upright_scenes as scenes
from grader.sandbox.codec import is_number
from grader.tests.public.test_sequential import (SWEEPS, answer_problem, describe, follow_targets, landing_ball,
                                                 point_problem, prestep_cases, random_cases, random_joint_rows,
                                                 random_step_cases, random_sweep_cases, random_targets, scene_calls,
                                                 step_problem, sweep_problem)
from solutions.body import Body
from solutions import joints as joint_solver
from solutions.contact import Contact
from solutions.joints import DistanceJoint, JointSolver
from solutions.response import contact_solver
from solutions.response.contact_solver import ContactSolver, SolverSettings
from solutions.response.sweep_solver import SweepWorld
from solutions.scenes import pyramid
from solutions.solver import contact_sweeps
from solutions.solver.contact_point import apply_friction_impulse, apply_normal_impulse
from solutions.world import World, WorldSettings

MODULE = "solver.contact_point"
BOXES, CHAIN, STEPS, DT, G = 10, 3, 60, 1 / 60, 9.81
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
@pytest.mark.title("Sequential impulses: random visits against the reference (normal, joint rows and friction)")
def test_random_against_reference(student):
    against_reference(student, "apply_normal_impulse", apply_normal_impulse,
                      random_cases(901, 40, friction=False) + random_joint_rows(903, 20))
    against_reference(student, "apply_friction_impulse", apply_friction_impulse, random_cases(902, 40, friction=True))


#: The program's functions (StudentCode.run_program), by index.
NORMAL, FRICTION = 0, 1
SWEEP_FUNCTIONS = [(MODULE, "apply_normal_impulse"), (MODULE, "apply_friction_impulse")]
STACK = "the stack of ten boxes and the hanging chain with your sweeps"


def student_sweeps(student):
    """A ``solve_constraints`` (:mod:`solutions.solver.kernel`, accumulated rows, friction
    first or none (joints), no block solve) whose visits are the student's functions, run in
    their sandbox in one round trip; which row is visited when, what each visit is
    given and where its answer goes are decided here; the visits' answers come back
    as the velocities and accumulated impulses after the sweeps."""

    def solve_constraints(velocity, rows, iterations, normal_total, tangent_total, target, mass_scale,
                          impulse_scale, accumulate=True, friction_first=False, use_friction=True, use_block=True):
        if not accumulate or (use_friction and not friction_first) or (use_block and np.any(rows.block)):
            raise AssertionError("the stack scene solves accumulated rows, friction first or none, without block "
                                 "solves")
        registers = {f"v{i}": [float(x) for x in row] for i, row in enumerate(velocity)}
        groups = []
        for g in range(len(rows.first)):
            a, b = int(rows.a[g]), int(rows.b[g])
            members = range(int(rows.first[g]), int(rows.first[g] + rows.count[g]))
            groups.append((a, b, members))
            for k in members:
                registers[f"p{k}"] = [float(x) for x in (
                    rows.nx[g], rows.ny[g], rows.rn_a[k], rows.rn_b[k], rows.rt_a[k], rows.rt_b[k], rows.ima[g],
                    rows.imb[g], rows.iia[g], rows.iib[g], rows.mass_normal[k], rows.mass_tangent[k],
                    rows.friction[k], rows.lower[k])]
                registers[f"N{k}"], registers[f"T{k}"] = float(normal_total[k]), float(tangent_total[k])
        calls = []
        for _ in range(iterations):
            for a, b, members in groups:
                bodies = [register(f"v{a}"), register(f"v{b}")]
                for k in members:
                    if use_friction and rows.friction[k] != 0.0:
                        calls.append((FRICTION, [*bodies, register(f"p{k}"), register(f"N{k}"), register(f"T{k}")],
                                      [f"v{a}", f"v{b}", f"T{k}"]))
                for k in members:
                    calls.append((NORMAL, [*bodies, register(f"p{k}"), register(f"N{k}"), float(target[k]),
                                           float(mass_scale[k]), float(impulse_scale[k])], [f"v{a}", f"v{b}", f"N{k}"]))
        names = [f"v{i}" for i in range(len(velocity))]
        totals = [f"{kind}{k}" for kind in "NT" for k in range(len(normal_total))]
        found, _ = student.run_program(SWEEP_FUNCTIONS, registers, calls, names + totals, STACK, timeout=60.0)
        velocities = [found[name] for name in names]
        bad = [v for v in velocities if not isinstance(v, list) or len(v) != 3 or not all(map(is_number, v))]
        bad += [found[name] for name in totals if not is_number(found[name])]
        if bad:
            fail(f"{STACK}: your functions returned {show(bad[0])[:300]} where (vx, vy, w) and an accumulated impulse "
                 "(numbers) were expected")
        velocity[:] = np.array(velocities, dtype=float)
        normal_total[:] = [float(found[f"N{k}"]) for k in range(len(normal_total))]
        tangent_total[:] = [float(found[f"T{k}"]) for k in range(len(tangent_total))]

    return solve_constraints


def stack_of_boxes(steps: int, count: int, dt: float, iterations: int = 20,
                   chain: int = CHAIN) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``count`` 1 m, 1 kg boxes stacked on static ground, and ``chain`` 0.5 m, 1 kg boxes
    hanging beside them from a static ceiling by rigid distance joints (0.5 m long, top
    anchor to bottom anchor), stepped with the reference's contact and joint solvers (the
    block solver off, so that every normal impulse is a visit; the sweeps are whatever
    :func:`solutions.solver.kernel.kernel` gives).  The contacts are exact (each face on
    the one below, depth 0) and the joints start at their length.  Per step the boxes'
    (y, vy), the stack's then the chain's, the accumulated normal impulse of each contact,
    bottom first, and of each joint, ceiling first."""
    ground = Body.box(10.0, 1.0, is_static=True, position=(0.0, -0.5), friction=0.6)
    bodies = [ground] + [Body.box(1.0, 1.0, position=(0.0, 0.5 + k), friction=0.6) for k in range(count)]
    ceiling = Body.box(2.0, 1.0, is_static=True, position=(8.0, count + 2.5))
    hanging = [ceiling] + [Body.box(0.5, 0.5, position=(8.0, count + 1.25 - k)) for k in range(chain)]
    rods = [DistanceJoint(k, k + 1, anchor_a=(0.0, -0.5 if k == 0 else -0.25), anchor_b=(0.0, 0.25), length=0.5)
            for k in range(chain)]
    solver = ContactSolver(SolverSettings(iterations=iterations, block_solver=False, position_correction="none",
                                          restitution_threshold=0.0))
    joints = JointSolver(iterations=iterations)
    trajectory, impulses, pulls = [], [], []
    for _ in range(steps):
        for body in bodies[1:] + hanging[1:]:
            body.velocity = body.velocity + dt * np.array([0.0, -G])
        manifolds = []
        for k in range(count):
            top = float(bodies[k].position[1]) + 0.5
            manifolds.append((k, k + 1, Contact((0.0, 1.0), 0.0, [(-0.5, top), (0.5, top)],
                                                feature_ids=("left", "right"))))
        solver.solve(bodies, manifolds, dt)
        joints.solve(hanging, rods, dt)
        for body in bodies[1:] + hanging[1:]:
            body.position = body.position + dt * body.velocity
            body.angle += dt * body.angular_velocity
        trajectory.append([[float(b.position[1]), float(b.velocity[1])] for b in bodies[1:] + hanging[1:]])
        totals = [0.0] * count
        for i, _, _, normal, _ in solver.contact_impulses:
            totals[i] += float(normal)
        impulses.append(totals)
        pulls.append([joints.impulses.get(k, 0.0) for k in range(chain)])
    return np.array(trajectory), np.array(impulses), np.array(pulls)


@pytest.mark.points(2)
@pytest.mark.visibility("hidden")
@pytest.mark.title("Sequential impulses: a stack of ten boxes rests on the complementarity answer, a chain of "
                   "three hangs from its joints")
def test_stack_of_ten(student, monkeypatch):
    monkeypatch.setattr(contact_solver, "kernel", lambda backend: student_sweeps(student))
    monkeypatch.setattr(joint_solver, "kernel", lambda backend: student_sweeps(student))
    trajectory, impulses, pulls = stack_of_boxes(STEPS, BOXES, DT)
    if not (np.all(np.isfinite(trajectory)) and np.all(np.isfinite(impulses)) and np.all(np.isfinite(pulls))):
        fail("the stack of ten boxes and the chain produced non-finite positions, velocities or impulses")
    want = np.array([(BOXES - k) * G * DT for k in range(BOXES)])       # N s per step, bottom contact first
    worst = int(np.argmax(np.abs(impulses[-1] - want)))
    if abs(impulses[-1, worst] - want[worst]) > LOAD_TOLERANCE * want[worst]:
        fail(f"after {STEPS} steps contact {worst} (counted from the ground) carries {impulses[-1, worst]:.6g} N s "
             f"per step; a resting stack puts the weight of the {BOXES - worst} boxes above it there, "
             f"{want[worst]:.6g} N s (all contacts: {np.round(impulses[-1], 6).tolist()})")
    hold = np.array([-(CHAIN - k) * G * DT for k in range(CHAIN)])     # N s per step, the top joint first
    worst = int(np.argmax(np.abs(pulls[-1] - hold)))
    if abs(pulls[-1, worst] - hold[worst]) > LOAD_TOLERANCE * abs(hold[worst]):
        fail(f"after {STEPS} steps joint {worst} of the hanging chain (counted from the ceiling) carries "
             f"{pulls[-1, worst]:.6g} N s per step; it must pull up the {CHAIN - worst} boxes below it, "
             f"{hold[worst]:.6g} N s (a joint row's lower bound is -inf: its impulse may be negative; all joints: "
             f"{np.round(pulls[-1], 6).tolist()})")
    sinking = float(np.abs(trajectory[-1, :, 1]).max())
    if sinking > SPEED_TOLERANCE:
        moving = int(np.argmax(np.abs(trajectory[-1, :, 1])))
        which = (f"box {moving} of the stack" if moving < BOXES else f"box {moving - BOXES} of the chain")
        fail(f"after {STEPS} steps {which} still moves at {sinking:.3g} m/s: the stack and the chain do not rest")



# The prestep and the sweeps, against the reference and in the engine's world -----------
@pytest.mark.points(1)
@pytest.mark.visibility("hidden")
@pytest.mark.title("Prestep, sweeps and step: random points, targets, manifolds and bodies against the reference")
def test_prestep_and_sweeps_against_reference(student):
    for function, cases, problem in (
            ("prestep_point", prestep_cases(911, 40), lambda got, want, _: point_problem(got, list(want))),
            ("contact_target", random_targets(912, 60),
             lambda got, want, _: None if isinstance(got, (int, float)) and abs(got - want) <= 1e-9 * (1 + abs(want))
             else f"the target is {show(got)}, {want!r} expected"),
            ("sweep_contacts", random_sweep_cases(913, 30),
             lambda got, want, _: sweep_problem(got, [[list(v) for v in want[0]], want[1], want[2]])),
            ("step_bodies", random_step_cases(914, 30), lambda got, _, args: step_problem(got, args))):
        answers = student.call_many(SWEEPS, function, [list(args) for args, _ in cases])
        reference = getattr(contact_sweeps, function)
        check_cases(list(zip(cases, answers)), lambda ca: problem(ca[1], reference(*ca[0][0]), ca[0][0]),
                    f"random {function}", category=lambda ca: ca[0][1])


def world_with(student, bodies, scene: str, **settings) -> World:
    """A plain-step world whose step after the contact search is the student's
    step_bodies (with their prestep and sweeps), called from here through the sandbox."""
    return SweepWorld(bodies, WorldSettings(solver=SolverSettings(block_solver=False, **settings)),
                      scene_calls(student, scene))


def tall_box(velocity_y: float = -3.0) -> list[Body]:
    ground = Body.box(10.0, 1.0, position=(0.0, -0.5), is_static=True, friction=0.6)
    return [ground, Body.box(0.4, 3.0, mass=1.0, position=(0.0, 1.5), velocity=(0.0, velocity_y), friction=0.6)]


def follow_reference(student, make_bodies, scene: str, steps: int, hint: str = "") -> World:
    """Step ``make_bodies()`` with the student's step_bodies and with the reference's,
    side by side; fail at the first step where a body's pose differs by more than 1e-6."""
    world = world_with(student, make_bodies(), scene)
    reference = SweepWorld(make_bodies(), WorldSettings(solver=SolverSettings(block_solver=False)))
    for step in range(steps):
        world.step(DT)
        reference.step(DT)
        for index, (body, want) in enumerate(zip(world.bodies[1:], reference.bodies[1:]), start=1):
            got_pose, want_pose = [*body.position, body.angle], [*want.position, want.angle]
            if not np.allclose(got_pose, want_pose, atol=1e-6):
                which = f"body {index}" if len(world.bodies) > 2 else "the box"
                fail(f"{scene}, step {step + 1}: {which} is at (x, y, angle) = {np.round(got_pose, 5).tolist()}, "
                     f"the reference's step puts it at {np.round(want_pose, 5).tolist()}{hint}")
    return world


@pytest.mark.points(2)
@pytest.mark.visibility("hidden")
@pytest.mark.title("World, your step: a tall box landing flat at 3 m/s stops upright, as the reference's "
                   "step stops it")
def test_tall_box_landing(student):
    scene = "the tall box (0.4 x 3 m) landing flat at 3 m/s"
    world = follow_reference(student, tall_box, scene, 30)
    angle = abs(float(world.bodies[1].angle))
    assert angle < 0.01, f"{scene}: it turned by {angle:.4f} rad (the reference: 0.004 rad)"


def bouncing_bodies() -> list[Body]:
    """The ground (e = 1), a ball (e = 0.7) and a tilted box (e = 0.4) dropped onto it, a
    ball (e = 0.8) dropped onto a box resting on it."""
    return [Body.box(20.0, 1.0, position=(0.0, -0.5), is_static=True, friction=0.6, restitution=1.0),
            Body.circle(0.4, mass=1.0, position=(-4.0, 1.5), restitution=0.7, friction=0.3),
            Body.box(0.8, 0.6, mass=2.0, position=(0.0, 1.2), angle=0.3, restitution=0.4, friction=0.5),
            Body.box(1.0, 1.0, mass=3.0, position=(4.0, 0.5), friction=0.6),
            Body.circle(0.3, mass=0.5, position=(4.1, 2.0), restitution=0.8, friction=0.3)]


@pytest.mark.points(2)
@pytest.mark.visibility("hidden")
@pytest.mark.title("World, your step: balls and a box dropped onto the ground and onto a box bounce as the "
                   "reference's step makes them (1 s)")
def test_bouncing_bodies(student):
    follow_reference(student, bouncing_bodies,
                     "the balls and the tilted box dropped onto the ground and onto a box (e = 0.4 to 0.8)", 60,
                     " (a landing faster than the threshold leaves at e times its closing speed)")


@pytest.mark.points(2)
@pytest.mark.visibility("hidden")
@pytest.mark.title("World, your step: a pyramid of five rows stands for 1 s (engine contacts)")
def test_pyramid_stands(student):
    scene = "the pyramid of five rows"
    bodies = pyramid(5)
    start = np.array([body.position.tolist() for body in bodies])
    world = world_with(student, bodies, scene)
    for _ in range(60):
        world.step(DT)
    moved = float(np.abs(np.array([body.position.tolist() for body in bodies]) - start).max())
    assert moved < 0.02, f"{scene}: after 1 s a box has moved {moved:.3f} m from where it rested"


#: The balls landing either side of a 0.5 m/s restitution threshold: (the closing speed
#: when they touch the ground, on the second step (m/s), e, the height of their lowest
#: point at the start (m)).
LANDINGS = [(0.3, 0.9, 0.0005), (0.45, 0.7, 0.002), (0.55, 0.6, 0.001), (0.7, 0.5, 0.004), (0.8, 0.3, 0.0005),
            (1.0, 0.4, 0.003), (1.2, 0.2, 0.001), (2.0, 0.2, 0.006)]


@pytest.mark.points(2)
@pytest.mark.visibility("hidden")
@pytest.mark.title("Scene: eight balls landing either side of a 0.5 m/s restitution threshold bounce only above it "
                   "and are pushed out to the slop")
def test_landings_either_side_of_the_threshold(student):
    settings = scenes.SceneSettings(restitution_threshold=0.5)
    balls = [landing_ball(speed, e, above, x=2.0 * k) for k, (speed, e, above) in enumerate(LANDINGS)]
    follow_targets(student, "the eight balls landing either side of a 0.5 m/s threshold", balls, settings, 60,
                   "a contact closing faster than the threshold leaves at e times its speed, a slower one does not "
                   "bounce; an overlap beyond the slop is pushed out at bias_factor (overlap - slop) / h")
