"""The soft step (solutions/response/soft_step.py) and its switches.

Oracles: sympy (implicit Euler of a spring-damper gives the soft coefficients, and
the sag of a loaded contact), a brute-force enumeration of the 2x2 complementarity
problem for the soft block solver, free fall (a speculative point never pulls), the
geometry of the moved shapes for the updated separations, and the comparisons that
each switch exists to show, run on the named hard scenes.
"""
import itertools
import math

import numpy as np
import pytest
import sympy as sp

from solutions import scene_metrics as metrics
from solutions.body import Body
from solutions.contact import Contact
from solutions.narrowphase.speculative import speculative_polygon_manifold
from solutions.response.contact_solver import SolverSettings
from solutions.response.solver_settings import SoftStepSettings, split_overrides
from solutions.body_state import BodyState
from solutions.response.soft_step import SoftStepSolver, soft_coefficients
from solutions.solver import kernel_numba
from solutions.solver.constraint_rows import ConstraintRows
from solutions.solver.kernel import solve_constraints
from solutions.scenes import get_scene, ground
from solutions.world import World, WorldSettings

G = 9.81
DT = 1 / 60


def soft_world(bodies, substeps=8, **settings):
    settings.setdefault("iterations", 1)
    solver, soft = split_overrides(settings)
    return World(bodies, WorldSettings(soft_step=True, substeps=substeps, solver=SolverSettings(**solver),
                                       soft=SoftStepSettings(**soft)))


def scene_world(name, **overrides):
    """The scene under its recommended (soft) settings, with solver or world overrides."""
    scene = get_scene(name)
    settings = scene.recommended_settings()
    for key, value in overrides.items():
        if hasattr(settings.solver, key):
            setattr(settings.solver, key, value)
        elif hasattr(settings.soft, key):
            setattr(settings.soft, key, value)
        else:
            setattr(settings, key, value)
    return scene, scene.build_world(settings)


def run(world, seconds, dt=DT, every=None):
    for k in range(round(seconds / dt)):
        world.step(dt)
        if every is not None:
            every(k)
    return world


# --- The soft constraint --------------------------------------------------------------
def implicit_spring_impulse():
    """Impulse lambda (N s) of one implicit Euler step of a spring-damper k = m w^2,
    c = 2 m zeta w on a constraint with position error C (m) and velocity v (m/s)."""
    m, w, zeta, h, C, v, v2 = sp.symbols("m omega zeta h C v v2", positive=True)
    k, c = m * w**2, 2 * m * zeta * w
    # m (v2 - v) = h (-k C2 - c v2) with C2 = C + h v2.
    v2_solved = sp.solve(sp.Eq(m * (v2 - v), h * (-k * (C + h * v2) - c * v2)), v2)[0]
    return (m, w, zeta, h, C, v), sp.simplify(m * (v2_solved - v))


def test_soft_coefficients_are_implicit_euler_of_a_spring_damper():
    (m, w, zeta, h, C, v), impulse = implicit_spring_impulse()
    f = sp.Symbol("f", positive=True)
    bias_rate, mass_scale, impulse_scale = (sp.lambdify((f, zeta, h), e) for e in (
        w / (2 * zeta + h * w), h * w * (2 * zeta + h * w) / (1 + h * w * (2 * zeta + h * w)),
        1 / (1 + h * w * (2 * zeta + h * w))))
    # The soft update from rest (accumulated impulse 0) is -m mass_scale (v + bias_rate C).
    soft = -m * (h * w * (2 * zeta + h * w) / (1 + h * w * (2 * zeta + h * w))) * (v + w / (2 * zeta + h * w) * C)
    assert sp.simplify(impulse - soft) == 0
    for hertz, ratio, step in itertools.product((5.0, 30.0, 120.0), (0.0, 1.0, 10.0), (1 / 60, 1 / 480)):
        want = [g(hertz, ratio, step) for g in (bias_rate, mass_scale, impulse_scale)]
        want = [float(x.subs(w, 2 * math.pi * hertz)) if isinstance(x, sp.Expr) else float(x) for x in want]
        np.testing.assert_allclose(soft_coefficients(hertz, ratio, step), want, rtol=1e-12)
    assert soft_coefficients(0.0, 10.0, 0.01) == (0.0, 1.0, 0.0)   # 0 Hz: rigid


def test_repeated_sweeps_converge_to_the_implicit_spring():
    # Fixed point of P <- P + (-m ms (v0 + P / m + br C) - is P): the same impulse.
    (m, w, zeta, h, C, v), impulse = implicit_spring_impulse()
    P = sp.Symbol("P")
    a2 = h * w * (2 * zeta + h * w)
    ms, is_, br = a2 / (1 + a2), 1 / (1 + a2), w / (2 * zeta + h * w)
    fixed = sp.solve(sp.Eq(-m * ms * (v + P / m + br * C) - is_ * P, 0), P)[0]
    assert sp.simplify(fixed - impulse) == 0


