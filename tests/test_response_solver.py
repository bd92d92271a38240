"""The sequential-impulse ContactSolver on hand-made scenes.

Contacts come from a tiny box-on-face clipper written here (the course's narrow phase
is developed elsewhere), and the step follows the calling contract of
solutions.response.contact_solver: v += g dt; solve; x += v dt; finish_step.
Oracles: conservation laws, the 1D collision law, weight times dt for resting
contacts, and the comparisons the switches exist to show.
"""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from solutions.body import Body
from solutions.contact import Contact
from solutions.response.contact_solver import ContactSolver, SolverSettings
from solutions.response.pyramid_contacts import pyramid_contacts
from solutions.response.impulse import relative_normal_velocity
from solutions.response.momentum_1d import collision_1d

GRAVITY = np.array([0.0, -9.81])  # m/s^2
DT = 1 / 60  # s
TOUCHING = 1e-9  # m: rounding slack of "touching" in the test's contact generation


def up_axis(body):
    return np.array([-math.sin(body.angle), math.cos(body.angle)])


def face_contact(lower, upper):
    """The bottom edge of box ``upper`` clipped to the top face of box ``lower``.

    Normal: ``lower``'s up axis (from lower to upper).  Points: the two ends of the
    clipped edge, kept when they touch or overlap the face (depth >= 0, with
    ``TOUCHING`` m of slack for rounding), placed halfway between the surfaces;
    feature id = which end of the edge."""
    normal = up_axis(lower)
    side = np.array([normal[1], -normal[0]])
    half_width, half_height = lower.shape.half_extents
    up = up_axis(upper)
    upper_half_width, upper_half_height = upper.shape.half_extents
    ends = [upper.position + sign * upper_half_width * np.array([up[1], -up[0]]) - upper_half_height * up
            for sign in (-1.0, 1.0)]
    lateral = [float((p - lower.position) @ side) for p in ends]
    height = [float((p - lower.position) @ normal) for p in ends]
    points, depths, ids = [], [], []
    for k, other in ((0, 1), (1, 0)):
        s, h = lateral[k], height[k]
        if abs(s) > half_width:
            if abs(lateral[other]) > half_width and math.copysign(1, lateral[other]) == math.copysign(1, s):
                continue
            limit = math.copysign(half_width, s)
            h += (limit - s) / (lateral[other] - s) * (height[other] - h)
            s = limit
        depth = half_height - h
        if depth >= -TOUCHING:
            depth = max(depth, 0.0)
            points.append(lower.position + s * side + (half_height - depth / 2) * normal)
            depths.append(depth)
            ids.append(k)
    return Contact(normal, max(depths), points, depths, tuple(ids)) if points else None


def stack(masses, friction=0.5):
    """Static ground (top at y = 0) and unit boxes of ``masses`` (kg) stacked on it, touching."""
    bodies = [Body.box(40.0, 1.0, position=(0.0, -0.5), is_static=True, friction=1.0)]
    for level, mass in enumerate(masses):
        bodies.append(Body.box(1.0, 1.0, mass=mass, position=(0.0, 0.5 + level), friction=friction))
    return bodies


def stack_manifolds(bodies):
    found = [(k, k + 1, face_contact(bodies[k], bodies[k + 1])) for k in range(len(bodies) - 1)]
    return [m for m in found if m[2] is not None]


def world_step(bodies, manifolds, solver, dt=DT):
    """The World.step of the contact_solver module docstring."""
    for body in bodies:
        if not body.is_static:
            body.velocity = body.velocity + dt * GRAVITY
    solver.solve(bodies, manifolds, dt)
    for body in bodies:
        if not body.is_static:
            body.position = body.position + dt * body.velocity
            body.angle += dt * body.angular_velocity
    solver.finish_step(bodies, manifolds, dt)


