"""Build the same scene in Box2D 2.3 (pybox2d, ``import Box2D``) and copy its state back.

The second oracle engine beside pymunk (:mod:`tools.pymunk_mirror`): bodies, shapes,
masses, materials, distance joints and gravity of a scene are mirrored into a
``b2World``, which is stepped with its own solver (sequential impulses with warm
starting, ``velocity_iterations`` / ``position_iterations``, default 8 / 3 as in the
Box2D testbed) and whose state is copied back into the reference bodies, so that the
yardstick of :mod:`solutions.scene_metrics` measures it like the other two engines.

Box2D 2.3.10 facts this relies on (measured on pybox2d 2.3.10):

- **Floats.**  Box2D stores everything in 32-bit floats: positions near 1e5 m are
  rounded to 8 mm (pyramid_20_far), and the state copied back carries float32
  rounding (about 1e-7 relative).
- **Skin.**  A Box2D polygon is its vertex polygon grown by a radius of
  ``b2_polygonRadius`` = 0.01 m (:data:`SKIN`), and the position solver drives a
  contact's separation of these grown shapes to ``-b2_linearSlop`` (-0.005 m), but
  stops as soon as no overlap exceeds ``3 b2_linearSlop`` (0.015 m).  Mirrored with the
  scene's vertices, every box would be 2 cm wider and taller in effect: a resting
  20-box stack stands 0.19 m taller (30/10 iterations) and every box "drifts" upwards.
  So by default (``skin="inset"``) each polygon is given to Box2D *shrunk* (every edge
  moved inwards) by :data:`INSET` = ``SKIN - CONTACT_MARGIN``: the grown shape Box2D
  collides with is the scene's shape with corners rounded to 0.01 m, grown by 0.1 mm
  (:data:`CONTACT_MARGIN`).  Without that margin, bodies the scene places exactly
  touching start at a float32 tie: 16 of stack_20's 20 contacts (344 of pyramid_20's
  590) are missed in the first step, the boxes above fall onto each other, and the
  overlaps of up to 0.015 m that Box2D then accepts leave the stack 0.15 m low for
  good.  A resting contact then overlaps by about the linear slop, 0.005 m, like
  pymunk's ``collision_slop`` and the reference's ``slop`` here.  ``skin="keep"`` hands
  Box2D the scene's vertices as they are (Box2D as a user would set it up); then
  compare drift horizontally (:func:`horizontal_drift`) or subtract up to ``2 * SKIN``
  per resting contact.  Circles have no skin.
- **Mass.**  Box2D would compute mass from density and the (inset) vertex polygon;
  the mirror sets each body's mass, centre (the body origin) and moment of inertia to
  the reference's instead.  An infinite moment (``fixed_rotation`` or AABB shape)
  becomes ``fixedRotation``.
- **Materials.**  Box2D mixes a pair's friction as ``sqrt(mu_a mu_b)`` and its
  restitution as ``max(e_a, e_b)``; the reference and pymunk multiply them.  With
  ``mixing="reference"`` (default) the mirror gives Box2D per-fixture values whose
  Box2D mix is the reference's product (:func:`fixture_materials`): friction ``mu^2``
  (``sqrt(mu_a^2 mu_b^2) = mu_a mu_b`` for every pair), and restitution
  ``x_i = e_i min_j e_j`` over the bodies ``j`` that ``i`` can touch, which gives
  ``max(x_i, x_j) = e_i e_j`` for every pair whenever any per-fixture values can (all
  scenes in :mod:`solutions.scenes`; e.g. ball_drop: ground 0, ball 0.8).  When none
  can (say three touching bodies of e = 0.5, 0.6, 0.7), or with ``mixing="listener"``,
  a contact listener sets each new contact's restitution (and friction) to the
  products in ``BeginContact`` instead: Box2D 2.3 sets them once, when the contact is
  created.  The listener is the fallback only because pybox2d then calls Python for
  every contact in every step (``PreSolve``, ``PostSolve``): pyramid_20 steps in
  1.1 ms instead of 0.37 ms.  ``mixing="box2d"`` keeps Box2D's own rules with the
  scene's values.  Box2D applies restitution only above an approach speed of
  ``b2_velocityThreshold`` = 1 m/s.
- **Limits.**  A body moves at most ``b2_maxTranslation`` = 2 m and turns at most pi/2
  per step (120 m/s at 60 Hz: bullet_wall's 100 m/s passes).  Every dynamic body is
  swept continuously against static ones (``continuousPhysics``); a reference bullet
  becomes a Box2D ``bullet`` (swept against dynamic ones too).
- **Sleep.**  Box2D puts bodies at rest to sleep after 0.5 s; the reference and
  pymunk (as mirrored) never sleep, so ``allow_sleeping=False`` by default: a sleeping
  pyramid_20 steps in 0.01 ms instead of 0.35 ms and stops drifting, which would make
  both timings and errors incomparable.  In pybox2d 2.3.10 the world's flag alone
  (``doSleep``/``allowSleeping``) does not keep bodies awake (measured: pyramid_20
  sleeps after 4 s), so each body's ``allowSleep`` is switched off too.
- **Joints.**  A reference :class:`~solutions.joints.DistanceJoint` becomes a
  ``b2DistanceJoint`` with the same local anchors and length, rigid for frequency 0
  and otherwise soft with the same frequency and damping ratio (Box2D's soft joint is
  Catto's soft constraint, as the reference's).  Jointed bodies do not collide with each other.
- **Scene switches.**  As for pymunk, a scene's ``needs_rotation``/``needs_friction``
  are not mirrored (Box2D always turns bodies and applies friction; the scenes that
  switch them off are circles without friction or head-on boxes) and continuous
  detection is Box2D's own (above).
- **Integration.**  Semi-implicit Euler: ``v += g h`` then ``x += v h``, so a free fall
  is ``g t h / 2`` below the analytic ``-g t^2 / 2`` (first order in ``h``).
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import dataclass, field

import Box2D
import numpy as np

from solutions import scene_metrics as metrics
from solutions.body import Body
from solutions.scenes import get_scene
from solutions.shapes import AABB, OBB, Circle, box_vertices

#: Box2D's polygon skin (m): ``b2_polygonRadius``, twice the linear slop.
SKIN = float(Box2D.b2_polygonRadius)
#: Box2D's linear slop (m): the overlap its position solver leaves on a resting contact.
LINEAR_SLOP = float(Box2D.b2_linearSlop)
#: How much larger (m) than the scene's shapes the inset polygons plus skin are, so
#: that shapes the scene places exactly touching touch in float32 too.
CONTACT_MARGIN = 1e-4
#: How far (m) ``skin="inset"`` moves each polygon edge inwards.
INSET = SKIN - CONTACT_MARGIN
VELOCITY_ITERATIONS = 8
POSITION_ITERATIONS = 3


def polygon_vertices_local(body: Body) -> np.ndarray:
    """The body's polygon (n, 2) in its local frame, CCW; ValueError for a circle."""
    s = body.shape
    if isinstance(s, Circle):
        raise ValueError("a circle has no vertices")
    if isinstance(s, AABB):
        return np.asarray(s.vertices(), dtype=float)
    if isinstance(s, OBB):
        return np.asarray(box_vertices(s.center, s.half_extents, s.angle), dtype=float)
    return np.asarray(s.vertices, dtype=float)


