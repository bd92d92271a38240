"""Hidden impulse tests: conservation laws, and a scene stepped with the student's resolver.

Instructor's side only: these may use the reference engine (``solutions``) and the
``reference`` fixture.  The conservation test needs no expected answer at all: one
impulse, +P to B and -P to A, conserves linear momentum and angular momentum about any
point whatever P is, a single contact with e <= 1 and Coulomb friction gains no
kinetic energy, and the velocity changes must be the impulses the function returned.
The scene test steps balls dropped in a box here, in the trusted process, calling the
student's ``resolve_collision`` and ``correct_positions`` on each step's contacts in
their sandbox (one program of calls per step, :meth:`StudentCode.run_program`; gravity,
the contacts and the integration are computed here), and the same with the
reference's functions in the reference's sandbox; when the trajectories part, it
replays the scene here with the reference engine up to the first step that differs
and calls the student's ``resolve_collision`` and ``correct_positions`` on that step's
contacts one at a time, to name the first call whose answer differs.
"""
from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from grader.sandbox.codec import encode_body, encode_contact, is_number
from grader.harness.compare import as_vector, number, show, vector
from grader.harness.credit import check_cases, fail
from grader.harness.reference_runs import kept_reference_run
from grader.harness.student_code import register
from grader.oracles.impulse_sympy import show_body, show_contact
from solutions.body import Body
from solutions.contact import Contact
from solutions.response.impulse import relative_normal_velocity, resolve_collision
from solutions.response.positional_correction import correct_positions

MODULE = "response.impulse"
CORRECTION = "response.positional_correction"


# Conservation ---------------------------------------------------------------------------------
def random_body(rng: np.random.Generator, kind: str, position) -> Body:
    static, fixed = kind == "static", kind == "fixed"
    kwargs = dict(mass=float(rng.uniform(0.3, 5.0)), position=position, angle=float(rng.uniform(-3, 3)),
                  velocity=(0.0, 0.0) if static else rng.normal(0, 3, 2),
                  angular_velocity=0.0 if static or fixed else float(rng.normal(0, 2.5)),
                  restitution=float(rng.uniform(0.1, 1.0)), friction=float(rng.uniform(0.0, 1.2)),
                  is_static=static, fixed_rotation=fixed)
    if rng.random() < 0.5:
        return Body.circle(float(rng.uniform(0.2, 0.9)), **kwargs)
    return Body.box(float(rng.uniform(0.4, 1.8)), float(rng.uniform(0.3, 1.2)), **kwargs)


def approaching_case(rng: np.random.Generator, kinds: tuple[str, str], points: int) -> tuple[Body, Body, Contact]:
    """Two bodies along a random normal, 1 or 2 points between them, the first approaching."""
    while True:
        n = np.array([math.cos(a := rng.uniform(-math.pi, math.pi)), math.sin(a)])
        t = np.array([n[1], -n[0]])
        a = random_body(rng, kinds[0], rng.uniform(-3, 3, 2))
        b = random_body(rng, kinds[1], a.position + float(rng.uniform(0.6, 1.6)) * n + rng.normal(0, 0.2, 2))
        middle = (a.position + b.position) / 2
        offset, half = float(rng.uniform(-0.3, 0.3)), float(rng.uniform(0.2, 0.6))
        chosen = [middle + offset * t] if points == 1 else [middle + (offset - half) * t, middle + (offset + half) * t]
        v_n = relative_normal_velocity(a, b, chosen[0], n)
        if v_n > 0:
            for body in (a, b):
                body.velocity, body.angular_velocity = -body.velocity, -body.angular_velocity
        if abs(v_n) > 0.05:
            return a, b, Contact(n, 0.05, chosen)


def momenta(bodies: list[Body]) -> tuple[np.ndarray, float]:
    """Linear momentum and angular momentum about the origin of dynamic bodies."""
    linear, angular = np.zeros(2), 0.0
    for body in bodies:
        linear += body.mass * body.velocity
        spin = 0.0 if math.isinf(body.inertia) else body.inertia * body.angular_velocity
        angular += spin + body.mass * float(body.position[0] * body.velocity[1] - body.position[1] * body.velocity[0])
    return linear, angular


