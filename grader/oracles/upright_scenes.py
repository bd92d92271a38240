"""Small worlds of upright boxes and discs on a flat ground, stepped with a contact
solver's three functions (the solver exercise: ``prestep_point``, ``contact_target``,
``sweep_contacts``), written here without the reference engine.

The narrow phase is exact for these shapes: a disc touches the ground (the line y = 0,
normal (0, 1) from the ground to the body) at one point below its centre, an upright box
at its two bottom corners, a box resting on the box below it at the two ends of the
shorter of their faces (the stack's boxes share x).  A contact exists while the overlap
is >= 0.  Each step: gravity into the velocities, the prestep of every point, its target
from the closing speed before any impulse, the sweeps with the impulses of the last
step's points (same manifold, same point: warm starting), then ``x += h v`` and
``angle += h w``.  Body 0 is the static ground.  The functions are called in one batch
per function and step through ``call_many(name, cases) -> results``.  SI units.
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


def step_scene(bodies: list[Upright], call_many, settings: SceneSettings, memory: dict,
               stacked: bool = False) -> list:
    """One step; ``memory`` maps (a, b, point number) to last step's (normal, tangent)
    impulses and is replaced.  Returns the manifolds as ``(a, b, normal totals)``."""
    h = settings.dt
    for body in bodies:
        body.velocity[1] -= G * h
    manifolds = manifolds_of(bodies, stacked)
    centre = [(0.0, -1.0)] + [(b.x, b.y) for b in bodies]
    inverse = [(0.0, 0.0)] + [(1.0 / b.mass, 0.0 if not b.turns else 1.0 / b.inertia) for b in bodies]
    material = [(settings.ground_friction, settings.ground_restitution)] + [(b.friction, b.restitution)
                                                                            for b in bodies]
    cases, owners = [], []
    for a, b, points, depths in manifolds:
        for k, point in enumerate(points):
            cases.append((list(point), [0.0, 1.0], list(centre[a]), list(centre[b]), inverse[a][0], inverse[b][0],
                          inverse[a][1], inverse[b][1], material[a][0] * material[b][0]))
            owners.append((a, b, k, depths[k]))
    rows = call_many("prestep_point", cases) if cases else []
    velocity = [[0.0, 0.0, 0.0]] + [list(b.velocity) for b in bodies]
    target_cases = []
    for row, (a, b, k, depth) in zip(rows, owners):
        va, vb = velocity[a], velocity[b]
        closing = vb[1] - va[1] + vb[2] * row[3] - va[2] * row[2]
        target_cases.append((closing, material[a][1] * material[b][1], depth, h, settings.restitution_threshold,
                             settings.bias_factor, settings.slop, settings.max_push))
    targets = call_many("contact_target", target_cases) if target_cases else []
    sweep_input, first = [], 0
    for a, b, points, _ in manifolds:
        count = len(points)
        remembered = [memory.get((a, b, k), (0.0, 0.0)) for k in range(count)]
        sweep_input.append([a, b, rows[first:first + count], targets[first:first + count],
                            [n for n, _ in remembered], [t for _, t in remembered]])
        first += count
    if sweep_input:
        velocity, normal, tangent = call_many("sweep_contacts", [(velocity, sweep_input, settings.iterations)])[0]
    else:
        normal, tangent = [], []
    memory.clear()
    for (a, b, points, _), normals, tangents in zip(manifolds, normal, tangent):
        for k in range(len(points)):
            memory[a, b, k] = (normals[k], tangents[k])
    for body, v in zip(bodies, velocity[1:]):
        body.velocity = [float(x) for x in v]
        body.x += h * body.velocity[0]
        body.y += h * body.velocity[1]
        body.angle += h * body.velocity[2]
    return [(a, b, list(normals)) for (a, b, _, _), normals in zip(manifolds, normal)]


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
