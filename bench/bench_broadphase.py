"""Broad phase benchmark: the numpy grid and its numba twin against brute force, the
readable grid and quadtree of the course, scipy's cKDTree and pymunk's two spatial indexes.

    python bench/bench_broadphase.py [--quick]

Prints one table (median time of several runs, pair count, peak memory), the speed
ratios of the numpy grid and of the numba grid over every rival measured side by side
in this run, and whether the goals are met.  ``run(quick)`` returns the rows for
another script.

Scenes
    N boxes with sides drawn uniformly in [0.5, 1.5] m.  "uniform": centres uniform in
    a square world of side sqrt(4 N / 3) m, about 3 overlapping neighbours per box.
    "clustered": N / 200 cluster centres in the same world, bodies normally
    distributed around them (sigma 3 m), about 10 neighbours per box.

How each method is timed (CPU time of the process, ``time.process_time``: on a shared
machine it does not count the time spent waiting for a CPU, unlike wall time; every
method here runs on one thread, so on an idle machine the two agree)
    - Ours and scipy run in this process, in rounds: every round calls each method
      once, so a slow spell of the machine hits all of them alike.  A method faster
      than 0.1 s is called once untimed just before its timed call, so that it does not
      pay for the memory churn of the method timed before it (a broad phase runs every
      frame).  Every call starts from the (N, 4) array and ends with the exact pairs
      (cell sizes and radii are computed inside the timed call).
    - Brute force at 100 000 boxes would take minutes: its time is estimated from the
      10 000-box median times 100 (it is O(N^2)) and labelled "estimated".
    - scipy cKDTree: ``query_pairs`` on the box centres with radius r = hypot(largest
      width, largest height).  Two overlapping boxes have |dx| <= (w_i + w_j) / 2 <=
      max width and |dy| <= max height, so their centres are within r; the exact AABB
      test then removes the extra candidates.
    - pymunk (Chipmunk, C): every box is a kinematic body with a ``Poly`` box shape.
      Timed: one ``space.step`` in which pymunk's index finds every pair of touching
      bounding boxes, with no narrow phase and no Python callback: all shapes share
      one ``ShapeFilter`` group, so Chipmunk rejects each pair right after the
      bounding-box test.  Before each timed step every body is moved 10 km (untimed),
      so the BB tree must re-insert every leaf and the spatial hash (which rehashes
      everything each step anyway) starts from scratch: without that, the BB tree
      would just replay the pairs it cached at the previous step.  Object creation and
      ``space.add`` are not timed (Python overhead).  Spatial hash: cell ``dim`` = median
      box extent, ``count`` = 10 N, as pymunk's documentation suggests.  The same
      indexes without the filter count the colliding pairs (cached arbiters after the
      first step), which checks that pymunk finds the same pairs; "step incl. narrow
      phase" times such a space (BB tree) the same way: what a pymunk user pays for
      collision detection.
      pymunk runs in a worker process (its teardown of 10^5 bodies takes minutes, and
      its memory lives in C), which also times the numpy grid and the numba grid
      alternately with each pymunk step: the pymunk ratios come from those paired runs.
    - numba grid (:func:`solutions.broadphase.grid_numba.pairs_grid_numba`): compile
      time is excluded.  Every process that times it (this one and the pymunk worker)
      first calls it once on a small scene, untimed, which compiles it or loads the
      machine code cached in ``__pycache__`` by an earlier run.

Memory
    "tracemalloc": peak of Python and numpy allocations during one call.  "RSS": growth
    of the resident memory of a fresh worker process during one call (cKDTree, pymunk
    and the numba grid allocate outside numpy's allocator, invisible to tracemalloc);
    for pymunk, from ``space.add`` to the end of the first step (index, plus arbiters
    for the step with narrow phase); for the numba grid, after its warm-up call.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import resource
import statistics
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

REPO_ROOT = Path(__file__).resolve().parents[1]
if str(REPO_ROOT) not in sys.path:
    sys.path.insert(0, str(REPO_ROOT))

from solutions.broadphase import (  # noqa: E402
    pairs_brute_force_numpy,
    pairs_grid_numpy,
    pairs_quadtree,
    pairs_uniform_grid,
    suggest_cell_size,
)
from solutions.broadphase.grid_numba import pairs_grid_numba  # noqa: E402

BRUTE = "brute force (numpy, chunked)"
READABLE_GRID = "readable grid (every_cell)"
NUMPY_GRID = "numpy grid (sorted strips)"
NUMBA_GRID = "numba grid (compiled strips)"
QUADTREE = "quadtree (readable)"
CKDTREE = "scipy cKDTree"
PYMUNK_TREE = "pymunk BB tree, broad phase"
PYMUNK_HASH = "pymunk spatial hash, broad phase"
PYMUNK_TREE_FULL = "pymunk BB tree, step incl. narrow phase"
PYMUNK_METHODS = (PYMUNK_TREE, PYMUNK_HASH, PYMUNK_TREE_FULL)

SCENES = ("uniform", "clustered")
SIZES = (1_000, 10_000, 100_000)
BOX_SIDES = (0.5, 1.5)          # m, range of box widths and heights
CLUSTER_BODIES = 200            # bodies per cluster in the clustered scene
CLUSTER_SIGMA = 3.0             # m
PYMUNK_SHIFT = 10_000.0         # m, how far bodies jump between timed steps
DT = 1.0 / 60.0                 # s

clock = time.process_time      # the timer of every measurement (see the module docstring)
WARM_UP_BELOW_S = 0.1           # s: faster methods get an untimed call before each timed one
GOAL_BRUTE_RATIO = 20.0         # at 10k: numpy grid >= 20x faster than brute force
GOAL_PYMUNK_RATIO = 4.0         # at 10k: >= 4x faster than pymunk's faster index
GOAL_CKDTREE_RATIO = 1.0        # at 100k: no slower than cKDTree
GOAL_NUMBA_HASH_RATIO = 4.0     # at 10k: numba grid >= 4x faster than pymunk's spatial hash


# ------------------------------------------------------------------------- scenes
def make_scene(kind: str, n: int, seed: int = 0) -> np.ndarray:
    """(n, 4) AABBs of the named scene; the same (kind, n, seed) gives the same boxes."""
    rng = np.random.default_rng([seed, n, SCENES.index(kind)])
    world_side = math.sqrt(4 * n / 3)
    if kind == "uniform":
        centres = rng.uniform(0, world_side, (n, 2))
    elif kind == "clustered":
        clusters = rng.uniform(0, world_side, (max(1, n // CLUSTER_BODIES), 2))
        centres = clusters[rng.integers(0, len(clusters), n)] + rng.normal(0, CLUSTER_SIGMA, (n, 2))
    else:
        raise ValueError(f"unknown scene {kind!r}")
    half = rng.uniform(*BOX_SIDES, (n, 2)) / 2
    return np.hstack([centres - half, centres + half])


# ------------------------------------------------------------------------ rivals
def pairs_ckdtree(aabbs: np.ndarray) -> np.ndarray:
    """Overlapping pairs via scipy's cKDTree on centres, then the exact AABB test."""
    centres = (aabbs[:, :2] + aabbs[:, 2:]) / 2
    extents = aabbs[:, 2:] - aabbs[:, :2]
    radius = math.hypot(extents[:, 0].max(), extents[:, 1].max())
    # The relative margin covers rounding of the centres (about 1e-16 of the coordinates).
    candidates = cKDTree(centres).query_pairs(radius * (1 + 1e-9), output_type="ndarray")
    i, j = candidates[:, 0], candidates[:, 1]
    keep = ((aabbs[i, 2] >= aabbs[j, 0]) & (aabbs[j, 2] >= aabbs[i, 0])
            & (aabbs[i, 3] >= aabbs[j, 1]) & (aabbs[j, 3] >= aabbs[i, 1]))
    return candidates[keep]