def state_after(body: Body, data) -> Body | None:
    """``body`` with the velocities the student's call left (None if they are not numbers)."""
    if not isinstance(data, dict):
        return None
    after = copy.deepcopy(body)
    try:
        after.velocity = np.array(data["velocity"], dtype=float).reshape(2)
        after.angular_velocity = float(data["angular_velocity"])
    except (KeyError, TypeError, ValueError):
        return None
    if not (np.all(np.isfinite(after.velocity)) and math.isfinite(after.angular_velocity)):
        return None
    return after


def conservation_problem(case, result) -> str | None:
    a, b, contact = case
    value, after = result
    a2, b2 = state_after(a, after[0]), state_after(b, after[1])
    if a2 is None or b2 is None:
        return f"the bodies' velocities after the call are not finite numbers: {show(after)}"
    if not isinstance(value, list) or len(value) != 2:
        return f"must return (normal_impulses, tangent_impulses), got {show(value)}"
    count = len(contact.points)
    jn, jt = as_vector(value[0], count), as_vector(value[1], count)
    if jn is None or jt is None or not (np.all(np.isfinite(jn)) and np.all(np.isfinite(jt))):
        return (f"must return (normal_impulses, tangent_impulses), {count} finite number(s) each (one per contact "
                f"point), got {show(value)}")
    if np.any(jn < 0):
        return f"normal impulses {show(jn.tolist())} include a pull (j_i < 0): a contact only pushes"
    # The velocity changes must be the returned impulses: m_B dv_B = sum P_i, m_A dv_A = -sum P_i.
    n = contact.normal
    t = np.array([n[1], -n[0]])
    total = sum((jn[i] * n + jt[i] * t for i in range(count)), np.zeros(2))
    for label, before, later, sign in (("A", a, a2, -1.0), ("B", b, b2, 1.0)):
        if before.is_static:
            continue
        change = before.mass * (later.velocity - before.velocity)
        problem = vector(f"momentum change of {label}, m (v' - v)", change.tolist(), sign * total, atol=1e-9, rtol=1e-9)
        if problem is None and not math.isinf(before.inertia):
            arms = [p - before.position for p in contact.points]
            torque = sum(float(r[0] * (jn[i] * n + jt[i] * t)[1] - r[1] * (jn[i] * n + jt[i] * t)[0])
                         for i, r in enumerate(arms))
            problem = number(f"angular momentum change of {label}, I (w' - w)",
                             before.inertia * (later.angular_velocity - before.angular_velocity), sign * torque,
                             atol=1e-9, rtol=1e-9)
        if problem:
            return (f"{problem}: the velocity changes must be the returned impulses j_i n + j_t,i t "
                    f"(t = (n_y, -n_x)), +P to B and -P to A, turning each body by r x P / I; "
                    f"returned j = {show(jn.tolist())}, j_t = {show(jt.tolist())}")
    if not (a.is_static or b.is_static):
        (l0, h0), (l1, h1) = momenta([a, b]), momenta([a2, b2])
        problem = vector("total linear momentum after", l1.tolist(), l0, atol=1e-9, rtol=1e-9)
        if problem is None and not (a.fixed_rotation or b.fixed_rotation):
            # A fixed rotation takes torque from outside: only then is angular momentum not kept.
            problem = number("total angular momentum about the origin after", h1, h0, rtol=1e-9, atol=1e-9)
        if problem:
            return (f"{problem}: momentum must be conserved; apply ONE impulse per point, +P to B and -P to A "
                    "(erratum 22: computing a separate impulse for each body breaks this)")
    # Every case approaches: the response must push (a resolver that does nothing keeps
    # momentum and energy, and fails here); without friction, which turns the bodies
    # after the normal impulse, no contact point may still close in afterwards.
    if not np.any(jn > 0):
        return (f"the bodies approach at the contact, but the normal impulses are {show(jn.tolist())}: a "
                "contact that closes in must be pushed apart (j > 0)")
    if a.friction * b.friction == 0.0:
        for point in contact.points:
            closing = float((b2.velocity_at(point) - a2.velocity_at(point)) @ n)
            if closing < -1e-9:
                return (f"after the call the bodies still approach at the contact point {show(list(point))}: "
                        f"relative normal velocity {closing:.6g} m/s < 0 (no friction here); the impulses must "
                        f"stop the approach (returned j = {show(jn.tolist())})")
    if count == 1:
        energy_before = a.kinetic_energy() + b.kinetic_energy()
        energy_after = a2.kinetic_energy() + b2.kinetic_energy()
        if energy_after > energy_before * (1 + 1e-9) + 1e-12:
            return f"the kinetic energy grew from {energy_before:.10g} J to {energy_after:.10g} J"
    return None


