"""Small worlds of upright boxes and discs on a flat ground, stepped with a contact
solver's functions (the solver exercise: ``prestep_point`` and ``sweep_contacts``, or
``step_bodies`` for the whole step), written here without the reference engine.

The narrow phase is exact for these shapes: a disc touches the ground (the line y = 0,
normal (0, 1) from the ground to the body) at one point below its centre, an upright box
at its two bottom corners, a box resting on the box below it at the two ends of the
shorter of their faces (the stack's boxes share x).  A contact exists while the overlap
is >= 0.  Each step (:func:`step_scene`): gravity into the velocities, the prestep of
every point, the sweeps (their targets from the closing speed before any impulse, then
the warm start with the impulses of the last step's points: same manifold, same point),
then ``x += h v`` and ``angle += h w``; or all of it by ``step_bodies``
(:func:`step_scene_whole`).  Body 0 is the static ground.  The functions are called in
one batch per function and step through ``call_many(name, cases) -> results``.  SI units.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

G = 9.81


@dataclass
class Upright:
    """A dynamic body: a disc (``radius``) or a box (``half_width``, ``half_height``)."""

    mass: float
    half_width: float = 0.0
    half_height: float = 0.0
    radius: float = 0.0
    x: float = 0.0
    y: float = 0.0
    angle: float = 0.0
    velocity: list = field(default_factory=lambda: [0.0, 0.0, 0.0])
    friction: float = 0.5
    restitution: float = 0.0
    turns: bool = True

    @property
    def inertia(self) -> float:
        """kg m^2 (inf for a body that does not turn)."""
        if not self.turns:
            return math.inf
        if self.radius:
            return 0.5 * self.mass * self.radius ** 2
        return self.mass * ((2 * self.half_width) ** 2 + (2 * self.half_height) ** 2) / 12.0


@dataclass
class SceneSettings:
    dt: float = 1 / 60
    iterations: int = 10
    restitution_threshold: float = 1.0
    bias_factor: float = 0.2
    slop: float = 0.005
    max_push: float = 3.0
    ground_friction: float = 1.0
    ground_restitution: float = 1.0


def corners_on_ground(body: Upright) -> list[tuple[tuple[float, float], float]]:
    """(point, depth) of the bottom corners of a box turned by ``angle`` (its lowest two)."""
    c, s = math.cos(body.angle), math.sin(body.angle)
    corners = []
    for lx, ly in ((-body.half_width, -body.half_height), (body.half_width, -body.half_height),
                   (body.half_width, body.half_height), (-body.half_width, body.half_height)):
        x, y = body.x + c * lx - s * ly, body.y + s * lx + c * ly
        corners.append(((x, 0.0), -y))
    corners.sort(key=lambda corner: -corner[1])
    return [corner for corner in corners[:2] if corner[1] >= 0.0]


def manifolds_of(bodies: list[Upright], stacked: bool) -> list[tuple[int, int, list, list]]:
    """``(a, b, points, depths)`` per touching pair, body indices 1.. (0 is the ground)."""
    found = []
    for index, body in enumerate(bodies, start=1):
        if body.radius:
            depth = body.radius - body.y
            if depth >= 0.0:
                found.append((0, index, [(body.x, 0.0)], [depth]))
        elif stacked and index > 1:
            below = bodies[index - 2]
            depth = (below.y + below.half_height) - (body.y - body.half_height)
            if depth >= 0.0:
                half = min(body.half_width, below.half_width)
                top = below.y + below.half_height
                found.append((index - 1, index, [(body.x - half, top), (body.x + half, top)], [depth, depth]))
        else:
            corners = corners_on_ground(body)
            if corners:
                found.append((0, index, [p for p, _ in corners], [d for _, d in corners]))
    return found


def step_settings(settings: SceneSettings) -> list:
    """The exercise's ``StepSettings`` fields: dt, iterations, restitution_threshold,
    bias_factor, slop, max_push."""
    return [settings.dt, settings.iterations, settings.restitution_threshold, settings.bias_factor, settings.slop,
            settings.max_push]


def scene_input(bodies: list[Upright], settings: SceneSettings, memory: dict, stacked: bool):
    """The arguments of ``step_bodies`` for the scene: body rows ``(x, y, angle, vx, vy, w,
    1/m, 1/I)`` with the ground first (its centre 1 m below the surface), the touching
    pairs ``(a, b, normal, points, depths, friction, restitution, normal totals, tangent
    totals)`` with last step's impulses from ``memory``, gravity and the settings."""
    rows = [[0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]]
    rows += [[b.x, b.y, b.angle, *b.velocity, 1.0 / b.mass, 1.0 / b.inertia if b.turns else 0.0] for b in bodies]
    material = [(settings.ground_friction, settings.ground_restitution)] + [(b.friction, b.restitution)
                                                                            for b in bodies]
    pairs = []
    for a, b, points, depths in manifolds_of(bodies, stacked):
        remembered = [memory.get((a, b, k), (0.0, 0.0)) for k in range(len(points))]
        pairs.append([a, b, [0.0, 1.0], [list(p) for p in points], list(depths), material[a][0] * material[b][0],
                      material[a][1] * material[b][1], [n for n, _ in remembered], [t for _, t in remembered]])
    return rows, pairs, [0.0, -G], step_settings(settings)


