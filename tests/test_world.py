"""World step: the pipeline, its switches, and named scenes against independent oracles."""
import hashlib
import math

import numpy as np
import pytest

from solutions import scene_metrics as metrics
from solutions import world as world_module
from solutions.body import Body
from solutions.shapes import Circle
from solutions.response.contact_solver import SolverSettings
from solutions.scenes import KMH, SCENES, get_scene
from solutions.world import World, WorldSettings


def run(world, seconds, dt=1 / 60):
    for _ in range(round(seconds / dt)):
        world.step(dt)
    return world


def test_truck_and_car_move_on_together_at_the_momentum_average():
    # Worked example 1 (erratum 15): the common speed is the momentum average.
    scene = get_scene("truck_and_car")
    world = run(scene.build_world(), 1.0)
    truck, car = world.bodies
    want = (5000 * 80 + 1000 * 60) / 6000 * KMH  # 76.67 km/h = 21.30 m/s
    np.testing.assert_allclose([truck.velocity[0], car.velocity[0]], [want, want], rtol=1e-6)


def test_elastic_balls_swap_to_minus_ten_and_plus_five():
    # Worked example 2: momentum and energy give exactly -10 and +5 m/s.
    world = run(get_scene("elastic_balls").build_world(), 0.2)
    np.testing.assert_allclose([b.velocity[0] for b in world.bodies], [-10.0, 5.0], rtol=1e-9)


def test_ball_bounces_back_at_e_times_the_impact_speed():
    world = get_scene("ball_drop").build_world()
    ball = world.bodies[1]
    speeds = []
    for _ in range(240):
        before = ball.velocity[1]
        world.step(1 / 60)
        if before < 0 < ball.velocity[1]:
            speeds.append((before, ball.velocity[1]))
    impact, rebound = speeds[0]
    # Gravity acts for one step inside the impact step: compare with the speed at contact.
    assert rebound / -(impact - 9.81 / 60) == pytest.approx(0.8, rel=0.02)


def test_stack_of_ten_stays_up_for_ten_seconds():
    # Recommended settings for stacks: 20 iterations with warm starting (the default).
    scene = get_scene("stack_10")
    world = scene.build_world(iterations=20)
    start = metrics.start_positions(world.bodies)
    deepest = 0.0
    for _ in range(scene.steps):
        world.step(scene.dt)
        deepest = max(deepest, world.stats.max_penetration)
    assert deepest < 0.01, f"penetration {deepest:.4f} m"
    assert metrics.max_drift(world.bodies, start) < 0.05


@pytest.mark.parametrize("continuous, passes", [(False, True), (True, False)])
def test_bullet_tunnels_only_without_continuous_detection(continuous, passes):
    scene = get_scene("bullet_wall")
    settings = scene.world_settings()
    settings.continuous = continuous
    world = run(World(scene.make_bodies(), settings), 0.2)
    wall, bullet = world.bodies
    assert bool(bullet.position[0] > wall.position[0]) is passes


def test_bullet_is_stopped_at_many_start_offsets():
    # Whatever phase the wall falls at within a step, the bullet never passes it.
    scene = get_scene("bullet_wall")
    for offset in np.linspace(0, 100 / 60, 25, endpoint=False):
        bodies = scene.make_bodies()
        bodies[1].position = bodies[1].position + (offset, 0)
        world = run(World(bodies, scene.world_settings()), 0.1)
        assert world.bodies[1].position[0] < world.bodies[0].position[0]


def test_static_static_pairs_are_never_tested(monkeypatch):
    tested = []
    real_collide = world_module.collide
    monkeypatch.setattr(world_module, "collide", lambda a, b: tested.append((a, b)) or real_collide(a, b))
    walls = [Body.box(1, 1, is_static=True, position=(k * 0.5, 0)) for k in range(30)]
    ball = Body.circle(0.3, position=(0, 0.8))
    world = World(walls + [ball])
    world.step(1 / 60)
    assert tested and all(ball.world_shape().radius in (getattr(s, "radius", None) for s in pair) for pair in tested)


def test_tiny_scenes_skip_the_broad_phase(monkeypatch):
    def forbidden(*args, **kwargs):
        raise AssertionError("broad phase ran on a tiny scene")

    monkeypatch.setattr(world_module, "pairs_grid_numpy", forbidden)
    world = get_scene("elastic_balls").build_world()
    world.step(1 / 60)
    big = get_scene("many_uniform").build_world()
    with pytest.raises(AssertionError, match="broad phase ran"):
        big.step(1 / 60)


def test_scene_switches_follow_what_the_scene_needs():
    circles = get_scene("many_uniform").world_settings()
    assert not circles.solver.rotation and not circles.solver.friction and not circles.continuous
    stack = get_scene("stack_10").world_settings()
    assert stack.solver.rotation and stack.solver.friction
    assert get_scene("bullet_wall").world_settings().continuous


