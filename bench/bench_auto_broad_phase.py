"""Which broad phase is fastest for a world of N bodies, and what ``"auto"`` picks.

    python bench/bench_auto_broad_phase.py [--quick]

Times one step's collision detection, ``World.broad_phase`` then ``World.narrow_phase``
(the part the ``broad_phase`` setting changes), for every setting of
:data:`solutions.world.BROAD_PHASES` but ``"auto"``, on four kinds of scene of 2 to 160
bodies:

- "balls in walls": the speed chapter's ``many_bodies`` (balls among four static box walls);
- "boxes on a ground": 1 m boxes in rows of 8 on a static ground (every box touches);
- "scattered balls" and "scattered boxes": 0.2 m balls / 0.5 m boxes at random
  positions (boxes at random angles) over 10 m x 10 m, no walls.

Cost: processor time (``time.process_time``, so a busy machine inflates it less than
wall-clock time), best of 15 runs of 5 calls each, garbage collector off.  Every method
must find the same contacts (checked).  Prints one table per scene kind, the fastest
method of each row, and the method ``"auto"`` picks (:func:`solutions.world.auto_broad_phase`).
"""
from __future__ import annotations

import argparse
import gc
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from solutions.body import Body  # noqa: E402
from solutions.scenes import many_bodies  # noqa: E402
from solutions.world import BROAD_PHASES, World, WorldSettings, auto_broad_phase  # noqa: E402

METHODS = tuple(method for method in BROAD_PHASES if method != "auto")
SIZES = (2, 3, 4, 6, 8, 12, 16, 24, 32, 40, 48, 64, 80, 96, 128, 160)
QUICK_SIZES = (2, 8, 32, 64, 96)
SLOW_ALL_PAIRS = 64          # all pairs beyond this many bodies only confirms the trend


def detection_time(bodies, method: str, repeats: int = 15, inner: int = 5) -> tuple[float, list]:
    """Best time (s) of one detection with ``method``, and the contact pairs it finds."""
    world = World(bodies, WorldSettings(gravity=(0.0, 0.0), broad_phase=method))
    shapes = world.world_shapes()
    best = math.inf
    gc.disable()
    try:
        for _ in range(repeats):
            tic = time.process_time()
            for _ in range(inner):
                manifolds = world.narrow_phase(shapes, world.broad_phase(shapes))
            best = min(best, (time.process_time() - tic) / inner)
    finally:
        gc.enable()
    return best, sorted((i, j) for i, j, _ in manifolds)


def boxes_on_a_ground(n: int) -> list[Body]:
    ground = Body.box(40.0, 1.0, is_static=True, position=(0.0, -0.5))
    return [ground] + [Body.box(1.0, 1.0, mass=1.0, position=(1.0 * (k % 8) - 4.0, 0.5 + k // 8))
                       for k in range(n - 1)]


def scattered_balls(n: int) -> list[Body]:
    rng = np.random.default_rng(2)
    return [Body.circle(0.2, mass=1.0, position=p) for p in rng.uniform(-5.0, 5.0, (n, 2))]


def scattered_boxes(n: int) -> list[Body]:
    rng = np.random.default_rng(3)
    return [Body.box(0.5, 0.5, mass=1.0, position=p, angle=a)
            for p, a in zip(rng.uniform(-5.0, 5.0, (n, 2)), rng.uniform(0.0, 3.0, n))]


SCENES = {"balls in walls": lambda n: many_bodies(n - 4) if n > 4 else None,
          "boxes on a ground": boxes_on_a_ground, "scattered balls": scattered_balls,
          "scattered boxes": scattered_boxes}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="five sizes only")
    args = parser.parse_args(argv)
    for name, make in SCENES.items():
        print(f"\n{name}: detection time per step (us)")
        print(f"{'N':>4} " + " ".join(f"{m:>13}" for m in METHODS) + f"  {'fastest':>13} {'auto picks':>13}")
        for n in QUICK_SIZES if args.quick else SIZES:
            bodies = make(n)
            if bodies is None:
                continue
            times, found = {}, {}
            for method in METHODS:
                if method == "all_pairs" and n > SLOW_ALL_PAIRS:
                    continue
                times[method], found[method] = detection_time(bodies, method)
            if any(pairs != found["brute_force"] for pairs in found.values()):
                print(f"methods disagree on the contacts of {name}, N = {n}", file=sys.stderr)
                return 1
            picked = auto_broad_phase(World(bodies).world_shapes())
            cells = " ".join(f"{times[m] * 1e6:13.1f}" if m in times else f"{'-':>13}" for m in METHODS)
            print(f"{n:>4} {cells}  {min(times, key=times.get):>13} {picked:>13}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
