"""Where the compiled soft step spends its time, stage by stage, on one hard scene.

    python -m tools.profile_soft_step [--scene pyramid_20] [--substeps 8] [--blocks 60]

The compiled step (:mod:`solutions.response.soft_step_numba`) is one function whose
stages are inlined, so they cannot be timed from outside one by one.  This tool
compiles a copy of its outline, ``_step_on_pairs``, made from the module's own source
when it runs (so it always times the code in the tree), with two switches added: stop
after the narrow phase or after the prestep, and a mask of the sub-steps' stages to
run (integrate velocities, warm start, soft solve, integrate positions, relax; then
restitution and the impulse memory).  The scene is stepped one second at its
recommended settings with ``backend="numba"``; then every variant steps from that same
state (position, angle, velocity and the step's figures put back before each step)
many times, the variants taking turns in blocks, and each variant's cost is the
least of its blocks' means (the machine is shared: the least is the run least
disturbed).  A stage's cost is the difference between a variant and the one before
it; the candidate pairs (the strip grid's, for 64 bodies or more) are found by the
module's own compiled functions called from Python, as ``_soft_step`` calls them.

Prints microseconds per step and per sub-step, and the whole ``World.step`` beside them.
"""
from __future__ import annotations

import argparse
import importlib.util
import inspect
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

#: The variants timed, in order: (stop, stage mask); stop 1: after the manifolds, 2: after
#: the prestep, 3: the sub-steps with the stages of the mask (bits in STAGE_BITS' order).
STAGE_BITS = ("integrate velocities", "warm start", "solve (soft, biased)", "integrate positions", "relax",
              "restitution", "store impulses")
#: Text of the outline and what each switch puts in its place.
SWITCHES = (
    ("    # 3. The prestep", "    if stop == 1:\n        return 0\n    # 3. The prestep"),
    ("    # 4. The sub-steps.", "    if stop == 2:\n        return 0\n    # 4. The sub-steps."),
    ("        integrate_velocities(velocity, inverse_mass, h, gravity_x, gravity_y)\n        if p_count:",
     "        if mask & 1:\n            integrate_velocities(velocity, inverse_mass, h, gravity_x, gravity_y)\n"
     "        if p_count and mask & 2:"),
    ("            separation_is_current = solve_contacts(True,",
     "        if p_count and mask & 4:\n            separation_is_current = solve_contacts(True,"),
    ("        integrate_positions(position, angle, velocity, inverse_mass, inverse_inertia, h)",
     "        if mask & 8:\n            integrate_positions(position, angle, velocity, inverse_mass, inverse_inertia, h)"),
    ("        if p_count and relax:", "        if p_count and relax and mask & 16:"),
    ("    if p_count:\n        apply_restitution(", "    if p_count and mask & 32:\n        apply_restitution("),
    ("    store_impulses(order", "    if mask & 64:\n      store_impulses(order"),
)


