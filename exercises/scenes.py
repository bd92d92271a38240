# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/scenes.py on the instructor's side.
"""Named scenes as data: bodies, time step, duration, and what each scene needs.

A :class:`Scene` declares the techniques it needs (rotation, friction, continuous
detection) and :meth:`Scene.build_world` turns on only those: circles without friction
skip all angular work, a scene without bullets skips the sweep, and the world's
``"auto"`` broad phase tests all pairs directly in tiny scenes.  Static-static pairs
are never tested by the world.

Units: SI (m, kg, s).  Boxes in stacks are 1 m cubes of 1 kg unless stated.

>>> [name for name in sorted(SCENES) if name.startswith("b")]
['ball_drop', 'box_on_slope', 'bullet_wall']
>>> world = get_scene("elastic_balls").build_world()
>>> len(world.bodies)
2
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from .body import Body
from .joints import DistanceJoint
from .shapes import polygon_centroid
from .response.contact_solver import SolverSettings
from .response.solver_settings import SoftStepSettings, split_overrides
from .world import World, WorldSettings

KMH = 1000.0 / 3600.0  # m/s per km/h


@dataclass(frozen=True)
class Scene:
    """A named scene; ``make_bodies()`` builds fresh bodies each call."""

    name: str
    description: str
    make_bodies: Callable[[], list[Body]]
    dt: float = 1.0 / 60.0
    duration: float = 10.0
    gravity: tuple[float, float] = (0.0, -9.81)
    needs_rotation: bool = True
    needs_friction: bool = True
    needs_continuous: bool = False
    solver: SolverSettings = field(default_factory=SolverSettings)
    make_joints: Callable[[], list[DistanceJoint]] | None = None
    hard: bool = False
    recommended: dict = field(default_factory=dict)

    def world_settings(self, **solver_overrides) -> WorldSettings:
        """World switches for this scene: only what it needs, then ``solver_overrides``
        (settings of :class:`SolverSettings` or of :class:`SoftStepSettings`, by name)."""
        solver_changes, soft_changes = split_overrides(solver_overrides)
        solver = replace(self.solver, rotation=self.needs_rotation, friction=self.needs_friction)
        solver = replace(solver, **solver_changes)
        return WorldSettings(gravity=self.gravity, continuous=self.needs_continuous, solver=solver,
                             soft=SoftStepSettings(**soft_changes))

    def build_world(self, settings: WorldSettings | None = None, **solver_overrides) -> World:
        """A new :class:`World` of this scene's bodies."""
        joints = self.make_joints() if self.make_joints else None
        return World(self.make_bodies(), settings or self.world_settings(**solver_overrides), joints)

    def recommended_settings(self) -> WorldSettings:
        """The settings this scene is tested with: for a hard scene the soft step
        (:data:`HARD_SCENE_STEP`, updated by the scene's ``recommended``), otherwise
        :meth:`world_settings`."""
        if not self.hard:
            return self.world_settings()
        step = {**HARD_SCENE_STEP, **self.recommended}
        settings = self.world_settings(iterations=step.pop("iterations"))
        return replace(settings, **step)

    @property
    def steps(self) -> int:
        """Number of steps of ``dt`` in ``duration``."""
        return round(self.duration / self.dt)


def ground(width: float = 40.0, thickness: float = 1.0, top: float = 0.0, friction: float = 0.6,
           restitution: float = 0.0, x: float = 0.0) -> Body:
    """A static slab whose top face is at height ``top`` (m)."""
    return Body.box(width, thickness, is_static=True, position=(x, top - thickness / 2),
                    friction=friction, restitution=restitution, name="ground")


def truck_and_car() -> list[Body]:
    """Worked example 1: a 5000 kg truck at 80 km/h hits a 1000 kg car at 60 km/h ahead.

    They stay together (restitution 0): 76.67 km/h afterwards.
    """
    truck = Body.box(6.0, 2.5, mass=5000.0, position=(0.0, 0.0), velocity=(80 * KMH, 0), name="truck")
    car = Body.box(4.0, 1.5, mass=1000.0, position=(5.5, 0.0), velocity=(60 * KMH, 0), name="car")
    return [truck, car]


