"""Grading speed: one submission end to end, and a class at ``--jobs 2``.

    python bench/bench_grading.py [--quick] [--count 100] [--jobs 2]

Submissions are copies of the reference engine (``solutions/`` handed in as
``exercises/``, every test runs to the end) and of the stubs (``exercises/``, every
test stops at the first call), half each; the reference copies are folders, the stubs
zips, so extraction is timed too.  Prints

- the wall-clock seconds of ``python -m grader.grade`` on one submission (process
  start, spec, worker start, every public and hidden test), reference and stubs,
  against the goal of 10 s;
- a class of ``--count`` submissions at ``--jobs``: total seconds, seconds per
  submission, and the goal (5 minutes per 100 submissions at ``--jobs 2``);
- the same command again, where everything is skipped.

The load average is printed too: on a shared machine it explains slow figures.
This is a benchmark that reports figures, not a test that fails.
"""
from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from grader.grade import grade_submissions  # noqa: E402

GOAL_ONE_SECONDS = 10.0
GOAL_CLASS_SECONDS_PER_100 = 300.0
IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc")


def folder_copy(package: Path, path: Path) -> Path:
    shutil.copytree(package, path / "exercises", ignore=IGNORE)
    return path


def zip_copy(package: Path, path: Path) -> Path:
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        for file in sorted(package.rglob("*")):
            if file.is_file() and "__pycache__" not in file.parts:
                archive.write(file, "exercises/" + file.relative_to(package).as_posix())
    return path


def load() -> str:
    return "load average %.1f %.1f %.1f" % os.getloadavg()


def one_submission(submission: Path, out: Path) -> float:
    started = time.perf_counter()
    subprocess.run([sys.executable, "-m", "grader.grade", str(submission), "--out", str(out), "--jobs", "1",
                    "--no-progress", "--no-html"], cwd=REPO, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - started


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a class of 10, for a smoke run")
    parser.add_argument("--count", type=int, default=100, help="submissions in the class (default 100)")
    parser.add_argument("--jobs", type=int, default=2, help="parallel jobs (default 2)")
    args = parser.parse_args(argv)
    count = 10 if args.quick else args.count
    print(f"{os.cpu_count()} cores, {load()}")
    with tempfile.TemporaryDirectory(prefix="bench-grading-") as scratch:
        scratch = Path(scratch)
        reference = folder_copy(REPO / "solutions", scratch / "one" / "reference")
        stubs = zip_copy(REPO / "exercises", scratch / "one" / "stubs.zip")
        print("\none submission, `python -m grader.grade` end to end (goal: at most "
              f"{GOAL_ONE_SECONDS:g} s)")
        for name, submission in (("reference", reference), ("stubs", stubs)):
            seconds = one_submission(submission, scratch / f"out-{name}")
            print(f"  {name:10s} {seconds:6.2f} s   {'ok' if seconds <= GOAL_ONE_SECONDS else 'OVER THE GOAL'}")

        subs = scratch / "class"
        subs.mkdir()
        paths = []
        for number in range(count):
            if number % 2 == 0:
                paths.append(folder_copy(REPO / "solutions", subs / f"ref{number:03d}"))
            else:
                paths.append(zip_copy(REPO / "exercises", subs / f"stub{number:03d}.zip"))
        goal = GOAL_CLASS_SECONDS_PER_100 * count / 100
        print(f"\na class of {count} ({(count + 1) // 2} reference folders, {count // 2} stub zips) at "
              f"--jobs {args.jobs} (goal: at most {goal:g} s)")
        started = time.perf_counter()
        rows = grade_submissions(paths, scratch / "out-class", jobs=args.jobs, progress=False, html=False)
        seconds = time.perf_counter() - started
        wrong = [r["id"] for r in rows if r["state"] != "graded"
                 or (r["id"].startswith("ref") and r["score"] != r["max_score"])
                 or (r["id"].startswith("stub") and r["score"] != 0)]
        print(f"  total      {seconds:6.1f} s   {'ok' if seconds <= goal else 'OVER THE GOAL'}")
        print(f"  per submission {seconds / count:6.2f} s wall clock, {seconds * args.jobs / count:6.2f} s per job")
        if wrong:
            print(f"  UNEXPECTED SCORES: {wrong}")
        started = time.perf_counter()
        rows = grade_submissions(paths, scratch / "out-class", jobs=args.jobs, progress=False, html=False)
        skipped = sum(r["state"] == "skipped" for r in rows)
        print(f"  rerun      {time.perf_counter() - started:6.2f} s   ({skipped} of {count} skipped)")
    print(f"\n{load()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