def approach_residual(bodies, manifolds):
    """Largest closing speed (m/s) left at any contact point after a solve."""
    return max([-relative_normal_velocity(bodies[i], bodies[j], p, c.normal) for i, j, c in manifolds for p in c.points]
               + [0.0])


def run_stack(masses, solver_settings, steps=120):
    """Simulate; return the bodies, the per-step residual and max penetration."""
    bodies = stack(masses)
    solver = ContactSolver(solver_settings)
    residuals, penetrations = [], []
    for _ in range(steps):
        manifolds = stack_manifolds(bodies)
        for body in bodies[1:]:
            body.velocity = body.velocity + DT * GRAVITY
        solver.solve(bodies, manifolds, DT)
        residuals.append(approach_residual(bodies, manifolds))
        penetrations.append(solver.stats.max_penetration)
        for body in bodies[1:]:
            body.position = body.position + DT * body.velocity
            body.angle += DT * body.angular_velocity
        solver.finish_step(bodies, manifolds, DT)
    return bodies, np.array(residuals), np.array(penetrations)


def mechanical_energy(bodies):
    return sum(b.kinetic_energy() - b.mass * float(GRAVITY @ b.position) for b in bodies if not b.is_static)


# ------------------------------------------------------------- resting contact
@pytest.mark.parametrize("mode", ["none", "baumgarte", "projection", "split_impulse"])
@pytest.mark.parametrize("backend", ["python", "numba"])
def test_resting_box_does_not_sink_or_gain_energy(mode, backend):
    bodies = stack([2.0])
    box = bodies[1]
    solver = ContactSolver(SolverSettings(position_correction=mode), backend=backend)
    start = mechanical_energy(bodies)  # kinetic + potential, J
    for _ in range(120):
        manifolds = stack_manifolds(bodies)
        assert manifolds, "the box lost contact with the ground"
        world_step(bodies, manifolds, solver)
        # 1e-6 relative (50 nm of height here) admits the first step's unconverged
        # friction tilting the box on a corner; a box gaining energy would bounce.
        assert mechanical_energy(bodies) <= start * (1 + 1e-6)
    # A resting contact lags gravity by at most one step of fall, g dt^2 (0.0027 m).
    assert solver.stats.max_penetration <= solver.settings.slop + 9.81 * DT**2
    assert -box.position[1] + 0.5 <= solver.settings.slop + 9.81 * DT**2
    assert box.kinetic_energy() < 1e-12
    assert solver.stats.contact_points == 2
    # The ground carries the weight: total normal impulse per step = m g dt.
    assert solver.stats.total_normal_impulse == pytest.approx(box.mass * 9.81 * DT, rel=1e-6)


def test_accumulated_impulses_hold_a_stack_better_than_clamped_increments():
    on, _, pen_on = run_stack([1.0] * 5, SolverSettings())
    off, _, pen_off = run_stack([1.0] * 5, SolverSettings(accumulate_impulses=False))
    sink_on, sink_off = 4.5 - on[-1].position[1], 4.5 - off[-1].position[1]
    assert 2 * sink_on < sink_off
    assert 2 * pen_on[60:].max() < pen_off[60:].max()
    # A single box solved point by point: the first corner's impulse overshoots, and
    # clamped increments can never take it back, so the box jitters.  The block solver
    # gets both corners right in one go, so it needs nothing taken back.
    point_by_point = dict(block_solver=False)
    single_on, _, _ = run_stack([1.0], SolverSettings(**point_by_point))
    single_off, _, _ = run_stack([1.0], SolverSettings(accumulate_impulses=False, **point_by_point))
    assert single_on[1].kinetic_energy() < 1e-20 < 1e-9 < single_off[1].kinetic_energy()
    single_block, _, _ = run_stack([1.0], SolverSettings(accumulate_impulses=False))
    assert single_block[1].kinetic_energy() < 1e-20