def elastic_balls() -> list[Body]:
    """Worked example 2: 0.1 kg at +10 m/s meets 0.2 kg at -5 m/s, elastic (e = 1)."""
    return [Body.circle(0.05, mass=0.1, position=(-0.5, 0), velocity=(10, 0), restitution=1.0, name="ball 1"),
            Body.circle(0.05, mass=0.2, position=(0.5, 0), velocity=(-5, 0), restitution=1.0, name="ball 2")]


def ball_drop() -> list[Body]:
    """A 0.5 m ball dropped from 5 m onto the ground; e = 0.8 (product of 0.8 and 1)."""
    return [ground(restitution=1.0),
            Body.circle(0.5, mass=1.0, position=(0, 5.0), restitution=0.8, name="ball")]


def box_on_slope(angle_deg: float = 20.0) -> list[Body]:
    """A box resting on a 20 degree slope; pair friction 0.8 * 0.8 = 0.64 > tan 20 deg."""
    a = math.radians(angle_deg)
    slope = Body.box(20.0, 1.0, is_static=True, angle=a, friction=0.8, name="slope")
    normal = np.array([-math.sin(a), math.cos(a)])
    box = Body.box(1.0, 1.0, mass=1.0, angle=a, position=1.0 * normal, friction=0.8, name="box")
    return [slope, box]


def vertical_stack(count: int) -> list[Body]:
    """``count`` 1 m boxes of 1 kg stacked exactly touching on the ground."""
    return [ground()] + [Body.box(1.0, 1.0, mass=1.0, position=(0.0, 0.5 + k), friction=0.6, name=f"box {k}")
                         for k in range(count)]


def pyramid(base: int, origin=(0.0, 0.0)) -> list[Body]:
    """A pyramid of 1 m boxes, ``base`` on the bottom row: base (base + 1) / 2 boxes."""
    ox, oy = origin
    bodies = [ground(width=base + 20.0, x=ox, top=oy)]
    for row in range(base):
        for k in range(base - row):
            x = ox + (k - (base - row - 1) / 2) * 1.0
            bodies.append(Body.box(1.0, 1.0, mass=1.0, position=(x, oy + 0.5 + row), friction=0.6,
                                   name=f"row {row} box {k}"))
    return bodies


def mass_ratio(ratio: float) -> list[Body]:
    """A heavy box (``ratio`` kg) resting on a light 1 kg box on the ground."""
    return [ground(),
            Body.box(1.0, 1.0, mass=1.0, position=(0, 0.5), friction=0.6, name="light"),
            Body.box(1.0, 1.0, mass=float(ratio), position=(0, 1.5), friction=0.6, name="heavy")]


def bullet_wall() -> list[Body]:
    """A 0.05 m radius ball at 100 m/s towards a 0.1 m thick static wall (60 Hz: 1.67 m per step)."""
    wall = Body.box(0.1, 4.0, is_static=True, position=(5.0, 0.0), restitution=1.0, name="wall")
    ball = Body.circle(0.05, mass=0.1, position=(0.0, 0.0), velocity=(100.0, 0.0), restitution=0.5,
                       is_bullet=True, name="bullet")
    return [wall, ball]


