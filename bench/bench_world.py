"""World step against pymunk on the same scenes, with each engine's error.

    python bench/bench_world.py [--quick]

For each scene both engines run the same simulated time at 60 Hz with the same
iteration count, side by side in one run; the error columns use one yardstick for
both (see solutions/scene_metrics.py).  Timing excludes the measurements.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from tools.demo import format_rows, run_scene  # noqa: E402

SCENES = [("stack_10", 10.0), ("stack_20", 10.0), ("pyramid_10", 5.0), ("pyramid_20", 3.0)]
QUICK_SCENES = [("stack_10", 2.0), ("pyramid_10", 1.0)]


def run(quick: bool = False, iterations: int = 10) -> list[dict]:
    rows = []
    for name, seconds in QUICK_SCENES if quick else SCENES:
        pair = run_scene(name, seconds, iterations)
        ratio = pair[0]["ms/step"] / pair[1]["ms/step"]
        for row in pair:
            rows.append({"scene": name, "seconds": seconds, **row, "time vs pymunk": ratio if row["engine"] == "reference" else 1.0})
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--iterations", type=int, default=10)
    args = parser.parse_args(argv)
    print(f"World step, reference engine vs pymunk, {args.iterations} iterations, dt = 1/60 s")
    print(format_rows(run(args.quick, args.iterations)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
