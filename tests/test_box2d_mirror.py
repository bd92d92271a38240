"""The Box2D 2.3 mirror of a scene (tools/box2d_mirror.py): geometry, integration,
resting contacts, material mixing and the hard scenes.

Box2D works in 32-bit floats, so "equal" below means equal to float32 rounding (the
spacing of float32 numbers at the coordinate in question).  Its polygons carry a skin
of ``SKIN`` = 0.01 m; the mirror insets them by ``INSET`` so that the skinned shape is
the scene's shape plus ``CONTACT_MARGIN`` (0.1 mm).
"""
import math

import numpy as np
import pytest

from solutions import scene_metrics as metrics
from solutions.body import Body
from solutions.joints import DistanceJoint, anchor_world
from solutions.scenes import SCENES, ground
from solutions.shapes import Circle
from tools.box2d_mirror import (CONTACT_MARGIN, INSET, LINEAR_SLOP, SKIN, Box2DMirror, build_world,
                                fixture_materials, inset_polygon, polygon_vertices_local, simulate)

G = 9.81
HARD = sorted(name for name, scene in SCENES.items() if scene.hard)


def f32_tolerance(*values) -> float:
    """A few float32 spacings at the largest magnitude of ``values``."""
    return 4 * float(np.spacing(np.float32(max(1.0, *map(abs, values)))))


# Geometry at t = 0 ---------------------------------------------------------------------

@pytest.mark.parametrize("name", sorted(SCENES))
def test_bodies_start_where_the_scene_puts_them(name):
    mirror = Box2DMirror.from_scene(name)
    for body, b2 in zip(SCENES[name].make_bodies(), mirror.b2_bodies):
        x, y = body.position
        tol = f32_tolerance(x, y)
        assert tuple(b2.position) == pytest.approx(tuple(body.position), abs=tol)
        assert b2.angle == pytest.approx(body.angle, abs=1e-6)
        assert tuple(b2.linearVelocity) == pytest.approx(tuple(body.velocity), rel=1e-6, abs=1e-6)
        assert b2.angularVelocity == pytest.approx(body.angular_velocity, abs=1e-6)
        if body.is_static:
            assert b2.type == 0  # b2_staticBody
            continue
        assert b2.mass == pytest.approx(body.mass, rel=1e-6)
        assert tuple(b2.localCenter) == (0.0, 0.0)
        if math.isinf(body.inertia):
            assert b2.fixedRotation
        else:
            assert b2.inertia == pytest.approx(body.inertia, rel=1e-6)


@pytest.mark.parametrize("name", ["pyramid_10", "arch", "overlap_recovery", "friction_ramp", "ball_drop",
                                  "bullet_wall", "truck_and_car"])
def test_skinned_shapes_are_the_scene_shapes(name):
    """Along every edge normal of a scene polygon, Box2D's polygon plus its skin reaches
    as far as the scene's polygon plus the contact margin; circles are the same."""
    mirror = Box2DMirror.from_scene(name)
    for body, b2 in zip(mirror.bodies, mirror.b2_bodies):
        (fixture,) = b2.fixtures
        shape = fixture.shape
        if isinstance(body.shape, Circle):
            assert shape.radius == pytest.approx(body.shape.radius, rel=1e-6)
            assert tuple(shape.pos) == pytest.approx(tuple(body.shape.center), abs=1e-6)
            continue
        assert shape.radius == pytest.approx(SKIN)
        scene = polygon_vertices_local(body)
        core = np.array(shape.vertices, dtype=float)
        assert len(core) == len(scene)
        edges = np.roll(scene, -1, axis=0) - scene
        normals = np.stack([edges[:, 1], -edges[:, 0]], axis=1) / np.linalg.norm(edges, axis=1)[:, None]
        reach_scene = (scene @ normals.T).max(axis=0)
        reach_box2d = (core @ normals.T).max(axis=0) + shape.radius
        np.testing.assert_allclose(reach_box2d, reach_scene + CONTACT_MARGIN, atol=f32_tolerance(*scene.ravel()))