def many_bodies(count: int = 400, clustered: bool = False, seed: int = 1) -> list[Body]:
    """``count`` frictionless balls moving in a closed 40 m box, no gravity.

    Uniform: positions spread over the box.  Clustered: around 5 centres (normal
    spread 1.5 m), so a few cells hold most bodies.
    """
    rng = np.random.default_rng(seed)
    half = 20.0
    walls = [Body.box(2 * half + 2, 1.0, is_static=True, position=(0, -half - 0.5), restitution=1.0),
             Body.box(2 * half + 2, 1.0, is_static=True, position=(0, half + 0.5), restitution=1.0),
             Body.box(1.0, 2 * half, is_static=True, position=(-half - 0.5, 0), restitution=1.0),
             Body.box(1.0, 2 * half, is_static=True, position=(half + 0.5, 0), restitution=1.0)]
    if clustered:
        centres = rng.uniform(-half + 4, half - 4, size=(5, 2))
        positions = centres[rng.integers(0, 5, count)] + rng.normal(0, 1.5, size=(count, 2))
    else:
        positions = rng.uniform(-half + 1, half - 1, size=(count, 2))
    positions = np.clip(positions, -half + 0.3, half - 0.3)
    velocities = rng.normal(0, 2.0, size=(count, 2))
    radii = rng.uniform(0.1, 0.25, count)
    return walls + [Body.circle(r, mass=math.pi * r * r * 100, position=p, velocity=v, restitution=0.9)
                    for r, p, v in zip(radii, positions, velocities)]


def arch(blocks: int = 9, inner: float = 2.0, outer: float = 2.6) -> list[Body]:
    """A semicircular arch of ``blocks`` wedge-shaped voussoirs (convex quadrilaterals)
    between radii ``inner`` and ``outer`` (m), standing on the ground; friction 0.8 each."""
    bodies = [ground(friction=0.8)]
    for k in range(blocks):
        a0, a1 = math.pi * k / blocks, math.pi * (k + 1) / blocks
        corners = [(outer * math.cos(a0), outer * math.sin(a0)), (outer * math.cos(a1), outer * math.sin(a1)),
                   (inner * math.cos(a1), inner * math.sin(a1)), (inner * math.cos(a0), inner * math.sin(a0))]
        corners = np.array(corners)
        # Body.polygon recentres the shape on its area centroid: the body goes there.
        bodies.append(Body.polygon(corners, mass=1.0, friction=0.8, position=polygon_centroid(corners),
                                   name=f"voussoir {k}"))
    return bodies


def overlap_recovery(count: int = 12, seed: int = 3) -> list[Body]:
    """``count`` 1 m boxes spawned overlapping each other by up to half their size."""
    rng = np.random.default_rng(seed)
    bodies = [ground()]
    for k in range(count):
        x = float(rng.uniform(-1.0, 1.0))
        y = 0.5 + 0.5 * k + float(rng.uniform(0.0, 0.1))
        bodies.append(Body.box(1.0, 1.0, mass=1.0, position=(x, y), angle=float(rng.uniform(-0.3, 0.3)),
                               friction=0.6, name=f"box {k}"))
    return bodies


def chain_links(links: int = 40, spacing: float = 0.25, anchor=(0.0, 12.0)) -> list[Body]:
    """A static anchor and ``links`` small balls in a horizontal row, ``spacing`` apart."""
    pin = Body.circle(0.05, is_static=True, position=anchor, name="anchor")
    return [pin] + [Body.circle(0.05, mass=0.1, position=(anchor[0] + spacing * (k + 1), anchor[1]), name=f"link {k}")
                    for k in range(links)]


def chain_joints(links: int = 40, spacing: float = 0.25) -> list[DistanceJoint]:
    """Rigid distance joints between consecutive links (and the anchor and the first)."""
    return [DistanceJoint(k, k + 1, length=spacing) for k in range(links)]


def friction_ramp(angle_deg: float = 30.0, frictions=(0.2, 0.4, 0.5, 0.7, 0.9)) -> list[Body]:
    """Boxes on a ramp of ``angle_deg``; the ramp's friction is 1, so each pair's
    friction is the box's.  tan 30 deg = 0.577: the first three slide, the others stick."""
    a = math.radians(angle_deg)
    ramp = Body.box(30.0, 1.0, is_static=True, angle=a, friction=1.0, name="ramp")
    along = np.array([math.cos(a), math.sin(a)])
    normal = np.array([-math.sin(a), math.cos(a)])
    boxes = [Body.box(0.8, 0.8, mass=1.0, angle=a, friction=mu, name=f"box mu={mu}",
                      position=(2.5 * k - 5.0) * along + (0.5 + 0.4) * normal)
             for k, mu in enumerate(frictions)]
    return [ramp] + boxes


