"""Hard scenes under a grid of settings: time per frame against error, reference, pymunk, Box2D 2.3 and v3.

    python bench/bench_hard_cases.py [--quick] [--scenes NAME ...] [--out DIR]

Every scene runs under every setting of the grid, side by side in one run:

- the reference engine's plain step: time step x iterations x position correction x
  plain sub-steps (each sub-step a whole step, contacts found again);
- the reference engine's soft step (Box2D v3 style, contacts found once per step):
  time step x sub-steps x sweeps per pass, readable (``backend="python"``) and
  compiled (``backend="numba"``, engine "reference-numba": the same motion to 1e-12,
  compiled before timing);
- pymunk 7: time step x iterations;
- Box2D 2.3 (tools/box2d_mirror.py: polygons inset by Box2D's 0.01 m skin, materials
  mixed as the reference's products): time step x velocity/position iterations;
- Box2D v3 (Box2D 3.1.1 through pyb2d3, tools/box2d_v3_mirror.py: one thread, polygons
  without skin, exact rotations, materials mixed as the reference's products): time
  step x its default settings (4 sub-steps, 30 Hz contacts) and stiffer ones (16
  sub-steps, 120 Hz contacts).

The runs of one scene advance together, 20 frames (of 1/60 s of simulated time) each in
turn, in a new random order for each block, so a busy machine slows all of them alike
and each runs with its own code and data in the caches, as a program stepping one
world does.  The cost is the processor time per frame spent stepping, measured in a
second pass on fresh worlds that only step (the first pass's probes, and copying
pymunk's and Box2D's state into the reference bodies to measure them, would leave the
caches cold for the next frame); the readable runs, whose frames take milliseconds, are
timed in the first pass.  Every run is measured by one
yardstick (solutions/scene_metrics.py, the reference narrow phase for overlaps): the
deepest overlap, the largest drift of a body from its start, the largest gain of
total energy over the start, and the momentum left at the end (|sum m v|, kg m/s; 0
for a scene that comes to rest).  The error of a scene is what its goal is about:
max(overlap, drift) for stacks, pyramids and the mass ratio, the largest stretch of a
link for the chain, and the overlap left after one second for overlap recovery.
Prints a table marking the Pareto-optimal settings of each scene (no other setting is
both cheaper and more accurate), then the goals measured in this run: per scene, at
each time per frame a pymunk or Box2D setting takes, the compiled reference's best
error within that time against theirs, and per peer engine how many of its settings the
reference beats so; and pyramid_20 at its recommended settings
against Box2D at 8/3 iterations and pymunk at 30.  Writes DIR/hard_cases.md and
DIR/hard_cases.png.
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import numpy as np  # noqa: E402

from solutions import scene_metrics as metrics  # noqa: E402
from solutions.joints import anchor_world  # noqa: E402
from solutions.scenes import get_scene  # noqa: E402
from solutions.world import World  # noqa: E402
from tools.box2d_mirror import Box2DMirror  # noqa: E402
from tools.box2d_v3_mirror import SETTINGS as BOX2D_V3_SETTINGS  # noqa: E402
from tools.box2d_v3_mirror import Box2DV3Mirror  # noqa: E402
from tools.pymunk_mirror import build_space, copy_state  # noqa: E402

FRAME = 1 / 60          # s of simulated time per frame
SCENES = {"stack_20": 3.0, "pyramid_10": 2.0, "pyramid_20": 2.0, "mass_ratio_1000": 3.0, "chain_40": 3.0,
          "overlap_recovery": 2.0}
#: Scenes whose readable runs (about 0.1 s of processor time per frame) are left out:
#: only the compiled reference, pymunk and Box2D run them.
COMPILED_ONLY = {"pyramid_20"}
QUICK_SCENES = {"stack_20": 1.0, "mass_ratio_1000": 1.0}
TIME_STEPS = (1 / 60, 1 / 120)
PLAIN_GRID = [(iterations, correction, substeps) for iterations in (10, 30)
              for correction in ("baumgarte", "split_impulse") for substeps in (1, 2)]
SOFT_GRID = [(substeps, sweeps) for substeps in (4, 8) for sweeps in (1, 2)]
#: The compiled soft step also runs cheaper and dearer settings (it is fast enough).
COMPILED_SOFT_GRID = [(substeps, 1) for substeps in (1, 2, 3, 4, 6, 8, 12, 16)] + [(8, 2)]
PYMUNK_ITERATIONS = (10, 30)
BOX2D_ITERATIONS = ((8, 3), (30, 10))  # (velocity, position) iterations
#: The peer engines, each with how its settings are named in the tables.
PEERS = {"pymunk": "pymunk", "box2d": "Box2D 2.3", "box2d-v3": "Box2D v3"}
QUICK_PLAIN_GRID = [(10, "split_impulse", 1), (30, "split_impulse", 1), (10, "baumgarte", 1)]
QUICK_SOFT_GRID = [(4, 1), (8, 1)]
QUICK_COMPILED_SOFT_GRID = [(2, 1), (4, 1), (8, 1)]
QUICK_TIME_STEPS = (1 / 60, 1 / 120)
PROBES = 30             # overlap measurements per run
#: The runs of a scene take turns in blocks of this many frames, in a new random order
#: for every block.  Frame by frame in a fixed order, each run found the caches full of
#: the previous run's code and data: the run after one of another engine measured 2 to 3
#: times slower than the same setting elsewhere in the list (pymunk at 10 iterations
#: slower than at 30, Box2D at 8/3 slower than at 30/10), and every engine ran cold,
#: as no program that steps one world runs.
BLOCK_FRAMES = 20
SHUFFLE_SEED = 2026


@dataclass
class Run:
    """One scene under one setting, advanced frame by frame."""

    scene: str
    engine: str
    setting: str
    dt: float
    bodies: list
    step: object                       # advances the run by dt
    joints: list = field(default_factory=list)
    sync: object = None                # untimed: copies an oracle's state into ``bodies``
    seconds: float = 0.0               # processor time spent stepping
    penetration: float = 0.0
    drift: float = 0.0
    energy_gain: float = 0.0
    stretch: float = 0.0
    overlap_after_1s: float = 0.0

    def __post_init__(self):
        self.start = metrics.start_positions(self.bodies)


def make_runs(name: str, quick: bool) -> list[Run]:
    scene = get_scene(name)
    runs = []
    for dt in (QUICK_TIME_STEPS if quick else TIME_STEPS):
        label = f"dt=1/{round(1 / dt)}"
        readable = name not in COMPILED_ONLY
        for iterations, correction, substeps in (QUICK_PLAIN_GRID if quick else PLAIN_GRID) if readable else []:
            settings = scene.world_settings(iterations=iterations, position_correction=correction)
            settings.substeps = substeps
            world = scene.build_world(settings)
            runs.append(Run(name, "reference", f"{label} plain it={iterations} {correction} sub={substeps}", dt,
                            world.bodies, lambda w=world, h=dt: w.step(h), world.joints))
        soft_runs = [(substeps, sweeps, "python") for substeps, sweeps in (QUICK_SOFT_GRID if quick else SOFT_GRID)
                     if readable]
        soft_runs += [(substeps, sweeps, "numba")
                      for substeps, sweeps in (QUICK_COMPILED_SOFT_GRID if quick else COMPILED_SOFT_GRID)]
        for substeps, sweeps, backend in soft_runs:
            settings = scene.world_settings(iterations=sweeps)
            settings.soft_step, settings.substeps, settings.backend = True, substeps, backend
            world = scene.build_world(settings)
            engine = "reference" if backend == "python" else "reference-numba"
            runs.append(Run(name, engine, f"{label} soft sub={substeps} it={sweeps}", dt, world.bodies,
                            lambda w=world, h=dt: w.step(h), world.joints))
        for iterations in PYMUNK_ITERATIONS:
            bodies = scene.make_bodies()
            joints = scene.make_joints() if scene.make_joints else []
            space, pm_bodies = build_space(bodies, scene.gravity, iterations, 0.005, joints)

            runs.append(Run(name, "pymunk", f"{label} it={iterations}", dt, bodies,
                            lambda space=space, h=dt: space.step(h), joints,
                            lambda pm_bodies=pm_bodies, bodies=bodies: copy_state(pm_bodies, bodies)))
        for velocity_iterations, position_iterations in BOX2D_ITERATIONS:
            mirror = Box2DMirror.from_scene(scene, velocity_iterations=velocity_iterations,
                                            position_iterations=position_iterations)
            runs.append(Run(name, "box2d", f"{label} it={velocity_iterations}/{position_iterations}", dt,
                            mirror.bodies, lambda m=mirror, h=dt: m.step(h, copy=False), mirror.joints,
                            mirror.copy_state))
        for setting, options in BOX2D_V3_SETTINGS.items():
            mirror = Box2DV3Mirror.from_scene(scene, setting)
            hertz = options["contact_hertz"]
            described = f"{setting} ({options['substeps']} sub, {'30' if hertz is None else f'{hertz:g}'} Hz)"
            runs.append(Run(name, "box2d-v3", f"{label} {described}", dt, mirror.bodies,
                            lambda m=mirror, h=dt: m.step(h, copy=False), mirror.joints, mirror.copy_state))
    return runs


def longest_stretch(run: Run) -> float:
    worst = 0.0
    for joint in run.joints:
        a = anchor_world(run.bodies[joint.a], joint.anchor_a)
        b = anchor_world(run.bodies[joint.b], joint.anchor_b)
        worst = max(worst, abs(math.dist(a, b) - joint.length))
    return worst


def time_steps(runs: list[Run], frames: int) -> None:
    """Add to each run's ``seconds`` the processor time of ``frames`` frames of its step
    alone: the runs take turns in blocks of ``BLOCK_FRAMES`` frames in a shuffled order,
    with nothing between two frames of a block (no copy of a peer's state, no probe)."""
    shuffle = np.random.default_rng(SHUFFLE_SEED)
    for block in range(0, frames, BLOCK_FRAMES):
        for index in shuffle.permutation(len(runs)):
            run = runs[index]
            steps = round(FRAME / run.dt)
            for _ in range(block, min(block + BLOCK_FRAMES, frames)):
                start = time.process_time()
                for _ in range(steps):
                    run.step()
                run.seconds += time.process_time() - start


def simulate(name: str, seconds: float, quick: bool) -> list[dict]:
    """Every run of scene ``name`` for ``seconds``: its errors from one pass that probes
    the bodies, its cost from a second pass on fresh worlds that only steps (the probes
    and a peer's copy into the reference bodies would leave the caches cold for the next
    frame: 30 % on the compiled pyramid_20).  The readable runs, whose frames take
    milliseconds, are timed in the first pass."""
    scene = get_scene(name)
    runs = make_runs(name, quick)
    energy0 = [metrics.total_energy(run.bodies, scene.gravity) for run in runs]
    frames = round(seconds / FRAME)
    shuffle = np.random.default_rng(SHUFFLE_SEED)
    for block in range(0, frames, BLOCK_FRAMES):
        for index in shuffle.permutation(len(runs)):
            run, e0 = runs[index], energy0[index]
            for frame in range(block, min(block + BLOCK_FRAMES, frames)):
                probe = frame % max(1, frames // PROBES) == 0 or frame == frames - 1
                steps = round(FRAME / run.dt)
                start = time.process_time()
                for _ in range(steps):
                    run.step()
                run.seconds += time.process_time() - start
                if run.sync:
                    run.sync()
                run.stretch = max(run.stretch, longest_stretch(run))
                if probe or frame == round(1.0 / FRAME) - 1:
                    deepest = metrics.max_penetration(run.bodies)
                    run.penetration = max(run.penetration, deepest)
                    run.drift = max(run.drift, metrics.max_drift(run.bodies, run.start))
                    run.energy_gain = max(run.energy_gain, metrics.total_energy(run.bodies, scene.gravity) - e0)
                    if frame == round(1.0 / FRAME) - 1 or (frame == frames - 1 and frames < round(1.0 / FRAME)):
                        run.overlap_after_1s = deepest
    fast = [k for k, run in enumerate(runs) if run.engine != "reference"]
    timed = make_runs(name, quick)
    time_steps([timed[k] for k in fast], frames)
    for k in fast:
        runs[k].seconds = timed[k].seconds
    rows = []
    for run in runs:
        error = {"chain_40": run.stretch, "overlap_recovery": run.overlap_after_1s}.get(
            name, max(run.penetration, run.drift))
        rows.append({"scene": name, "engine": run.engine, "setting": run.setting,
                     "ms_per_frame": 1e3 * run.seconds / frames, "penetration": run.penetration,
                     "drift": run.drift, "energy_gain": run.energy_gain,
                     "momentum": float(np.linalg.norm(metrics.linear_momentum(run.bodies))), "error": error})
    return rows


def warm_up_compiled_twins() -> None:
    """Compile (or load from numba's cache) every compiled twin before anything is timed."""
    scene = get_scene("pyramid_10")
    settings = scene.world_settings(iterations=1)
    settings.soft_step, settings.substeps, settings.backend = True, 2, "numba"
    world = scene.build_world(settings)
    world.step(FRAME)


def run(quick: bool = False, scenes: list[str] | None = None) -> list[dict]:
    """Every scene (``scenes``: only these, of ``SCENES``), side by side within a scene."""
    warm_up_compiled_twins()
    rows = []
    for name, seconds in (QUICK_SCENES if quick else SCENES).items():
        if scenes is None or name in scenes:
            rows.extend(simulate(name, seconds, quick))
    mark_pareto(rows)
    return rows


def mark_pareto(rows: list[dict]) -> None:
    """``pareto`` is True for a row that no row of the same scene beats on both axes."""
    for row in rows:
        rivals = [r for r in rows if r["scene"] == row["scene"] and r is not row]
        row["pareto"] = not any(r["ms_per_frame"] <= row["ms_per_frame"] and r["error"] <= row["error"]
                                and (r["ms_per_frame"] < row["ms_per_frame"] or r["error"] < row["error"])
                                for r in rivals)


ERROR_MEANING = {"chain_40": "largest link stretch", "overlap_recovery": "overlap left after 1 s"}


def table(rows: list[dict]) -> str:
    lines = ["| scene | engine | setting | ms/frame | penetration (m) | drift (m) | energy gain (J) | "
             "momentum left (kg m/s) | error (m) | Pareto |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in rows:
        lines.append(f"| {r['scene']} | {r['engine']} | {r['setting']} | {r['ms_per_frame']:.3f} | "
                     f"{r['penetration']:.4f} | {r['drift']:.4f} | {r['energy_gain']:.3g} | {r['momentum']:.3g} | "
                     f"{r['error']:.4f} | {'yes' if r['pareto'] else ''} |")
    notes = [f"error of {name}: {meaning}" for name, meaning in ERROR_MEANING.items()
             if any(r["scene"] == name for r in rows)]
    return "\n".join(lines + ([""] + ["Error is max(penetration, drift) except: " + "; ".join(notes) + "."]
                              if notes else []))


def figure(rows: list[dict], path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    fig, axes = plt.subplots(1, len(scenes), figsize=(4.2 * len(scenes), 3.8), squeeze=False)
    for ax, name in zip(axes[0], scenes):
        for engine, kind, marker in (("reference", "plain", "o"), ("reference", "soft", "^"),
                                     ("reference-numba", "soft", "v"), ("pymunk", "", "s"), ("box2d", "", "D"),
                                     ("box2d-v3", "", "P")):
            pts = [r for r in rows if r["scene"] == name and r["engine"] == engine and kind in r["setting"]]
            ax.scatter([r["ms_per_frame"] for r in pts], [max(r["error"], 1e-6) for r in pts], marker=marker,
                       label=f"{engine} {kind}".strip(), alpha=0.8)
        front = sorted((r for r in rows if r["scene"] == name and r["pareto"]), key=lambda r: r["ms_per_frame"])
        ax.plot([r["ms_per_frame"] for r in front], [max(r["error"], 1e-6) for r in front], "k--", lw=1,
                label="Pareto front")
        ax.set(xscale="log", yscale="log", title=name, xlabel="processor time per frame (ms)", ylabel="error (m)")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def equal_time_goals(rows: list[dict]) -> str:
    """Per scene and per peer setting (pymunk, Box2D 2.3 or v3): the compiled reference's
    best error among its settings that take at most that setting's time per frame, and
    the time its cheapest setting at least as accurate as the peer takes (as a multiple
    of the peer's: above 1, how much faster the reference must become to meet the goal); then,
    per peer engine, at how many of its settings' times the reference has the lower error."""
    lines = ["| scene | peer setting | peer ms/frame | peer error (m) | compiled reference at that time "
             "| its cheapest as accurate | met |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    beaten = {engine: [0, 0] for engine in PEERS}      # [settings beaten, settings]
    for name in dict.fromkeys(r["scene"] for r in rows):
        compiled = [r for r in rows if r["scene"] == name and r["engine"] == "reference-numba"]
        fastest = min((r["ms_per_frame"] for r in compiled), default=math.inf)
        for peer in (r for r in rows if r["scene"] == name and r["engine"] in PEERS):
            within = [r for r in compiled if r["ms_per_frame"] <= peer["ms_per_frame"]]
            best = min(within, key=lambda r: r["error"], default=None)
            shown = (f"{best['error']:.4f} m ({best['setting']}, {best['ms_per_frame']:.3f} ms)" if best else
                     f"none: its fastest takes {fastest:.2f} ms, {fastest / peer['ms_per_frame']:.0f}x as long")
            accurate = [r for r in compiled if r["error"] < peer["error"]]
            cheapest = min(accurate, key=lambda r: r["ms_per_frame"], default=None)
            needed = (f"{cheapest['ms_per_frame']:.3f} ms, {cheapest['ms_per_frame'] / peer['ms_per_frame']:.2f}x"
                      if cheapest else "none")
            met = best is not None and best["error"] < peer["error"]
            beaten[peer["engine"]][0] += met
            beaten[peer["engine"]][1] += 1
            lines.append(f"| {name} | {peer['engine']} {peer['setting']} | {peer['ms_per_frame']:.3f} | "
                         f"{peer['error']:.4f} | {shown} | {needed} | {'yes' if met else 'no'} |")
    lines.append("")
    lines += [f"At equal time the reference has the lower error at {won} of {count} {PEERS[engine]} settings."
              for engine, (won, count) in beaten.items() if count]
    return "\n".join(lines)


def pyramid_20_goal(seconds: float = 1.0) -> str:
    """pyramid_20 at its recommended settings (compiled) against Box2D 2.3 at 8/3
    iterations, Box2D v3 at its default and stiff settings and pymunk at 30, processor
    time per frame measured side by side."""
    scene = get_scene("pyramid_20")
    settings = scene.recommended_settings()
    settings.backend = "numba"
    world = scene.build_world(settings)
    bodies = scene.make_bodies()
    space, _ = build_space(bodies, scene.gravity, 30, 0.005, [])
    mirror = Box2DMirror.from_scene(scene, velocity_iterations=8, position_iterations=3)
    v3 = {setting: Box2DV3Mirror.from_scene(scene, setting) for setting in BOX2D_V3_SETTINGS}
    steppers = {"reference (recommended, numba)": lambda: world.step(FRAME),
                "Box2D 8/3": lambda: mirror.step(FRAME, copy=False), "pymunk 30": lambda: space.step(FRAME),
                **{f"Box2D v3 {setting}": (lambda m=m: m.step(FRAME, copy=False)) for setting, m in v3.items()}}
    spent = dict.fromkeys(steppers, 0.0)
    frames = round(seconds / FRAME)
    shuffle = np.random.default_rng(SHUFFLE_SEED)
    labels = list(steppers)
    for block in range(0, frames, BLOCK_FRAMES):       # in blocks, as simulate() runs them
        for index in shuffle.permutation(len(labels)):
            label = labels[index]
            for _ in range(min(BLOCK_FRAMES, frames - block)):
                start = time.process_time()
                steppers[label]()
                spent[label] += time.process_time() - start
    ms = {label: 1e3 * value / frames for label, value in spent.items()}
    ours = ms["reference (recommended, numba)"]
    return (f"pyramid_20, ms per frame over {seconds:g} s: " + ", ".join(f"{k} {v:.2f}" for k, v in ms.items())
            + f"\n  goal: at most Box2D's time ({ours / ms['Box2D 8/3']:.1f}x it: "
            f"{'met' if ours <= ms['Box2D 8/3'] else 'not met'}) and at most half of pymunk's "
            f"({ours / ms['pymunk 30']:.1f}x it: {'met' if ours <= 0.5 * ms['pymunk 30'] else 'not met'})")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="two scenes, one simulated second, a smaller grid")
    parser.add_argument("--out", type=Path, default=Path("out"), help="folder for hard_cases.md and .png")
    parser.add_argument("--scenes", nargs="+", choices=list(SCENES), help="only these scenes (default: all)")
    args = parser.parse_args(argv)
    rows = run(args.quick, args.scenes)
    text = table(rows)
    text += ("\n\nGoal: at equal processor time per frame, the compiled reference's error below pymunk's, "
             "Box2D 2.3's and Box2D v3's\n\n" + equal_time_goals(rows) + "\n\n" + pyramid_20_goal(0.5 if args.quick else 1.0))
    print(text)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "hard_cases.md").write_text(text + "\n")
    figure(rows, args.out / "hard_cases.png")
    print(f"\nwrote {args.out / 'hard_cases.md'} and {args.out / 'hard_cases.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