def describe(case) -> str:
    a, b, contact = case
    return (f"resolve_collision(A: {show_body(encode_body(a))}; B: {show_body(encode_body(b))}; "
            f"{show_contact(encode_contact(contact))})")


@pytest.mark.points(3)
@pytest.mark.visibility("after_due_date")
@pytest.mark.title("Response conserves momentum and gains no energy")
def test_resolve_conserves_momentum(student):
    """One impulse per point, +P to B and -P to A: momentum kept, no energy gained."""
    rng = np.random.default_rng(605)
    cases = []
    for k in range(12):
        a, b, contact = approaching_case(rng, ("dynamic", "dynamic"), 1)
        if k % 4 == 1:
            a.restitution = b.restitution = 1.0
        elif k % 4 == 2:
            a.friction = 0.0
        cases.append((a, b, contact))
    for kinds in (("dynamic", "dynamic"), ("fixed", "dynamic"), ("dynamic", "fixed"), ("dynamic", "dynamic")):
        cases.append(approaching_case(rng, kinds, 2))
    for kinds in (("static", "dynamic"), ("dynamic", "static"), ("fixed", "static"), ("fixed", "dynamic")):
        cases.append(approaching_case(rng, kinds, 1))
    results = [student.call_with_state(MODULE, "resolve_collision", *case) for case in cases]
    check_cases(zip(cases, results), lambda cr: conservation_problem(*cr), "resolve_collision",
                describe=lambda cr: describe(cr[0]))


# The scene ---------------------------------------------------------------------------------------
STEPS = 120
#: Allowed deviation from the reference (m, RMS of the final positions): the same
#: algorithm in another order of floating-point operations stays far below this.
POSITION_TOLERANCE = 1e-6
#: A step "differs" when a position or velocity differs by more than this (m, m/s).
STEP_TOLERANCE = 1e-9
GRAVITY = 9.81


#: The box's walls, (nx, ny, offset): n . x >= offset inside.
WALLS = ((0.0, 1.0, 0.0), (1.0, 0.0, -1.5), (-1.0, 0.0, -1.5))
#: The program's functions (StudentCode.run_program), by index.
RESOLVE, CORRECT = 0, 1
SCENE_FUNCTIONS = [(MODULE, "resolve_collision"), (CORRECTION, "correct_positions")]


def initial_balls(count: int = 16, radius: float = 0.2):
    """Positions on a jittered grid (deterministic), velocities, radius (m)."""
    balls = []
    for k in range(count):
        row, column = divmod(k, 4)
        jitter = 0.03 * math.sin(7.3 * k)
        balls.append(((-0.9 + 0.6 * column + jitter, 0.5 + 0.55 * row), (0.4 * math.cos(3.1 * k), 0.0)))
    return balls, radius


def take_state(body: Body, data, where: str) -> None:
    """Set ``body``'s position, velocity, angle and angular velocity from a body the
    worker sent back (plain data); the test fails if it is not one."""
    if not isinstance(data, dict):
        fail(f"{where}: a body came back as {show(data)[:300]}, not a body")
    position, velocity = as_vector(data.get("position"), 2), as_vector(data.get("velocity"), 2)
    angle, spin = data.get("angle"), data.get("angular_velocity")
    if position is None or velocity is None or not (is_number(angle) and is_number(spin)):
        fail(f"{where}: a body came back as {show(data)[:300]}, not a body")
    body.position, body.velocity = position, velocity
    body.angle, body.angular_velocity = float(angle), float(spin)