def test_warm_starting_needs_fewer_iterations():
    # No position correction, so the residual is the solver's error alone.
    warm, residual_warm, _ = run_stack([1.0] * 5, SolverSettings(iterations=5, position_correction="none"))
    cold, residual_cold, _ = run_stack([1.0] * 5, SolverSettings(iterations=20, warm_starting=False,
                                                                  position_correction="none"))
    assert 4 * residual_warm[20:].mean() < residual_cold[20:].mean()
    assert 4 * (4.5 - warm[-1].position[1]) < 4.5 - cold[-1].position[1]
    # More iterations help a cold solver: the comparison runs in the expected direction.
    _, residual_cold_5, _ = run_stack([1.0] * 5, SolverSettings(iterations=5, warm_starting=False,
                                                                 position_correction="none"))
    assert residual_cold[20:].mean() < residual_cold_5[20:].mean()


def on_slope(friction, angle):
    """Static ground tilted by ``angle`` (rad) through the origin and a 1 kg unit box
    resting on it; returns the bodies, the slope's normal and its downhill direction."""
    normal = np.array([-math.sin(angle), math.cos(angle)])
    ground = Body.box(40.0, 1.0, position=-0.5 * normal, angle=angle, is_static=True, friction=1.0)
    box = Body.box(1.0, 1.0, position=0.5 * normal, angle=angle, friction=friction)
    return [ground, box], normal, -np.array([math.cos(angle), math.sin(angle)])


@pytest.mark.parametrize("friction", [0.0, 0.1, 0.2, 0.3])
def test_box_slides_down_a_slope_as_coulomb_friction_says(friction):
    # tan(20 deg) = 0.36 > mu: the box slides with a = g (sin - mu cos); semi-implicit
    # Euler from rest covers a dt^2 n (n + 1) / 2 in n steps.
    angle, steps = math.radians(20), 60
    bodies, normal, downhill = on_slope(friction, angle)
    solver = ContactSolver()
    for _ in range(steps):
        world_step(bodies, stack_manifolds(bodies), solver)
    acceleration = 9.81 * (math.sin(angle) - friction * math.cos(angle))
    travelled = float((bodies[1].position - 0.5 * normal) @ downhill)
    assert travelled == pytest.approx(acceleration * DT**2 * steps * (steps + 1) / 2, rel=1e-6)
    assert bodies[1].angle == pytest.approx(angle, abs=1e-6)  # slides flat, no tipping


def test_warm_started_friction_holds_a_box_on_a_slope():
    # mu = 0.6 > tan(20 deg): the box must stay; with 2 iterations only the impulses
    # carried over from the last step (normal and friction) keep it in place.
    creep = {}
    for warm_starting in (True, False):
        bodies, normal, downhill = on_slope(0.6, math.radians(20))
        solver = ContactSolver(SolverSettings(iterations=2, warm_starting=warm_starting))
        for _ in range(120):
            world_step(bodies, stack_manifolds(bodies), solver)
        creep[warm_starting] = abs(float((bodies[1].position - 0.5 * normal) @ downhill))
    assert creep[True] < 1e-3
    assert 4 * creep[True] < creep[False]


def test_mass_ratio_1_to_1000_holds_better_with_more_iterations():
    # 1000 kg resting on a 1 kg box: the hard case for Gauss-Seidel.
    worst = []
    for iterations in (10, 100, 300):
        _, _, penetration = run_stack([1.0, 1000.0], SolverSettings(iterations=iterations), steps=60)
        worst.append(penetration.max())
    assert worst[0] > worst[1] > worst[2]
    assert worst[0] > 0.1 > 0.03 > worst[2]


def test_pyramid_converges_to_the_weight():
    bodies, manifolds = pyramid_contacts(base=6)
    boxes = bodies[1:]
    for body in boxes:
        body.velocity = np.array([0.0, -9.81 * DT])  # one step of gravity from rest
    solver = ContactSolver(SolverSettings(iterations=400, position_correction="none"))
    solver.solve(bodies, manifolds, DT)
    assert max(np.abs(b.velocity).max() for b in boxes) < 1e-9
    on_ground = sum(pn for i, _, _, pn, _ in solver.contact_impulses if i == 0)
    assert on_ground == pytest.approx(sum(b.mass for b in boxes) * 9.81 * DT, rel=1e-9)