#: The recommended step of the hard scenes: Box2D v3's soft step with 8 sub-steps of one
#: sweep each (:mod:`exercises.response.soft_step`).  At 60 Hz its contacts are springs of
#: 120 Hz (240 Hz on static bodies), stiff enough that a 20-box stack sags less than
#: 1 cm, and it finds contacts once per step: it costs about what the plain solver
#: costs at 30 iterations on a stack and less on a pyramid (bench/bench_hard_cases.py).
HARD_SCENE_STEP = dict(soft_step=True, substeps=8, iterations=1)

ZERO_G = (0.0, 0.0)
#: The worked examples check velocities exactly: split impulses fix the overlap of the
#: impact step without adding the Baumgarte bias to the real velocities.
EXACT_VELOCITIES = SolverSettings(position_correction="split_impulse")

SCENES: dict[str, Scene] = {scene.name: scene for scene in [
    Scene("truck_and_car", truck_and_car.__doc__, truck_and_car, duration=1.0, gravity=ZERO_G,
          needs_rotation=False, needs_friction=False, solver=EXACT_VELOCITIES),
    Scene("elastic_balls", elastic_balls.__doc__, elastic_balls, duration=0.2, gravity=ZERO_G,
          needs_rotation=False, needs_friction=False, solver=EXACT_VELOCITIES),
    Scene("ball_drop", ball_drop.__doc__, ball_drop, duration=4.0, needs_rotation=False, needs_friction=False),
    Scene("box_on_slope", box_on_slope.__doc__, box_on_slope, duration=3.0),
    Scene("stack_10", vertical_stack.__doc__, lambda: vertical_stack(10), hard=True),
    Scene("stack_20", vertical_stack.__doc__, lambda: vertical_stack(20), hard=True),
    Scene("pyramid_10", pyramid.__doc__, lambda: pyramid(10), hard=True),
    Scene("pyramid_20", pyramid.__doc__, lambda: pyramid(20), hard=True),
    Scene("mass_ratio_100", mass_ratio.__doc__, lambda: mass_ratio(100), hard=True),
    Scene("mass_ratio_1000", mass_ratio.__doc__, lambda: mass_ratio(1000), hard=True),
    Scene("arch", arch.__doc__, arch, hard=True),
    Scene("overlap_recovery", overlap_recovery.__doc__, overlap_recovery, duration=3.0, hard=True),
    Scene("pyramid_20_far", "The 20-base pyramid at (1e5, -8e4) m: same physics far from the origin.",
          lambda: pyramid(20, origin=(1e5, -8e4)), hard=True),
    Scene("chain_40", "A chain of 40 balls on rigid distance joints, released horizontally from a static anchor.",
          chain_links, duration=5.0, needs_rotation=False, needs_friction=False, make_joints=chain_joints, hard=True),
    Scene("friction_ramp", friction_ramp.__doc__, friction_ramp, duration=3.0, hard=True),
    Scene("bullet_wall", bullet_wall.__doc__, bullet_wall, duration=0.2, gravity=ZERO_G,
          needs_rotation=False, needs_friction=False, needs_continuous=True, hard=True),
    Scene("many_uniform", many_bodies.__doc__, lambda: many_bodies(400, clustered=False), duration=2.0,
          gravity=ZERO_G, needs_rotation=False, needs_friction=False),
    Scene("many_clustered", many_bodies.__doc__, lambda: many_bodies(400, clustered=True), duration=2.0,
          gravity=ZERO_G, needs_rotation=False, needs_friction=False),
]}


def get_scene(name: str) -> Scene:
    """The scene called ``name``; ValueError listing the known names otherwise."""
    try:
        return SCENES[name]
    except KeyError:
        raise ValueError(f"unknown scene {name!r}; known scenes: {', '.join(sorted(SCENES))}") from None
