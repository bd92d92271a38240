"""The upright-scene oracle's exact one-contact paths (``vertical_paths``) are what the
full step (prestep, target, warm-started sweeps), written in the oracle or the
reference's ``step_bodies``, gives for the bodies they are for: a
disc, or an upright box that cannot turn, alone on the ground and moving only up and
down.  The sequential exercise's scenes of ``contact_target`` rely on it: they grade the
target alone, the contact solved by the oracle."""
import numpy as np
import pytest

from grader.oracles import upright_scenes as scenes
from solutions.solver import contact_sweeps


def reference_calls(name, cases):
    return [getattr(contact_sweeps, name)(*case) for case in cases]


def bodies():
    h = 1 / 60
    return [scenes.Upright(1.0, radius=0.5, x=0.0, y=0.501, velocity=[0.0, -1.2 + 2 * scenes.G * h, 0.0],
                           restitution=0.6),
            scenes.Upright(1.0, 0.5, 0.5, x=2.0, y=0.2, restitution=0.5, turns=False),
            scenes.Upright(2.0, 0.4, 0.25, x=4.0, y=0.5, velocity=[0.0, -3.0, 0.0], restitution=0.8, turns=False),
            scenes.Upright(1.0, radius=0.3, x=6.0, y=0.26, restitution=1.0)]


@pytest.mark.parametrize("step_once", [scenes.step_scene, scenes.step_scene_whole])
@pytest.mark.parametrize("settings", [scenes.SceneSettings(), scenes.SceneSettings(max_push=1.0, iterations=3),
                                      scenes.SceneSettings(restitution_threshold=0.3, bias_factor=0.1)])
def test_exact_paths_are_the_stepped_paths(settings, step_once):
    exact = scenes.vertical_paths(bodies(), settings, 90)
    with_targets = scenes.vertical_paths(bodies(), settings, 90, reference_calls)
    np.testing.assert_allclose(with_targets, exact, rtol=0.0, atol=1e-12)
    stepped, memory = bodies(), {}
    for step in range(90):
        step_once(stepped, reference_calls, settings, memory)
        got = [(depth, body.velocity[1]) for depth, body in zip(scenes.overlaps(stepped), stepped)]
        np.testing.assert_allclose(got, exact[step], rtol=0.0, atol=1e-12, err_msg=f"step {step + 1}")
    assert any(depth < 0.0 for depth, _ in exact[20]), "a body must be off the ground at times"
    assert all(abs(body.velocity[0]) == 0.0 and body.angle == 0.0 for body in stepped)


def test_overlaps_of_a_stack_and_a_turned_box():
    stack = [scenes.Upright(1.0, 0.5, 0.5, y=0.47), scenes.Upright(1.0, 0.5, 0.5, y=1.44)]
    assert scenes.overlaps(stack, stacked=True) == pytest.approx([0.03, 0.03])
    turned = scenes.Upright(1.0, 0.5, 0.5, y=0.6, angle=0.5)
    deepest = max(depth for _, depth in scenes.corners_on_ground(turned))
    assert scenes.overlaps([turned]) == pytest.approx([deepest])
    assert deepest == pytest.approx(0.5 * (0.4794255386 + 0.8775825619) - 0.6)


def test_the_oracles_step_is_the_reference_step_bodies():
    """A turning box sliding and a warm-started stack: the oracle's step around the
    reference's prestep and sweeps and the reference's whole step agree to rounding."""
    def scene():
        return [scenes.Upright(1.0, 0.5, 0.5, x=-3.0, y=0.5, velocity=[3.0, 0.0, 0.0], friction=0.5)], \
            [scenes.Upright(1.0, 0.5, 0.5, y=0.5 + k, friction=0.6, turns=False) for k in range(4)]
    (outlined, outlined_stack), (whole, whole_stack) = scene(), scene()
    memories = [{}, {}, {}, {}]
    settings = scenes.SceneSettings(iterations=4)
    for _ in range(40):
        scenes.step_scene(outlined, reference_calls, settings, memories[0])
        scenes.step_scene_whole(whole, reference_calls, settings, memories[1])
        scenes.step_scene(outlined_stack, reference_calls, settings, memories[2], stacked=True)
        scenes.step_scene_whole(whole_stack, reference_calls, settings, memories[3], stacked=True)
    for got, want in ((whole, outlined), (whole_stack, outlined_stack)):
        np.testing.assert_allclose([[b.x, b.y, b.angle, *b.velocity] for b in got],
                                   [[b.x, b.y, b.angle, *b.velocity] for b in want], rtol=0.0, atol=1e-12)
    for got, want in ((memories[1], memories[0]), (memories[3], memories[2])):
        assert sorted(got) == sorted(want)
        np.testing.assert_allclose([got[key] for key in sorted(got)], [want[key] for key in sorted(want)], atol=1e-12)
    assert whole[0].angle != 0.0 and len(memories[3]) == 8
