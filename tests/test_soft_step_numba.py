"""The soft step compiled whole (solutions/response/soft_step_numba.py) equals the
readable soft step of World: the same motion to 1e-12 on random piles of boxes under
every switch of the soft step, and the same contacts, impulses and figures.  (The hard
scenes of boxes are stepped side by side in tests/test_solver_kernel.py, whose numba
worlds run this step.)"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from solutions.body import Body
from solutions.joints import DistanceJoint
from solutions.response.contact_solver import SolverSettings
from solutions.response.solver_settings import SoftStepSettings, split_overrides
from solutions.scenes import SCENES, get_scene, ground
from solutions.world import World, WorldSettings

TOLERANCE = 1e-12     # relative to the scene's size and speeds (bit for bit on this machine)


def assert_same_motion(readable: World, compiled: World, seconds: float, dt: float) -> None:
    for step in range(round(seconds / dt)):
        readable.step(dt)
        compiled.step(dt)
        want = np.column_stack([readable.state.position, readable.state.angle, readable.state.velocity])
        got = np.column_stack([compiled.state.position, compiled.state.angle, compiled.state.velocity])
        error = np.abs(got - want) / np.maximum(np.abs(want).max(axis=0), 1.0)
        assert error.max() <= TOLERANCE, f"step {step}: the compiled step differs by {error.max():.3g}"
    assert np.all(np.isfinite(want))


def box_pile(seed: int, count: int = 14) -> list[Body]:
    """A ground and boxes of random sizes, materials and velocities dropped in a heap,
    some overlapping, some turned, one fixed in rotation."""
    rng = np.random.default_rng(seed)
    bodies = [ground(width=14.0, friction=float(rng.uniform(0.2, 1.0)), restitution=float(rng.uniform(0.0, 1.0)))]
    for k in range(count):
        bodies.append(Body.box(rng.uniform(0.3, 1.3), rng.uniform(0.3, 1.3), mass=rng.uniform(0.3, 6.0),
                               position=(rng.uniform(-2.5, 2.5), 0.3 + 0.55 * k), angle=rng.uniform(-0.6, 0.6),
                               velocity=rng.normal(0.0, 1.5, 2), angular_velocity=rng.normal(0.0, 2.0),
                               friction=rng.uniform(0.0, 1.0), restitution=rng.uniform(0.0, 0.9),
                               fixed_rotation=k == 3))
    bodies.append(Body.box(1.0, 0.4, is_static=True, position=(3.5, 1.5), angle=0.3, friction=0.5))
    return bodies


SWITCHES = [dict(), dict(relax=False), dict(warm_starting=False), dict(block_solver=False),
            dict(order="colours"), dict(friction=False), dict(iterations=3), dict(contact_hertz=15.0)]


def pair(bodies_of, settings: WorldSettings) -> tuple[World, World]:
    readable = World(bodies_of(), settings)
    compiled = World(bodies_of(), replace(settings, backend="numba"))
    assert readable.compiled_soft_step is None and compiled.compiled_soft_step is not None
    return readable, compiled


@pytest.mark.parametrize("switches", SWITCHES, ids=lambda s: ",".join(f"{k}={v}" for k, v in s.items()) or "default")
@pytest.mark.parametrize("seed", range(2))
def test_the_compiled_soft_step_moves_random_piles_as_the_readable_one(seed, switches):
    solver, soft = split_overrides(switches)
    settings = WorldSettings(soft_step=True, substeps=1 + seed * 3, solver=SolverSettings(**solver),
                             soft=SoftStepSettings(**soft))
    readable, compiled = pair(lambda: box_pile(seed), settings)
    assert_same_motion(readable, compiled, 1.0, 1 / 60)
    assert readable.stats.manifolds > 5


def test_the_compiled_step_gives_the_readable_contacts_impulses_and_figures():
    scene = get_scene("pyramid_10")
    readable, compiled = pair(scene.make_bodies, scene.recommended_settings())
    for _ in range(20):
        readable.step(scene.dt)
        compiled.step(scene.dt)
    assert compiled.stats == readable.stats and compiled.solver.stats == readable.solver.stats
    assert compiled.stats.manifolds == 145 and compiled.solver.stats.warm_started_points > 200
    want, got = readable.manifolds, compiled.manifolds
    assert [(i, j) for i, j, _ in got] == [(i, j) for i, j, _ in want]
    for (_, _, c_want), (_, _, c_got) in zip(want, got):
        assert c_got.feature_ids == c_want.feature_ids
        for name in ("normal", "points", "depths", "depth"):
            np.testing.assert_array_equal(getattr(c_got, name), getattr(c_want, name))
    assert compiled.solver.contact_impulses == readable.solver.contact_impulses
    assert readable.time == compiled.time


def test_the_compiled_steps_buffers_grow_without_changing_the_motion(monkeypatch):
    """The points and the work space live in buffers made for a number of candidate
    pairs that grows: a step that finds more pairs than they are made for changes
    nothing, and runs again on bigger buffers."""
    from solutions.response.soft_step_numba import CompiledSoftStep

    scene = get_scene("pyramid_10")
    roomy = scene.build_world(replace(scene.recommended_settings(), backend="numba"))
    monkeypatch.setattr(CompiledSoftStep, "INITIAL_PAIR_CAPACITY", 1)
    tight = scene.build_world(replace(scene.recommended_settings(), backend="numba"))
    capacities = set()
    for _ in range(10):
        roomy.step(scene.dt)
        tight.step(scene.dt)
        capacities.add(tight.compiled_soft_step.memory_ints.shape[1])
        np.testing.assert_array_equal(tight.state.position, roomy.state.position)
        np.testing.assert_array_equal(tight.state.velocity, roomy.state.velocity)
    assert min(capacities) >= len(tight.compiled_soft_step.point_ints) > 200
    assert tight.solver.contact_impulses == roomy.solver.contact_impulses and tight.stats == roomy.stats


def test_settings_changed_between_compiled_steps_take_effect():
    """The compiled step writes its parameters again whenever a setting it reads changes."""
    readable, compiled = pair(lambda: box_pile(1), WorldSettings(soft_step=True, substeps=2))
    changes = [lambda w: setattr(w.settings.solver, "iterations", 3),
               lambda w: setattr(w.settings.soft, "relax", False),
               lambda w: setattr(w.settings, "gravity", (1.0, -4.0)),
               lambda w: setattr(w.settings.soft, "contact_hertz", 20.0),
               lambda w: setattr(w.settings, "substeps", 3),
               lambda w: setattr(w.settings.solver, "friction", False)]
    for change in changes:
        assert_same_motion(readable, compiled, 0.1, 1 / 60)
        change(readable)
        change(compiled)
    assert_same_motion(readable, compiled, 0.1, 1 / 90)


def disc_chain(seed: int) -> tuple[list[Body], list[DistanceJoint]]:
    """Discs on a static pin: a chain of rods and springs (some anchors off centre) that
    folds onto itself, and loose discs dropped on it."""
    rng = np.random.default_rng(seed)
    bodies = [Body.circle(0.1, is_static=True, position=(0.0, 4.0))]
    joints = []
    for k in range(12):
        bodies.append(Body.circle(rng.uniform(0.08, 0.2), mass=rng.uniform(0.2, 2.0), friction=rng.uniform(0.0, 1.0),
                                  position=(0.3 * (k + 1), 4.0 + rng.uniform(-0.05, 0.05)),
                                  restitution=rng.uniform(0.0, 0.5)))
        spring = k % 4 == 3
        joints.append(DistanceJoint(k, k + 1, anchor_a=(0.0, 0.05 * (k % 2)), length=0.3,
                                    frequency=4.0 if spring else 0.0, damping_ratio=0.5 if spring else 0.0))
    for k in range(6):
        bodies.append(Body.circle(0.15, mass=1.0, position=(0.5 + 0.4 * k, 5.0 + 0.3 * k),
                                  velocity=rng.normal(0.0, 1.0, 2), friction=0.5))
    return bodies, joints


@pytest.mark.parametrize("rotation", [True, False])
@pytest.mark.parametrize("seed", range(2))
def test_the_compiled_soft_step_moves_discs_on_joints_as_the_readable_one(seed, rotation):
    """Joints and discs; not bit for bit (CPython's math.hypot and libm's round
    differently in the last place), to 1e-12."""
    settings = WorldSettings(soft_step=True, substeps=4,
                             solver=SolverSettings(iterations=1 + seed, rotation=rotation))
    readable = World(*disc_chain(seed)[:1], settings, disc_chain(seed)[1])
    compiled = World(*disc_chain(seed)[:1], replace(settings, backend="numba"), disc_chain(seed)[1])
    assert compiled.compiled_soft_step is not None
    touched = 0
    for _ in range(4):
        assert_same_motion(readable, compiled, 0.25, 1 / 60)
        touched += readable.stats.manifolds
    assert touched > 0


def test_the_compiled_step_runs_worlds_of_boxes_or_of_discs():
    """Polygons, boxes mixed with discs, and bullets take the readable stages (with their twins)."""
    numba_soft = dict(soft_step=True, backend="numba")
    chosen = {name: scene.build_world(replace(scene.recommended_settings(), **numba_soft)).compiled_soft_step
              is not None for name, scene in SCENES.items()}
    assert chosen["pyramid_20"] and chosen["stack_10"] and chosen["friction_ramp"] and chosen["mass_ratio_1000"]
    assert chosen["chain_40"] and chosen["elastic_balls"]
    assert not chosen["arch"] and not chosen["bullet_wall"] and not chosen["ball_drop"]
    boxes = box_pile(0)
    assert World(boxes, WorldSettings(**numba_soft)).compiled_soft_step is not None
    assert World(box_pile(0), WorldSettings(soft_step=True)).compiled_soft_step is None
    assert World(box_pile(0), WorldSettings(backend="numba")).compiled_soft_step is None
    offset = box_pile(0)
    offset[2] = Body(offset[2].shape.__class__((0.1, 0.0), (0.5, 0.5), 0.0), mass=1.0)   # not centred on its body
    assert World(offset, WorldSettings(**numba_soft)).compiled_soft_step is None


def test_a_second_world_takes_the_bodies_and_the_first_keeps_its_state():
    bodies = box_pile(1, count=4)
    first = World(bodies, WorldSettings(soft_step=True, backend="numba"))
    first.step(1 / 60)
    kept = first.state.position.copy()
    second = World(bodies, WorldSettings(soft_step=True, backend="numba"))
    second.step(1 / 60)
    np.testing.assert_array_equal(first.state.position, kept)
    assert bodies[1].position.tolist() == second.state.position[1].tolist() != kept[1].tolist()


@pytest.mark.parametrize("order", ["manifolds", "colours"])
def test_the_compiled_sweep_order_is_the_readable_one(order):
    """Random manifolds among a few bodies, some of them static: the same visiting order
    (the batches stably sorted) as solutions.solver.sweep_order."""
    from solutions.solver.sweep_order_numba import sweep_order as compiled_sweep_order
    from solutions.solver.sweep_order import sweep_order

    rng = np.random.default_rng(7)
    for _ in range(300):
        n, m = int(rng.integers(1, 30)), int(rng.integers(0, 50))
        body_a, body_b = rng.integers(0, n, m), rng.integers(0, n, m)
        movable = rng.random(n) < 0.8
        want, _ = sweep_order(body_a, body_b, movable, order)
        got = np.empty(m, dtype=np.int64)
        compiled_sweep_order(body_a, body_b, movable, order == "colours", np.empty(2 * m + n + 2, dtype=np.int64), got)
        assert got.tolist() == want.tolist()


@pytest.mark.parametrize("layout", ["few", "heap", "pile", "tall_scatter"])
def test_the_compiled_candidate_pairs_are_the_brute_force_ones(layout):
    """The compiled step's candidate pairs (insertion-sorted sweep for a few bodies, also
    into the step's own buffers, which must hold every overlapping pair; strip grid for
    many, sweep again for bodies scattered over great heights; a heap where every box
    meets every other fills the sweep's first buffers) are the pairs
    whose AABBs, grown by half the margin, overlap or touch: sorted, without two static
    bodies, without joined pairs."""
    from solutions.broadphase.aabb_array import aabb_array
    from solutions.broadphase.brute_force import pairs_brute_force
    from solutions.narrowphase.box_pairs_numba import faces_of_boxes, matmul_rounding
    from solutions.broadphase.pairs_numba import (STRIP_GRID_MIN_BODIES, aabbs, candidate_pairs,
                                                  few_candidate_pairs)
    from solutions.response.soft_step_layout import NO_PAIR

    rng = np.random.default_rng({"few": 1, "heap": 4, "pile": 2, "tall_scatter": 3}[layout])
    margin = 0.04
    for trial in range(20):
        n = {"few": int(rng.integers(2, 12)), "heap": int(rng.integers(20, 60))}.get(layout,
                                                                                     int(rng.integers(64, 160)))
        position = rng.uniform(-3.0, 3.0, (n, 2)) * (0.05 if layout == "heap" else 1.0)
        if layout == "tall_scatter":       # strips would span far more heights than there are bodies
            position[:, 1] *= 1e6
            position[: n // 2, 1] = rng.uniform(-1.0, 1.0, n // 2)
        half = rng.uniform(0.05, 1.0, (n, 2))
        half[rng.integers(n)] = (0.5, 0.5)
        angle = rng.uniform(-np.pi, np.pi, n)
        angle[: n // 3] = 0.0                          # exactly touching boxes are kept too
        position[1] = position[0] + (half[0, 0] + half[1, 0] + margin, 0.0)
        angle[1] = 0.0
        dynamic = rng.random(n) < 0.7
        joined = sorted({min(i, j) * n + max(i, j) for i, j in rng.integers(0, n, (3, 2)) if i != j})
        jointed = np.full(len(joined) + 2, NO_PAIR, dtype=np.int64)
        jointed[:len(joined)] = joined
        bodies = [Body.box(2 * hx, 2 * hy, mass=1.0, position=p, angle=a)
                  for (hx, hy), p, a in zip(half, position, angle)]
        boxes = aabb_array([b.world_shape() for b in bodies]) + 0.5 * margin * np.array([-1.0, -1.0, 1.0, 1.0])
        want = [(i, j) for i, j in sorted(pairs_brute_force(boxes))
                if (dynamic[i] or dynamic[j]) and i * n + j not in joined]
        faces = np.empty((n, 2, 4, 2))
        faces_of_boxes(position, half, angle, matmul_rounding()[0], faces)
        aabb = np.empty((n, 4))
        aabbs(position, half, faces, margin, False, aabb)
        keys, first, second = candidate_pairs(aabb, dynamic, jointed)
        assert list(zip(first.tolist(), second.tolist())) == want, f"trial {trial}"
        assert keys.tolist() == [i * n + j for i, j in want]
        if n < STRIP_GRID_MIN_BODIES:       # the step's own sweep for a few bodies, into buffers
            found = len(pairs_brute_force(boxes))
            for capacity, fits in ((found + n, True), (found - 1, False)):     # (room for a box's partners)
                out = np.full((3, max(capacity, 0)), -7, dtype=np.int64)
                work = np.empty(2 * n + 3 * max(capacity, 0) + 1, dtype=np.int64)
                m = few_candidate_pairs(aabb, dynamic, jointed, work, np.empty((n, 4)), out[0], out[1], out[2])
                if fits:
                    assert m == len(want) and out[:, :m].tolist() == [keys.tolist(), first.tolist(), second.tolist()]
                else:
                    assert m == -1, "more overlapping pairs than room: the step must ask for larger buffers"


EXACT_CAPACITY_RUN = """
import numpy as np
from dataclasses import replace
from solutions.scenes import get_scene
for name in ("pyramid_20", "chain_40", "overlap_recovery"):
    scene = get_scene(name)
    settings = replace(scene.recommended_settings(), backend="numba")
    exact, roomy = scene.build_world(settings), scene.build_world(settings)
    filled = 0
    for _ in range(40):
        exact.step(scene.dt)
        roomy.step(scene.dt)
        step = exact.compiled_soft_step
        filled += step.capacity == max(step.candidate_pairs, 1)
        step.make_buffers(max(step.candidate_pairs, 1))   # the next step may fill every block to its end
        assert np.array_equal(exact.state.position, roomy.state.position), name
        assert np.array_equal(exact.state.velocity, roomy.state.velocity), name
    # pyramid_20's pairs come from the strip grid, and most steps fill the buffers exactly;
    # the few bodies' own sweep asks for room to spare, so they grow again every step.
    assert filled >= 30 if name == "pyramid_20" else filled == 0, (name, filled)
