"""Every benchmark of the project in one run: broad phase, batch SAT, world step.

    python bench/run_all.py [--quick]

Each benchmark prints its own table of medians and ratios measured side by side.
"""
from __future__ import annotations

import argparse
import runpy
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
BENCHMARKS = ["bench_broadphase.py", "bench_sat.py", "bench_world.py", "bench_hard_cases.py"]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="small sizes, for a smoke run")
    args = parser.parse_args(argv)
    for name in BENCHMARKS:
        print(f"\n=== {name} ===", flush=True)
        started = time.perf_counter()
        sys.argv = [name] + (["--quick"] if args.quick else [])
        try:
            runpy.run_path(str(HERE / name), run_name="__main__")
        except SystemExit as exc:
            if exc.code not in (0, None):
                print(f"{name} exited with {exc.code}", file=sys.stderr)
                return int(exc.code) if isinstance(exc.code, int) else 1
        print(f"({name}: {time.perf_counter() - started:.1f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
