"""Simulate a named scene with the reference engine and with pymunk, and summarise both.

    python -m tools.demo [SCENE] [--seconds S] [--iterations N] [--recommended] [--compiled]
    python -m tools.demo --list

Prints, for each engine: wall time per step, deepest penetration and largest drift
seen, and the change of total energy and of linear momentum.  Both engines are
measured by the same yardstick (:mod:`solutions.scene_metrics`).  With
``--recommended`` the reference engine runs the scene's recommended settings (the
soft step for the hard scenes) and pymunk still runs ``--iterations``; with
``--compiled`` it runs the compiled twins (``backend="numba"``: the same motion).
"""
from __future__ import annotations

import argparse
import re
import sys
import time

import numpy as np

from solutions import scene_metrics as metrics
from solutions.scenes import SCENES, get_scene
from tools.pymunk_mirror import build_space, copy_state


def summarise(label, bodies, gravity, run_step, steps, probe_every):
    """Run ``steps`` steps and return a row of measurements."""
    start = metrics.start_positions(bodies)
    energy0 = metrics.total_energy(bodies, gravity)
    momentum0 = metrics.linear_momentum(bodies)
    worst_depth = 0.0
    elapsed = 0.0
    for k in range(steps):
        t0 = time.perf_counter()
        run_step()
        elapsed += time.perf_counter() - t0
        if k % probe_every == 0 or k == steps - 1:
            worst_depth = max(worst_depth, metrics.max_penetration(bodies))
    return {
        "engine": label,
        "ms/step": 1e3 * elapsed / steps,
        "max penetration (m)": worst_depth,
        "max drift (m)": metrics.max_drift(bodies, start),
        "energy change (J)": metrics.total_energy(bodies, gravity) - energy0,
        "|momentum change| (kg m/s)": float(np.linalg.norm(metrics.linear_momentum(bodies) - momentum0)),
    }


def run_scene(name: str, seconds: float | None = None, iterations: int = 10,
              recommended: bool = False, compiled: bool = False) -> list[dict]:
    """Measurements of scene ``name`` for the reference engine and pymunk."""
    scene = get_scene(name)
    steps = round((seconds if seconds is not None else scene.duration) / scene.dt)
    probe_every = max(1, steps // 60)
    settings = scene.recommended_settings() if recommended else scene.world_settings(iterations=iterations)
    if compiled:
        settings.backend = "numba"
        scene.build_world(settings).step(scene.dt)        # compile (or load the cache) before timing
    world = scene.build_world(settings)
    rows = [summarise("reference", world.bodies, scene.gravity, lambda: world.step(scene.dt), steps, probe_every)]
    mirror_bodies = scene.make_bodies()
    space, pm_bodies = build_space(mirror_bodies, scene.gravity, iterations, world.settings.solver.slop)

    def pymunk_step():
        space.step(scene.dt)
        copy_state(pm_bodies, mirror_bodies)

    rows.append(summarise("pymunk", mirror_bodies, scene.gravity, pymunk_step, steps, probe_every))
    return rows


def format_rows(rows: list[dict]) -> str:
    """A plain text table."""
    columns = list(rows[0])
    cells = [[c for c in columns]] + [[f"{r[c]:.4g}" if isinstance(r[c], float) else str(r[c]) for c in columns]
                                      for r in rows]
    widths = [max(len(row[k]) for row in cells) for k in range(len(columns))]
    return "\n".join("  ".join(cell.rjust(w) for cell, w in zip(row, widths)) for row in cells)


def plain_text(text: str) -> str:
    """A docstring line without its reStructuredText markup (``code``, :role:`x`, *x*)."""
    text = re.sub(r":[a-z]+:`~?([^`]+)`", r"\1", text)
    text = re.sub(r"`+([^`]+)`+", r"\1", text)
    return re.sub(r"\*{1,2}(\S(?:[^*]*\S)?)\*{1,2}", r"\1", text)  # *emphasis*, not "0.8 * 0.8"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Simulate a named scene and summarise it.")
    parser.add_argument("scene", nargs="?", default="stack_10", help="scene name (see --list)")
    parser.add_argument("--seconds", type=float, default=None, help="simulated time (default: the scene's)")
    parser.add_argument("--iterations", type=int, default=10, help="solver iterations for both engines")
    parser.add_argument("--recommended", action="store_true",
                        help="the reference engine runs the scene's recommended settings (soft step for hard scenes)")
    parser.add_argument("--compiled", action="store_true",
                        help="the reference engine runs its compiled twins (backend='numba', the same motion)")
    parser.add_argument("--list", action="store_true", help="list the scenes and exit")
    args = parser.parse_args(argv)
    if args.list:
        for name, scene in sorted(SCENES.items()):
            print(f"{name:16s} {plain_text(scene.description.strip().splitlines()[0])}")
        return 0
    try:
        scene = get_scene(args.scene)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    seconds = args.seconds if args.seconds is not None else scene.duration
    print(f"scene {scene.name}: {plain_text(scene.description.strip().splitlines()[0])}")
    if args.recommended:
        settings = scene.recommended_settings()
        step = (f"soft step, {settings.substeps} sub-steps x {settings.solver.iterations} sweeps"
                if settings.soft_step else f"{settings.solver.iterations} solver iterations")
        print(f"{seconds:g} s simulated at dt = {scene.dt:.4g} s; reference: {step}"
              f"{', compiled' if args.compiled else ''}; pymunk: {args.iterations} iterations\n")
    else:
        print(f"{seconds:g} s simulated at dt = {scene.dt:.4g} s, {args.iterations} solver iterations\n")
    print(format_rows(run_scene(args.scene, seconds, args.iterations, args.recommended, args.compiled)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
