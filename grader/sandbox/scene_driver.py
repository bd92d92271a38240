"""A small scene stepped with the student's resolver, run inside the sandbox.

Balls dropped into a box: the contacts (ball-ball, ball-wall) are computed here with
plain formulas, so that only the student's ``resolve_collision`` and
``correct_positions`` decide the motion.  Returns the trajectory as plain lists; the
trusted parent measures it.  Imports only the student's ``exercises`` package.
"""
from __future__ import annotations

import math

WALLS = ((0.0, 1.0, 0.0), (1.0, 0.0, -1.5), (-1.0, 0.0, -1.5))  # (nx, ny, offset): n . x >= offset inside


def initial_balls(count: int = 16, radius: float = 0.2):
    """Positions on a jittered grid (deterministic), velocities, radius (m)."""
    balls = []
    for k in range(count):
        row, column = divmod(k, 4)
        jitter = 0.03 * math.sin(7.3 * k)
        balls.append(((-0.9 + 0.6 * column + jitter, 0.5 + 0.55 * row), (0.4 * math.cos(3.1 * k), 0.0)))
    return balls, radius


def drop_balls(steps: int = 120, dt: float = 1 / 60, restitution: float = 0.5, friction: float = 0.2) -> dict:
    import numpy as np
    from exercises.body import Body
    from exercises.contact import Contact
    from exercises.response.impulse import resolve_collision
    from exercises.response.positional_correction import correct_positions

    start, radius = initial_balls()
    balls = [Body.circle(radius, mass=1.0, position=p, velocity=v, restitution=restitution, friction=friction)
             for p, v in start]
    ground = Body.box(10.0, 1.0, is_static=True, position=(0.0, -0.5), restitution=1.0, friction=1.0)
    trajectory = []
    for _ in range(steps):
        for ball in balls:
            ball.velocity = ball.velocity + dt * np.array([0.0, -9.81])
        contacts = []
        for i in range(len(balls)):
            xi, yi = balls[i].position
            for nx, ny, offset in WALLS:
                depth = offset - (nx * xi + ny * yi - radius)
                if depth >= 0:
                    # Normal from the ball (A) to the wall (B) points out of the box.
                    point = (xi - nx * (radius - depth / 2), yi - ny * (radius - depth / 2))
                    contacts.append((balls[i], ground, Contact((-nx, -ny), depth, [point])))
            for j in range(i + 1, len(balls)):
                dx, dy = balls[j].position[0] - xi, balls[j].position[1] - yi
                distance = math.hypot(dx, dy)
                depth = 2 * radius - distance
                if depth >= 0 and distance > 0:
                    n = (dx / distance, dy / distance)
                    point = (xi + n[0] * (radius - depth / 2), yi + n[1] * (radius - depth / 2))
                    contacts.append((balls[i], balls[j], Contact(n, depth, [point])))
        for a, b, contact in contacts:
            resolve_collision(a, b, contact)
        for a, b, contact in contacts:
            correct_positions(a, b, contact.normal, contact.depth, 0.8, 0.01)
        for ball in balls:
            ball.position = ball.position + dt * ball.velocity
        trajectory.append([[float(c) for c in (*b.position, *b.velocity)] for b in balls])
    return {"radius": radius, "dt": dt, "trajectory": trajectory}


def stack_of_boxes(steps: int = 60, count: int = 10, dt: float = 1 / 60, iterations: int = 20) -> dict:
    """``count`` 1 m, 1 kg boxes stacked on static ground, stepped with the student's
    contact solver (whose sweeps call their ``apply_normal_impulse`` and
    ``apply_friction_impulse``; the block solver off, so that every normal impulse is
    theirs).  The contacts are exact (each face on the one below, depth 0).  Returns
    per step the boxes' (y, vy) and the accumulated normal impulse of each contact,
    bottom first."""
    import numpy as np
    from exercises.body import Body
    from exercises.contact import Contact
    from exercises.response.contact_solver import ContactSolver, SolverSettings

    ground = Body.box(10.0, 1.0, is_static=True, position=(0.0, -0.5), friction=0.6)
    bodies = [ground] + [Body.box(1.0, 1.0, position=(0.0, 0.5 + k), friction=0.6) for k in range(count)]
    solver = ContactSolver(SolverSettings(iterations=iterations, block_solver=False, position_correction="none",
                                          restitution_threshold=0.0))
    trajectory, impulses = [], []
    for _ in range(steps):
        for body in bodies[1:]:
            body.velocity = body.velocity + dt * np.array([0.0, -9.81])
        manifolds = []
        for k in range(count):
            top = float(bodies[k].position[1]) + 0.5
            manifolds.append((k, k + 1, Contact((0.0, 1.0), 0.0, [(-0.5, top), (0.5, top)],
                                                feature_ids=("left", "right"))))
        solver.solve(bodies, manifolds, dt)
        for body in bodies[1:]:
            body.position = body.position + dt * body.velocity
            body.angle += dt * body.angular_velocity
        trajectory.append([[float(b.position[1]), float(b.velocity[1])] for b in bodies[1:]])
        totals = [0.0] * count
        for i, _, _, normal, _ in solver.contact_impulses:
            totals[i] += float(normal)
        impulses.append(totals)
    return {"trajectory": trajectory, "impulses": impulses}
