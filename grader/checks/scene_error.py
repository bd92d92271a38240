"""Speed and error of the student's resolver on a scene, against the reference and pymunk.

The same scene (:mod:`grader.scene_driver`) runs in the student's sandbox and in a
sandbox holding the reference engine, side by side in one run; pymunk runs it in the
trusted process.  Measured from the returned trajectories: the deepest overlap (m),
the energy gained (J, should be <= 0) and the distance of the final positions from the
reference's and from pymunk's (m, RMS over the balls).
"""
from __future__ import annotations

import math

import numpy as np
import pymunk

from .. import scene_driver
from ..outcome import Outcome

STEPS = 120
#: Allowed deviation from the reference (m, RMS of final positions): the same
#: algorithm in another order of floating-point operations stays far below this.
POSITION_TOLERANCE = 1e-6
GRAVITY = 9.81


def trajectory_metrics(trajectory: np.ndarray, radius: float) -> dict:
    """Deepest overlap and energy gain of a (steps, balls, 4) trajectory."""
    positions, velocities = trajectory[..., :2], trajectory[..., 2:]
    deepest = 0.0
    for frame in positions:
        gaps = np.linalg.norm(frame[:, None, :] - frame[None, :, :], axis=-1)
        np.fill_diagonal(gaps, np.inf)
        deepest = max(deepest, float(2 * radius - gaps.min()), float(radius - frame[:, 1].min()),
                      float(frame[:, 0].max() + radius - 1.5), float(-1.5 - (frame[:, 0].min() - radius)))
    energy = 0.5 * np.sum(velocities**2, axis=(1, 2)) + GRAVITY * np.sum(positions[..., 1], axis=1)
    return {"max_penetration": max(deepest, 0.0), "energy_gain": float(energy.max() - energy[0])}


def pymunk_trajectory(dt: float, restitution: float = 0.5, friction: float = 0.2) -> np.ndarray:
    start, radius = scene_driver.initial_balls()
    space = pymunk.Space()
    space.gravity = (0, -GRAVITY)
    space.collision_slop = 0.01
    walls = [pymunk.Segment(space.static_body, (-3, 0), (3, 0), 0), pymunk.Segment(space.static_body, (-1.5, 0),
             (-1.5, 10), 0), pymunk.Segment(space.static_body, (1.5, 0), (1.5, 10), 0)]
    for wall in walls:
        wall.elasticity, wall.friction = 1.0, 1.0
    space.add(*walls)
    bodies = []
    for p, v in start:
        body = pymunk.Body(1.0, pymunk.moment_for_circle(1.0, 0, radius))
        body.position, body.velocity = p, v
        shape = pymunk.Circle(body, radius)
        shape.elasticity, shape.friction = restitution, friction
        space.add(body, shape)
        bodies.append(body)
    frames = []
    for _ in range(STEPS):
        space.step(dt)
        frames.append([[*b.position, *b.velocity] for b in bodies])
    return np.array(frames)


def run_driver(code) -> tuple[np.ndarray, float, float]:
    code.sandbox.call("scene_driver", "drop_balls", [2], timeout=60.0)  # untimed: imports, first calls
    result = code.sandbox.call("scene_driver", "drop_balls", [STEPS], timeout=60.0)
    data = code.value_of(result, "the ball scene with your resolve_collision")
    trajectory = np.array(data["trajectory"], dtype=float)
    return trajectory, float(data["radius"]), result.elapsed


def compare_scene(student, reference) -> Outcome:
    trajectory, radius, seconds = run_driver(student)
    if trajectory.ndim != 3 or not np.all(np.isfinite(trajectory)):
        return Outcome.failed("the ball scene produced non-finite positions or velocities")
    metrics = {"seconds": seconds, **trajectory_metrics(trajectory, radius)}
    oracle = pymunk_trajectory(1 / 60)
    metrics["distance_from_pymunk"] = float(np.sqrt(np.mean(np.sum((trajectory[-1, :, :2] - oracle[-1, :, :2])**2, -1))))
    if reference is None:
        return Outcome.passed("scene ran", **metrics)
    expected, _, reference_seconds = run_driver(reference)
    metrics["reference_seconds"] = reference_seconds
    metrics["reference_max_penetration"] = trajectory_metrics(expected, radius)["max_penetration"]
    distance = float(np.sqrt(np.mean(np.sum((trajectory[-1, :, :2] - expected[-1, :, :2])**2, -1))))
    metrics["distance_from_reference"] = distance
    if not distance <= POSITION_TOLERANCE:
        return Outcome.failed(f"after {STEPS} steps the balls are {distance:.3g} m (RMS) from where the reference "
                              f"puts them (tolerance {POSITION_TOLERANCE:g} m); deepest overlap "
                              f"{metrics['max_penetration']:.3g} m, energy gained {metrics['energy_gain']:.3g} J",
                              **metrics)
    return Outcome.passed(f"{STEPS} steps in {seconds * 1e3:.0f} ms (reference {reference_seconds * 1e3:.0f} ms)",
                          **metrics)