def inset_polygon(vertices, distance: float) -> np.ndarray:
    """The convex CCW polygon ``vertices`` with every edge moved inwards by ``distance``.

    Vertex ``i`` moves along its bisector to where the two moved edges meet:
    ``v - d (n_prev + n_next) / (1 + n_prev . n_next)`` with outward unit normals.
    """
    v = np.asarray(vertices, dtype=float)
    edges = np.roll(v, -1, axis=0) - v                        # edge i: v[i] -> v[i+1]
    normals = np.stack([edges[:, 1], -edges[:, 0]], axis=1)   # outward for CCW
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    n_prev, n_next = np.roll(normals, 1, axis=0), normals
    cos = (n_prev * n_next).sum(1, keepdims=True)
    return v - distance * (n_prev + n_next) / (1.0 + cos)


def box2d_shape(body: Body, skin: str = "inset") -> Box2D.b2Shape:
    """The Box2D shape of ``body.shape`` (local frame); polygons shrunk by :data:`INSET`
    when ``skin == "inset"`` so that Box2D's grown polygon is the scene's."""
    s = body.shape
    if isinstance(s, Circle):
        return Box2D.b2CircleShape(pos=tuple(map(float, s.center)), radius=float(s.radius))
    vertices = polygon_vertices_local(body)
    if skin == "inset":
        inset = inset_polygon(vertices, INSET)
        turned = (np.diff(inset, axis=0, append=inset[:1]) * np.diff(vertices, axis=0, append=vertices[:1])).sum(1)
        if np.any(turned <= 0):
            raise ValueError(f"body {body.name!r} is too thin for Box2D's {SKIN:.3g} m skin; use skin='keep'")
        vertices = inset
    elif skin != "keep":
        raise ValueError(f"skin must be 'inset' or 'keep', got {skin!r}")
    return Box2D.b2PolygonShape(vertices=[tuple(map(float, p)) for p in vertices])


