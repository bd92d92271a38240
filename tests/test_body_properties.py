"""Body properties set after the world is built move both backends alike.

A body's mass, inertia, friction, restitution, shape and flags live in its row of the
world's state (solutions/body_state.py), which the setters write and every step reads,
readable (``backend="python"``) and compiled (``backend="numba"``, the soft step
compiled whole).  Each change below is made in a readable and a compiled world after
they have stepped, and the two must then move alike to the tolerance of the other
equality tests (1e-12 relative to the scene's size and speeds), and differently from a
world left unchanged (the change took effect).
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from solutions.body import Body
from solutions.scenes import SCENES, get_scene, ground
from solutions.shapes import OBB, Circle, ConvexPolygon
from solutions.world import World, WorldSettings
from test_soft_step_numba import assert_same_motion

DT = 1 / 60
HARD_SCENES = sorted(name for name, scene in SCENES.items() if scene.hard)
SOFT = WorldSettings(soft_step=True, substeps=4)


def twin_worlds(make_bodies, settings: WorldSettings = SOFT) -> tuple[World, World]:
    readable = World(make_bodies(), settings)
    compiled = World(make_bodies(), replace(settings, backend="numba"))
    assert readable.compiled_soft_step is None and compiled.compiled_soft_step is not None
    return readable, compiled


def motion(world: World) -> np.ndarray:
    return np.column_stack([world.state.position, world.state.angle, world.state.velocity])


def test_friction_set_to_zero_after_building_lets_a_box_slide_in_both_backends():
    """The example of issue 26: at 3 m/s on friction 1, then friction 0 on both bodies."""
    def bodies():
        return [ground(width=40.0, friction=1.0), Body.box(1.0, 1.0, position=(0.0, 0.5), velocity=(3.0, 0.0),
                                                            friction=1.0)]

    for world in twin_worlds(bodies):
        world.bodies[0].friction = world.bodies[1].friction = 0.0
        for _ in range(60):
            world.step(DT)
        box = world.bodies[1]
        assert box.position[0] == pytest.approx(3.0, abs=1e-9) and box.velocity[0] == pytest.approx(3.0, abs=1e-9)


def drop_scene() -> list[Body]:
    """A box resting on the ground and a turning, sliding box falling onto it."""
    return [ground(width=20.0, friction=0.8), Body.box(1.2, 0.6, mass=1.0, position=(0.0, 0.3), friction=0.8),
            Body.box(0.8, 0.5, mass=2.0, position=(0.3, 1.6), velocity=(1.5, -1.0), angular_velocity=2.0,
                     friction=0.8)]


def grow(body: Body, factor: float) -> None:
    """The body's shape, scaled by ``factor`` about the body's origin (of the same kind)."""
    shape = body.shape
    if isinstance(shape, Circle):
        body.shape = Circle(shape.center, shape.radius * factor)
    elif isinstance(shape, OBB):
        body.shape = OBB(shape.center, shape.half_extents * factor, shape.angle)
    else:
        body.shape = ConvexPolygon(shape.vertices * factor)


#: Each change is made to the bodies of drop_scene (ground, resting box, falling box).
CHANGES = {
    "mass": lambda bodies: setattr(bodies[1], "mass", 6.0),
    "inertia": lambda bodies: setattr(bodies[2], "inertia", 5.0 * bodies[2].inertia),
    "friction": lambda bodies: [setattr(body, "friction", 0.0) for body in bodies],
    "restitution": lambda bodies: [setattr(body, "restitution", 0.9) for body in bodies],
    "shape": lambda bodies: grow(bodies[2], 1.5),
    "is_static": lambda bodies: setattr(bodies[1], "is_static", True),
    "fixed_rotation": lambda bodies: setattr(bodies[2], "fixed_rotation", True),
    "static pose": lambda bodies: setattr(bodies[0], "position", bodies[0].position + (0.0, -0.2)),
}


@pytest.mark.parametrize("change", sorted(CHANGES))
def test_each_property_set_after_building_moves_both_backends_alike(change):
    readable, compiled = twin_worlds(drop_scene)
    unchanged = World(drop_scene(), replace(SOFT, backend="numba"))
    assert_same_motion(readable, compiled, 5 * DT, DT)
    for _ in range(5):
        unchanged.step(DT)
    CHANGES[change](readable.bodies)
    CHANGES[change](compiled.bodies)
    assert_same_motion(readable, compiled, 0.75, DT)
    for _ in range(45):
        unchanged.step(DT)
    assert np.abs(motion(compiled) - motion(unchanged)).max() > 1e-6, f"setting {change} changed nothing"


@pytest.mark.parametrize("name", HARD_SCENES)
def test_properties_set_after_building_move_both_backends_alike_on_the_hard_scenes(name):
    """Every hard scene at its recommended settings: two steps, then a few dynamic
    bodies get another mass, inertia, friction, restitution and size, then four steps."""
    scene = get_scene(name)
    settings = scene.recommended_settings()
    readable, compiled = scene.build_world(settings), scene.build_world(replace(settings, backend="numba"))
    assert_same_motion(readable, compiled, 2 * scene.dt, scene.dt)
    for world in (readable, compiled):
        movable = [body for body in world.bodies if not body.is_static]
        a, b, c = movable[len(movable) // 2], movable[-1], movable[0]
        a.mass, b.friction, b.restitution = 3.0 * a.mass, 0.0, 0.7
        if not math.isinf(c.inertia):
            c.inertia = 4.0 * c.inertia
        grow(c, 1.1)
    assert_same_motion(readable, compiled, 4 * scene.dt, scene.dt)


def test_a_bullet_flag_set_after_building_is_swept_by_the_readable_stages():
    """The compiled step has no continuous detection: a world whose body becomes a bullet
    runs the readable stages from the next step on, and the fast box does not tunnel."""
    def bodies():
        return [Body.box(0.1, 4.0, is_static=True, position=(1.0, 0.0)),
                Body.box(0.2, 0.2, position=(0.0, 0.0), velocity=(200.0, 0.0))]

    settings = replace(SOFT, gravity=(0.0, 0.0), backend="numba")
    world = World(bodies(), settings)
    world.bodies[1].is_bullet = True
    world.step(DT)
    assert world.compiled_soft_step is None and world.bodies[1].position[0] < 1.0


def test_a_shape_the_compiled_step_cannot_take_hands_the_world_to_the_readable_stages():
    readable, compiled = twin_worlds(drop_scene)
    assert_same_motion(readable, compiled, 3 * DT, DT)
    for world in (readable, compiled):
        world.bodies[2].shape = ConvexPolygon([(-0.4, -0.25), (0.4, -0.25), (0.0, 0.3)])
    assert_same_motion(readable, compiled, 30 * DT, DT)
    assert compiled.compiled_soft_step is None


def test_setters_keep_the_mass_properties_consistent():
    box = Body.box(2.0, 1.0, mass=3.0, angular_velocity=1.0)
    inertia = box.inertia
    box.mass = 6.0          # the shape's inertia for the new mass
    assert box.inverse_mass == 1 / 6.0 and box.inertia == pytest.approx(2 * inertia, rel=1e-15)
    box.inertia = 5.0       # set by hand: kept through a change of mass or shape
    box.mass, box.shape = 1.0, OBB((0.0, 0.0), (3.0, 3.0), 0.0)
    assert box.inertia == 5.0 and box.inverse_inertia == 0.2 and box.property_row()[0:2].tolist() == [3.0, 3.0]
    box.fixed_rotation = True
    assert box.inverse_inertia == 0.0 and math.isinf(box.inertia) and box.angular_velocity == 0.0
    box.is_static = True
    assert box.inverse_mass == 0.0 and box.mass == 1.0
    box.is_static, box.fixed_rotation = False, False
    assert box.inverse_mass == 1.0 and box.inertia == 5.0


@pytest.mark.parametrize("change, error, message", [
    (lambda body: setattr(body, "mass", 0.0), ValueError, "mass > 0"),
    (lambda body: setattr(body, "mass", -1.0), ValueError, "mass must be >= 0"),
    (lambda body: setattr(body, "inertia", 0.0), ValueError, "inertia must be > 0"),
    (lambda body: setattr(body, "friction", math.nan), ValueError, "friction must be finite"),
    (lambda body: setattr(body, "restitution", -0.1), ValueError, "restitution must be >= 0"),
    (lambda body: setattr(body, "shape", "box"), TypeError, "must be a Circle, AABB, OBB or ConvexPolygon"),
])
def test_bad_values_set_after_building_raise_and_change_nothing(change, error, message):
    body = Body.box(1.0, 1.0, mass=2.0, friction=0.5, restitution=0.2)
    before = body.property_row()
    with pytest.raises(error, match=message):
        change(body)
    assert body.property_row().tolist() == before.tolist()


def test_the_state_arrays_are_views_of_one_array_cut_alike_by_both_backends():
    """The compiled step is called with the state's ``numbers`` alone and cuts the
    position, angle, velocity and property arrays from it as the readable state does."""
    from solutions.body_state import state_arrays
    from solutions.body_state_numba import state_arrays as compiled_state_arrays
    from numba import njit

    world = get_scene("pyramid_10").build_world()
    state = world.state
    readable = (state.position, state.angle, state.velocity, state.properties)
    for array, cut in zip(readable, state_arrays(state.numbers)):
        assert np.shares_memory(array, state.numbers) and array.flags.c_contiguous
        np.testing.assert_array_equal(array, cut)
    compiled = njit(lambda numbers: compiled_state_arrays(numbers))(state.numbers)
    for array, cut in zip(readable, compiled):
        assert cut.shape == array.shape and np.shares_memory(cut, state.numbers)
        np.testing.assert_array_equal(array, cut)
    world.bodies[3].velocity = (1.0, -2.0)
    assert compiled[2][3, :2].tolist() == [1.0, -2.0]
