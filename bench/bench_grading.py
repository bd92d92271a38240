"""Grading speed: processor time per submission, where it goes, and a class at ``--jobs 2``.

    python bench/bench_grading.py [--quick] [--count 100] [--jobs 2] [--slope 4]

Submissions are copies of the reference engine (``solutions/`` handed in as
``exercises/``, every test runs to the end) and of the stubs (``exercises/``, every
test stops at the first call); the reference copies are folders, the stubs zips, so
extraction is timed too.  Processor time is that of every process a command starts,
the sandboxed workers included, measured through a cgroup of its own
(:mod:`cgroup_cpu`; the method used is printed first; without a cgroup it falls back to
``getrusage``, which misses the sandboxes).  Prints

- ``grader grade`` on one submission in a new process (start, test collection, worker
  start, every public and hidden test), reference and stubs;
- the processor time per submission: ``grader grade`` on 1 and on ``--slope`` reference
  copies (new processes, ``--jobs 1``), (CPU(N) - CPU(1)) / (N - 1) (goal: at most 3 s),
  and the start-up cost, CPU(1) less that;
- where one submission's time goes (:mod:`grading_phases`: a reference copy graded in
  this process after a first one warmed it up), phase by phase, and the tests that
  cost most;
- ``grader similarity`` on the ``--slope`` copies, per submission;
- a class of ``--count`` submissions (half reference, half stubs) at ``--jobs``: total
  seconds against the goal (3 minutes per 100 submissions at ``--jobs 2``), processor
  time per submission, and the same command again, where everything is skipped.

The load average is printed too: on a shared machine it explains slow figures (other
jobs on the same cores also make each processor second do less).
This is a benchmark that reports figures, not a test that fails.
"""
from __future__ import annotations

import argparse
import csv
import os
import shutil
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
sys.path[:0] = [str(HERE), str(REPO)]

from cgroup_cpu import CpuMeter  # noqa: E402

GOAL_PROCESSOR_SECONDS = 3.0
GOAL_CLASS_SECONDS_PER_100 = 180.0
IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc")
GRADE = [sys.executable, "-m", "grader.batch.grade", "--no-progress"]
#: Tests listed by cost in the phase split.
COSTLIEST = 12


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


def grade(meter: CpuMeter, submissions: list[Path], out: Path, jobs: int = 1) -> tuple[float, float, str]:
    """(wall, processor) seconds of one `python -m grader.batch.grade` run (no HTML), every
    process counted, and its summary line."""
    started = time.perf_counter()
    summary = out.parent / f"{out.name}.txt"
    with open(summary, "w") as handle:
        processor = meter.run(GRADE + [*map(str, submissions), "--out", str(out), "--jobs", str(jobs), "--no-html"],
                              cwd=REPO, stdout=handle)
    return time.perf_counter() - started, processor, summary.read_text().splitlines()[0]


def scores(out: Path) -> dict[str, tuple[float, float]]:
    """{submission: (score, max_score)} from the gradebook."""
    with open(out / "gradebook.csv", newline="") as handle:
        return {row["submission"]: (float(row["score"] or 0), float(row["max_score"] or 0))
                for row in csv.DictReader(handle)}


def cpu_inflation(runs: int = 9) -> float:
    """How many processor seconds a second of an idle machine's work takes now: other jobs on
    the same cores (caches, switches) make each do less.  The fixed work of
    :func:`grader.batch.calibration.reference_work` timed in processor time (fastest of
    ``runs``) over its idle wall-clock figure."""
    from grader.batch.calibration import NOMINAL_SECONDS, reference_work

    best = float("inf")
    for _ in range(runs):
        started = time.process_time()
        reference_work()
        best = min(best, time.process_time() - started)
    return best / NOMINAL_SECONDS


def verdict(met: bool) -> str:
    return "goal met" if met else "short of the goal (a figure, not an error)"


def per_submission(meter: CpuMeter, scratch: Path, count: int) -> tuple[float, float, float, list[Path]]:
    """(per submission, start-up, per submission on an idle machine) processor seconds:
    ``grader grade`` on 1 and on ``count`` copies.  The idle figure divides each run's
    seconds by the inflation (:func:`cpu_inflation`) measured around it, so that a load
    that changes between the two runs does not land in the difference."""
    copies = [folder_copy(REPO / "solutions", scratch / "slope" / f"ref{n}") for n in range(count)]
    figures = []
    for chosen in (copies[:1], copies):
        before = cpu_inflation()
        _, seconds, _ = grade(meter, chosen, scratch / f"out-slope-{len(chosen)}")
        figures.append((seconds, seconds / ((before + cpu_inflation()) / 2)))
    (one, one_idle), (many, many_idle) = figures
    per = (many - one) / (count - 1)
    return per, one - per, (many_idle - one_idle) / (count - 1), copies


