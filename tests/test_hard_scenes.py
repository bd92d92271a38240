"""Each hard scene under its recommended settings, held to its stated bounds.

``Scene.recommended_settings()`` of a hard scene is the soft step
(``solutions.scenes.HARD_SCENE_STEP``).  The bounds are those of the course's goal for
the reference engine: stacks and pyramids stay up for the scene's 10 s with every
overlap and every body's drift below 1 cm; the heavy box of a 1:1000 pair stays on
the light one; overlapping boxes are pushed apart within 1 s without being launched;
the pyramid far from the origin behaves as the one at the origin; chain links keep
their length; friction follows Coulomb's law.  Oracles: the scenes' own geometry
(the start positions), Coulomb's law, and the origin pyramid for the far one.
"""
import math

import numpy as np
import pytest

from solutions import scene_metrics as metrics
from solutions.joints import anchor_world
from solutions.scenes import HARD_SCENE_STEP, SCENES, get_scene

CENTIMETRE = 0.01
PROBE_EVERY = 10   # steps between measurements of the overlap (a full narrow phase)


def recommended_world(name):
    """The scene under its recommended settings, stepped by the compiled twins
    (``backend="numba"``): the same motion as the readable step to 1e-12
    (tests/test_solver_kernel.py), four times faster over these ten-second runs."""
    scene = get_scene(name)
    settings = scene.recommended_settings()
    settings.backend = "numba"
    return scene, scene.build_world(settings)


def test_hard_scenes_are_recommended_the_soft_step():
    hard = sorted(name for name, scene in SCENES.items() if scene.hard)
    assert {"stack_20", "pyramid_20", "pyramid_20_far", "mass_ratio_1000", "overlap_recovery", "chain_40",
            "arch", "friction_ramp", "bullet_wall"} <= set(hard)
    for name in hard:
        scene = get_scene(name)
        settings = scene.recommended_settings()
        assert settings.soft_step and settings.substeps == HARD_SCENE_STEP["substeps"]
        assert settings.solver.iterations == {**HARD_SCENE_STEP, **scene.recommended}["iterations"]
    assert not get_scene("elastic_balls").recommended_settings().soft_step


@pytest.mark.parametrize("name", ["stack_10", "stack_20", "pyramid_10", "pyramid_20", "arch"])
def test_stays_up_for_ten_seconds_within_a_centimetre(name):
    scene, world = recommended_world(name)
    assert scene.duration == 10.0
    start = metrics.start_positions(world.bodies)
    deepest = drift = 0.0
    for k in range(scene.steps):
        world.step(scene.dt)
        if k % PROBE_EVERY == PROBE_EVERY - 1:
            deepest = max(deepest, metrics.max_penetration(world.bodies))
            drift = max(drift, metrics.max_drift(world.bodies, start))
    assert deepest < CENTIMETRE, f"penetration {deepest:.4f} m"
    assert drift < CENTIMETRE, f"drift {drift:.4f} m"


@pytest.mark.parametrize("name, offset", [("mass_ratio_100", 0.01), ("mass_ratio_1000", 0.05)])
def test_heavy_box_stays_on_the_light_one(name, offset):
    scene, world = recommended_world(name)
    worst = 0.0
    for _ in range(scene.steps):
        world.step(scene.dt)
        _, light, heavy = world.bodies
        worst = max(worst, float(np.linalg.norm(heavy.position - light.position - (0.0, 1.0))),
                    float(np.linalg.norm(light.position - (0.0, 0.5))))
    assert worst < offset, f"moved {worst:.4f} m"
    assert abs(heavy.angle) < 1e-3 and abs(light.angle) < 1e-3


def test_overlapping_boxes_separate_within_a_second_without_explosion():
    scene, world = recommended_world("overlap_recovery")
    boxes = [b for b in world.bodies if not b.is_static]
    cap = world.settings.solver.max_push_velocity
    fastest_up = highest = 0.0
    separated_at = None
    for k in range(scene.steps):
        world.step(scene.dt)
        fastest_up = max(fastest_up, max(b.velocity[1] for b in boxes))
        highest = max(highest, max(b.position[1] for b in boxes))
        if separated_at is None and metrics.max_penetration(world.bodies) < CENTIMETRE:
            separated_at = world.time
    assert separated_at is not None and separated_at <= 1.0
    # Boxes pushed up fall back onto others (a new overlap lasts a step or two); by
    # the end of the scene the pile rests with every overlap below a centimetre.
    assert metrics.max_penetration(world.bodies) < CENTIMETRE
    # Launched would be: faster upward than the push of two capped contacts, or higher
    # than all the boxes stacked one on another.
    assert fastest_up < 2 * cap
    assert highest < len(boxes) * 1.0