def test_a_resting_box_sags_as_far_as_its_spring_carries_its_weight():
    # Steady state of one soft sweep with P = m g h, v = 0: C = g / w^2, with the
    # doubled frequency of contacts on static bodies.  (The block solver makes the two
    # corners of a face one spring of the box's mass.)
    C, gee, w = sp.symbols("C g omega", positive=True)
    h, m = sp.symbols("h m", positive=True)
    a2 = h * w * (2 * 10 + h * w)
    sag = sp.solve(sp.Eq(m * a2 / (1 + a2) * (w / (20 + h * w)) * C, 1 / (1 + a2) * m * gee * h), C)[0]
    assert sp.simplify(sag - gee / w**2) == 0
    for hertz in (10.0, 20.0):
        box = Body.box(1.0, 1.0, mass=3.0, position=(0.0, 0.5), friction=0.6)
        world = run(soft_world([ground(), box], contact_hertz=hertz), 2.0)
        omega = 2 * math.pi * 2 * hertz
        assert 0.5 - box.position[1] == pytest.approx(float(sag.subs({gee: G, w: omega})), rel=0.02)
        assert abs(box.velocity[1]) < 1e-9 and abs(box.angle) < 1e-12
        assert world.solver.stats.block_manifolds == 1


def lcp_solutions(k, b):
    """x >= 0, K x + b >= 0, x (K x + b) = 0, by trying the four active sets."""
    found = []
    for active in ((), (0,), (1,), (0, 1)):
        x = np.zeros(2)
        if active:
            x[list(active)] = np.linalg.solve(k[np.ix_(active, active)], -b[list(active)])
        v = k @ x + b
        fits = np.all(x >= -1e-12) and all(v[i] >= -1e-12 for i in range(2) if i not in active)
        if fits and not any(np.allclose(x, other, atol=1e-12) for other in found):
            found.append(x)   # a point exactly on the boundary fits two sets
    return found


@pytest.mark.parametrize("b", [(-0.3, -0.2), (-0.3, 0.4), (0.1, -0.5), (0.2, 0.3)])
@pytest.mark.parametrize("mass_scale", [1.0, 0.6])
def test_soft_block_update_is_the_scaled_rigid_lcp_solution(b, mass_scale):
    # A 1 kg, 1 m box on static ground: lever arms -0.5 and +0.5, inertia 1/6.
    k11 = k22 = 1.0 + 6.0 * 0.25
    k12 = 1.0 - 6.0 * 0.25
    k = np.array([[k11, k12], [k12, k22]])
    old = np.array([0.05, 0.02])
    target = np.array([0.1, 0.0])
    # Velocities that give normal velocities b + target + K old at the two points.
    normal_velocity = np.array(b) + target + k @ old
    vy, w = normal_velocity.mean(), (normal_velocity[1] - normal_velocity[0]) / 1.0
    # Body 0 static ground, body 1 the box (1/m = 1, 1/I = 6); one block group, normal up.
    rows = ConstraintRows(a=np.array([0]), b=np.array([1]), nx=np.array([0.0]), ny=np.array([1.0]),
                          ima=np.array([0.0]), imb=np.array([1.0]), iia=np.array([0.0]), iib=np.array([6.0]),
                          first=np.array([0]), count=np.array([2]), block=np.array([True]), k11=np.array([k11]),
                          k12=np.array([k12]), k22=np.array([k22]), rn_a=np.zeros(2), rn_b=np.array([-0.5, 0.5]),
                          rt_a=np.zeros(2), rt_b=np.zeros(2), mass_normal=np.array([1 / k11, 1 / k22]),
                          mass_tangent=np.ones(2), friction=np.zeros(2), lower=np.zeros(2))
    normal = old.copy()
    velocity = np.array([[0.0, 0.0, 0.0], [0.0, vy, w]])
    solve_constraints(velocity, rows, 1, normal, np.zeros(2), target, np.full(2, mass_scale),
                      np.full(2, 1.0 - mass_scale), use_friction=False)
    (want,) = lcp_solutions(k, np.array(b))
    np.testing.assert_allclose(normal, mass_scale * want, rtol=1e-12, atol=1e-15)
    # The velocities moved by exactly the change of impulse.
    change = normal - old
    assert velocity[1, 1] == pytest.approx(vy + change.sum(), abs=1e-15)
    assert velocity[1, 2] == pytest.approx(w + 6.0 * (0.5 * change[1] - 0.5 * change[0]), abs=1e-15)