@pytest.mark.parametrize("name, contacts", [("stack_20", 20), ("pyramid_20", 590), ("arch", 10)])
def test_bodies_placed_touching_touch_from_the_first_step(name, contacts):
    """The contact margin: with an inset of exactly the skin, float32 rounding leaves
    16 of stack_20's 20 contacts apart in the first step and the boxes fall."""
    mirror = Box2DMirror.from_scene(name)
    mirror.step(1 / 60)
    assert sum(c.touching for c in mirror.world.contacts) == contacts


def test_keep_skin_hands_box2d_the_scene_vertices():
    mirror = Box2DMirror.from_scene("stack_10", skin="keep")
    body, b2 = mirror.bodies[1], mirror.b2_bodies[1]
    box2d = sorted(map(tuple, np.array(b2.fixtures[0].shape.vertices)))   # Box2D reorders the hull
    np.testing.assert_allclose(box2d, sorted(map(tuple, polygon_vertices_local(body))), atol=1e-7)
    assert b2.fixtures[0].shape.radius == pytest.approx(SKIN)


def test_inset_polygon_moves_every_edge_in_by_the_distance():
    square = np.array([(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)])
    np.testing.assert_allclose(inset_polygon(square, 0.01), square * 0.98)
    voussoir = polygon_vertices_local(SCENES["arch"].make_bodies()[3])
    inset = inset_polygon(voussoir, 0.01)
    for k in range(len(voussoir)):
        a, b = voussoir[k], voussoir[(k + 1) % len(voussoir)]
        n = np.array([b[1] - a[1], a[0] - b[0]]) / math.dist(a, b)
        assert float(n @ (inset[k] - a)) == pytest.approx(-0.01)
        assert float(n @ (inset[(k + 1) % len(inset)] - a)) == pytest.approx(-0.01)
    with pytest.raises(ValueError, match="too thin"):
        Box2DMirror([Body.box(0.015, 1.0, mass=1.0)])      # narrower than two skins


# Integration ---------------------------------------------------------------------------

def test_free_fall_is_semi_implicit_euler_first_order():
    """Box2D's y after n steps of h is y0 - g h^2 n (n + 1) / 2 (v += g h, then
    x += v h): g t h / 2 below the analytic fall, an error that halves with h."""
    errors = []
    for h in (1 / 60, 1 / 120, 1 / 240):
        mirror = Box2DMirror([Body.circle(0.5, mass=2.0, position=(1.0, 100.0))])
        n = round(1.0 / h)
        for _ in range(n):
            mirror.step(h)
        t = n * h
        y = mirror.bodies[0].position[1]
        assert y == pytest.approx(100.0 - G * h * h * n * (n + 1) / 2, abs=f32_tolerance(100.0))
        assert mirror.bodies[0].velocity[1] == pytest.approx(-G * t, rel=1e-5)
        errors.append((100.0 - G * t * t / 2) - y)
        assert errors[-1] == pytest.approx(G * t * h / 2, rel=1e-3)
    assert errors[0] / errors[1] == pytest.approx(2.0, rel=1e-2)
    assert errors[1] / errors[2] == pytest.approx(2.0, rel=1e-2)


# Resting contact -----------------------------------------------------------------------

@pytest.mark.parametrize("drop", [0.0, 0.5])
@pytest.mark.parametrize("make", [lambda y: Body.box(1.0, 1.0, mass=1.0, position=(0.3, y), friction=0.6),
                                  lambda y: Body.circle(0.5, mass=1.0, position=(0.3, y))], ids=["box", "ball"])