# ------------------------------------------------------- two implementations
def random_scene(rng, static=True, restitution=True):
    count = int(rng.integers(2, 6))
    bodies = []
    for k in range(count):
        is_static = static and k == 0
        # A fixed rotation (infinite inertia) keeps w = 0: a spinning one would be an
        # energy source, like a moving static body.
        fixed_rotation = static and bool(rng.random() < 0.1)
        common = dict(mass=rng.uniform(0.1, 10), position=rng.uniform(-2, 2, 2), angle=rng.uniform(-3, 3),
                      velocity=(0.0, 0.0) if is_static else rng.uniform(-3, 3, 2),
                      angular_velocity=0.0 if is_static or fixed_rotation else rng.uniform(-3, 3),
                      friction=rng.uniform(0, 1), restitution=rng.uniform(0, 1) if restitution else 0.0,
                      is_static=is_static, fixed_rotation=fixed_rotation)
        if rng.random() < 0.5:
            bodies.append(Body.box(rng.uniform(0.2, 2), rng.uniform(0.2, 2), **common))
        else:
            bodies.append(Body.circle(rng.uniform(0.2, 1), **common))
    manifolds = []
    for _ in range(int(rng.integers(1, 7))):
        i, j = (int(x) for x in rng.choice(count, 2, replace=False))
        angle = rng.uniform(0, 2 * np.pi)
        k = int(rng.integers(1, 3))
        ids = tuple(rng.integers(0, 3, k).tolist()) if rng.random() < 0.5 else None
        if ids is not None and len(set(ids)) < k:
            ids = None
        manifolds.append((i, j, Contact((math.cos(angle), math.sin(angle)), 0.0, rng.uniform(-2, 2, (k, 2)),
                                        rng.uniform(0, 0.05, k), ids)))
    return bodies, manifolds


def clone(bodies):
    return [Body(b.shape, mass=b.mass, position=b.position, angle=b.angle, velocity=b.velocity,
                 angular_velocity=b.angular_velocity, restitution=b.restitution, friction=b.friction,
                 is_static=b.is_static, fixed_rotation=b.fixed_rotation) for b in bodies]