@pytest.mark.parametrize("seed", [0, 1])
def test_the_numba_twin_equals_the_readable_kernel_on_soft_rows(seed):
    # A settled pyramid's contacts (colour order: it has more than 256 manifolds),
    # random soft scales and targets, warm impulses.
    _, world = scene_world("pyramid_10")
    run(world, 0.2)
    c = world.solver._contacts
    assert c.rows.block.any() and c.rows.group_count > 100
    rng = np.random.default_rng(seed)
    target, mass_scale = rng.uniform(-0.05, 0.05, c.point_count), rng.uniform(0.3, 1.0, c.point_count)
    normal, tangent = rng.uniform(0.0, 0.2, c.point_count), rng.uniform(-0.02, 0.02, c.point_count)
    velocity = rng.normal(0.0, 0.1, (len(c.members), 3)) * np.array([not b.is_static for b in c.members])[:, None]
    results = []
    for solve in (solve_constraints, kernel_numba.solve_constraints):
        v, n, tt = velocity.copy(), normal.copy(), tangent.copy()
        solve(v, c.rows, 3, n, tt, target, mass_scale, 1.0 - mass_scale)
        results.append((v, n, tt))
    for got, want in zip(results[1], results[0]):
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-14)
    assert not np.allclose(results[0][0], velocity)       # the sweeps did something


# --- Speculative points and separations ------------------------------------------------
def test_a_speculative_point_never_pulls_a_falling_box():
    box = Body.box(1.0, 1.0, position=(0.0, 0.515))         # 1.5 cm above the ground, at rest
    world = soft_world([ground(), box])
    world.step(DT)
    assert world.stats.contact_points == 2                  # seen, 1.5 cm < the 2 cm margin
    assert box.velocity[1] == pytest.approx(-G * DT, rel=1e-12)   # free fall all the same


def test_a_speculative_point_lands_a_fast_box_on_the_surface():
    box = Body.box(1.0, 1.0, position=(0.0, 0.51), velocity=(0.0, -3.0))   # 1 cm above, 5 cm per step
    world = soft_world([ground(), box])
    world.step(DT)
    assert metrics.max_penetration(world.bodies) < 1e-3
    assert 0.499 < box.position[1] < 0.5 + 1e-12 and abs(box.velocity[1]) < 0.2


@pytest.mark.parametrize("shift, turn", [((0.0, 0.004), 0.0), ((0.003, -0.002), 0.0), ((0.0, 0.0), 0.002)])
def test_separations_follow_the_moved_bodies(shift, turn):
    floor = Body.box(4.0, 1.0, position=(0.0, -0.5), is_static=True)
    box = Body.box(1.0, 1.0, position=(0.1, 0.498), angle=0.001)
    contact = speculative_polygon_manifold(floor.world_shape(), box.world_shape())
    solver = SoftStepSolver(SolverSettings(iterations=1))
    solver.begin_step([floor, box], [(0, 1, contact)], DT)
    box.position = box.position + shift
    box.angle += turn
    got = solver.separations(BodyState.gather([floor, box]))
    want = speculative_polygon_manifold(floor.world_shape(), box.world_shape()).separations
    # Exact for a translation; a turn moves the corners along a circle, which the
    # linearised normal distance follows to second order in the angle.
    np.testing.assert_allclose(got, want, atol=1e-15 if turn == 0.0 else 1e-5)


def test_bad_input_is_refused():
    ground_body, box = ground(), Body.box(1.0, 1.0, position=(0.0, 0.5))
    touching = Contact((0.0, 1.0), 0.0, [(-0.5, 0.0), (0.5, 0.0)])
    with pytest.raises(ValueError, match="accumulate_impulses"):
        SoftStepSolver(SolverSettings(accumulate_impulses=False)).begin_step([ground_body, box], [(0, 1, touching)], DT)
    with pytest.raises(ValueError, match="2 contact points but 1 separations"):
        Contact((0.0, 1.0), 0.0, [(-0.5, 0.0), (0.5, 0.0)], separations=[0.0])
    with pytest.raises(ValueError, match="h must be > 0"):
        SoftStepSolver().begin_step([ground_body, box], [(0, 1, touching)], 0.0)
    for bad in (dict(contact_hertz=-1.0), dict(contact_damping_ratio=-0.5), dict(max_push_velocity=-1.0)):
        solver, soft = split_overrides(bad)
        with pytest.raises(ValueError, match=next(iter(bad))):
            SolverSettings(**solver) if solver else SoftStepSettings(**soft)
    with pytest.raises(TypeError, match="unknown solver setting.* relaxx"):
        get_scene("stack_10").world_settings(relaxx=False)
    with pytest.raises(ValueError, match="margin"):
        speculative_polygon_manifold(ground_body.world_shape(), box.world_shape(), margin=-0.01)