def test_a_body_on_the_ground_rests_within_the_slop(make, drop):
    """Placed on the ground it stays put; dropped onto it, it settles overlapping the
    ground by Box2D's linear slop (0.005 m, less the contact margin) and no more: the
    skin is accounted for, and the body stays awake (no sleeping)."""
    mirror = Box2DMirror([ground(), make(0.5 + drop)])
    deepest = []
    for k in range(180):
        mirror.step(1 / 60)
        if k >= 120:
            deepest.append(metrics.max_penetration(mirror.bodies))
    body = mirror.bodies[1]
    assert max(deepest) <= LINEAR_SLOP + 1e-6
    assert body.position[1] == pytest.approx(0.5, abs=LINEAR_SLOP + 1e-6)
    assert body.position[0] == pytest.approx(0.3, abs=1e-6)
    if drop == 0.0:
        assert max(deepest) < 1e-6
    assert mirror.b2_bodies[1].awake


# Materials -----------------------------------------------------------------------------

def test_contacts_carry_the_reference_products():
    mirror = Box2DMirror.from_scene("friction_ramp")
    mirror.step(1 / 60)
    touching = [c for c in mirror.world.contacts if c.touching]
    assert len(touching) == 5
    for contact in touching:
        a, b = mirror.bodies[contact.fixtureA.body.userData], mirror.bodies[contact.fixtureB.body.userData]
        assert contact.friction == pytest.approx(a.friction * b.friction, rel=1e-6)
        assert contact.restitution == pytest.approx(a.restitution * b.restitution, abs=1e-7)
    assert mirror.world.mixing == "fixtures"


def test_materials_no_fixture_values_can_match_fall_back_to_a_listener():
    def bodies():
        return [ground(restitution=0.5, friction=0.3),
                Body.circle(0.5, position=(0.0, 0.5), restitution=0.6, friction=0.7),
                Body.circle(0.5, position=(1.0, 0.5), restitution=0.7, friction=0.9)]
    assert not fixture_materials(bodies())[2]
    for mixing, expected in (("reference", "products"), ("listener", "products"), ("box2d", "box2d")):
        world, _ = build_world(bodies(), mixing=mixing)
        world.Step(1 / 60, 8, 3)
        pairs = sorted((round(c.friction, 4), round(c.restitution, 4)) for c in world.contacts if c.touching)
        if expected == "products":
            assert world.mixing == "listener"
            assert pairs == [(0.21, 0.3), (0.27, 0.35), (0.63, 0.42)]
        else:
            assert pairs == [(round(math.sqrt(0.3 * 0.7), 4), 0.6), (round(math.sqrt(0.3 * 0.9), 4), 0.7),
                             (round(math.sqrt(0.7 * 0.9), 4), 0.7)]


def test_fixture_restitution_reproduces_products_where_possible():
    friction, restitution, exact = fixture_materials(SCENES["many_uniform"].make_bodies())
    assert exact
    assert sorted(set(restitution)) == pytest.approx([0.81, 0.9])   # balls 0.9 * 0.9, walls 0.9
    friction, restitution, exact = fixture_materials(SCENES["ball_drop"].make_bodies())
    assert exact and restitution == [pytest.approx(0.8), pytest.approx(0.8)]


def slope(mu: float, angle_deg: float = 30.0) -> list[Body]:
    a = math.radians(angle_deg)
    normal = np.array([-math.sin(a), math.cos(a)])
    return [Body.box(20.0, 1.0, is_static=True, angle=a, friction=mu),
            Body.box(1.0, 1.0, mass=1.0, angle=a, position=1.0 * normal, friction=mu)]


@pytest.mark.parametrize("mu, mixing, slides", [
    (0.7, "reference", True),    # 0.7 * 0.7 = 0.49 < tan 30 = 0.577
    (0.8, "reference", False),   # 0.64 > 0.577
    (0.7, "box2d", False),       # Box2D's own sqrt(0.7 * 0.7) = 0.7 would hold it
])
def test_box_on_a_slope_slides_as_the_friction_product_predicts(mu, mixing, slides):
    mirror = Box2DMirror(slope(mu), mixing=mixing)
    start = mirror.bodies[1].position.copy()
    for _ in range(120):
        mirror.step(1 / 60)
    moved = float(np.linalg.norm(mirror.bodies[1].position - start))
    assert (moved > 0.5) if slides else (moved < 1e-3)