@pytest.mark.parametrize("mode", ["none", "baumgarte", "projection", "split_impulse"])
@pytest.mark.parametrize("accumulate", [True, False])
@pytest.mark.parametrize("order, block_solver", [("manifolds", True), ("colours", True), ("manifolds", False)])
def test_the_readable_kernel_and_its_numba_twin_agree(mode, accumulate, order, block_solver):
    rng = np.random.default_rng(21)
    scenes = [random_scene(rng) for _ in range(30)] + [pyramid_contacts(base=4)]
    for bodies, manifolds in scenes:
        results = []
        for backend in ("python", "numba"):
            copy = clone(bodies)
            solver = ContactSolver(SolverSettings(position_correction=mode, accumulate_impulses=accumulate,
                                                  order=order, block_solver=block_solver), backend=backend)
            for _ in range(3):  # later steps are warm started
                world_step(copy, manifolds, solver)
            results.append((np.array([[*b.position, b.angle, *b.velocity, b.angular_velocity] for b in copy]),
                            np.array([c[3:] for c in solver.contact_impulses])))
        np.testing.assert_allclose(results[0][0], results[1][0], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(results[0][1], results[1][1], rtol=1e-12, atol=1e-12)


# ------------------------------------------------------------ conservation
def momenta(bodies):
    linear = sum(b.mass * b.velocity for b in bodies)
    angular = sum(b.mass * (b.position[0] * b.velocity[1] - b.position[1] * b.velocity[0]) + b.inertia * b.angular_velocity
                  for b in bodies)
    return linear, angular


@settings(max_examples=120, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from(["none", "baumgarte", "projection", "split_impulse"]),
       st.booleans(), st.booleans(), st.booleans(), st.integers(1, 15))
def test_solve_conserves_momentum_without_static_bodies(seed, mode, accumulate, friction, rotation, iterations):
    bodies, manifolds = random_scene(np.random.default_rng(seed), static=False)
    solver = ContactSolver(SolverSettings(position_correction=mode, accumulate_impulses=accumulate, friction=friction,
                                          rotation=rotation, iterations=iterations, restitution_threshold=0.0))
    for _ in range(2):  # the second solve is warm started
        linear, angular = momenta(bodies)
        scale = sum(b.mass * (1 + np.linalg.norm(b.velocity)) * (1 + np.linalg.norm(b.position)) + b.inertia * (1 + abs(b.angular_velocity)) for b in bodies)
        solver.solve(bodies, manifolds, DT)
        linear_after, angular_after = momenta(bodies)
        np.testing.assert_allclose(linear_after, linear, atol=1e-9 * scale)
        if rotation:  # without rotation the torques of the impulses are dropped on purpose
            assert angular_after == pytest.approx(angular, abs=1e-9 * scale)


@settings(max_examples=150, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from(["none", "projection", "split_impulse"]),
       st.booleans(), st.booleans(), st.booleans(), st.integers(1, 20))
def test_solve_never_gains_kinetic_energy_without_restitution(seed, mode, accumulate, friction, static, iterations):
    # Baumgarte is left out: its bias pushes overlapping bodies apart with real velocity.
    bodies, manifolds = random_scene(np.random.default_rng(seed), static=static, restitution=False)
    before = sum(b.kinetic_energy() for b in bodies)
    solver = ContactSolver(SolverSettings(position_correction=mode, accumulate_impulses=accumulate,
                                          friction=friction, iterations=iterations))
    solver.solve(bodies, manifolds, DT)
    assert sum(b.kinetic_energy() for b in bodies) <= before * (1 + 1e-12) + 1e-12


# ------------------------------------------------------------------- switches
@pytest.mark.parametrize("rotation", [True, False])
def test_head_on_discs_match_collision_1d(rotation):
    rng = np.random.default_rng(5)
    for _ in range(20):
        m1, m2 = rng.uniform(0.1, 10, 2)
        v1, v2 = rng.uniform(1, 5), -rng.uniform(1, 5)
        e1, e2 = rng.uniform(0, 1, 2)
        a = Body.circle(0.5, mass=m1, position=(-0.5, 0.0), velocity=(v1, 0.0), restitution=e1)
        b = Body.circle(0.5, mass=m2, position=(0.5, 0.0), velocity=(v2, 0.0), restitution=e2)
        solver = ContactSolver(SolverSettings(restitution_threshold=0.0, rotation=rotation))
        solver.solve([a, b], [(0, 1, Contact((1.0, 0.0), 0.0, [(0.0, 0.0)]))], DT)
        assert (a.velocity[0], b.velocity[0]) == pytest.approx(collision_1d(m1, v1, m2, v2, e1 * e2), rel=1e-12, abs=1e-12)


def test_restitution_threshold_stops_slow_bounces():
    for speed, bounces in ((0.5, False), (2.0, True)):
        ground = Body.box(10.0, 1.0, position=(0.0, -0.5), is_static=True, restitution=1.0)
        ball = Body.circle(0.5, position=(0.0, 0.5), velocity=(0.0, -speed), restitution=0.8)
        ContactSolver().solve([ground, ball], [(0, 1, Contact((0.0, 1.0), 0.0, [(0.0, 0.0)]))], DT)
        assert ball.velocity[1] == pytest.approx(0.8 * speed if bounces else 0.0, abs=1e-12)


def test_rotation_switch_skips_angular_terms():
    def hit(rotation):
        ground = Body.box(10.0, 1.0, position=(0.0, -0.5), is_static=True)
        box = Body.box(1.0, 1.0, position=(0.0, 0.5), velocity=(0.0, -1.0), angular_velocity=0.3)
        ContactSolver(SolverSettings(rotation=rotation, friction=False, iterations=1)).solve(
            [ground, box], [(0, 1, Contact((0.0, 1.0), 0.0, [(0.4, 0.0)]))], DT)
        return box
    free, sliding = hit(True), hit(False)
    assert free.angular_velocity != 0.3 and free.velocity[1] > -1.0
    assert sliding.angular_velocity == 0.3          # untouched
    assert sliding.velocity[1] == pytest.approx(0.0)  # a point mass stopped in one impulse


@pytest.mark.parametrize("mode", ["baumgarte", "projection", "split_impulse"])
def test_position_correction_modes_lift_a_sunk_box(mode):
    depth, slop, beta, percent = 0.1, 0.005, 0.2, 0.8
    ground = Body.box(10.0, 1.0, position=(0.0, -0.5), is_static=True)
    box = Body.box(1.0, 1.0, position=(0.0, 0.5 - depth))
    bodies = [ground, box]
    manifolds = [(0, 1, Contact((0.0, 1.0), depth, [(-0.5, -depth / 2), (0.5, -depth / 2)], feature_ids=(0, 1)))]
    solver = ContactSolver(SolverSettings(position_correction=mode, iterations=50, slop=slop, baumgarte=beta,
                                          correction_percent=percent))
    solver.solve(bodies, manifolds, DT)
    after_solve = box.velocity.copy()
    box.position = box.position + DT * box.velocity
    solver.finish_step(bodies, manifolds, DT)
    if mode == "baumgarte":   # a real velocity: the box will fly up with kinetic energy
        assert after_solve[1] == pytest.approx(beta / DT * (depth - slop), rel=1e-9)
        assert box.position[1] == pytest.approx(0.5 - depth + beta * (depth - slop), rel=1e-9)
    else:                     # positions only: no kinetic energy
        assert np.abs(after_solve).max() < 1e-12
        lift = percent * (depth - slop) if mode == "projection" else beta * (depth - slop)
        assert box.position[1] == pytest.approx(0.5 - depth + lift, rel=1e-9)
    assert box.angle == pytest.approx(0.0, abs=1e-9)


def test_projection_uses_the_overlap_after_integration():
    # Discs approaching: after the step they overlap more than the contact said.
    a = Body.circle(0.5, position=(-0.45, 0.0), velocity=(0.0, 0.0))
    b = Body.circle(0.5, position=(0.45, 0.0), velocity=(-6.0, 0.0))
    manifolds = [(0, 1, Contact((1.0, 0.0), 0.1, [(0.0, 0.0)]))]
    solver = ContactSolver(SolverSettings(position_correction="projection", iterations=0, slop=0.0, correction_percent=1.0))
    solver.solve([a, b], manifolds, DT)
    b.position = b.position + DT * b.velocity
    solver.correct_positions([a, b], manifolds)
    assert np.linalg.norm(b.position - a.position) == pytest.approx(1.0, rel=1e-12)  # exactly touching


def test_warm_start_matches_features_and_nearby_points():
    def resting(points, ids):
        ground = Body.box(10.0, 1.0, position=(0.0, -0.5), is_static=True)
        box = Body.box(1.0, 1.0, position=(0.0, 0.5))
        return [ground, box], [(0, 1, Contact((0.0, 1.0), 0.0, points, feature_ids=ids))]
    corners = np.array([(-0.5, 0.0), (0.5, 0.0)])
    for ids, shift, matched in ((None, 0.01, 2), (None, 0.2, 0), ((0, 1), 0.2, 2)):
        solver = ContactSolver(SolverSettings(position_correction="none"))
        world_step(*resting(corners, ids), solver)
        bodies, manifolds = resting(corners + [shift, 0.0], ids)
        world_step(bodies, manifolds, solver)
        assert solver.stats.warm_started_points == matched
    # New feature ids (the narrow phase swapped reference faces, say) fall back to the
    # nearest old point of the pair: found where the points stayed, not 0.2 m away.
    for shift, matched in ((0.0, 2), (0.2, 0)):
        solver = ContactSolver()
        world_step(*resting(corners, (0, 1)), solver)
        bodies, manifolds = resting(corners + [shift, 0.0], (7, 8))
        world_step(bodies, manifolds, solver)
        assert solver.stats.warm_started_points == matched
    # A swapped pair with the flipped normal finds both.
    world_step(bodies, manifolds, solver)
    swapped = [(1, 0, manifolds[0][2].flipped())]
    world_step(bodies, swapped, solver)
    assert solver.stats.warm_started_points == 2
    assert bodies[1].velocity == pytest.approx([0.0, 0.0], abs=1e-12)


def test_warm_start_scales_with_the_time_step():
    ground = Body.box(10.0, 1.0, position=(0.0, -0.5), is_static=True)
    box = Body.box(1.0, 1.0, mass=3.0, position=(0.0, 0.5))
    manifolds = [(0, 1, Contact((0.0, 1.0), 0.0, [(-0.5, 0.0), (0.5, 0.0)], feature_ids=(0, 1)))]
    solver = ContactSolver(SolverSettings(position_correction="none"))
    for _ in range(5):
        world_step([ground, box], manifolds, solver)
    solver.settings.iterations = 0  # the warm start alone
    world_step([ground, box], manifolds, solver, dt=DT / 2)
    assert solver.stats.total_normal_impulse == pytest.approx(3.0 * 9.81 * DT / 2, rel=1e-9)
    assert solver.stats.warm_started_points == 2


def test_stats_report_points_penetration_and_impulse():
    bodies, manifolds = pyramid_contacts(base=3, depth=0.002)
    solver = ContactSolver()
    world_step(bodies, manifolds, solver)
    assert solver.stats.manifolds == 9 and solver.stats.contact_points == 18
    assert solver.stats.max_penetration == pytest.approx(0.002)
    assert solver.stats.total_normal_impulse == pytest.approx(sum(c[3] for c in solver.contact_impulses))
    assert solver.stats.total_pseudo_impulse == 0.0
    empty = ContactSolver()
    empty.solve(bodies, [], DT)
    assert (empty.stats.contact_points, empty.stats.total_normal_impulse, empty.stats.max_penetration) == (0, 0.0, 0.0)


@pytest.mark.parametrize("bad", [dict(position_correction="penalty"), dict(iterations=-1), dict(iterations=2.5),
                                 dict(baumgarte=1.5), dict(correction_percent=-0.1), dict(slop=-0.01),
                                 dict(restitution_threshold=math.nan), dict(order="random")])
def test_settings_are_validated(bad):
    with pytest.raises(ValueError):
        SolverSettings(**bad)


def test_an_unknown_backend_is_refused_with_the_choices():
    with pytest.raises(ValueError, match="backend must be one of .'python', 'numba'., got 'gpu'"):
        ContactSolver(backend="gpu")


def test_solve_rejects_bad_input():
    bodies = stack([1.0])
    with pytest.raises(ValueError):
        ContactSolver().solve(bodies, stack_manifolds(bodies), 0.0)
    with pytest.raises(ValueError):
        ContactSolver().solve(bodies, [(1, 1, Contact((0.0, 1.0), 0.0, [(0.0, 0.0)]))], DT)
    with pytest.raises(RuntimeError):
        ContactSolver(SolverSettings(position_correction="projection")).correct_positions(bodies, stack_manifolds(bodies))
