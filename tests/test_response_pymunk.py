"""Collision response against pymunk (Chipmunk2D 7) on small scenes.

How pymunk 7.3.1 steps (read from Chipmunk's cpSpaceStep and checked here): positions
are integrated first with the velocities of the previous step, then contacts are
found, the restitution target ``-e v_n`` is taken from the velocities before gravity
is added, gravity is integrated, and the impulses are iterated.  Penetration is fixed
with separate bias velocities that never enter ``body.velocity``.  A pair's
elasticity and friction are the products of the two shapes' values.  Its default
``collision_slop`` (0.1) is meant for pixels, so the scenes here, in metres, set it
small.

So the state our functions must see at the impact step is: position and angle moved
on by one step of the old velocities, velocity plus ``g dt``.  With one contact point
and no friction a single impulse is exact, so pymunk and our code agree to rounding;
the tolerances below (1e-9 relative) leave room for that and nothing else.
"""
import math

import numpy as np
import pymunk
import pytest

from solutions.body import Body
from solutions.contact import Contact
from solutions.response.contact_solver import ContactSolver, SolverSettings
from solutions.response.impulse import relative_normal_velocity, resolve_collision
from solutions.response.momentum_1d import collision_1d

DT = 1 / 600  # s
TOLERANCE = dict(rel=1e-9, abs=1e-9)


def metre_space(gravity=(0.0, 0.0), iterations=20):
    space = pymunk.Space()
    space.gravity = gravity
    space.iterations = iterations
    space.collision_slop = 1e-6  # m; pymunk's default 0.1 is 10 cm at this scale
    return space


def add_circle(space, mass, radius, position, velocity, elasticity, friction=0.0):
    body = pymunk.Body(mass, pymunk.moment_for_circle(mass, 0, radius))
    body.position, body.velocity = position, velocity
    shape = pymunk.Circle(body, radius)
    shape.elasticity, shape.friction = elasticity, friction
    space.add(body, shape)
    return body


@pytest.mark.parametrize("m1, v1, e1, m2, v2, e2", [
    (2.0, 3.0, 0.8, 5.0, -1.0, 0.9),
    (1.0, 4.0, 1.0, 1.0, 0.0, 1.0),     # elastic, equal masses: velocities swap
    (0.1, 10.0, 1.0, 0.2, -5.0, 1.0),   # the notes' two balls
    (3.0, 2.0, 0.0, 0.5, -6.0, 0.7),    # e = 0: they move on together
    (0.01, 5.0, 0.5, 10.0, 0.5, 0.5),   # mass ratio 1:1000
])
def test_head_on_circles_match_collision_1d(m1, v1, e1, m2, v2, e2):
    space = metre_space()
    a = add_circle(space, m1, 0.5, (-1.0, 0.0), (v1, 0.0), e1)
    b = add_circle(space, m2, 0.5, (1.0, 0.0), (v2, 0.0), e2)
    changes = []
    for _ in range(3000):
        before = (a.velocity.x, b.velocity.x)
        space.step(DT)
        if (a.velocity.x, b.velocity.x) != before:
            changes.append((before, (a.velocity.x, b.velocity.x)))
    before, after = changes[0]  # the impact step
    assert before == (v1, v2)
    want = collision_1d(m1, v1, m2, v2, e1 * e2)
    assert after == pytest.approx(want, **TOLERANCE)
    # Later steps change nothing beyond rounding (e = 0: the discs stay in contact).
    assert (a.velocity.x, b.velocity.x) == pytest.approx(want, **TOLERANCE)
    assert a.velocity.y == b.velocity.y == 0.0 and a.angular_velocity == b.angular_velocity == 0.0


def drop_ball_pymunk(elasticity, height=2.0, radius=0.25):
    """(speed before the impact step, speed after it) of a ball dropped on static ground."""
    space = metre_space(gravity=(0.0, -9.81))
    ground = pymunk.Segment(space.static_body, (-10.0, 0.0), (10.0, 0.0), 0.0)
    ground.elasticity, ground.friction = 1.0, 0.0
    space.add(ground)
    ball = add_circle(space, 1.0, radius, (0.0, height), (0.0, 0.0), elasticity)
    for _ in range(5000):
        falling = ball.velocity.y
        space.step(DT)
        if ball.velocity.y > 0.0 > falling:
            return -falling, ball.velocity.y
    raise AssertionError("the ball never bounced")


def drop_ball_ours(restitution, height=2.0, radius=0.25, position_correction="baumgarte"):
    """The same drop with our solver and a hand-made ball-ground contact.

    Our step is v += g dt; solve; x += v dt, so the solver sees the velocity after
    gravity: that is the impact speed here."""
    ground = Body.box(20.0, 1.0, position=(0.0, -0.5), is_static=True, restitution=1.0)
    ball = Body.circle(radius, position=(0.0, height), restitution=restitution)
    bodies = [ground, ball]
    solver = ContactSolver(SolverSettings(position_correction=position_correction, restitution_threshold=0.0))
    for _ in range(5000):
        ball.velocity = ball.velocity + DT * np.array([0.0, -9.81])
        gap = ball.position[1] - radius  # ground top at y = 0
        manifolds = []
        if gap <= 0.0:
            manifolds = [(0, 1, Contact((0.0, 1.0), -gap, [(ball.position[0], gap / 2)]))]
        impact_speed = -ball.velocity[1]
        solver.solve(bodies, manifolds, DT)
        ball.position = ball.position + DT * ball.velocity
        solver.finish_step(bodies, manifolds, DT)
        if manifolds and ball.velocity[1] > 0.0:
            return impact_speed, ball.velocity[1]
    raise AssertionError("the ball never bounced")


