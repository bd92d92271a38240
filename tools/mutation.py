"""Mutation testing of the graded tests: does every plausible bug in a solution block
lose points?

    python -m tools.mutation [--exercise NAME ...] [--jobs 2] [--limit N] [--out DIR]

Cosmic Ray (``cosmic-ray`` 8.7, from the package index) finds every mutation of the
reference's ``### BEGIN SOLUTION`` blocks (its session database keeps them, those
outside the blocks marked skipped, as its own filters do).  Each mutant is one
operator applied once -- a number changed, ``+`` for ``-``, ``<`` for ``<=``, a
condition negated, a loop that never runs -- and is graded like a submission: a copy
of ``solutions/`` named ``exercises`` with that one change, run in the sandbox by the
public graded tests of its exercise, then the other public ones that can see the
mutated module, then the hidden ones in the same order, each stopping at the first test
that does not pass.  A mutant is killed by the public tests, by the hidden ones, or
survives.  A test file sees a module when a module of the package that it names (or
that a grader module it imports names) imports it (:mod:`tools.mutation_scope`); the
other tests never run the mutated code, so leaving them out changes no outcome and an
exercise's run costs what its own tests cost (``--every-test`` runs them all, to
compare).  The workers' copies of the package and their sandboxes live in one temporary
folder, removed at the end, on Ctrl-C and on SIGTERM.

Mutants that behave exactly as the reference (a change no input can tell apart) are
*equivalent*: each is listed, with the reason, in ``tools/mutation_equivalent.toml``
and left out of the scores.  The command prints per exercise the share of the other
mutants killed by the public and hidden tests together and by the public tests alone,
then every survivor with its diff, and writes ``DIR/mutation.json`` and Cosmic Ray's
session ``DIR/session.sqlite`` (``cr-report DIR/session.sqlite`` reads it).

Operators: arithmetic among ``+ - * /``, comparisons, unary operators, ``and``/``or``,
``True``/``False``, ``not`` added, numbers, ``break``/``continue`` and loops that never
run.  Bitwise and exotic arithmetic replacements on floats (``+`` for ``^``) only make
code that raises at once, which any test kills; they are left out to save time.
"""
from __future__ import annotations

import argparse
import concurrent.futures
import difflib
import hashlib
import json
import os
import re
import shutil
import signal
import sys
import tempfile
import time
import tomllib
from dataclasses import asdict, dataclass
from pathlib import Path

from grader.harness.spec import EXERCISES

REPO = Path(__file__).resolve().parent.parent
SOLUTIONS = REPO / "solutions"
EQUIVALENT_FILE = Path(__file__).resolve().parent / "mutation_equivalent.toml"
BEGIN, END = "### BEGIN SOLUTION", "### END SOLUTION"
KEPT_OPERATORS = re.compile(
    r"(ReplaceBinaryOperator_(Add|Sub|Mul|Div)_(Add|Sub|Mul|Div)$|ReplaceComparisonOperator_|"
    r"ReplaceUnaryOperator_|ReplaceAndWithOr|ReplaceOrWithAnd|ReplaceTrueWithFalse|ReplaceFalseWithTrue|"
    r"AddNot|NumberReplacer|ReplaceBreakWithContinue|ReplaceContinueWithBreak|ZeroIterationForLoop)")


def exercise_of(module: str, function: str) -> str:
    """The exercise a mutated function belongs to: the generator's table, which also
    names the ``grader check`` command in each stub (one table for both)."""
    from grader.release.exercises import exercise_of as table_exercise

    return table_exercise(module, function) or table_exercise(module, function.split(".")[-1]) or "other"


def solution_lines(path: Path) -> list[tuple[int, int]]:
    """(first, last) line numbers (1-based) strictly inside each solution block."""
    blocks, start = [], None
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        if line.strip() == BEGIN:
            start = number
        elif line.strip() == END and start is not None:
            blocks.append((start + 1, number - 1))
            start = None
    return blocks


@dataclass
class Mutant:
    job_id: str
    module: str          # relative to the package, e.g. "broadphase/quadtree.py"
    function: str
    operator: str
    occurrence: int
    line: int
    exercise: str
    key: str = ""        # stable name: module, function, operator and the changed lines
    diff: str = ""
    killed_by: str = ""  # "public", "hidden" or "" (survived); "none" when no mutation applied
    test: str = ""       # the test that killed it
    status: str = ""     # that test's status (failed, error, timeout, ...)
    seconds: float = 0.0