def fixture_materials(bodies: list[Body]) -> tuple[list[float], list[float], bool]:
    """Per-fixture friction and restitution whose Box2D mix is the reference's product.

    Friction ``mu^2``: ``sqrt(mu_a^2 mu_b^2) = mu_a mu_b``.  Restitution
    ``x_i = e_i min_j e_j`` over the bodies ``j`` that body ``i`` can touch (all but
    itself, static ones only for a dynamic ``i``): each ``x_i`` is as large as
    ``max(x_i, x_j) = e_i e_j`` allows, so if any per-fixture values give every pair's
    product these do.  Returns the two lists and whether every pair's
    ``max(x_i, x_j)`` equals ``e_i e_j`` (jointed pairs are counted too).
    """
    friction = [b.friction ** 2 for b in bodies]
    # Bodies of equal restitution and kind get equal values: work on those classes.
    classes: dict[tuple[float, bool], int] = {}
    for b in bodies:
        classes[(b.restitution, b.is_static)] = classes.get((b.restitution, b.is_static), 0) + 1

    def touch(a, b) -> bool:
        return not (a[1] and b[1]) and (a != b or classes[a] > 1)

    value = {}
    for c in classes:
        partners = [d[0] for d in classes if touch(c, d)]
        value[c] = c[0] * min(partners, default=1.0)
    exact = all(math.isclose(max(value[c], value[d]), c[0] * d[0], rel_tol=1e-12, abs_tol=1e-15)
                for c in classes for d in classes if touch(c, d))
    return friction, [value[(b.restitution, b.is_static)] for b in bodies], exact


class ProductMixing(Box2D.b2ContactListener):
    """Sets a new contact's friction and restitution to the products of the reference
    values kept in its fixtures' ``userData`` (``(friction, restitution)``)."""

    def BeginContact(self, contact):  # noqa: N802 (Box2D's name)
        (mu_a, e_a), (mu_b, e_b) = contact.fixtureA.userData, contact.fixtureB.userData
        contact.friction = mu_a * mu_b
        contact.restitution = e_a * e_b