def readable_grid(aabbs: np.ndarray) -> set:
    return pairs_uniform_grid(aabbs, suggest_cell_size(aabbs), "every_cell")


IN_PROCESS = {
    BRUTE: pairs_brute_force_numpy,
    READABLE_GRID: readable_grid,
    NUMPY_GRID: pairs_grid_numpy,
    NUMBA_GRID: pairs_grid_numba,
    QUADTREE: pairs_quadtree,
    CKDTREE: pairs_ckdtree,
}


#: Methods whose memory is measured as RSS growth in a worker (allocations outside numpy).
RSS_WORKER_METHODS = {CKDTREE: pairs_ckdtree, NUMBA_GRID: pairs_grid_numba}


# ------------------------------------------------------------------- measuring
def warm_up_numba() -> None:
    """Compile the numba grid (or load its cached machine code): not part of any timing."""
    pairs_grid_numba(make_scene("uniform", 200))


def rounds_of_timings(methods: dict, aabbs: np.ndarray, rounds: int,
                      budget_s: float) -> tuple[dict[str, list[float]], dict[str, int]]:
    """Call every method once per round; a method stops once it has used ``budget_s``.

    A method that took under :data:`WARM_UP_BELOW_S` is first called once untimed, so
    that it finds caches and the allocator as it left them, as a broad phase run every
    frame would (otherwise a fast method pays for the memory churn of the slow method
    timed just before it).  Returns the times (s) of each method and its pair count.
    """
    times: dict[str, list[float]] = {name: [] for name in methods}
    counts: dict[str, int] = {}
    for _ in range(rounds):
        for name, method in methods.items():
            if times[name] and sum(times[name]) > budget_s:
                continue
            if times[name] and times[name][-1] < WARM_UP_BELOW_S:
                method(aabbs)
            started = clock()
            pairs = method(aabbs)
            times[name].append(clock() - started)
            counts[name] = len(pairs)
    return times, counts