def find_mutants(session: Path, exercises: set[str] | None) -> list[Mutant]:
    """Every kept mutation inside a solution block, recorded in a Cosmic Ray session."""
    from cosmic_ray.commands.init import init
    from cosmic_ray.mutating import mutate_code
    from cosmic_ray.plugins import get_operator
    from cosmic_ray.work_db import WorkDB, use_db
    from cosmic_ray.work_item import WorkerOutcome, WorkResult

    from grader.release.exercises import EXERCISES as EXERCISES_OF_MODULES

    def wanted(path: Path) -> bool:  # a module serving none of the exercises asked for holds no mutant kept
        entry = EXERCISES_OF_MODULES.get(path.relative_to(SOLUTIONS).as_posix(), "other")
        return not exercises or bool(set(entry.values() if isinstance(entry, dict) else [entry]) & exercises)

    files = sorted(p for p in SOLUTIONS.rglob("*.py") if BEGIN in p.read_text(encoding="utf-8") and wanted(p))
    blocks = {path: solution_lines(path) for path in files}
    mutants = []
    with use_db(str(session), WorkDB.Mode.create) as db:
        init(files, db, {})
        skipped = []
        for item in db.work_items:
            spec = item.mutations[0]
            path = Path(spec.module_path)
            module = path.relative_to(SOLUTIONS).as_posix()
            line = spec.start_pos[0]
            inside = any(first <= line <= last for first, last in blocks[path])
            operator = spec.operator_name.split("/")[-1]
            function = spec.definition_name or "?"
            exercise = exercise_of(module, function)
            if not inside or not KEPT_OPERATORS.search(operator) or (exercises and exercise not in exercises):
                skipped.append(item.job_id)
                continue
            source = path.read_text(encoding="utf-8")
            mutated = mutate_code(source, get_operator(spec.operator_name)(**(spec.operator_args or {})),
                                  spec.occurrence)
            if mutated is None or mutated == source:
                skipped.append(item.job_id)
                continue
            diff = "".join(difflib.unified_diff(source.splitlines(True), mutated.splitlines(True),
                                                f"a/{module}", f"b/{module}", n=0))
            changed = [l for l in diff.splitlines() if l[:1] in "+-" and not l.startswith(("+++", "---"))]
            key = f"{module}:{function}:{operator}:" + hashlib.sha1(
                "\n".join(l[0] + l[1:].strip() for l in changed).encode()).hexdigest()[:10]
            mutants.append(Mutant(item.job_id, module, function, spec.operator_name, spec.occurrence, line,
                                  exercise, key, diff))
        db.set_multiple_results(skipped, WorkResult(worker_outcome=WorkerOutcome.SKIPPED))
    seen: dict[str, int] = {}
    for mutant in mutants:  # two identical changes of one function: number them
        seen[mutant.key] = seen.get(mutant.key, 0) + 1
        if seen[mutant.key] > 1:
            mutant.key += f"#{seen[mutant.key]}"
    return mutants


# Workers ------------------------------------------------------------------------------------
_WORKSPACE: Path | None = None
_SLOT = 0
_EVERY_TEST = False


def _start_worker(slots, root: str, every_test: bool = False) -> None:
    """One worker process: its sandbox slot, its copy of the package, all under ``root``
    (the run's temporary folder, removed by the parent whatever happens), where the
    sandboxes' own folders go too.  Interrupting is the parent's job (it ends the workers)."""
    global _WORKSPACE, _SLOT, _EVERY_TEST
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _SLOT, _EVERY_TEST = slots.get(), every_test
    tempfile.tempdir = root
    _WORKSPACE = Path(tempfile.mkdtemp(prefix=f"worker-{_SLOT}-", dir=root))
    shutil.copytree(SOLUTIONS, _WORKSPACE / "exercises", ignore=shutil.ignore_patterns("__pycache__"))


def _graded_tests():
    from grader.harness.run import load_spec

    return load_spec()


def _first_failure(run_tests, tests: list, limits):
    """The first of ``tests`` that does not pass on this worker's copy, or None.

    Each run has a budget of 60 s (a mutant that loops stops there); tests it leaves
    unstarted (``not_run``: a long group on a loaded machine) run again in a run of their
    own, so only a test that ran and did not pass kills a mutant."""
    while tests:
        results = run_tests(_WORKSPACE, tests, limits, slot=_SLOT, budget_seconds=60, exitfirst=True)
        failing = [r for r in results if r.outcome.status not in ("passed", "not_run")]
        if failing:
            return failing[0]
        ran = {r.test.name for r in results if r.outcome.status == "passed"}
        if not ran:  # nothing could start: count it, as before
            left = [r for r in results if r.outcome.status != "passed"]
            return left[0] if left else None
        tests = [t for t in tests if t.name not in ran]
    return None