def test_friction_ramp_first_three_slide_the_others_stick():
    mirror = Box2DMirror.from_scene("friction_ramp")
    start = metrics.start_positions(mirror.bodies)
    for _ in range(180):
        mirror.step(1 / 60)
    moved = [float(np.linalg.norm(b.position - p)) for b, p in zip(mirror.bodies[1:], start[1:])]
    assert all(m > 1.0 for m in moved[:3]) and all(m < 1e-3 for m in moved[3:])


def bounce_ratio(mixing: str, h: float = 1 / 240) -> float:
    """Apex height of ball_drop's first bounce over its drop height (both above contact)."""
    mirror = Box2DMirror.from_scene("ball_drop", mixing=mixing)
    ys = []
    for _ in range(round(3.0 / h)):
        mirror.step(h)
        ys.append(mirror.bodies[1].position[1])
    ys = np.array(ys)
    lowest = int(np.argmin(ys[:round(1.5 / h)]))
    return (ys[lowest:].max() - 0.5) / 4.5


def test_ball_bounces_to_the_restitution_product_squared():
    """Ball 0.8 on ground 1.0: the reference's pair e = 0.8 returns it to e^2 = 0.64 of
    its drop (Box2D's own max(0.8, 1) = 1 would return it all the way)."""
    assert bounce_ratio("reference") == pytest.approx(0.8 * 0.8, rel=0.02)
    assert bounce_ratio("box2d") == pytest.approx(1.0, rel=0.02)


# Joints --------------------------------------------------------------------------------

def test_distance_joints_are_mirrored():
    mirror = Box2DMirror.from_scene("chain_40")
    assert len(mirror.world.joints) == 40
    for _ in range(60):
        mirror.step(1 / 60)
    stretch = max(abs(math.dist(anchor_world(mirror.bodies[j.a], j.anchor_a),
                                anchor_world(mirror.bodies[j.b], j.anchor_b)) - j.length) for j in mirror.joints)
    assert stretch < 0.05
    soft = Box2DMirror([Body.circle(0.1, is_static=True), Body.circle(0.1, mass=1.0, position=(1.0, 0.0))],
                       joints=[DistanceJoint(0, 1, length=1.0, frequency=4.0, damping_ratio=0.5)])
    (joint,) = soft.world.joints
    assert (joint.frequency, joint.dampingRatio, joint.length) == pytest.approx((4.0, 0.5, 1.0))


# Hard scenes and metrics ---------------------------------------------------------------

@pytest.mark.parametrize("name", HARD)
def test_every_hard_scene_steps_a_second_without_nan(name):
    scene = SCENES[name]
    mirror = Box2DMirror.from_scene(scene)
    for _ in range(round(1.0 / scene.dt)):
        mirror.step(scene.dt, copy=False)
    mirror.copy_state()
    state = np.array([[*b.position, b.angle, *b.velocity, b.angular_velocity] for b in mirror.bodies])
    assert np.all(np.isfinite(state))
    assert math.isfinite(metrics.max_penetration(mirror.bodies))


def test_scene_metrics_of_a_stack_and_the_skin():
    """The skin lifts a stack given Box2D the scene's vertices (``keep``): measured
    by drift it looks far worse than inset, horizontally the two agree."""
    inset = simulate("stack_10", seconds=2.0, velocity_iterations=30, position_iterations=10)
    keep = simulate("stack_10", seconds=2.0, velocity_iterations=30, position_iterations=10, skin="keep")
    assert inset["skin"] == keep["skin"] == SKIN and inset["inset"] == INSET and keep["inset"] == 0.0
    assert inset["penetration"] < 3 * LINEAR_SLOP and inset["drift"] < 0.03
    assert keep["drift"] > 0.05 and keep["energy_gain"] > 1.0           # risen on the skins
    assert inset["horizontal_drift"] < 1e-3 and keep["horizontal_drift"] < 1e-2
    assert inset["mixing"] == "fixtures" and inset["ms_per_step"] > 0
