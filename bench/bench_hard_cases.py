"""Hard scenes under a grid of settings: time per step against error, reference and pymunk.

    python bench/bench_hard_cases.py [--quick] [--out DIR]

Every scene runs with every setting of the reference engine (iterations, position
correction, sub-steps) and of pymunk (iterations), side by side in one run, and is
measured by one yardstick (solutions/scene_metrics.py): the deepest overlap and the
largest drift seen, and the largest gain of total energy over the start.  Error is
max(penetration, drift) in m.  Prints a table marking the Pareto-optimal settings of
each scene (no other setting is both faster and more accurate) and writes DIR/hard_cases.md
and DIR/hard_cases.png.
"""
from __future__ import annotations

import argparse
import itertools
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import numpy as np  # noqa: E402

from solutions import scene_metrics as metrics  # noqa: E402
from solutions.scenes import get_scene  # noqa: E402
from solutions.world import World  # noqa: E402
from tools.pymunk_mirror import build_space, copy_state  # noqa: E402

SCENES = {"stack_20": 3.0, "pyramid_10": 2.0, "mass_ratio_1000": 3.0, "chain_40": 3.0, "overlap_recovery": 2.0}
QUICK_SCENES = {"stack_20": 1.0, "mass_ratio_1000": 1.0}
REFERENCE_GRID = {"iterations": (10, 30), "position_correction": ("baumgarte", "split_impulse"), "substeps": (1, 2)}
PYMUNK_ITERATIONS = (10, 30)
PROBES = 30  # penetration measurements per run


def measure(bodies, gravity, step, steps: int) -> dict:
    start = metrics.start_positions(bodies)
    energy0 = metrics.total_energy(bodies, gravity)
    deepest = drift = gain = 0.0
    elapsed = 0.0
    for k in range(steps):
        t0 = time.perf_counter()
        step()
        elapsed += time.perf_counter() - t0
        if k % max(1, steps // PROBES) == 0 or k == steps - 1:
            deepest = max(deepest, metrics.max_penetration(bodies))
            drift = max(drift, metrics.max_drift(bodies, start))
            gain = max(gain, metrics.total_energy(bodies, gravity) - energy0)
    return {"ms_per_step": 1e3 * elapsed / steps, "penetration": deepest, "drift": drift, "energy_gain": gain,
            "error": max(deepest, drift)}


def run(quick: bool = False) -> list[dict]:
    rows = []
    for name, seconds in (QUICK_SCENES if quick else SCENES).items():
        scene = get_scene(name)
        steps = round(seconds / scene.dt)
        for iterations, correction, substeps in itertools.product(*REFERENCE_GRID.values()):
            settings = scene.world_settings(iterations=iterations, position_correction=correction)
            settings.substeps = substeps
            joints = scene.make_joints() if scene.make_joints else None
            world = World(scene.make_bodies(), settings, joints)
            row = measure(world.bodies, scene.gravity, lambda: world.step(scene.dt), steps)
            rows.append({"scene": name, "engine": "reference",
                         "setting": f"it={iterations} {correction} sub={substeps}", **row})
        for iterations in PYMUNK_ITERATIONS:
            bodies = scene.make_bodies()
            joints = scene.make_joints() if scene.make_joints else None
            space, pm_bodies = build_space(bodies, scene.gravity, iterations, 0.005, joints)

            def step():
                space.step(scene.dt)
                copy_state(pm_bodies, bodies)

            rows.append({"scene": name, "engine": "pymunk", "setting": f"it={iterations}",
                         **measure(bodies, scene.gravity, step, steps)})
    mark_pareto(rows)
    return rows


def mark_pareto(rows: list[dict]) -> None:
    """``pareto`` is True for a row that no row of the same scene beats on both axes."""
    for row in rows:
        rivals = [r for r in rows if r["scene"] == row["scene"] and r is not row]
        row["pareto"] = not any(r["ms_per_step"] <= row["ms_per_step"] and r["error"] <= row["error"]
                                and (r["ms_per_step"] < row["ms_per_step"] or r["error"] < row["error"])
                                for r in rivals)


def table(rows: list[dict]) -> str:
    lines = ["| scene | engine | setting | ms/step | penetration (m) | drift (m) | energy gain (J) | Pareto |",
             "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in rows:
        lines.append(f"| {r['scene']} | {r['engine']} | {r['setting']} | {r['ms_per_step']:.2f} | "
                     f"{r['penetration']:.4f} | {r['drift']:.4f} | {r['energy_gain']:.3g} | "
                     f"{'yes' if r['pareto'] else ''} |")
    return "\n".join(lines)


def figure(rows: list[dict], path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    fig, axes = plt.subplots(1, len(scenes), figsize=(4.2 * len(scenes), 3.8), squeeze=False)
    for ax, name in zip(axes[0], scenes):
        for engine, marker in (("reference", "o"), ("pymunk", "s")):
            pts = [r for r in rows if r["scene"] == name and r["engine"] == engine]
            ax.scatter([r["ms_per_step"] for r in pts], [max(r["error"], 1e-6) for r in pts], marker=marker,
                       label=engine, alpha=0.8)
        front = sorted((r for r in rows if r["scene"] == name and r["pareto"]), key=lambda r: r["ms_per_step"])
        ax.plot([r["ms_per_step"] for r in front], [max(r["error"], 1e-6) for r in front], "k--", lw=1,
                label="Pareto front")
        ax.set(xscale="log", yscale="log", title=name, xlabel="time per step (ms)", ylabel="error (m)")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="two scenes, one simulated second each")
    parser.add_argument("--out", type=Path, default=Path("out"), help="folder for hard_cases.md and .png")
    args = parser.parse_args(argv)
    rows = run(args.quick)
    text = table(rows)
    print(text)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "hard_cases.md").write_text(text + "\n")
    figure(rows, args.out / "hard_cases.png")
    print(f"\nwrote {args.out / 'hard_cases.md'} and {args.out / 'hard_cases.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