def grade_mutant(mutant: Mutant) -> Mutant:
    """Apply the mutant in this worker's copy, run the tests that can see it in order
    (:func:`tools.mutation_scope.tests_seeing`), restore the copy."""
    from cosmic_ray.mutating import mutate_code
    from cosmic_ray.plugins import get_operator
    from grader.harness.run import run_tests
    from grader.sandbox.process import Limits
    from tools.mutation_scope import tests_seeing

    started = time.perf_counter()
    target = _WORKSPACE / "exercises" / mutant.module
    source = (SOLUTIONS / mutant.module).read_text(encoding="utf-8")
    mutated = mutate_code(source, get_operator(mutant.operator)(), mutant.occurrence)
    if mutated is None:
        mutant.killed_by = "none"
        return mutant
    groups = tests_seeing(mutant.module, mutant.exercise, _graded_tests(), every=_EVERY_TEST)
    limits = Limits(call_timeout=5.0, cpu_seconds=60)
    try:
        target.write_text(mutated, encoding="utf-8")
        for suite, chosen in groups:
            failing = _first_failure(run_tests, chosen, limits)
            if failing is not None:
                mutant.killed_by, mutant.test, mutant.status = suite, failing.test.name, failing.outcome.status
                break
    finally:
        target.write_text(source, encoding="utf-8")
    mutant.seconds = round(time.perf_counter() - started, 2)
    return mutant


def _stop_on_sigterm(signum, frame):
    raise SystemExit(128 + signum)


def _result(future: concurrent.futures.Future):
    """The future's result, waited for a second at a time: a signal handled by another
    thread of this process then still reaches this one (a wait without end never returns
    to Python to run the handler)."""
    while True:
        try:
            return future.result(timeout=1.0)
        except concurrent.futures.TimeoutError:
            continue


def run_mutants(mutants: list[Mutant], jobs: int, progress=None, every_test: bool = False) -> list[Mutant]:
    """Grade ``mutants`` in ``jobs`` worker processes, in a temporary folder that is gone
    when this returns or raises (Ctrl-C and SIGTERM included: the workers, and the
    sandboxes they started, are ended first)."""
    import multiprocessing

    context = multiprocessing.get_context("forkserver")
    slots = context.SimpleQueue()
    for slot in range(jobs):
        slots.put(slot)
    done = []
    previous = signal.signal(signal.SIGTERM, _stop_on_sigterm)
    try:
        with tempfile.TemporaryDirectory(prefix="mutation-", ignore_cleanup_errors=True) as root:
            pool = concurrent.futures.ProcessPoolExecutor(jobs, mp_context=context, initializer=_start_worker,
                                                          initargs=(slots, root, every_test))
            try:
                for future in [pool.submit(grade_mutant, mutant) for mutant in mutants]:
                    mutant = _result(future)
                    done.append(mutant)
                    if progress is not None:
                        progress(mutant, len(done), len(mutants))
            except BaseException:
                # Not wait for the queued mutants: end the workers (their sandboxes die with
                # them, bubblewrap's --die-with-parent) before the folder is removed.
                for process in list((getattr(pool, "_processes", None) or {}).values()):
                    process.terminate()
                pool.shutdown(wait=True, cancel_futures=True)
                raise
            pool.shutdown(wait=True)
    finally:
        signal.signal(signal.SIGTERM, previous)
    return done


def record(session: Path, mutants: list[Mutant]) -> None:
    """The outcomes into Cosmic Ray's session, so its reports read them."""
    from cosmic_ray.work_db import WorkDB, use_db
    from cosmic_ray.work_item import TestOutcome, WorkerOutcome, WorkResult

    with use_db(str(session), WorkDB.Mode.open) as db:
        for m in mutants:
            if m.killed_by == "none":
                db.set_result(m.job_id, WorkResult(worker_outcome=WorkerOutcome.NO_TEST))
                continue
            outcome = TestOutcome.KILLED if m.killed_by else TestOutcome.SURVIVED
            db.set_result(m.job_id, WorkResult(worker_outcome=WorkerOutcome.NORMAL, test_outcome=outcome,
                                               output=f"{m.killed_by or 'survived'} {m.test}".strip(), diff=m.diff))


