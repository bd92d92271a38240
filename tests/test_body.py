"""Bodies: mass properties against pymunk, frames and kinetic energy."""
import math

import numpy as np
import pymunk
import pytest

from solutions.body import Body
from solutions.shapes import OBB, Circle, ConvexPolygon


def test_inertia_matches_pymunk():
    assert Body.circle(0.3, mass=2.0).inertia == pytest.approx(pymunk.moment_for_circle(2.0, 0, 0.3))
    assert Body.box(2.0, 0.5, mass=3.0).inertia == pytest.approx(pymunk.moment_for_box(3.0, (2.0, 0.5)))
    hexagon = [(math.cos(a), math.sin(a)) for a in np.linspace(0, 2 * math.pi, 7)[:-1]]
    body = Body.polygon(hexagon, mass=1.5)
    assert body.inertia == pytest.approx(pymunk.moment_for_poly(1.5, hexagon, radius=0))


def test_polygon_body_is_recentred_on_its_centroid():
    body = Body.polygon([(0, 0), (4, 0), (0, 3)], mass=1.0, position=(10, 10))
    np.testing.assert_allclose(body.shape.center, (0, 0), atol=1e-12)


def test_static_and_fixed_rotation_have_zero_inverses():
    ground = Body.box(10, 1, is_static=True)
    assert ground.inverse_mass == 0 and ground.inverse_inertia == 0 and ground.kinetic_energy() == 0
    slider = Body.box(1, 1, mass=2.0, fixed_rotation=True)
    assert slider.inverse_mass == 0.5 and slider.inverse_inertia == 0


def test_world_shape_follows_position_and_angle():
    body = Body.box(2, 1, mass=1, position=(3, 4), angle=math.pi / 2)
    shape = body.world_shape()
    assert isinstance(shape, OBB)
    np.testing.assert_allclose(shape.vertices()[0], (3.5, 3.0), atol=1e-12)
    tri = Body.polygon([(0, 0), (3, 0), (0, 3)], mass=1, position=(1, 1), angle=math.pi)
    assert isinstance(tri.world_shape(), ConvexPolygon)
    np.testing.assert_allclose(tri.world_shape().center, (1, 1), atol=1e-12)
    assert isinstance(Body.circle(1, position=(2, 0)).world_shape(), Circle)


def test_point_velocity_and_energy():
    body = Body.box(2, 2, mass=3.0, velocity=(1, 0), angular_velocity=2.0)
    np.testing.assert_allclose(body.velocity_at((0, 1)), (1 - 2, 0))
    assert body.kinetic_energy() == pytest.approx(0.5 * 3 * 1 + 0.5 * body.inertia * 4)


@pytest.mark.parametrize("kwargs, message", [
    (dict(mass=0), "mass > 0"),
    (dict(mass=-1), "mass must be >= 0"),
    (dict(position=(math.nan, 0)), "position must be finite"),
    (dict(restitution=-0.5), "restitution must be >= 0"),
])
def test_bad_bodies_raise(kwargs, message):
    with pytest.raises(ValueError, match=message):
        Body.circle(1.0, **kwargs)


def test_a_body_is_a_row_of_its_worlds_state():
    from solutions.world import World

    ground = Body.box(10, 1, is_static=True, position=(0, -0.5))
    box = Body.box(1, 1, mass=1.0, position=(0, 2), angular_velocity=0.5)
    before = box.position
    world = World([ground, box])
    assert world.state.position.tolist() == [[0.0, -0.5], [0.0, 2.0]]
    world.step(1 / 60)
    # The body reads the world's arrays; a position read earlier is a copy of that moment.
    assert box.position.tolist() == world.state.position[1].tolist() and before.tolist() == [0.0, 2.0]
    assert box.angle == world.state.angle[1] != 0.0
    # Writing through the body writes the world's row, with += too.
    box.velocity += (1.0, 0.0)
    box.position = (3.0, 4.0)
    assert world.state.velocity[1, 0] == 1.0 and world.state.position[1].tolist() == [3.0, 4.0]


def test_a_body_that_cannot_turn_has_no_angular_velocity_in_a_world():
    from solutions.world import World

    slider = Body.box(1, 1, mass=1.0, fixed_rotation=True, angular_velocity=3.0)
    world = World([slider])
    world.step(1 / 60)
    assert slider.angular_velocity == 0.0 and slider.angle == 0.0


def test_a_world_refuses_bodies_added_after_it_was_made():
    from solutions.world import World

    world = World([Body.box(10, 1, is_static=True)])
    world.bodies.append(Body.circle(0.5, position=(0, 2)))
    with pytest.raises(ValueError, match="made with 1 bodies and now lists 2"):
        world.step(1 / 60)
