"""The solver kernel's two twins give the same motion: the readable loop
(solutions/solver/kernel.py) and its numba compilation (kernel_numba.py).

Whole worlds are stepped side by side, one with ``backend="python"`` and one with
``backend="numba"``, on every hard scene over 1 s (its recommended step: the soft step,
with joints where the scene has them) and on random scenes (plain and soft steps,
every position correction), and every body's pose and velocity must agree to 1e-12
(relative to the scene's size and speeds).  The kernel itself is also compared on
random rows with every switch (clamped increments, friction first or after, block
solve, bilateral rows), where it must agree to rounding.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from solutions.body import Body
from solutions.response.contact_solver import SolverSettings
from solutions.scenes import SCENES, get_scene, ground
from solutions.solver import kernel_numba
from solutions.solver.constraint_rows import ConstraintRows
from solutions.solver.kernel import kernel, solve_constraints
from solutions.world import World, WorldSettings

HARD_SCENES = sorted(name for name, scene in SCENES.items() if scene.hard)
TOLERANCE = 1e-12


def state(world: World) -> np.ndarray:
    return np.array([[*b.position, b.angle, *b.velocity, b.angular_velocity] for b in world.bodies])


def assert_same_motion(python_world: World, numba_world: World, seconds: float, dt: float) -> None:
    for step in range(round(seconds / dt)):
        python_world.step(dt)
        numba_world.step(dt)
        want, got = state(python_world), state(numba_world)
        # Positions relative to the scene's extent, velocities to its largest speed.
        scale = np.maximum(np.abs(want).max(axis=0), 1.0)
        error = np.abs(got - want) / scale
        assert error.max() <= TOLERANCE, (f"step {step}: the numba twin differs by {error.max():.3g} "
                                          f"(body {int(np.argmax(error.max(axis=1)))})")
    assert np.all(np.isfinite(want))


@pytest.mark.parametrize("name", HARD_SCENES)
def test_the_twins_agree_on_every_hard_scene_for_one_second(name):
    scene = get_scene(name)
    settings = scene.recommended_settings()
    python_world = scene.build_world(settings)
    numba_world = scene.build_world(replace(settings, backend="numba"))
    assert_same_motion(python_world, numba_world, 1.0, scene.dt)


def random_scene(seed: int) -> list[Body]:
    """A ground and a dozen boxes and discs dropped in a heap, overlapping a little."""
    rng = np.random.default_rng(seed)
    bodies = [ground(width=12.0)]
    for k in range(12):
        position = (rng.uniform(-3.0, 3.0), 0.4 + 0.7 * k)
        common = dict(position=position, velocity=rng.normal(0.0, 1.0, 2), angular_velocity=rng.normal(0.0, 2.0),
                      friction=rng.uniform(0.0, 1.0), restitution=rng.uniform(0.0, 0.8), mass=rng.uniform(0.5, 5.0))
        if k % 3 == 0:
            bodies.append(Body.circle(rng.uniform(0.2, 0.5), **common))
        else:
            bodies.append(Body.box(rng.uniform(0.3, 1.2), rng.uniform(0.3, 1.2), angle=rng.uniform(-0.5, 0.5),
                                   **common))
    return bodies


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("step", ["split_impulse", "baumgarte", "projection", "soft"])
def test_the_twins_agree_on_random_scenes(seed, step):
    if step == "soft":
        settings = WorldSettings(soft_step=True, substeps=4, solver=SolverSettings(iterations=2))
    else:
        settings = WorldSettings(solver=SolverSettings(position_correction=step, iterations=8))
    python_world = World(random_scene(seed), settings)
    numba_world = World(random_scene(seed), replace(settings, backend="numba"))
    assert_same_motion(python_world, numba_world, 1.0, 1 / 60)
    assert python_world.stats.manifolds > 0


def random_rows(rng, groups: int, bodies: int) -> ConstraintRows:
    """Random rows over ``bodies`` bodies (body 0 static): one- and two-point contact
    groups (some solved as blocks) and bilateral joint rows."""
    columns = {name: [] for name in ConstraintRows.GROUP_FIELDS + ConstraintRows.ROW_FIELDS}
    first = 0
    for _ in range(groups):
        a, b = rng.choice(bodies, 2, replace=False)
        angle = rng.uniform(0.0, 2 * math.pi)
        joint = rng.random() < 0.2
        count = 1 if joint else int(rng.integers(1, 3))
        inverse = [0.0 if body == 0 else rng.uniform(0.1, 2.0) for body in (a, b)]
        inertia = [0.0 if body == 0 else rng.uniform(0.5, 6.0) for body in (a, b)]
        rn = rng.uniform(-0.7, 0.7, (count, 2))
        k = [inverse[0] + inverse[1] + inertia[0] * r[0] ** 2 + inertia[1] * r[1] ** 2 for r in rn]
        block = count == 2 and rng.random() < 0.7
        k12 = inverse[0] + inverse[1] + inertia[0] * rn[0, 0] * rn[1, 0] + inertia[1] * rn[0, 1] * rn[1, 1] \
            if count == 2 else 0.0
        block = block and max(k) ** 2 < 1000 * (k[0] * k[1] - k12 * k12)
        for name, value in dict(a=a, b=b, nx=math.cos(angle), ny=math.sin(angle), ima=inverse[0], imb=inverse[1],
                                iia=inertia[0], iib=inertia[1], first=first, count=count, block=block,
                                k11=k[0] if block else 0.0, k12=k12 if block else 0.0,
                                k22=k[1] if block else 0.0).items():
            columns[name].append(value)
        for r, kn in zip(rn, k):
            rt = rng.uniform(-0.7, 0.7, 2)
            kt = inverse[0] + inverse[1] + inertia[0] * rt[0] ** 2 + inertia[1] * rt[1] ** 2
            for name, value in dict(rn_a=r[0], rn_b=r[1], rt_a=rt[0], rt_b=rt[1], mass_normal=1 / kn,
                                    mass_tangent=0.0 if joint else 1 / kt,
                                    friction=0.0 if joint else rng.choice([0.0, rng.uniform(0.1, 1.0)]),
                                    lower=-math.inf if joint else 0.0).items():
                columns[name].append(value)
        first += count
    return ConstraintRows(**{name: np.array(values) for name, values in columns.items()})


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("switches", [dict(), dict(accumulate=False), dict(friction_first=True),
                                      dict(accumulate=False, friction_first=False, use_block=False),
                                      dict(use_friction=False), dict(use_block=False, friction_first=True)],
                         ids=["v3", "increments", "friction-first", "increments-no-block", "no-friction",
                              "v2-point-by-point"])
def test_the_twins_agree_on_random_rows_with_every_switch(seed, switches):
    rng = np.random.default_rng(seed)
    rows = random_rows(rng, groups=40, bodies=12)
    m = rows.row_count
    velocity = rng.normal(0.0, 1.0, (12, 3))
    velocity[0] = 0.0
    normal, tangent = rng.uniform(0.0, 0.3, m) * (rows.lower == 0.0), rng.uniform(-0.05, 0.05, m)
    target, mass_scale = rng.uniform(-0.5, 0.5, m), rng.uniform(0.3, 1.0, m)
    results = []
    for solve in (solve_constraints, kernel_numba.solve_constraints):
        v, n, t = velocity.copy(), normal.copy(), tangent.copy()
        solve(v, rows, 4, n, t, target, mass_scale, 1.0 - mass_scale, **switches)
        results.append((v, n, t))
    for got, want in zip(results[1], results[0]):
        np.testing.assert_allclose(got, want, rtol=TOLERANCE, atol=TOLERANCE)
    assert not np.allclose(results[0][0], velocity)
    assert np.all(results[0][1][rows.lower == 0.0] >= 0.0)      # contacts only push


def test_the_kernel_is_chosen_by_name():
    assert kernel("python") is solve_constraints
    assert kernel("numba") is kernel_numba.solve_constraints
    with pytest.raises(ValueError, match="backend must be 'python' or 'numba', got 'gpu'"):
        kernel("gpu")
    with pytest.raises(ValueError, match="backend must be one of"):
        WorldSettings(backend="gpu")