def staged_outline():
    """A compiled copy of ``_step_on_pairs`` taking ``stop`` and ``mask`` after its arguments."""
    from solutions.response import soft_step_numba

    source = inspect.getsource(soft_step_numba)
    start = source.index("@njit(cache=True, _nrt=False, pipeline_class=NoAliasCompiler)\ndef _step_on_pairs")
    body = source[start:source.index("class CompiledSoftStep")]
    body = body.replace("cache=True, ", "").replace(
        "def _step_on_pairs(keys, key_i, key_j, position, angle, velocity, properties, ints, floats):",
        "def staged(keys, key_i, key_j, position, angle, velocity, properties, ints, floats, stop, mask):")
    for old, new in SWITCHES:
        if old not in body:
            raise RuntimeError(f"the outline no longer reads {old.strip()!r}: update tools/profile_soft_step.py")
        body = body.replace(old, new)
    head = source[:source.index('@njit(cache=True, inline="always")')]
    head = head.replace("from ..", "from solutions.").replace("from .", "from solutions.response.")
    stages = source[source.index('@njit(cache=True, inline="always")'):source.index("@njit(cache=True)\ndef _soft_step")]
    folder = Path(tempfile.mkdtemp(prefix="staged_outline_"))
    path = folder / "staged_outline.py"
    path.write_text(head + stages + body, encoding="utf-8")
    spec = importlib.util.spec_from_file_location("staged_outline", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.staged


def profile(scene_name: str, substeps: int, blocks: int, steps_per_block: int) -> list[tuple[str, float]]:
    """``(variant, us per step)`` for the variants of :data:`STAGE_BITS`, cumulative."""
    from solutions.body_state import EXTENT_X, EXTENT_Y, INVERSE_MASS
    from solutions.broadphase.pairs_numba import STRIP_GRID_MIN_BODIES, candidate_pairs, faces_and_aabbs
    from solutions.response.soft_step_layout import (JOINT_PAIRS, PARAMETER_MARGIN, SWITCH_CIRCLES,
                                                     SWITCH_CORNER_ROUNDING, sections)
    from solutions.scenes import get_scene

    staged = staged_outline()
    scene = get_scene(scene_name)
    settings = scene.recommended_settings()
    settings.backend, settings.substeps = "numba", substeps
    world = scene.build_world(settings)
    for _ in range(round(1.0 / scene.dt)):
        world.step(scene.dt)
    state, compiled = world.state, world.compiled_soft_step
    saved = state.numbers.copy(), compiled.figures.copy()
    properties, n = state.properties, len(state)
    none = np.zeros(0, dtype=np.int64)

    def pairs():
        if n < STRIP_GRID_MIN_BODIES:
            return none, none, none
        switches, _, joint_ints, _, _, parameters, _, _, _, work_floats = sections(n, compiled.ints, compiled.floats)
        _, aabb = faces_and_aabbs(state.position, state.angle, properties[:, EXTENT_X:EXTENT_Y + 1],
                                  parameters[PARAMETER_MARGIN], switches[SWITCH_CIRCLES] != 0,
                                  switches[SWITCH_CORNER_ROUNDING], work_floats)
        return candidate_pairs(aabb, properties[:, INVERSE_MASS], joint_ints[JOINT_PAIRS])

    def run(stop, mask):
        keys, key_i, key_j = pairs()
        if stop:
            staged(keys, key_i, key_j, state.position, state.angle, state.velocity, properties, compiled.ints,
                   compiled.floats, stop, mask)

    variants = {"put the state back": None, "candidate pairs": (0, 0), "+ manifolds": (1, 0),
                "+ prestep": (2, 0)}
    for bit, stage in enumerate(STAGE_BITS):
        variants["+ " + stage] = (3, (1 << (bit + 1)) - 1)
    variants["World.step (whole)"] = "world"
    best = dict.fromkeys(variants, np.inf)
    for _ in range(blocks):
        for name, variant in variants.items():
            start = time.process_time()
            for _ in range(steps_per_block):
                state.numbers[:], compiled.figures[:] = saved
                if variant == "world":
                    world.step(scene.dt)
                elif variant is not None:
                    run(*variant)
            best[name] = min(best[name], (time.process_time() - start) / steps_per_block)
    reset = best.pop("put the state back")
    return [(name, 1e6 * (value - reset)) for name, value in best.items()]


def report(scene_name: str, substeps: int, rows: list[tuple[str, float]]) -> str:
    lines = [f"{scene_name}, {substeps} sub-steps (recommended settings otherwise), compiled soft step:",
             "| stage | us per step | us per sub-step |", "| --- | --- | --- |"]
    previous = 0.0
    per_substep = {"+ " + stage for stage in STAGE_BITS[:5]}
    for name, total in rows:
        if name.startswith("World.step"):
            lines.append(f"| {name} | {total:.1f} | |")
            continue
        cost = total - previous
        shown = f"{cost / substeps:.1f}" if name in per_substep else ""
        lines.append(f"| {name.removeprefix('+ ')} | {cost:.1f} | {shown} |")
        previous = total
    lines.append(f"| all stages | {previous:.1f} | |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scene", default="pyramid_20")
    parser.add_argument("--substeps", type=int, default=8)
    parser.add_argument("--blocks", type=int, default=60, help="turns of every variant (the least is kept)")
    parser.add_argument("--steps", type=int, default=20, help="steps per turn")
    args = parser.parse_args(argv)
    print(report(args.scene, args.substeps, profile(args.scene, args.substeps, args.blocks, args.steps)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