def test_same_scene_same_soft_settings_same_final_state():
    def final_state():
        _, world = scene_world("pyramid_10")
        run(world, 0.5)
        return np.array([[*b.position, b.angle, *b.velocity, b.angular_velocity] for b in world.bodies]).tobytes()
    assert final_state() == final_state()


# --- Each switch, in the direction it exists for --------------------------------------
def deepest_over(world, seconds):
    deepest = [0.0]
    run(world, seconds, every=lambda k: deepest.__setitem__(0, max(deepest[0], metrics.max_penetration(world.bodies)))
        if k % 10 == 9 else None)
    return deepest[0]


def test_warm_starting_lowers_penetration_on_the_stack():
    with_warm = deepest_over(scene_world("stack_20")[1], 1.0)
    without = deepest_over(scene_world("stack_20", warm_starting=False)[1], 1.0)
    assert with_warm < 0.5 * without


def heavy_box_offset(world, seconds):
    run(world, seconds)
    light, heavy = world.bodies[1], world.bodies[2]
    return float(np.linalg.norm(heavy.position - light.position - (0.0, 1.0)))


def test_sub_stepping_holds_the_mass_ratio():
    assert heavy_box_offset(scene_world("mass_ratio_1000")[1], 3.0) < 0.05
    # One sub-step: the spring is four times softer per frame and the light box is crushed.
    assert heavy_box_offset(scene_world("mass_ratio_1000", substeps=1)[1], 3.0) > 0.3


def test_continuous_detection_stops_the_bullet_under_the_soft_step():
    # The wall falls at 25 phases within a step: swept, the bullet never passes it;
    # unswept it passes whenever no step starts with the ball inside the 0.1 m wall.
    passed = {True: 0, False: 0}
    for continuous in (True, False):
        for offset in np.linspace(0, 100 / 60, 25, endpoint=False):
            scene, world = scene_world("bullet_wall", continuous=continuous)
            world.bodies[1].position = world.bodies[1].position + (offset, 0.0)
            run(world, 0.1)
            passed[continuous] += bool(world.bodies[1].position[0] > world.bodies[0].position[0])
    assert passed[True] == 0 and passed[False] >= 20


def launch_speed(world, seconds):
    fastest = [0.0]
    run(world, seconds, every=lambda k: fastest.__setitem__(
        0, max(fastest[0], max(b.velocity[1] for b in world.bodies if not b.is_static))))
    return fastest[0]


def test_relaxation_and_the_push_cap_keep_overlapping_boxes_from_being_launched():
    both = launch_speed(scene_world("overlap_recovery")[1], 1.0)
    no_relax = launch_speed(scene_world("overlap_recovery", relax=False)[1], 1.0)
    no_cap = launch_speed(scene_world("overlap_recovery", max_push_velocity=math.inf)[1], 1.0)
    assert both < no_relax and both < no_cap
    assert no_cap > 2 * both


def test_the_push_cap_also_tames_baumgarte():
    scene = get_scene("overlap_recovery")
    capped = launch_speed(scene.build_world(position_correction="baumgarte"), 1.0)
    uncapped = launch_speed(scene.build_world(position_correction="baumgarte", max_push_velocity=math.inf), 1.0)
    assert capped < uncapped


def test_restitution_threshold_stops_slow_bounces_only():
    # Dropped from 2 cm, an elastic ball meets the ground at sqrt(2 g h) = 0.63 m/s.
    drop = 0.02
    def bounce_height(threshold):
        ball = Body.circle(0.25, mass=1.0, position=(0.0, 0.25 + drop), restitution=1.0)
        world = soft_world([ground(restitution=1.0), ball], restitution_threshold=threshold)
        highest = [0.0]
        run(world, 0.3, every=lambda k: highest.__setitem__(
            0, max(highest[0], ball.position[1] - 0.25) if k > 5 else 0.0))
        return highest[0]
    assert bounce_height(1.0) < 1e-4
    assert bounce_height(0.0) == pytest.approx(drop, rel=0.2)   # e = 1: back to where it fell from


def test_batched_and_looped_box_manifolds_give_the_same_simulation(monkeypatch):
    import solutions.world as world_module

    def final_state():
        _, world = scene_world("pyramid_10")
        run(world, 0.25)
        return np.array([[*b.position, b.angle, *b.velocity, b.angular_velocity] for b in world.bodies])

    batched = final_state()
    monkeypatch.setattr(world_module, "HAS_TWINS", False)       # the loop, as the student edition steps
    looped = final_state()
    np.testing.assert_allclose(batched, looped, rtol=0, atol=1e-12)
