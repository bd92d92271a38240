"""The solver kernel's two twins side by side: time per ContactSolver.solve() on the
contacts of pyramids of boxes (no narrow phase), readable Python against numba.

    python bench/bench_solver.py [--quick]

The boxes start each solve at rest plus one step of gravity; the figure is the fastest
of several warm-started solves (other processes only add time), processor time.  The
numba twin is compiled (or loaded from its cache) before timing.  Prints one table and
the speed-up of the compiled twin, measured in this run.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from solutions.response.contact_solver import ContactSolver, SolverSettings  # noqa: E402
from solutions.response.pyramid_contacts import pyramid_contacts  # noqa: E402


def best_solve_seconds(bodies, manifolds, settings: SolverSettings, backend: str, repeats: int,
                       dt: float = 1 / 60) -> float:
    solver = ContactSolver(settings, backend=backend)
    best = float("inf")
    for _ in range(repeats):
        for body in bodies[1:]:
            body.velocity = np.array((0.0, -9.81 * dt))
            body.angular_velocity = 0.0
        start = time.process_time()
        solver.solve(bodies, manifolds, dt)
        best = min(best, time.process_time() - start)
    return best


def run(quick: bool = False) -> list[dict]:
    rows = []
    bases = (10,) if quick else (10, 20)
    repeats = 3 if quick else 10
    for base in bases:
        bodies, manifolds = pyramid_contacts(base)
        points = sum(len(c.points) for _, _, c in manifolds)
        for iterations in (10, 30):
            times = {}
            for backend in ("python", "numba"):
                settings = SolverSettings(iterations=iterations)
                best_solve_seconds(bodies, manifolds, settings, backend, 1)      # compile / warm up
                times[backend] = best_solve_seconds(bodies, manifolds, settings, backend, repeats)
            rows.append({"boxes": len(bodies) - 1, "points": points, "iterations": iterations,
                         "python_ms": 1e3 * times["python"], "numba_ms": 1e3 * times["numba"],
                         "speedup": times["python"] / max(times["numba"], 1e-9)})
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args(argv)
    print("ContactSolver.solve() on pyramid contacts, best processor time (ms): readable kernel vs numba twin")
    print(f"{'boxes':>6} {'points':>7} {'iterations':>10} {'python':>10} {'numba':>10} {'speed-up':>9}")
    for row in run(args.quick):
        print(f"{row['boxes']:>6} {row['points']:>7} {row['iterations']:>10} {row['python_ms']:>10.2f} "
              f"{row['numba_ms']:>10.3f} {row['speedup']:>8.0f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
