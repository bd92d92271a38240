"""Build the same scene in Box2D v3 (Box2D 3.1.1 through pyb2d3, ``import pyb2d3``) and copy its state back.

The third peer engine beside pymunk (:mod:`tools.pymunk_mirror`) and Box2D 2.3
(:mod:`tools.box2d_mirror`), and the one the reference's soft step follows: sub-steps,
soft contacts, relax and restitution passes.  Bodies, shapes, masses, materials,
distance joints and gravity of a scene are mirrored into a v3 world, stepped with
``substeps`` sub-steps, and its state copied back into the reference bodies so that
:mod:`solutions.scene_metrics` measures it like the other engines.

Box2D 3.1.1 facts this relies on (pyb2d3 0.11.1, the SSE2 build of its wheel):

- **Settings.**  :data:`SETTINGS`: ``"default"`` is v3's own (4 sub-steps, contacts
  of 30 Hz and damping ratio 10, as ``b2DefaultWorldDef``); ``"stiff"`` takes 16
  sub-steps and 120 Hz contacts (v3 caps a contact's stiffness at an eighth of the
  sub-step rate: 120 Hz is the cap at 16 sub-steps of 1/60 s).
- **One thread.**  A world made without a thread pool has ``workerCount`` 1: the whole
  step runs on the calling thread, as the reference's and the other peers' do.
- **Floats.**  Everything is 32-bit; positions, velocities and the state copied back
  carry float32 rounding (about 1e-7 relative).
- **No skin.**  v3 polygons have a ``radius`` (rounded polygons); the mirror gives
  radius 0, so each polygon is the scene's polygon (v3's speculative contacts need no
  skin, unlike Box2D 2.3's).
- **Exact rotations.**  v3.1's ``b2MakeRot(angle)`` (pyb2d3's ``make_rot``, ``Rot(angle)``)
  approximates cos and sin (0.9549 for cos 0.3 = 0.9553); every rotation here is
  built from ``math.cos`` and ``math.sin`` (:func:`exact_rotation`).
- **Mass.**  v3 computes mass from density; the mirror sets each body's mass, centre
  (the body origin) and rotational inertia to the reference's instead (shapes made
  with ``update_body_mass=False``).  An infinite inertia becomes ``fixed_rotation``.
- **Materials.**  v3 mixes a pair's friction as ``sqrt(mu_a mu_b)`` and restitution
  as ``max(e_a, e_b)``, as Box2D 2.3 does; the mirror gives each shape the values of
  :func:`tools.box2d_mirror.fixture_materials` (friction ``mu^2``, restitution
  ``e_i min_j e_j``), whose mix is the reference's product for every pair of the
  scenes.  A scene where no per-shape values can do that raises ValueError (v3's
  per-contact callbacks are not reachable from pyb2d3); ``mixing="box2d"`` keeps v3's
  rules with the scene's values.  Restitution applies above 1 m/s of approach.
- **Sleep** is off (every body's ``enable_sleep`` and the world's), as in the other
  mirrors, so that timings and errors compare.  Continuous detection is v3's own
  (dynamic against static bodies; a reference bullet becomes a v3 bullet).
- **Joints.**  A reference :class:`~solutions.joints.DistanceJoint` becomes a v3
  distance joint with the same local anchors and length: rigid (v3's own joint
  softness) for frequency 0, otherwise a spring of the same frequency and damping ratio.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import pyb2d3 as b2

from solutions.body import Body
from solutions.scenes import get_scene
from solutions.shapes import OBB, Circle
from tools.box2d_mirror import fixture_materials, polygon_vertices_local

#: The v3 settings the benchmark runs: sub-steps per step and contact stiffness (Hz;
#: None: v3's default, 30 Hz).
SETTINGS = {"default": dict(substeps=4, contact_hertz=None), "stiff": dict(substeps=16, contact_hertz=120.0)}
#: Most vertices a v3 polygon takes (``B2_MAX_POLYGON_VERTICES``).
MAX_POLYGON_VERTICES = 8


def exact_rotation(angle: float) -> b2.Rot:
    """A v3 rotation of ``angle`` (rad) from exact cos and sin (not v3.1's approximation)."""
    rotation = b2.Rot()
    rotation.c, rotation.s = math.cos(angle), math.sin(angle)
    return rotation


def v3_shape(body: Body):
    """The v3 geometry of ``body.shape`` in the body's frame, polygons of radius 0."""
    s = body.shape
    if isinstance(s, Circle):
        return b2.circle(center=tuple(map(float, s.center)), radius=float(s.radius))
    if isinstance(s, OBB) and not s.center.any() and s.angle == 0.0:
        return b2.box(float(s.half_extents[0]), float(s.half_extents[1]))
    vertices = polygon_vertices_local(body)
    if len(vertices) > MAX_POLYGON_VERTICES:
        raise ValueError(f"body {body.name!r} has {len(vertices)} vertices; Box2D v3 takes at most "
                         f"{MAX_POLYGON_VERTICES}")
    return b2.polygon(points=vertices)      # (radius 0, placed at the origin unturned: exact)


def build_world(bodies: list[Body], gravity=(0.0, -9.81), joints=None, contact_hertz: float | None = None,
                mixing: str = "reference", allow_sleeping: bool = False) -> tuple[b2.World, list[b2.Body], list]:
    """A v3 world mirroring ``bodies`` (and distance ``joints``); returns it, the v3
    bodies and the v3 joints in order.  ``contact_hertz`` None keeps v3's default stiffness; see the
    module docstring for ``mixing`` (``"reference"`` or ``"box2d"``)."""
    if mixing not in ("reference", "box2d"):
        raise ValueError(f"mixing must be 'reference' or 'box2d', got {mixing!r}")
    friction = [b.friction for b in bodies]
    restitution = [b.restitution for b in bodies]
    if mixing == "reference":
        friction, restitution, exact = fixture_materials(bodies)
        if not exact:
            raise ValueError("no per-shape friction and restitution give every pair the reference's products "
                             "here; use mixing='box2d'")
    options = {} if contact_hertz is None else {"contact_hertz": float(contact_hertz)}
    world = b2.World(gravity=tuple(map(float, gravity)), **options)
    world.sleeping_enabled = allow_sleeping
    v3_bodies = []
    for body, mu, e in zip(bodies, friction, restitution):
        turns = not (body.is_static or math.isinf(body.inertia))
        v3_body = world.create_body(
            type=b2.BodyType.STATIC if body.is_static else b2.BodyType.DYNAMIC,
            position=tuple(map(float, body.position)), rotation=exact_rotation(body.angle),
            linear_velocity=tuple(map(float, body.velocity)),
            angular_velocity=body.angular_velocity if turns else 0.0, is_bullet=body.is_bullet,
            enable_sleep=allow_sleeping, fixed_rotation=not body.is_static and not turns)
        material = b2.surface_material(friction=float(mu), restitution=float(e))
        v3_body.create_shape(b2.shape_def(density=1.0, material=material, update_body_mass=False), v3_shape(body))
        if not body.is_static:
            mass = b2.MassData()
            mass.mass, mass.center, mass.rotational_inertia = body.mass, (0.0, 0.0), body.inertia if turns else 0.0
            v3_body.mass_data = mass
        v3_bodies.append(v3_body)
    v3_joints = []
    for joint in joints or []:
        v3_joints.append(world.create_distance_joint(v3_bodies[joint.a], v3_bodies[joint.b],
                                    local_anchor_a=tuple(map(float, joint.anchor_a)),
                                    local_anchor_b=tuple(map(float, joint.anchor_b)), length=float(joint.length),
                                    enable_spring=joint.frequency > 0, hertz=float(joint.frequency),
                                    damping_ratio=float(joint.damping_ratio), collide_connected=False))
    return world, v3_bodies, v3_joints


def copy_state(v3_bodies: list[b2.Body], bodies: list[Body]) -> None:
    """Copy v3's positions, angles and velocities into the reference bodies."""
    for v3_body, body in zip(v3_bodies, bodies):
        if body.is_static:
            continue
        p, rotation, v = v3_body.position, v3_body.rotation, v3_body.linear_velocity
        body.position = (p.x, p.y)
        body.angle = math.atan2(rotation.s, rotation.c)
        body.velocity = (v.x, v.y)
        body.angular_velocity = v3_body.angular_velocity


@dataclass
class Box2DV3Mirror:
    """A scene's bodies in Box2D v3, stepped with ``substeps`` sub-steps and copied back
    into ``bodies`` (the scene's fresh bodies when built by :meth:`from_scene`)."""

    bodies: list[Body]
    gravity: tuple[float, float] = (0.0, -9.81)
    joints: list = field(default_factory=list)
    substeps: int = SETTINGS["default"]["substeps"]
    contact_hertz: float | None = None
    mixing: str = "reference"
    allow_sleeping: bool = False

    def __post_init__(self):
        self.world, self.v3_bodies, self.v3_joints = build_world(self.bodies, self.gravity, self.joints, self.contact_hertz,
                                                 self.mixing, self.allow_sleeping)

    @classmethod
    def from_scene(cls, scene, setting: str = "default", **options) -> "Box2DV3Mirror":
        """The mirror of a :class:`~solutions.scenes.Scene` (or its name) under one of
        :data:`SETTINGS` (``options`` override it)."""
        scene = get_scene(scene) if isinstance(scene, str) else scene
        joints = scene.make_joints() if scene.make_joints else []
        return cls(scene.make_bodies(), scene.gravity, joints, **{**SETTINGS[setting], **options})

    def step(self, dt: float, copy: bool = True) -> None:
        """Advance v3 by ``dt`` (s); copy its state into ``bodies`` unless told not to."""
        self.world.step(dt, self.substeps)
        if copy:
            self.copy_state()

    def copy_state(self) -> None:
        """Copy v3's state into ``bodies``."""
        copy_state(self.v3_bodies, self.bodies)