def trajectory_metrics(trajectory: np.ndarray, radius: float) -> dict:
    """Deepest overlap (m) and energy gain (J) of a (steps, balls, 4) trajectory."""
    positions, velocities = trajectory[..., :2], trajectory[..., 2:]
    deepest = 0.0
    for frame in positions:
        gaps = np.linalg.norm(frame[:, None, :] - frame[None, :, :], axis=-1)
        np.fill_diagonal(gaps, np.inf)
        deepest = max(deepest, float(2 * radius - gaps.min()), float(radius - frame[:, 1].min()),
                      float(frame[:, 0].max() + radius - 1.5), float(-1.5 - (frame[:, 0].min() - radius)))
    energy = 0.5 * np.sum(velocities ** 2, axis=(1, 2)) + GRAVITY * np.sum(positions[..., 1], axis=1)
    return {"max_penetration": max(deepest, 0.0), "energy_gain": float(energy.max() - energy[0])}


def pymunk_trajectory(dt: float, restitution: float = 0.5, friction: float = 0.2) -> np.ndarray:
    """The same scene in pymunk (an error figure, not a pass mark)."""
    import pymunk

    start, radius = initial_balls()
    space = pymunk.Space()
    space.gravity = (0, -GRAVITY)
    space.collision_slop = 0.01
    walls = [pymunk.Segment(space.static_body, (-3, 0), (3, 0), 0),
             pymunk.Segment(space.static_body, (-1.5, 0), (-1.5, 10), 0),
             pymunk.Segment(space.static_body, (1.5, 0), (1.5, 10), 0)]
    for wall in walls:
        wall.elasticity, wall.friction = 1.0, 1.0
    space.add(*walls)
    bodies = []
    for p, v in start:
        body = pymunk.Body(1.0, pymunk.moment_for_circle(1.0, 0, radius))
        body.position, body.velocity = p, v
        shape = pymunk.Circle(body, radius)
        shape.elasticity, shape.friction = restitution, friction
        space.add(body, shape)
        bodies.append(body)
    frames = []
    for _ in range(STEPS):
        space.step(dt)
        frames.append([[*b.position, *b.velocity] for b in bodies])
    return np.array(frames)


def rms_distance(frame: np.ndarray, other: np.ndarray) -> float:
    """RMS over the balls of the distance between their positions in two frames (m)."""
    return float(np.sqrt(np.mean(np.sum((frame[:, :2] - other[:, :2]) ** 2, -1))))


#: Balls of the scene: the shape of every step of the trajectory is (BALLS, 4).
BALLS = len(initial_balls()[0])


def run_scene(code, who: str, restitution: float = 0.5, friction: float = 0.2,
              dt: float = 1 / 60) -> tuple[np.ndarray, float, float]:
    """(trajectory, radius, seconds) of the balls in the box stepped here with ``code``'s
    ``resolve_collision`` and ``correct_positions``: per step gravity, the contacts
    (:func:`scene_contacts`) and the integration are computed here, and the two
    functions run on that step's contacts, in order, in ``code``'s sandbox (one round
    trip a step; ``seconds`` adds up the round trips).  A first, untimed step pays for
    imports and first calls."""
    name = f"the ball scene with {who}"
    start, radius = initial_balls()
    balls = [Body.circle(radius, mass=1.0, position=p, velocity=v, restitution=restitution, friction=friction)
             for p, v in start]
    ground = Body.box(10.0, 1.0, is_static=True, position=(0.0, -0.5), restitution=1.0, friction=1.0)
    everyone = [*balls, ground]
    frames, seconds = [], 0.0
    for step in range(-1, STEPS):
        bodies = copy.deepcopy(everyone) if step < 0 else everyone  # the warm-up step moves nothing
        for ball in bodies[:-1]:
            ball.velocity = ball.velocity + dt * np.array([0.0, -GRAVITY])
        contacts = scene_contacts(bodies[:-1], bodies[-1], radius)
        if contacts:
            index = {id(body): k for k, body in enumerate(bodies)}
            calls = [(RESOLVE, [register(f"b{index[id(a)]}"), register(f"b{index[id(b)]}"), contact], None)
                     for a, b, contact in contacts]
            calls += [(CORRECT, [register(f"b{index[id(a)]}"), register(f"b{index[id(b)]}"), contact.normal,
                                 contact.depth, 0.8, 0.01], None) for a, b, contact in contacts]
            touched = sorted({index[id(body)] for a, b, _ in contacts for body in (a, b)})
            registers = {f"b{k}": bodies[k] for k in touched}
            found, elapsed = code.run_program(SCENE_FUNCTIONS, registers, calls, list(registers), name,
                                              timeout=60.0)
            seconds += elapsed if step >= 0 else 0.0
            for k in touched:
                take_state(bodies[k], found[f"b{k}"], f"{name}, step {step}")
        for ball in bodies[:-1]:
            ball.position = ball.position + dt * ball.velocity
        if step >= 0:
            frames.append([[*b.position, *b.velocity] for b in balls])
    return np.array(frames, dtype=float), radius, seconds


