"""Grading speed: one submission end to end, and a class at ``--jobs 2``.

    python bench/bench_grading.py [--quick] [--count 100] [--jobs 2]

Submissions are copies of the reference engine (``solutions/`` handed in as
``exercises/``, every test runs to the end) and of the stubs (``exercises/``, every
test stops at the first call), half each; the reference copies are folders, the stubs
zips, so extraction is timed too.  Prints

- the wall-clock and processor seconds of ``python -m grader.batch.grade`` on one
  submission (process start, collecting the graded tests, worker start, every public
  and hidden test), reference and stubs;
- a class of ``--count`` submissions at ``--jobs``: total seconds against the goal
  (3 minutes per 100 submissions at ``--jobs 2``), and the processor seconds per
  submission once the grading processes are warm (goal: at most 3 s for the
  reference, every public and hidden test);
- the same command again, where everything is skipped.

Processor time is the grader's and every process it started and waited for (the
sandboxed workers included), from ``getrusage``.

The load average is printed too: on a shared machine it explains slow figures.
This is a benchmark that reports figures, not a test that fails.
"""
from __future__ import annotations

import argparse
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from grader.batch.grade import grade_submissions  # noqa: E402

GOAL_PROCESSOR_SECONDS = 3.0
GOAL_CLASS_SECONDS_PER_100 = 180.0
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


def children_seconds() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def one_submission(submission: Path, out: Path) -> tuple[float, float]:
    """(wall, processor) seconds of one `python -m grader.batch.grade` run."""
    started, processor = time.perf_counter(), children_seconds()
    subprocess.run([sys.executable, "-m", "grader.batch.grade", str(submission), "--out", str(out), "--jobs", "1",
                    "--no-progress", "--no-html"], cwd=REPO, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - started, children_seconds() - processor


def verdict(met: bool) -> str:
    return "goal met" if met else "short of the goal (a figure, not an error)"


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
        print("\none submission, `python -m grader.batch.grade` end to end (a new process: imports and test "
              "collection included)")
        for name, submission in (("reference", reference), ("stubs", stubs)):
            wall, processor = one_submission(submission, scratch / f"out-{name}")
            print(f"  {name:10s} {wall:6.2f} s wall clock, {processor:6.2f} s of processor time")

        # One grading process grading 1 and then 5 submissions: the difference is the
        # processor time of 4 submissions without the process start and test collection.
        warm = [folder_copy(REPO / "solutions", scratch / "warm" / f"ref{n}") for n in range(6)]
        processor = children_seconds()
        grade_submissions(warm[:1], scratch / "out-warm-1", jobs=1, progress=False, html=False)
        one = children_seconds() - processor
        processor = children_seconds()
        grade_submissions(warm[1:], scratch / "out-warm-5", jobs=1, progress=False, html=False)
        five = children_seconds() - processor
        per = (five - one) / 4
        print(f"\nthe reference, every public and hidden test, in a running grading process (goal: at most "
              f"{GOAL_PROCESSOR_SECONDS:g} s of processor time)\n  {per:6.2f} s per submission   "
              f"{verdict(per <= GOAL_PROCESSOR_SECONDS)}")

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
        started, processor = time.perf_counter(), children_seconds()
        rows = grade_submissions(paths, scratch / "out-class", jobs=args.jobs, progress=False, html=False)
        seconds = time.perf_counter() - started
        processor = children_seconds() - processor
        wrong = [r["id"] for r in rows if r["state"] != "graded"
                 or (r["id"].startswith("ref") and r["score"] != r["max_score"])
                 or (r["id"].startswith("stub") and r["score"] != 0)]
        print(f"  total      {seconds:6.1f} s   {verdict(seconds <= goal)}")
        print(f"  per submission {seconds / count:6.2f} s wall clock, {seconds * args.jobs / count:6.2f} s per job")
        print(f"  processor time {processor / count:6.2f} s per submission on average (reference and stubs "
              "alike, warm workers)")
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