def test_far_pyramid_behaves_like_the_one_at_the_origin():
    origin_scene, at_origin = recommended_world("pyramid_20")
    far_scene, far = recommended_world("pyramid_20_far")
    offset = far.bodies[0].position - at_origin.bodies[0].position
    np.testing.assert_allclose(offset, (1e5, -8e4))
    differences = []
    for k in range(round(2.0 / origin_scene.dt)):
        at_origin.step(origin_scene.dt)
        far.step(far_scene.dt)
        if k % 30 == 29:
            moved = max(float(np.linalg.norm(b.position - offset - a.position))
                        for a, b in zip(at_origin.bodies, far.bodies))
            turned = max(abs(b.angle - a.angle) for a, b in zip(at_origin.bodies, far.bodies))
            differences.append((moved, turned))
    # Coordinates of 1e5 m round to 1.5e-11 m, and the narrow phase's tie-breaking
    # tolerances grow with the coordinates (1e-12 of them), so touching faces may be
    # resolved a little differently far away: the two pyramids differ by micrometres,
    # and the difference does not grow.
    assert max(moved for moved, _ in differences) < 1e-4
    assert max(turned for _, turned in differences) < 1e-4
    assert differences[-1][0] < 2 * differences[len(differences) // 2][0] + 1e-6
    assert metrics.max_penetration(far.bodies) == pytest.approx(metrics.max_penetration(at_origin.bodies), abs=1e-5)


def test_chain_links_keep_their_length_without_gaining_energy():
    scene, world = recommended_world("chain_40")
    energy0 = metrics.total_energy(world.bodies, scene.gravity)
    stretch = gain = 0.0
    for _ in range(scene.steps):
        world.step(scene.dt)
        for joint in world.joints:
            a, b = anchor_world(world.bodies[joint.a], joint.anchor_a), anchor_world(world.bodies[joint.b], joint.anchor_b)
            stretch = max(stretch, abs(math.dist(a, b) - joint.length))
        gain = max(gain, metrics.total_energy(world.bodies, scene.gravity) - energy0)
    spacing = world.joints[0].length
    assert stretch < 0.2 * spacing, f"a link stretched {stretch:.4f} m"
    assert gain < 1e-9 * abs(energy0) + 1e-9
    assert world.bodies[-1].position[1] < world.bodies[0].position[1] - 5.0   # it fell and hangs


def test_friction_ramp_follows_coulombs_law():
    scene, world = recommended_world("friction_ramp")
    ramp = world.bodies[0]
    start = metrics.start_positions(world.bodies)
    seconds = 2.0                            # before the fastest box runs off the 30 m ramp
    for _ in range(round(seconds / scene.dt)):
        world.step(scene.dt)
    slope = ramp.angle
    for box, origin in zip(world.bodies[1:], start[1:]):
        mu = box.friction * ramp.friction
        travelled = float(np.linalg.norm(box.position - origin))
        if mu < math.tan(slope):
            # Sliding from rest: s = g (sin a - mu cos a) t^2 / 2.
            want = 0.5 * 9.81 * (math.sin(slope) - mu * math.cos(slope)) * seconds**2
            assert travelled == pytest.approx(want, rel=0.02), box.name
        else:
            assert travelled < 1e-3, box.name


def test_demo_runs_the_recommended_settings(capsys):
    from tools.demo import main
    assert main(["stack_10", "--recommended", "--seconds", "0.25"]) == 0
    out = capsys.readouterr().out
    assert "reference: soft step, 8 sub-steps x 1 sweeps; pymunk: 10 iterations" in out
    assert out.count("reference") == 2 and "pymunk" in out
    assert main(["pyramid_10", "--recommended", "--compiled", "--seconds", "0.25"]) == 0
    assert "reference: soft step, 8 sub-steps x 1 sweeps, compiled; pymunk" in capsys.readouterr().out