def build_world(bodies: list[Body], gravity=(0.0, -9.81), joints=None, skin: str = "inset",
                mixing: str = "reference",
                allow_sleeping: bool = False) -> tuple[Box2D.b2World, list[Box2D.b2Body]]:
    """A ``b2World`` mirroring ``bodies`` (and distance ``joints``); returns it and the
    Box2D bodies in order (each one's ``userData`` its index).  See the module
    docstring for ``skin`` and ``mixing``; the world's ``mixing`` attribute says how
    materials were matched: ``"fixtures"``, ``"listener"`` or ``"box2d"``."""
    if mixing not in ("reference", "listener", "box2d"):
        raise ValueError(f"mixing must be 'reference', 'listener' or 'box2d', got {mixing!r}")
    friction = [b.friction for b in bodies]
    restitution = [b.restitution for b in bodies]
    if mixing == "reference":
        fixture_friction, fixture_restitution, exact = fixture_materials(bodies)
        mixing = "fixtures" if exact else "listener"
        if exact:
            friction, restitution = fixture_friction, fixture_restitution
    world = Box2D.b2World(gravity=tuple(map(float, gravity)), doSleep=allow_sleeping)
    if mixing == "listener":
        world.contactListener = ProductMixing()
    world.mixing = mixing
    b2_bodies = []
    for index, (body, mu, e) in enumerate(zip(bodies, friction, restitution)):
        kind = Box2D.b2_staticBody if body.is_static else Box2D.b2_dynamicBody
        b2_body = world.CreateBody(type=kind, position=tuple(map(float, body.position)), angle=body.angle,
                                   linearVelocity=tuple(map(float, body.velocity)),
                                   angularVelocity=body.angular_velocity, bullet=body.is_bullet,
                                   allowSleep=allow_sleeping, userData=index,
                                   fixedRotation=(not body.is_static and math.isinf(body.inertia)))
        b2_body.CreateFixture(shape=box2d_shape(body, skin), density=1.0, friction=mu, restitution=e,
                              userData=(body.friction, body.restitution))
        if not body.is_static:
            inertia = 0.0 if math.isinf(body.inertia) else body.inertia
            b2_body.massData = Box2D.b2MassData(mass=body.mass, center=(0.0, 0.0), I=inertia)
        b2_bodies.append(b2_body)
    for joint in joints or []:
        box2d_joint(world, joint, b2_bodies)
    return world, b2_bodies


def box2d_joint(world: Box2D.b2World, joint, b2_bodies: list[Box2D.b2Body]) -> Box2D.b2DistanceJoint:
    """The ``b2DistanceJoint`` of a reference :class:`~solutions.joints.DistanceJoint`."""
    return world.CreateDistanceJoint(bodyA=b2_bodies[joint.a], bodyB=b2_bodies[joint.b],
                                     localAnchorA=tuple(map(float, joint.anchor_a)),
                                     localAnchorB=tuple(map(float, joint.anchor_b)),
                                     length=joint.length, frequencyHz=joint.frequency,
                                     dampingRatio=joint.damping_ratio, collideConnected=False)


def copy_state(b2_bodies: list[Box2D.b2Body], bodies: list[Body]) -> None:
    """Copy Box2D's positions, angles and velocities into the reference bodies."""
    for b2_body, body in zip(b2_bodies, bodies):
        if body.is_static:
            continue
        body.position = np.array(b2_body.position, dtype=float)
        body.angle = float(b2_body.angle)
        body.velocity = np.array(b2_body.linearVelocity, dtype=float)
        body.angular_velocity = float(b2_body.angularVelocity)


def horizontal_drift(bodies: list[Body], start_positions: np.ndarray) -> float:
    """Largest horizontal distance (m) of a dynamic body from where it started: drift
    blind to the skin, which only lifts resting bodies."""
    moved = [abs(b.position[0] - p[0]) for b, p in zip(bodies, start_positions) if not b.is_static]
    return float(max(moved, default=0.0))


@dataclass
class Box2DMirror:
    """A scene's bodies in Box2D, stepped with fixed iterations and copied back.

    ``bodies`` are the reference bodies the state is copied into after each step (the
    scene's fresh bodies when built by :meth:`from_scene`).
    """

    bodies: list[Body]
    gravity: tuple[float, float] = (0.0, -9.81)
    joints: list = field(default_factory=list)
    velocity_iterations: int = VELOCITY_ITERATIONS
    position_iterations: int = POSITION_ITERATIONS
    skin: str = "inset"
    mixing: str = "reference"
    allow_sleeping: bool = False

    def __post_init__(self):
        self.world, self.b2_bodies = build_world(self.bodies, self.gravity, self.joints, self.skin, self.mixing,
                                                 self.allow_sleeping)

    @classmethod
    def from_scene(cls, scene, **options) -> "Box2DMirror":
        """The mirror of a :class:`~solutions.scenes.Scene` (or its name)."""
        scene = get_scene(scene) if isinstance(scene, str) else scene
        joints = scene.make_joints() if scene.make_joints else []
        return cls(scene.make_bodies(), scene.gravity, joints, **options)

    def step(self, dt: float, copy: bool = True) -> None:
        """Advance Box2D by ``dt`` (s); copy its state into ``bodies`` unless told not to."""
        self.world.Step(dt, self.velocity_iterations, self.position_iterations)
        if copy:
            self.copy_state()

    def copy_state(self) -> None:
        """Copy Box2D's state into ``bodies``."""
        copy_state(self.b2_bodies, self.bodies)