def scene_contacts(balls: list[Body], ground: Body, radius: float) -> list[tuple[Body, Body, Contact]]:
    """The contacts of one step of the ball scene (:func:`run_scene`): each ball with
    each wall and each later ball, the normal from the ball (A) out of the box or to
    the other ball."""
    contacts = []
    for i in range(len(balls)):
        xi, yi = balls[i].position
        for nx, ny, offset in WALLS:
            depth = offset - (nx * xi + ny * yi - radius)
            if depth >= 0:
                point = (xi - nx * (radius - depth / 2), yi - ny * (radius - depth / 2))
                contacts.append((balls[i], ground, Contact((-nx, -ny), depth, [point])))
        for j in range(i + 1, len(balls)):
            dx, dy = balls[j].position[0] - xi, balls[j].position[1] - yi
            distance = math.hypot(dx, dy)
            depth = 2 * radius - distance
            if depth >= 0 and distance > 0:
                n = (dx / distance, dy / distance)
                point = (xi + n[0] * (radius - depth / 2), yi + n[1] * (radius - depth / 2))
                contacts.append((balls[i], balls[j], Contact(n, depth, [point])))
    return contacts


def call_problem(student, function: str, module: str, args: tuple, reference_call) -> str | None:
    """The student's ``function(*args)`` against the reference on copies: returned
    values and both bodies' positions and velocities."""
    want_args = copy.deepcopy(args)
    want = reference_call(*want_args)
    value, after = student.call_with_state(module, function, *args)
    if not isinstance(value, list) or len(value) != 2:
        return f"returned {show(value)}, expected a tuple of two arrays {show([w.tolist() for w in want])}"
    for k, (got, expected) in enumerate(zip(value, want)):
        problem = vector(f"returned value [{k}]", got, expected, atol=STEP_TOLERANCE, rtol=1e-9)
        if problem:
            return problem
    for label, data, body in (("A", after[0], want_args[0]), ("B", after[1], want_args[1])):
        if not isinstance(data, dict):
            return f"body {label} did not come back as a body"
        problem = (vector(f"velocity of {label}", data.get("velocity"), body.velocity, atol=STEP_TOLERANCE)
                   or number(f"angular velocity of {label}", data.get("angular_velocity"), body.angular_velocity,
                             atol=STEP_TOLERANCE)
                   or vector(f"position of {label}", data.get("position"), body.position, atol=STEP_TOLERANCE))
        if problem:
            return problem
    return None