def remember(bodies: list[Upright], pairs: list, moved: list, normal: list, tangent: list, memory: dict) -> list:
    """Write ``moved`` rows back into the bodies and the impulses into ``memory``;
    returns the manifolds as ``(a, b, normal totals)``."""
    memory.clear()
    for (a, b, *_), normals, tangents in zip(pairs, normal, tangent):
        for k, (n, t) in enumerate(zip(normals, tangents)):
            memory[a, b, k] = (n, t)
    for body, (x, y, angle, vx, vy, w) in zip(bodies, moved[1:]):
        body.x, body.y, body.angle, body.velocity = x, y, angle, [float(vx), float(vy), float(w)]
    return [(a, b, list(normals)) for (a, b, *_), normals in zip(pairs, normal)]


def step_scene(bodies: list[Upright], call_many, settings: SceneSettings, memory: dict,
               stacked: bool = False) -> list:
    """One step, written here around ``prestep_point`` and ``sweep_contacts``; ``memory``
    maps (a, b, point number) to last step's (normal, tangent) impulses and is replaced.
    Returns the manifolds as ``(a, b, normal totals)``."""
    rows, pairs, (gx, gy), constants = scene_input(bodies, settings, memory, stacked)
    h = settings.dt
    velocity = [[vx + h * gx, vy + h * gy, w] if ima > 0.0 else [vx, vy, w] for _, _, _, vx, vy, w, ima, _ in rows]
    cases = [(point, normal, rows[a][:2], rows[b][:2], rows[a][6], rows[b][6], rows[a][7], rows[b][7], friction)
             for a, b, normal, points, _, friction, *_ in pairs for point in points]
    points = call_many("prestep_point", cases) if cases else []
    manifolds, first = [], 0
    for a, b, _, found, depths, _, restitution, normal_total, tangent_total in pairs:
        manifolds.append([a, b, points[first:first + len(found)], restitution, depths, normal_total, tangent_total])
        first += len(found)
    if manifolds:
        velocity, normal, tangent = call_many("sweep_contacts", [(velocity, manifolds, constants)])[0]
    else:
        normal, tangent = [], []
    moved = [[x + h * v[0], y + h * v[1], angle + h * v[2], *v] for (x, y, angle, *_), v in zip(rows, velocity)]
    return remember(bodies, pairs, moved, normal, tangent, memory)


def step_scene_whole(bodies: list[Upright], call_many, settings: SceneSettings, memory: dict,
                     stacked: bool = False) -> list:
    """One step by ``step_bodies`` alone (gravity, prestep, sweeps and positions are the
    function's); otherwise as :func:`step_scene`."""
    rows, pairs, gravity, constants = scene_input(bodies, settings, memory, stacked)
    moved, normal, tangent = call_many("step_bodies", [(rows, pairs, gravity, constants)])[0]
    return remember(bodies, pairs, moved, normal, tangent, memory)


def overlaps(bodies: list[Upright], stacked: bool = False) -> list[float]:
    """Each body's overlap (m, > 0 overlapping) with what it stands on: the ground (a disc
    below its centre, a box at its lowest corner) or, in a stack, the box below it."""
    found = []
    for index, body in enumerate(bodies):
        if body.radius:
            found.append(body.radius - body.y)
        elif stacked and index > 0:
            below = bodies[index - 1]
            found.append((below.y + below.half_height) - (body.y - body.half_height))
        else:
            c, s = abs(math.cos(body.angle)), abs(math.sin(body.angle))
            found.append(s * body.half_width + c * body.half_height - body.y)
    return found


def target_speed(closing: float, restitution: float, depth: float, settings: SceneSettings) -> float:
    """What a contact wants (m/s): the larger of a bounce, ``e`` times the closing speed
    (``closing`` < 0 closing) if it closes faster than the restitution threshold, and the
    Baumgarte push, ``bias_factor`` of the overlap beyond the slop in one step, at most
    ``max_push``."""
    bounce = -restitution * closing if -closing > settings.restitution_threshold else 0.0
    return max(bounce, min(settings.bias_factor * max(depth - settings.slop, 0.0) / settings.dt, settings.max_push))


def vertical_paths(bodies: list[Upright], settings: SceneSettings, steps: int, call_many=None) -> list[list]:
    """Per step, each body's ``(overlap with the ground (m), vertical velocity (m/s))``
    after it, for bodies moving only up and down, each alone over the ground with every
    contact point as deep: discs, or upright boxes that cannot turn, with no horizontal
    velocity.  The bodies are not changed.

    Their contact is solved exactly, without sweeps: each step gravity first; then a
    body that overlaps (>= 0) leaves at its contact's target, or keeps its velocity if
    it already leaves faster (a contact only pushes); then ``y += h v``.  The target is
    :func:`target_speed` (``e`` the ground's times the body's), or with ``call_many``
    what ``call_many("contact_target", cases)`` answers, one case ``(closing velocity,
    e, overlap, h, restitution_threshold, bias_factor, slop, max_push)`` per touching
    body.
    """
    h = settings.dt
    below = [body.radius or body.half_height for body in bodies]
    height = [body.y for body in bodies]
    velocity = [body.velocity[1] for body in bodies]
    paths = []
    for _ in range(steps):
        velocity = [v - G * h for v in velocity]
        touching = [i for i in range(len(bodies)) if below[i] - height[i] >= 0.0]
        cases = [(velocity[i], settings.ground_restitution * bodies[i].restitution, below[i] - height[i], h,
                  settings.restitution_threshold, settings.bias_factor, settings.slop, settings.max_push)
                 for i in touching]
        if call_many is None:
            targets = [target_speed(case[0], case[1], case[2], settings) for case in cases]
        else:
            targets = call_many("contact_target", cases) if cases else []
        for i, target in zip(touching, targets):
            velocity[i] = max(velocity[i], target)
        height = [y + h * v for y, v in zip(height, velocity)]
        paths.append([(b - y, v) for b, y, v in zip(below, height, velocity)])
    return paths