def print_phases(found: dict) -> None:
    phases = found["phases"]
    total = sum(phases.values())
    print(f"  {total:6.2f} s in all ({found['passed']} of {found['count']} tests passed):")
    for label, seconds in phases.items():
        print(f"  {seconds:6.2f} s  {100 * seconds / total:4.1f} %  {label}")
    print(f"  of the trusted seconds, {found['scenes']:.2f} s are those of the tests stepping a scene with the "
          "student's functions (StudentCode.run_program)")
    print(f"  the {COSTLIEST} costliest tests (trusted + sandboxed s):")
    for name, trusted, sandboxed, stepped in sorted(found["per_test"], key=lambda row: -(row[1] + row[2]))[:COSTLIEST]:
        print(f"    {trusted + sandboxed:5.2f} = {trusted:5.2f} + {sandboxed:5.2f}  {name}"
              + ("  (stepped scene)" if stepped else ""))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a class of 10 and a slope over 3, for a smoke run")
    parser.add_argument("--count", type=int, default=100, help="submissions in the class (default 100)")
    parser.add_argument("--jobs", type=int, default=2, help="parallel jobs (default 2)")
    parser.add_argument("--slope", type=int, default=4, help="reference copies of the slope (default 4)")
    args = parser.parse_args(argv)
    count = 10 if args.quick else args.count
    slope = 3 if args.quick else max(2, args.slope)
    meter = CpuMeter()
    print(f"{os.cpu_count()} cores, {load()}\nprocessor time: {meter.method}")
    try:
        with tempfile.TemporaryDirectory(prefix="bench-grading-") as scratch:
            run(Path(scratch), meter, count, slope, args.jobs)
    finally:
        meter.close()
    print(f"\n{load()}")
    return 0


def run(scratch: Path, meter: CpuMeter, count: int, slope: int, jobs: int) -> None:
    reference = folder_copy(REPO / "solutions", scratch / "one" / "reference")
    stubs = zip_copy(REPO / "exercises", scratch / "one" / "stubs.zip")
    print("\none submission, `python -m grader.batch.grade` end to end (a new process: imports and test "
          "collection included)")
    for name, submission in (("reference", reference), ("stubs", stubs)):
        wall, processor, _ = grade(meter, [submission], scratch / f"out-{name}")
        print(f"  {name:10s} {wall:6.2f} s wall clock, {processor:6.2f} s of processor time")

    per, startup, idle, copies = per_submission(meter, scratch, slope)
    print(f"\nthe reference, every public and hidden test, per submission: `grader grade` on 1 and on {slope} "
          f"copies, --jobs 1 (goal: at most {GOAL_PROCESSOR_SECONDS:g} s of processor time)\n"
          f"  {per:6.2f} s per submission   {verdict(per <= GOAL_PROCESSOR_SECONDS)}\n"
          f"  {startup:6.2f} s once per run (start, imports, test collection, workers' start)\n"
          f"  about {idle:6.2f} s per submission on an idle machine (each run's seconds divided by how much "
          "less a processor second does under the load around it, grader.batch.calibration's work timed in "
          "processor time; a rough figure, the load of other jobs varies)")

    started = time.perf_counter()
    processor = meter.run([sys.executable, "-m", "grader", "similarity", *map(str, copies), "--out",
                           str(scratch / "out-similarity")], cwd=REPO, stdout=subprocess.DEVNULL)
    print(f"\n`grader similarity` on the {slope} copies: {processor / slope:.2f} s of processor time per "
          f"submission ({time.perf_counter() - started:.1f} s wall clock in all; it compares every pair)")

    from grading_phases import phase_split   # imports the grader into this process

    print("\nwhere one reference submission's processor time goes (graded in this process after a first one)")
    print_phases(phase_split(copies[:2], meter, scratch / "phases"))

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
          f"--jobs {jobs} (goal: at most {goal:g} s)")
    seconds, processor, _ = grade(meter, paths, scratch / "out-class", jobs)
    found = scores(scratch / "out-class")
    wrong = sorted(name for name, (score, most) in found.items()
                   if (name.startswith("ref") and score != most) or (name.startswith("stub") and score != 0))
    wrong += sorted({p.stem for p in paths} - set(found))
    print(f"  total      {seconds:6.1f} s   {verdict(seconds <= goal)}")
    print(f"  per submission {seconds / count:6.2f} s wall clock, {seconds * jobs / count:6.2f} s per job")
    print(f"  processor time {processor / count:6.2f} s per submission on average (reference and stubs alike, "
          "start-up included)")
    if wrong:
        print(f"  UNEXPECTED SCORES: {wrong}")
    seconds, _, said = grade(meter, paths, scratch / "out-class", jobs)
    print(f"  rerun      {seconds:6.2f} s   ({said})")


if __name__ == "__main__":
    sys.exit(main())