def first_differing_call(student, step: int, expected: np.ndarray, restitution: float = 0.5,
                         friction: float = 0.2, dt: float = 1 / 60) -> str:
    """Replay the scene with the reference engine up to ``step`` and call the student's
    functions on that step's contacts; a sentence naming the first call that differs."""
    start, radius = initial_balls()
    balls = [Body.circle(radius, mass=1.0, position=p, velocity=v, restitution=restitution, friction=friction)
             for p, v in start]
    ground = Body.box(10.0, 1.0, is_static=True, position=(0.0, -0.5), restitution=1.0, friction=1.0)
    for k in range(step + 1):
        for ball in balls:
            ball.velocity = ball.velocity + dt * np.array([0.0, -GRAVITY])
        contacts = scene_contacts(balls, ground, radius)
        if k == step:
            for a, b, contact in contacts:
                args = (a, b, contact)
                problem = call_problem(student, "resolve_collision", MODULE, args, resolve_collision)
                if problem:
                    return (f"the first call that differs from the reference is at step {step}: "
                            f"{describe(args)}: {problem}")
                resolve_collision(a, b, contact)
            for a, b, contact in contacts:
                args = (a, b, contact.normal, contact.depth, 0.8, 0.01)
                problem = call_problem(student, "correct_positions", CORRECTION, args, correct_positions)
                if problem:
                    return (f"the first call that differs from the reference is at step {step}: correct_positions("
                            f"A: {show_body(encode_body(a))}; B: {show_body(encode_body(b))}; normal "
                            f"{show(contact.normal.tolist())}, depth {contact.depth:.6g}, percent 0.8, slop 0.01): "
                            f"{problem}")
                correct_positions(a, b, contact.normal, contact.depth, 0.8, 0.01)
        else:
            for a, b, contact in contacts:
                resolve_collision(a, b, contact)
            for a, b, contact in contacts:
                correct_positions(a, b, contact.normal, contact.depth, 0.8, 0.01)
        for ball in balls:
            ball.position = ball.position + dt * ball.velocity
        replayed = np.array([[*b.position, *b.velocity] for b in balls])
        if k < step and not np.allclose(replayed, expected[k], rtol=0, atol=STEP_TOLERANCE):
            return "(the grader could not replay the scene to find the call at fault)"
    return (f"at step {step} your resolve_collision and correct_positions give the reference's answers call by call, "
            "so the difference comes from elsewhere in your package (Body, Contact, or the vector helpers they use)")


@pytest.mark.points(3)
@pytest.mark.visibility("after_published")
@pytest.mark.leaderboard("resolver scene time (s)")
@pytest.mark.title("Balls in a box stepped with your resolver (speed and error)")
def test_scene(student, reference, metrics):
    """Balls dropped in a box, stepped with the student's resolve_collision and
    correct_positions; speed against the reference, error against reference and pymunk."""
    trajectory, radius, seconds = run_scene(student, "your resolve_collision")
    if trajectory.ndim != 3 or trajectory.shape[0] != STEPS or not np.all(np.isfinite(trajectory)):
        fail(f"the ball scene with your resolve_collision and correct_positions produced non-finite or missing "
             f"positions or velocities (trajectory of shape {trajectory.shape})")
    metrics["seconds"] = seconds
    metrics.update(trajectory_metrics(trajectory, radius))
    oracle = pymunk_trajectory(1 / 60)
    metrics["distance_from_pymunk"] = rms_distance(trajectory[-1], oracle[-1])
    # Kept per grading process: the same trajectory for every submission, timed again side by side
    # every few submissions and when the student's time is well over the kept one.
    expected, reference_seconds = kept_reference_run(
        reference, "ball scene", seconds, lambda: run_scene(reference, "the reference")[::2])
    metrics["reference_seconds"] = reference_seconds
    metrics["reference_max_penetration"] = trajectory_metrics(expected, radius)["max_penetration"]
    distance = rms_distance(trajectory[-1], expected[-1])
    metrics["distance_from_reference"] = distance
    if distance <= POSITION_TOLERANCE:
        return
    differs = np.any(np.abs(trajectory - expected) > STEP_TOLERANCE, axis=(1, 2))
    step = int(np.argmax(differs))
    culprit = first_differing_call(student, step, expected)
    fail(f"after {STEPS} steps the balls are {distance:.3g} m (RMS) from where the reference puts them (tolerance "
         f"{POSITION_TOLERANCE:g} m); deepest overlap {metrics['max_penetration']:.3g} m, energy gained "
         f"{metrics['energy_gain']:.3g} J. The trajectories part at step {step} of {STEPS}; {culprit}")