@pytest.mark.parametrize("method", ["all_pairs", "brute_force", "uniform_grid", "quadtree", "numpy_grid"])
def test_every_broad_phase_gives_the_same_simulation(method):
    scene = get_scene("many_clustered")
    reference = run(scene.build_world(), 0.1)
    settings = scene.world_settings()
    settings.broad_phase = method
    other = run(World(scene.make_bodies(), settings), 0.1)
    np.testing.assert_allclose([b.position for b in other.bodies], [b.position for b in reference.bodies],
                               rtol=0, atol=1e-9)


def state_hash(world):
    state = np.array([[*b.position, b.angle, *b.velocity, b.angular_velocity] for b in world.bodies])
    return hashlib.sha256(state.tobytes()).hexdigest()


def test_same_scene_same_settings_same_final_state():
    scene = get_scene("pyramid_10")
    assert state_hash(run(scene.build_world(), 0.5)) == state_hash(run(scene.build_world(), 0.5))


def test_frictionless_circles_conserve_momentum_without_walls():
    bodies = [b for b in get_scene("many_clustered").make_bodies() if not b.is_static]
    world = World(bodies, WorldSettings(gravity=(0, 0), solver=SolverSettings(rotation=False, friction=False)))
    p0 = metrics.linear_momentum(world.bodies)
    run(world, 0.5)
    np.testing.assert_allclose(metrics.linear_momentum(world.bodies), p0, atol=1e-9 * len(bodies))


@pytest.mark.parametrize("bad, message", [
    (dict(broad_phase="octree"), "broad_phase must be one of"),
    (dict(substeps=0), "substeps"),
    (dict(gravity=(0, math.nan)), "gravity"),
])
def test_bad_world_settings_raise(bad, message):
    with pytest.raises(ValueError, match=message):
        WorldSettings(**bad)


@pytest.mark.parametrize("dt", [0, -1 / 60, math.nan])
def test_bad_time_step_raises(dt):
    with pytest.raises(ValueError, match="dt must be"):
        World([]).step(dt)


def test_empty_and_single_body_worlds_step():
    run(World([]), 0.1)
    lone = run(World([Body.circle(1.0)]), 1.0)
    assert lone.bodies[0].position[1] == pytest.approx(-9.81 * 1.0 * (1 + 1 / 60) / 2, rel=1e-9)


def test_every_named_scene_builds_and_steps():
    for name, scene in SCENES.items():
        world = scene.build_world()
        world.step(scene.dt)
        assert all(np.all(np.isfinite(b.position)) for b in world.bodies), name


def test_unknown_scene_lists_the_known_ones():
    with pytest.raises(ValueError, match="known scenes: .*stack_10"):
        get_scene("stack_11")