@pytest.mark.parametrize("e", [0.3, 0.6, 0.9, 1.0])
def test_bounce_ratio_is_the_restitution(e):
    impact, rebound = drop_ball_pymunk(e)
    assert rebound / impact == pytest.approx(e, **TOLERANCE)
    impact_ours, rebound_ours = drop_ball_ours(e)
    assert rebound_ours / impact_ours == pytest.approx(e, **TOLERANCE)
    # Same drop: the impact speeds differ only by where in the step gravity acts.
    assert impact_ours == pytest.approx(impact, abs=2 * 9.81 * DT)


def drop_rod_pymunk(elasticity, friction, gravity, iterations=50):
    """A thin box tilted by 30 degrees falls onto static ground and hits with one corner.

    Returns the rod's state at the start of the impact step, the contact point on the
    rod and pymunk's velocities after the impact step."""
    space = metre_space(gravity=(0.0, gravity), iterations=iterations)
    space.static_body.position = (0.0, -0.5)
    ground = pymunk.Poly.create_box(space.static_body, (20.0, 1.0))
    ground.elasticity, ground.friction = 1.0, 1.0
    rod = pymunk.Body(0.5, pymunk.moment_for_box(0.5, (1.0, 0.05)))
    rod.position, rod.angle = (0.1, 0.5), math.radians(30)
    rod.velocity, rod.angular_velocity = (0.3, -2.0), 0.5
    shape = pymunk.Poly.create_box(rod, (1.0, 0.05))
    shape.elasticity, shape.friction = elasticity, friction
    space.add(ground, rod, shape)
    contacts = []
    space.on_collision(post_solve=lambda arbiter, space, data: contacts.append(arbiter.contact_point_set))
    for _ in range(2000):
        before = (tuple(rod.position), rod.angle, tuple(rod.velocity), rod.angular_velocity)
        space.step(DT)
        if contacts:
            break
    (contact,) = contacts
    assert len(contact.points) == 1 and tuple(contact.normal) == (0.0, 1.0)  # from ground to rod
    corner = np.array(contact.points[0].point_b)  # Chipmunk's point on the rod's surface
    return before, corner, -contact.points[0].distance, (tuple(rod.velocity), rod.angular_velocity), rod.moment


def rod_at_impact(before, gravity, elasticity, friction):
    """Our Body in the state pymunk's solver saw (see the module docstring)."""
    (x, y), angle, (vx, vy), w = before
    return Body.box(1.0, 0.05, mass=0.5, position=(x + DT * vx, y + DT * vy), angle=angle + DT * w,
                    velocity=(vx, vy + DT * gravity), angular_velocity=w,
                    restitution=elasticity, friction=friction)


@pytest.mark.parametrize("elasticity, gravity", [(0.0, -9.81), (0.5, 0.0), (1.0, 0.0)])
def test_tilted_rod_corner_impact_matches_resolve_collision(elasticity, gravity):
    # With gravity on, e = 0: pymunk's bounce target uses the pre-gravity velocity.
    before, corner, depth, (velocity, spin), moment = drop_rod_pymunk(elasticity, 0.0, gravity)
    rod = rod_at_impact(before, gravity, elasticity, 0.0)
    assert rod.inertia == pytest.approx(moment, rel=1e-14)
    ground = Body.box(20.0, 1.0, position=(0.0, -0.5), is_static=True, restitution=1.0)
    resolve_collision(ground, rod, Contact((0.0, 1.0), depth, [corner]))
    assert rod.angular_velocity == pytest.approx(spin, **TOLERANCE)
    assert tuple(rod.velocity) == pytest.approx(velocity, **TOLERANCE)
    # A large spin from a small linear impulse: the ruler of the notes.
    assert abs(rod.angular_velocity - before[3]) > 4.0


@pytest.mark.parametrize("elasticity, friction, gravity", [(0.0, 0.5, -9.81), (0.0, 0.2, -9.81), (0.5, 0.3, 0.0)])
def test_tilted_rod_with_friction_matches_the_iterated_solver(elasticity, friction, gravity):
    before, corner, depth, (velocity, spin), _ = drop_rod_pymunk(elasticity, friction, gravity, iterations=50)
    ground = Body.box(20.0, 1.0, position=(0.0, -0.5), is_static=True, restitution=1.0, friction=1.0)
    rod = rod_at_impact(before, gravity, elasticity, friction)
    solver = ContactSolver(SolverSettings(iterations=50, position_correction="none", restitution_threshold=0.0))
    solver.solve([ground, rod], [(0, 1, Contact((0.0, 1.0), depth, [corner]))], DT)
    assert rod.angular_velocity == pytest.approx(spin, **TOLERANCE)
    assert tuple(rod.velocity) == pytest.approx(velocity, **TOLERANCE)
    (_, _, _, normal_impulse, tangent_impulse), = solver.contact_impulses
    assert abs(tangent_impulse) <= friction * normal_impulse * (1 + 1e-12)
    # One pass of resolve_collision is not converged: friction disturbs the normal
    # velocity through the rotation it causes, which is why engines iterate.
    single = rod_at_impact(before, gravity, elasticity, friction)
    v_n = relative_normal_velocity(ground, single, corner, (0.0, 1.0))
    resolve_collision(ground, single, Contact((0.0, 1.0), depth, [corner]))
    residual = relative_normal_velocity(ground, single, corner, (0.0, 1.0)) + elasticity * v_n
    assert abs(residual) > 1e-3