print("ok")
"""


def test_the_compiled_step_stays_within_its_buffers_when_it_fills_them(tmp_path):
    """With the buffers made for exactly as many candidate pairs as the step finds (every
    pair of a pyramid gives two points; fewer bodies make the step grow them again each
    step), no block of the work space runs past its end:
    numba's bounds checks on (NUMBA_BOUNDSCHECK, compiled afresh in its own cache), no
    IndexError, and the motion is that of buffers with room to spare.  Compiled without
    LLVM's optimisations (NUMBA_OPT=0): a third less compile time, the compile being all
    of this test's cost, and every bounds check kept (optimisation only drops a check it
    proves cannot fail); both worlds run the same machine code, so their motions compare."""
    import os
    import subprocess
    import sys

    env = {**os.environ, "NUMBA_BOUNDSCHECK": "1", "NUMBA_OPT": "0", "NUMBA_CACHE_DIR": str(tmp_path)}
    result = subprocess.run([sys.executable, "-c", EXACT_CAPACITY_RUN], env=env, capture_output=True, text=True,
                            timeout=600, cwd=os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    assert result.returncode == 0 and result.stdout.strip() == "ok", result.stderr[-3000:]


def test_the_compiled_step_holds_no_reference_to_its_arrays_after_a_step():
    """The step runs mostly without numba's reference counts: a count taken and not given
    back would keep the world's arrays alive forever (and grow by one a step)."""
    import sys

    scene = get_scene("pyramid_10")
    world = scene.build_world(replace(scene.recommended_settings(), backend="numba"))
    world.step(scene.dt)
    step, state = world.compiled_soft_step, world.state
    arrays = [state.position, state.angle, state.velocity, state.dynamic, state.turning, state.properties, step.ints,
              step.floats]
    before = [sys.getrefcount(array) for array in arrays]
    for _ in range(20):
        world.step(scene.dt)
    assert step.floats is arrays[-1], "the buffers grew: the counts would not compare"
    assert [sys.getrefcount(array) for array in arrays] == before