def test_auto_broad_phase_takes_the_fastest_measured_method(monkeypatch):
    # Measured by bench/bench_auto_broad_phase.py: all pairs directly only for 2 bodies
    # and for scenes of circles only up to 40; the brute-force AABB test for other scenes
    # below 80 bodies; the numpy grid from 80 on.  The old rule (all pairs below 16
    # bodies, the numpy grid above) took the slowest method for the speed chapter's 4 balls
    # among 4 walls and for 4 to 12 scattered boxes.
    def boxes(n):
        return [Body.box(0.5, 0.5, mass=1.0, position=(1.0 * (k % 8), 1.0 * (k // 8))) for k in range(n)]

    def balls(n):
        return [Body.circle(0.2, mass=1.0, position=(1.0 * (k % 8), 1.0 * (k // 8))) for k in range(n)]

    cases = [(boxes(2), "all_pairs"), (balls(40), "all_pairs"), (balls(41), "brute_force"),
             (balls(39) + boxes(1), "brute_force"), (boxes(3), "brute_force"), (boxes(79), "brute_force"),
             (boxes(80), "numpy_grid"), (get_scene("stack_10").make_bodies(), "brute_force"),
             (get_scene("many_uniform").make_bodies(), "numpy_grid")]
    for bodies, expected in cases:
        called = []
        for name in ("pairs_brute_force", "pairs_grid_numpy", "pairs_uniform_grid", "pairs_quadtree"):
            real = getattr(world_module, name)
            monkeypatch.setattr(world_module, name,
                                lambda *args, real=real, name=name, **kwargs: called.append(name) or real(*args, **kwargs))
        auto = World(bodies, WorldSettings(gravity=(0.0, 0.0)))
        shapes = auto.world_shapes()
        found = {(i, j) for i, j, _ in auto.narrow_phase(shapes, auto.broad_phase(shapes))}
        assert called == ({"all_pairs": [], "brute_force": ["pairs_brute_force"],
                           "numpy_grid": ["pairs_grid_numpy"]}[expected]), (len(bodies), expected, called)
        every = World(bodies, WorldSettings(gravity=(0.0, 0.0), broad_phase="all_pairs"))
        assert found == {(i, j) for i, j, _ in every.narrow_phase(shapes, every.broad_phase(shapes))}
        monkeypatch.undo()


def step_by_hand(world: World, dt: float) -> None:
    """World.step's outline (solutions/world.py), written out with the world's stages."""
    soft = world.settings.soft_step
    rounds, substeps = (1, world.settings.substeps) if soft else (world.settings.substeps, 1)
    h = dt / world.settings.substeps
    for _ in range(rounds):
        shapes = world.world_shapes()
        world.manifolds = world.find_contacts(shapes)
        world.solver.begin_step(world.bodies, world.manifolds, h)
        starts = world.bullet_starts() if soft else {}
        for _ in range(substeps):
            world.apply_gravity(h)
            world.solver.solve_substep(world.state, h, use_bias=True)
            world.solve_joints(h, use_bias=True)
            world.integrate_positions({} if soft else world.sweep_bullets(shapes, h), h)
            world.solve_joints(h, use_bias=False)
            world.solver.solve_substep(world.state, h, use_bias=False)
            world.time += h
        world.solver.end_step(world.state, h)
        world.stop_bullets(shapes, starts)


OUTLINE_CASES = [("box_on_slope", False, dict(position_correction="projection"), 2),
                 ("stack_10", False, dict(position_correction="split_impulse"), 1),
                 ("ball_drop", False, dict(position_correction="baumgarte"), 3),
                 ("bullet_wall", False, {}, 2), ("chain_40", False, {}, 1),
                 ("pyramid_10", True, {}, 4), ("chain_40", True, {}, 4), ("bullet_wall", True, {}, 2),
                 ("chain_40", True, dict(relax=False), 4)]


@pytest.mark.parametrize("name, soft, overrides, substeps", OUTLINE_CASES,
                         ids=[f"{c[0]}-{'soft' if c[1] else 'plain'}-{c[3]}" for c in OUTLINE_CASES])
def test_the_plain_and_soft_steps_are_one_outline_of_stages(name, soft, overrides, substeps):
    """Both steps are configurations of one outline: running the world's stages by hand
    in the documented order moves every body bit for bit as World.step does."""
    scene = get_scene(name)
    settings = scene.world_settings(**overrides)
    settings.soft_step, settings.substeps = soft, substeps
    stepped, by_hand = scene.build_world(settings), scene.build_world(settings)
    for _ in range(20):
        stepped.step(scene.dt)
        step_by_hand(by_hand, scene.dt)
    assert np.array_equal(stepped.state.velocity, by_hand.state.velocity)
    assert np.array_equal(stepped.state.position, by_hand.state.position)
    assert stepped.stats == by_hand.stats and stepped.time == by_hand.time


@pytest.mark.parametrize("soft", [False, True])
def test_restitution_aims_at_the_closing_speed_after_gravity_plain_and_before_it_soft(soft):
    """A ball hitting the ground at 3 m/s with e = 0.5: the plain step (box2d-lite)
    measures the closing speed after this step's gravity, the soft step (Box2D v3)
    at the start of the step, before gravity."""
    ground = Body.box(10.0, 1.0, position=(0.0, -0.5), is_static=True, restitution=1.0)
    ball = Body.circle(0.5, position=(0.0, 0.5), velocity=(0.0, -3.0), restitution=0.5)
    settings = WorldSettings(soft_step=soft, solver=SolverSettings(position_correction="none"))
    World([ground, ball], settings).step(1 / 60)
    want = 0.5 * (3.0 + 9.81 / 60) if not soft else 0.5 * 3.0
    assert ball.velocity[1] == pytest.approx(want, abs=1e-12)


@pytest.mark.parametrize("soft", [False, True])
@pytest.mark.parametrize("stage", ["solve", "relax", "end"])
def test_a_solver_stage_before_begin_step_says_so(soft, stage):
    from solutions.body_state import BodyState
    from solutions.response.contact_solver import ContactSolver
    from solutions.response.soft_step import SoftStepSolver

    solver = SoftStepSolver() if soft else ContactSolver()
    state = BodyState.gather([Body.circle(0.5)])
    call = {"solve": lambda: solver.solve_substep(state, 0.01, use_bias=True),
            "relax": lambda: solver.solve_substep(state, 0.01, use_bias=False),
            "end": lambda: solver.end_step(state, 0.01)}[stage]
    with pytest.raises(RuntimeError, match=r"call begin_step\(\) before"):
        call()


@pytest.mark.parametrize("backend", ["python", "numba"])
def test_gravity_is_changed_by_assignment_and_every_step_sees_it(backend):
    """A list given as gravity is kept as a tuple (an in-place edit would go unseen by a
    world that keeps its compiled settings between steps): assigning a new gravity turns
    the fall around on the next step, in both backends."""
    settings = WorldSettings(gravity=[0.0, -9.81], soft_step=True, backend=backend)
    assert settings.gravity == (0.0, -9.81)
    with pytest.raises(TypeError):
        settings.gravity[1] = 9.81
    with pytest.raises(ValueError, match="gravity"):
        settings.gravity = (0.0,)
    world = World([Body(Circle((0.0, 0.0), 0.5), position=(0.0, 10.0))], settings)
    for _ in range(3):
        world.step(1 / 60)
    falling = world.bodies[0].velocity[1]
    world.settings.gravity = (0.0, 9.81)
    world.step(1 / 60)
    assert falling < 0 and world.bodies[0].velocity[1] == pytest.approx(falling + 9.81 / 60, abs=1e-12)
