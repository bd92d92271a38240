"""The Box2D v3 mirror of a scene (tools/box2d_v3_mirror.py): bodies, masses, materials
and joints as the scene has them, and a box resting on the ground stays at rest.

Box2D v3 works in 32-bit floats, so "equal" below means equal to float32 rounding.
"""
import math

import numpy as np
import pyb2d3
import pytest

from solutions.body import Body
from solutions.scenes import SCENES, ground
from solutions.shapes import OBB, Circle
from tools.box2d_mirror import polygon_vertices_local
from tools.box2d_v3_mirror import SETTINGS, Box2DV3Mirror, exact_rotation

HARD = sorted(name for name, scene in SCENES.items() if scene.hard)
FLOAT32 = float(np.finfo(np.float32).eps)


def f32_tolerance(*values) -> float:
    """A few float32 spacings at the largest magnitude of ``values``."""
    return 4 * float(np.spacing(np.float32(max(1.0, *map(abs, values)))))


@pytest.mark.parametrize("name", HARD)
def test_a_mirrored_scene_has_the_scenes_bodies_masses_shapes_and_materials(name):
    mirror = Box2DV3Mirror.from_scene(name)
    scene = SCENES[name]
    bodies = scene.make_bodies()
    assert len(mirror.v3_bodies) == len(bodies)
    for body, v3 in zip(bodies, mirror.v3_bodies):
        x, y = body.position
        assert (v3.position.x, v3.position.y) == pytest.approx((x, y), abs=f32_tolerance(x, y))
        assert math.atan2(v3.rotation.s, v3.rotation.c) == pytest.approx(body.angle, abs=4 * FLOAT32)
        assert (v3.linear_velocity.x, v3.linear_velocity.y) == pytest.approx(tuple(body.velocity), rel=1e-6)
        assert (v3.type == pyb2d3.BodyType.STATIC) == body.is_static
        if not body.is_static:
            assert v3.mass == pytest.approx(body.mass, rel=1e-6)
            assert tuple(v3.mass_data.center) == (0.0, 0.0)
            assert v3.fixed_rotation == math.isinf(body.inertia)
            if not math.isinf(body.inertia):
                assert v3.rotational_inertia() == pytest.approx(body.inertia, rel=1e-6)
        (shape,) = v3.shapes
        if isinstance(body.shape, Circle):
            assert shape.circle.radius == pytest.approx(body.shape.radius, rel=1e-6)
        else:
            polygon = shape.polygon
            assert polygon.radius == 0.0        # no skin
            want = polygon_vertices_local(body)
            got = np.asarray(polygon.vertices, dtype=float)[:polygon.count]
            # The same corners, perhaps from another first one.
            assert sorted(map(tuple, np.round(got, 5))) == sorted(map(tuple, np.round(want, 5)))
    # v3 mixes friction as sqrt(a b) and restitution as max(a, b): the shapes' values
    # make both the reference's products for every pair that can touch.
    shapes = [v3.shapes[0] for v3 in mirror.v3_bodies]
    for i, a in enumerate(bodies):
        for j, b in enumerate(bodies[:i]):
            if a.is_static and b.is_static:
                continue
            assert math.sqrt(shapes[i].friction * shapes[j].friction) == pytest.approx(a.friction * b.friction,
                                                                                       rel=1e-6, abs=1e-7)
            assert max(shapes[i].restitution, shapes[j].restitution) == pytest.approx(
                a.restitution * b.restitution, rel=1e-6, abs=1e-7)
    for joint, v3_joint in zip(scene.make_joints() if scene.make_joints else [], mirror.v3_joints):
        assert v3_joint.length == pytest.approx(joint.length, rel=1e-6)
        assert v3_joint.spring_enabled == (joint.frequency > 0)


def test_rotations_are_exact_where_v3s_own_constructor_approximates():
    assert exact_rotation(0.3).c == pytest.approx(math.cos(0.3), rel=FLOAT32)
    assert abs(pyb2d3.make_rot(0.3).c - math.cos(0.3)) > 1e-4         # v3.1's approximation


@pytest.mark.parametrize("setting", sorted(SETTINGS))
def test_a_resting_box_stays_at_rest(setting):
    box = Body.box(1.0, 1.0, mass=1.0, position=(0.0, 0.5), friction=0.6)
    mirror = Box2DV3Mirror([ground(width=10.0, friction=0.6), box], **SETTINGS[setting])
    for _ in range(120):
        mirror.step(1 / 60)
    # v3 lets a resting contact overlap by up to its linear slop, 5 mm.
    assert abs(box.position[0]) < 1e-6 and 0.5 - 0.005 <= box.position[1] <= 0.5 + 1e-6
    assert abs(box.angle) < 1e-6 and np.abs(box.velocity).max() < 1e-4 and abs(box.angular_velocity) < 1e-4


def test_a_scene_whose_restitutions_no_shape_values_can_mix_is_refused():
    bodies = [Body.circle(0.5, position=(x, 0.0), restitution=e) for x, e in ((0, 0.5), (1, 0.6), (2, 0.7))]
    with pytest.raises(ValueError, match="mixing='box2d'"):
        Box2DV3Mirror(bodies)
    mirror = Box2DV3Mirror(bodies, mixing="box2d")       # (a v3 body lives as long as its world)
    assert mirror.v3_bodies[2].shapes[0].restitution == pytest.approx(0.7)


def test_a_box_is_v3s_own_box_and_a_turned_box_its_polygon():
    mirrors = Box2DV3Mirror([Body.box(2.0, 1.0)]), Box2DV3Mirror([Body(OBB((0.0, 0.0), (1.0, 0.5), 0.4))])
    straight, turned = (mirror.v3_bodies[0].shapes[0].polygon for mirror in mirrors)
    assert np.allclose(np.abs(np.asarray(straight.vertices)[:4]), [1.0, 0.5])
    assert not np.allclose(np.abs(np.asarray(turned.vertices)[:4]), [1.0, 0.5])