def equivalent_mutants(path: Path = EQUIVALENT_FILE) -> dict[str, str]:
    """key -> reason, from the reviewed list."""
    if not path.is_file():
        return {}
    data = tomllib.loads(path.read_text(encoding="utf-8"))
    out = {}
    for entry in data.get("mutant", []):
        if not entry.get("reason", "").strip():
            raise ValueError(f"{path}: the equivalent mutant {entry.get('key')!r} needs a reason")
        out[str(entry["key"])] = str(entry["reason"])
    return out


def scores(mutants: list[Mutant], equivalent: dict[str, str]) -> dict[str, dict]:
    """Per exercise: mutants, equivalent, killed by public, by all, and the two shares."""
    table: dict[str, dict] = {}
    for m in mutants:
        if m.killed_by == "none":
            continue
        row = table.setdefault(m.exercise, {"mutants": 0, "equivalent": 0, "public": 0, "all": 0, "survivors": []})
        row["mutants"] += 1
        if m.key in equivalent:
            row["equivalent"] += 1
            continue
        row["public"] += m.killed_by == "public"
        row["all"] += m.killed_by in ("public", "hidden")
        if not m.killed_by:
            row["survivors"].append(m.key)
    for row in table.values():
        counted = row["mutants"] - row["equivalent"]
        row["public_share"] = row["public"] / counted if counted else 1.0
        row["all_share"] = row["all"] / counted if counted else 1.0
    return table


def format_table(table: dict[str, dict]) -> str:
    lines = ["| exercise | mutants | equivalent | killed (public + hidden) | killed (public alone) |",
             "| --- | --- | --- | --- | --- |"]
    for exercise in sorted(table):
        row = table[exercise]
        lines.append(f"| {exercise} | {row['mutants']} | {row['equivalent']} | {row['all_share']:.1%} "
                     f"({row['all']}) | {row['public_share']:.1%} ({row['public']}) |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tools.mutation", description=__doc__.split("\n\n")[0])
    parser.add_argument("--exercise", action="append", default=None,
                        help="only this exercise's mutants (repeatable): " + ", ".join(EXERCISES))
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--limit", type=int, default=None, help="grade only every k-th mutant so that about N run")
    parser.add_argument("--out", default="out/mutation")
    parser.add_argument("--every-test", action="store_true",
                        help="grade each mutant by every graded test, not only those that can see its module "
                             "(slower; the same scores, which this checks)")
    parser.add_argument("--rescore", action="store_true",
                        help="print the scores of DIR/mutation.json again (after editing the equivalent list)")
    args = parser.parse_args(argv)
    if args.rescore:
        data = json.loads((Path(args.out) / "mutation.json").read_text(encoding="utf-8"))
        graded = [Mutant(**m) for m in data["mutants"]]
        for mutant in graded:
            mutant.exercise = exercise_of(mutant.module, mutant.function)
        equivalent = equivalent_mutants()
        print(format_table(scores(graded, equivalent)))
        return 0
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    session = out / "session.sqlite"
    mutants = find_mutants(session, set(args.exercise) if args.exercise else None)
    if args.limit and len(mutants) > args.limit:
        step = len(mutants) / args.limit
        mutants = [mutants[int(i * step)] for i in range(args.limit)]
    print(f"{len(mutants)} mutants in the solution blocks; grading them with {args.jobs} jobs", flush=True)
    started = time.perf_counter()

    def progress(mutant, done, total):
        if done % 25 == 0 or done == total:
            print(f"  {done}/{total} graded ({time.perf_counter() - started:.0f} s)", flush=True)

    try:
        graded = run_mutants(mutants, args.jobs, progress, every_test=args.every_test)
    except KeyboardInterrupt:
        print("interrupted: nothing graded is kept (the workers and their folders are gone)", file=sys.stderr)
        return 130
    record(session, graded)
    equivalent = equivalent_mutants()
    table = scores(graded, equivalent)
    (out / "mutation.json").write_text(json.dumps({"scores": table, "mutants": [asdict(m) for m in graded]},
                                                  indent=1), encoding="utf-8")
    print(format_table(table))
    survivors = [m for m in graded if not m.killed_by and m.key not in equivalent]
    if survivors:
        print(f"\n{len(survivors)} survivors (add an equivalent one to {EQUIVALENT_FILE.name} with a reason):")
        for m in survivors:
            print(f"\n{m.key}  ({m.exercise}, line {m.line})\n{m.diff.rstrip()}")
    print(f"\n{time.perf_counter() - started:.0f} s; details in {out / 'mutation.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
