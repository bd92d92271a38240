"""Batch SAT (numpy) against a Python loop of pymunk ``shapes_collide`` calls.

    python bench/bench_sat.py [--quick]

The same seeded OBB pairs (boxes of 0.05..2 m in a 6 m square, any angle; about half
overlap) go through

- ``obbs_overlap_batch`` on all pairs at once;
- a Python loop calling pymunk's ``shapes_collide`` on prebuilt pymunk shapes (the
  cost a pymunk user pays per pair from Python); timed on a subset and scaled;
- the readable per-pair ``obbs_overlap`` on prebuilt OBBs; timed on a subset and scaled.

Each figure is the median of several runs.  The goal is "batch at most 0.3x the pymunk
loop".  The batch's answers are checked against pymunk's on the subset, leaving out
pairs within 1e-9 m of touching, where roundoff may decide either way.  Peak memory of
one batch call is measured with tracemalloc.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np
import pymunk

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from solutions.narrowphase.batch_sat import obbs_overlap_batch  # noqa: E402
from solutions.narrowphase.polygon_polygon import obbs_overlap  # noqa: E402
from solutions.shapes import OBB  # noqa: E402

GOAL_RATIO = 0.3
TOUCH_BAND = 1e-9   # m


def make_pairs(n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    return (rng.uniform(-3, 3, (n, 2)), rng.uniform(0.05, 2.0, (n, 2)), rng.uniform(-np.pi, np.pi, n),
            rng.uniform(-3, 3, (n, 2)), rng.uniform(0.05, 2.0, (n, 2)), rng.uniform(-np.pi, np.pi, n))


def pymunk_box(center, half, angle):
    body = pymunk.Body(body_type=pymunk.Body.STATIC)
    body.position = (float(center[0]), float(center[1]))
    body.angle = float(angle)
    hx, hy = float(half[0]), float(half[1])
    shape = pymunk.Poly(body, [(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)], radius=0)
    shape.cache_bb()   # never stepped in a space: refresh the world vertices
    return body, shape


def pymunk_overlaps(shape_pairs) -> np.ndarray:
    result = np.empty(len(shape_pairs), dtype=bool)
    for i, (a, b) in enumerate(shape_pairs):
        try:
            result[i] = bool(a.shapes_collide(b).points)
        except AssertionError:     # pymunk raises for pairs that do not touch
            result[i] = False
    return result


def touching_margin(centers_a, half_a, angles_a, centers_b, half_b, angles_b) -> np.ndarray:
    """Largest gap over the four box axes (m): |margin| small means nearly touching."""
    d = centers_b - centers_a

    def reach(half, angle, angle_axis):     # half-width of a box's projection (m)
        return half[:, 0] * np.abs(np.cos(angle - angle_axis)) + half[:, 1] * np.abs(np.sin(angle - angle_axis))

    margins = []
    for angle_axis in (angles_a, angles_a + np.pi / 2, angles_b, angles_b + np.pi / 2):
        axis = np.c_[np.cos(angle_axis), np.sin(angle_axis)]
        margins.append(np.abs((d * axis).sum(1)) - reach(half_a, angles_a, angle_axis)
                       - reach(half_b, angles_b, angle_axis))
    return np.max(margins, axis=0)


def median_time(function, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        function()
        times.append(time.perf_counter() - started)
    return statistics.median(times)


def run(quick: bool = False) -> list[dict]:
    pairs = 100_000
    subset = 2_000 if quick else 10_000
    repeats = 3 if quick else 7
    arrays = make_pairs(pairs)
    batch_s = median_time(lambda: obbs_overlap_batch(*arrays), repeats)

    ca, ha, ta, cb, hb, tb = (x[:subset] for x in arrays)
    keep_alive = []
    shape_pairs = []
    for i in range(subset):
        body_a, a = pymunk_box(ca[i], ha[i], ta[i])
        body_b, b = pymunk_box(cb[i], hb[i], tb[i])
        keep_alive += [body_a, body_b]
        shape_pairs.append((a, b))
    pymunk_s = median_time(lambda: pymunk_overlaps(shape_pairs), max(1, repeats // 2)) * pairs / subset

    boxes = [(OBB(ca[i], ha[i], ta[i]), OBB(cb[i], hb[i], tb[i])) for i in range(subset)]
    readable_s = median_time(lambda: [obbs_overlap(a, b) for a, b in boxes], max(1, repeats // 2)) * pairs / subset

    got = obbs_overlap_batch(*arrays)[:subset]
    want = pymunk_overlaps(shape_pairs)
    clear = np.abs(touching_margin(ca, ha, ta, cb, hb, tb)) > TOUCH_BAND
    mismatches = int(np.sum((got != want) & clear))

    tracemalloc.start()
    obbs_overlap_batch(*arrays)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()

    ratio = batch_s / pymunk_s
    return [
        {"method": "obbs_overlap_batch (numpy)", "pairs": pairs, "timed pairs": pairs, "median ms": batch_s * 1e3,
         "vs pymunk loop": ratio, "peak MB": peak / 1e6},
        {"method": "pymunk shapes_collide loop", "pairs": pairs, "timed pairs": subset, "median ms": pymunk_s * 1e3,
         "vs pymunk loop": 1.0, "peak MB": float("nan")},
        {"method": "obbs_overlap loop (readable)", "pairs": pairs, "timed pairs": subset, "median ms": readable_s * 1e3,
         "vs pymunk loop": readable_s / pymunk_s, "peak MB": float("nan")},
        {"method": "check", "goal met": ratio <= GOAL_RATIO, "compared with pymunk": int(clear.sum()),
         "mismatches": mismatches, "overlapping fraction": float(want.mean())},
    ]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats, smaller timed subsets")
    args = parser.parse_args(argv)
    rows = run(args.quick)
    print("Batch SAT vs a Python loop of pymunk shapes_collide, OBB pairs "
          "(loops timed on 'timed pairs' and scaled to 'pairs')")
    print(f"{'method':32} {'pairs':>8} {'timed':>8} {'median ms':>10} {'vs pymunk':>10} {'peak MB':>8}")
    for row in rows[:3]:
        print(f"{row['method']:32} {row['pairs']:>8} {row['timed pairs']:>8} {row['median ms']:>10.2f} "
              f"{row['vs pymunk loop']:>10.3f} {row['peak MB']:>8.1f}")
    check = rows[3]
    print(f"goal 'batch <= {GOAL_RATIO}x pymunk loop': {'met' if check['goal met'] else 'NOT met'} "
          f"(ratio {rows[0]['vs pymunk loop']:.3f})")
    print(f"batch vs pymunk answers: {check['mismatches']} mismatches on {check['compared with pymunk']} pairs "
          f"away from touching ({check['overlapping fraction']:.0%} overlapping)")
    return 0 if check["mismatches"] == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