def tracemalloc_peak_mb(method, aabbs: np.ndarray) -> float:
    """Peak of traced Python/numpy allocations during one call (MB)."""
    tracemalloc.start()
    try:
        method(aabbs)
        return tracemalloc.get_traced_memory()[1] / 1e6
    finally:
        tracemalloc.stop()


def _status_kb(field: str) -> int:
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    raise KeyError(field)


class RssGrowth:
    """Context manager: growth of the peak resident memory inside the block (MB).

    Linux resets the peak (VmHWM) to the current RSS when "5" is written to
    /proc/self/clear_refs; elsewhere ru_maxrss before/after gives a lower bound.
    """

    def __enter__(self):
        try:
            self.base_kb = _status_kb("VmRSS")
            with open("/proc/self/clear_refs", "w") as clear_refs:
                clear_refs.write("5")
            self.exact = True
        except OSError:
            self.base_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
            self.exact = False
        return self

    def __exit__(self, *exc):
        peak_kb = _status_kb("VmHWM") if self.exact else resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        self.mb = max(0, peak_kb - self.base_kb) / 1024
        return False


def run_worker(*args: str) -> dict:
    """Run this file as a worker process and return its JSON answer."""
    done = subprocess.run([sys.executable, __file__, *args], capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"worker {args} failed:\n{done.stderr[-2000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def finish_worker(answer: dict) -> None:
    """Print the worker's answer and leave at once (skipping pymunk's slow teardown)."""
    print(json.dumps(answer), flush=True)
    os._exit(0)


def rss_memory_worker(method: str, kind: str, n: int) -> None:
    aabbs = make_scene(kind, n)
    RSS_WORKER_METHODS[method](aabbs[:200])      # first-call setup (and compilation) outside the measurement
    with RssGrowth() as growth:
        RSS_WORKER_METHODS[method](aabbs)
    finish_worker({"rss_mb": growth.mb})


def pymunk_worker(kind: str, n: int, rounds: int) -> None:
    """Time pymunk's indexes against the numpy grid in one process; see the module doc."""
    import pymunk

    aabbs = make_scene(kind, n)
    median_extent = suggest_cell_size(aabbs) / 2

    def build(index: str, broad_phase_only: bool):
        space = pymunk.Space()
        if index == "hash":
            space.use_spatial_hash(median_extent, 10 * n)
        one_group = pymunk.ShapeFilter(group=1)
        bodies, objects = [], []
        for min_x, min_y, max_x, max_y in aabbs.tolist():
            body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
            body.position = ((min_x + max_x) / 2, (min_y + max_y) / 2)
            shape = pymunk.Poly.create_box(body, (max_x - min_x, max_y - min_y), radius=0.0)
            if broad_phase_only:
                shape.filter = one_group
            bodies.append(body)
            objects += [body, shape]
        return space, bodies, objects

    def move_all(bodies, shift):
        for body in bodies:
            x, y = body.position
            body.position = (x + shift, y)

    warm_up_numba()
    answer = {"times_ms": {}, "grid_times_ms": {}, "numba_times_ms": {}, "pairs": {}, "rss_mb": {}}
    keep_alive = []
    for method, index, broad_phase_only in ((PYMUNK_TREE, "tree", True), (PYMUNK_HASH, "hash", True),
                                            (PYMUNK_TREE_FULL, "tree", False)):
        space, bodies, objects = build(index, broad_phase_only)
        with RssGrowth() as growth:
            space.add(*objects)
            space.step(DT)
        answer["rss_mb"][method] = growth.mb
        if not broad_phase_only:
            answer["pairs"][method] = len(space._get_arbiters())
        pymunk_times, grid_times, numba_times = [], [], []
        for round_index in range(rounds):
            move_all(bodies, PYMUNK_SHIFT if round_index % 2 == 0 else -PYMUNK_SHIFT)
            started = clock()
            space.step(DT)
            pymunk_times.append(clock() - started)
            started = clock()
            pairs_grid_numpy(aabbs)
            grid_times.append(clock() - started)
            started = clock()
            pairs_grid_numba(aabbs)
            numba_times.append(clock() - started)
        answer["times_ms"][method] = 1e3 * statistics.median(pymunk_times)
        answer["grid_times_ms"][method] = 1e3 * statistics.median(grid_times)
        answer["numba_times_ms"][method] = 1e3 * statistics.median(numba_times)
        keep_alive.append(space)
    # Pair counts of the broad-phase configurations: the same indexes without the filter.
    # (Space._get_arbiters is pymunk's own, private, list of cached arbiters; pymunk is pinned.)
    for method, index in ((PYMUNK_TREE, "tree"), (PYMUNK_HASH, "hash")):
        space, _, objects = build(index, broad_phase_only=False)
        space.add(*objects)
        space.step(DT)
        answer["pairs"][method] = len(space._get_arbiters())
        keep_alive.append(space)
    finish_worker(answer)


# ---------------------------------------------------------------------- the run
def run(quick: bool) -> list[dict]:
    """Measure every method on every scene; one dict per (N, scene, method).

    Keys: ``n``, ``scene``, ``method``, ``median_ms`` (None if skipped), ``runs``,
    ``estimated`` (bool), ``pairs`` and ``pairs_match`` (count equal to the numpy
    grid's), ``peak_mb`` and ``memory_tool``, ``grid_ms_alongside`` and
    ``numba_ms_alongside`` (numpy and numba grid medians measured in the same worker,
    for pymunk rows) and ``note``.

    ``quick``: 3 rounds instead of 7; at 100 000 boxes only the numpy and numba grids
    and cKDTree; pymunk only at 10 000; memory only for the two grids and cKDTree at
    100 000.
    """
    warm_up_numba()
    rows = []
    for n in SIZES:
        big = n >= 100_000
        rounds = (3 if quick else 7) if not big else (2 if quick else 5)
        for kind in SCENES:
            aabbs = make_scene(kind, n)
            skipped = {}
            if big:
                skipped[BRUTE] = "estimated from 10 000 x 100 (O(N^2))"
                if quick:
                    skipped.update({name: "skipped (--quick)" for name in (READABLE_GRID, QUADTREE)})
            methods = {name: method for name, method in IN_PROCESS.items() if name not in skipped}
            times, counts = rounds_of_timings(methods, aabbs, rounds, budget_s=0.5 if quick else 12.0)
            reference = counts[NUMPY_GRID]
            for name in IN_PROCESS:
                row = _empty_row(n, kind, name, skipped.get(name, ""))
                if name in methods:
                    row.update(median_ms=1e3 * statistics.median(times[name]), runs=len(times[name]),
                               pairs=counts[name], pairs_match=counts[name] == reference)
                    if name in RSS_WORKER_METHODS and (not quick or big):
                        row.update(peak_mb=run_worker("--rss-memory", name, kind, str(n))["rss_mb"], memory_tool="RSS")
                    elif name not in RSS_WORKER_METHODS and (not quick or name == NUMPY_GRID):
                        row.update(peak_mb=tracemalloc_peak_mb(methods[name], aabbs), memory_tool="tracemalloc")
                elif name == BRUTE:
                    ten_k = _row(rows, 10_000, kind, BRUTE)
                    row.update(median_ms=ten_k["median_ms"] * (n / 10_000) ** 2, estimated=True)
                rows.append(row)
            if quick and n != 10_000:
                rows += [_empty_row(n, kind, name, "skipped (--quick)") for name in PYMUNK_METHODS]
                continue
            pymunk_rounds = max(rounds, 3)
            worker = run_worker("--pymunk", kind, str(n), str(pymunk_rounds))
            for name in PYMUNK_METHODS:
                row = _empty_row(n, kind, name, "info: what a pymunk user pays" if name == PYMUNK_TREE_FULL else "")
                row.update(median_ms=worker["times_ms"][name], runs=pymunk_rounds,
                           pairs=worker["pairs"][name], pairs_match=worker["pairs"][name] == reference,
                           peak_mb=worker["rss_mb"][name], memory_tool="RSS",
                           grid_ms_alongside=worker["grid_times_ms"][name],
                           numba_ms_alongside=worker["numba_times_ms"][name])
                rows.append(row)
    return rows


def _empty_row(n: int, scene: str, method: str, note: str) -> dict:
    return {"n": n, "scene": scene, "method": method, "median_ms": None, "runs": 0, "estimated": False,
            "pairs": None, "pairs_match": None, "peak_mb": None, "memory_tool": "",
            "grid_ms_alongside": None, "numba_ms_alongside": None, "note": note}


# ------------------------------------------------------------------------ report
def _row(rows, n, scene, method):
    return next((r for r in rows if r["n"] == n and r["scene"] == scene and r["method"] == method), None)


def speedup(rows: list[dict], n: int, scene: str, rival: str, ours: str = NUMPY_GRID) -> float | None:
    """How many times faster ``ours`` (the numpy or the numba grid) is than ``rival``
    (for pymunk, from the paired runs in its worker)."""
    other = _row(rows, n, scene, rival)
    mine = _row(rows, n, scene, ours)
    if rival == ours or other is None or other["median_ms"] is None or mine is None or mine["median_ms"] is None:
        return None
    alongside = other["numba_ms_alongside" if ours == NUMBA_GRID else "grid_ms_alongside"]
    return other["median_ms"] / (alongside or mine["median_ms"])


def goals(rows: list[dict]) -> list[tuple[str, str, float | None, bool | None]]:
    """(goal, scene, measured ratio, met) for the three goals of the brief."""
    out = []
    for scene in SCENES:
        ratio = speedup(rows, 10_000, scene, BRUTE)
        out.append((f"10k: >= {GOAL_BRUTE_RATIO:g}x faster than brute force", scene, ratio,
                    None if ratio is None else ratio >= GOAL_BRUTE_RATIO))
    for scene in SCENES:
        ratios = [r for r in (speedup(rows, 10_000, scene, m) for m in (PYMUNK_TREE, PYMUNK_HASH)) if r is not None]
        ratio = min(ratios) if ratios else None
        out.append((f"10k: >= {GOAL_PYMUNK_RATIO:g}x faster than pymunk (faster index, broad phase)", scene, ratio,
                    None if ratio is None else ratio >= GOAL_PYMUNK_RATIO))
    for scene in SCENES:
        ratio = speedup(rows, 100_000, scene, CKDTREE)
        out.append(("100k: no slower than cKDTree", scene, ratio, None if ratio is None else ratio >= GOAL_CKDTREE_RATIO))
    for scene in SCENES:
        ratio = speedup(rows, 10_000, scene, PYMUNK_HASH, ours=NUMBA_GRID)
        out.append((f"10k: numba grid >= {GOAL_NUMBA_HASH_RATIO:g}x faster than pymunk spatial hash", scene, ratio,
                    None if ratio is None else ratio >= GOAL_NUMBA_HASH_RATIO))
    return out


def report(rows: list[dict]) -> str:
    lines = ["Broad phase benchmark: median CPU time of several runs; 'same' = pair count equals the numpy grid's;",
             "peak = extra memory of one call (see the module docstring for how each rival is timed).", ""]
    header = f"{'N':>7}  {'scene':<9}  {'method':<40} {'median ms':>11} {'runs':>4} {'pairs':>8} {'same':>4} {'peak MB':>8}  note"
    lines += [header, "-" * len(header)]
    for r in rows:
        median = "-" if r["median_ms"] is None else f"{r['median_ms']:.2f}" + ("*" if r["estimated"] else "")
        same = "" if r["pairs_match"] is None else ("yes" if r["pairs_match"] else "NO")
        peak = "-" if r["peak_mb"] is None else f"{r['peak_mb']:.1f} {'T' if r['memory_tool'] == 'tracemalloc' else 'R'}"
        note = r["note"] or ("estimated" if r["estimated"] else "")
        lines.append(f"{r['n']:>7}  {r['scene']:<9}  {r['method']:<40} {median:>11} {r['runs'] or '':>4} "
                     f"{'' if r['pairs'] is None else r['pairs']:>8} {same:>4} {peak:>8}  {note}")
    lines += ["", "* estimated.  Peak MB: T = tracemalloc, R = RSS growth in a worker process.",
              "numba grid: compile time excluded (an untimed warm-up call in each process first)."]
    rivals = [BRUTE, READABLE_GRID, QUADTREE, CKDTREE, NUMPY_GRID, NUMBA_GRID,
              PYMUNK_TREE, PYMUNK_HASH, PYMUNK_TREE_FULL]
    short = ["brute", "read.grid", "quadtree", "cKDTree", "np grid", "nb grid", "pm tree", "pm hash", "pm full"]
    for ours in (NUMPY_GRID, NUMBA_GRID):
        lines += ["", f"How many times faster the {ours.split(' (')[0]} is (pymunk: paired runs in the pymunk worker):"]
        lines.append(f"{'N':>7}  {'scene':<9}  " + " ".join(f"{s:>9}" for s in short))
        for n in sorted({r["n"] for r in rows}):
            for scene in SCENES:
                cells = []
                for rival in rivals:
                    ratio = speedup(rows, n, scene, rival, ours)
                    estimated = (_row(rows, n, scene, rival) or {}).get("estimated")
                    cells.append("-".rjust(9) if ratio is None else f"{ratio:8.1f}{'*' if estimated else 'x'}")
                lines.append(f"{n:>7}  {scene:<9}  " + " ".join(cells))
    lines += ["", "Goals:"]
    for goal, scene, ratio, met in goals(rows):
        verdict = "not measured" if met is None else ("met" if met else "short of it (a figure, not an error)")
        measured = "-" if ratio is None else f"{ratio:.1f}x"
        lines.append(f"  {goal:<66} {scene:<9} {measured:>7}  {verdict}")
    mismatched = [r for r in rows if r["pairs_match"] is False]
    lines.append("")
    lines.append("Pair counts: all equal to the numpy grid's." if not mismatched else
                 "Pair counts DIFFER: " + ", ".join(f"{r['method']} N={r['n']} {r['scene']}" for r in mismatched))
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer runs and methods (see run()), for a smoke run")
    parser.add_argument("--pymunk", nargs=3, metavar=("SCENE", "N", "ROUNDS"), help=argparse.SUPPRESS)
    parser.add_argument("--rss-memory", nargs=3, metavar=("METHOD", "SCENE", "N"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.pymunk:
        pymunk_worker(args.pymunk[0], int(args.pymunk[1]), int(args.pymunk[2]))
    if args.rss_memory:
        rss_memory_worker(args.rss_memory[0], args.rss_memory[1], int(args.rss_memory[2]))
    started = time.perf_counter()
    rows = run(quick=args.quick)
    print(report(rows))
    print(f"\n(total {time.perf_counter() - started:.0f} s{', --quick' if args.quick else ''})")
    return 0 if all(r["pairs_match"] is not False for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