def simulate(scene, seconds: float | None = None, dt: float | None = None, probes: int = 30,
             **options) -> dict:
    """Step ``scene`` (a Scene or its name) in Box2D for ``seconds`` (default: the
    scene's duration) at ``dt`` (default: the scene's; ``options`` go to
    :class:`Box2DMirror`) and measure it with :mod:`solutions.scene_metrics` on the
    copied-back state at ``probes`` evenly spaced steps and the last: deepest overlap
    and largest drift (m, the scene's shapes, as for the other engines), largest
    horizontal drift (m), largest gain of total energy (J), momentum left (kg m/s),
    processor time per step without the copying (ms), Box2D's ``skin`` and the
    ``inset`` the polygons were given (m), and how materials were ``mixing``."""
    scene = get_scene(scene) if isinstance(scene, str) else scene
    dt = scene.dt if dt is None else dt
    steps = round((scene.duration if seconds is None else seconds) / dt)
    mirror = Box2DMirror.from_scene(scene, **options)
    bodies = mirror.bodies
    start = metrics.start_positions(bodies)
    energy0 = metrics.total_energy(bodies, scene.gravity)
    result = dict(penetration=0.0, drift=0.0, horizontal_drift=0.0, energy_gain=0.0)
    spent = 0.0
    for k in range(steps):
        t0 = time.process_time()
        mirror.step(dt, copy=False)
        spent += time.process_time() - t0
        if k % max(1, steps // probes) == 0 or k == steps - 1:
            mirror.copy_state()
            result["penetration"] = max(result["penetration"], metrics.max_penetration(bodies))
            result["drift"] = max(result["drift"], metrics.max_drift(bodies, start))
            result["horizontal_drift"] = max(result["horizontal_drift"], horizontal_drift(bodies, start))
            result["energy_gain"] = max(result["energy_gain"], metrics.total_energy(bodies, scene.gravity) - energy0)
    result.update(momentum=float(np.linalg.norm(metrics.linear_momentum(bodies))),
                  ms_per_step=1e3 * spent / max(steps, 1), skin=SKIN,
                  inset=INSET if mirror.skin == "inset" else 0.0, mixing=mirror.world.mixing)
    return result


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description="Step a scene in Box2D and print its metrics.")
    parser.add_argument("scene", nargs="+", help="scene names (solutions/scenes.py)")
    parser.add_argument("--seconds", type=float, help="simulated time (default: the scene's duration)")
    parser.add_argument("--iterations", type=int, nargs=2, default=(VELOCITY_ITERATIONS, POSITION_ITERATIONS),
                        metavar=("VELOCITY", "POSITION"))
    parser.add_argument("--skin", choices=("inset", "keep"), default="inset")
    parser.add_argument("--mixing", choices=("reference", "listener", "box2d"), default="reference")
    args = parser.parse_args(argv)
    for name in args.scene:
        r = simulate(name, args.seconds, velocity_iterations=args.iterations[0],
                     position_iterations=args.iterations[1], skin=args.skin, mixing=args.mixing)
        print(f"{name}: {r['ms_per_step']:.3f} ms/step, penetration {r['penetration']:.4f} m, drift "
              f"{r['drift']:.4f} m (horizontal {r['horizontal_drift']:.4f} m), energy gain {r['energy_gain']:.3g} J, "
              f"momentum left {r['momentum']:.3g} kg m/s; skin {r['skin']:.3f} m, inset {r['inset']:.4f} m, "
              f"materials: {r['mixing']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
