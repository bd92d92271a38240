"""Per-function loss table: does a systematic bug in one exercise function lose at least
half of that function's points?

    python -m tools.function_losses [--out DIR] [--slot N]

A function's points are those of the graded tests that reach it, as the example class's
probe measures (:func:`grader.samples.example_class.grade_probe`: the reference with every
exercise function announcing itself), whether they call it directly or through another
exercise function.  The systematic bugs are the example class's samples
(:data:`~grader.samples.example_class.BUGGY_SAMPLES`) and the shortcuts of
:mod:`grader.samples.shortcuts`, each graded with the tests reaching the functions it
rewrites (a test that reaches none of them runs the very code the reference runs; tests
through a caller blind to the bug, :data:`grader.samples.shortcuts.BLIND_CALLERS`, are not
at stake).  The command prints, per bug, the points at stake, the points it loses and the
share, then per exercise function the worst share of the bugs in it and the functions no
bug covers; it writes ``DIR/function_losses.json``.  Exit status 1 if a bug
loses less than half of its points at stake or a failed test keeps more than half of its own.
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

from grader.harness.run import load_spec, run_tests
from grader.samples.example_class import (BUGGY_SAMPLES, BuggySample, build_buggy_sample, exercise_functions_flat,
                                          grade_probe, loses_enough, sample_functions)
from grader.samples.shortcuts import BLIND_CALLERS, SHORTCUTS


def systematic_bugs() -> list[BuggySample]:
    """The example class's samples, then the shortcuts (as samples expecting nothing)."""
    return list(BUGGY_SAMPLES) + [BuggySample(name=name, mistake="a shortcut (grader/samples/shortcuts.py)",
                                              erratum=0, replacements=replacements, expected_failures=frozenset())
                                  for name, replacements in SHORTCUTS.items()]


def at_stake(functions: frozenset[str], reached: dict, blind: frozenset[str] = frozenset()) -> set[str]:
    """The tests reaching any of ``functions`` (all of them if the probe saw none reached),
    but none of the ``blind`` callers (:data:`grader.samples.shortcuts.BLIND_CALLERS`)."""
    return {name for name, found in reached.items() if found is None or (found & functions and not found & blind)}


def measure(slot: int = 0, progress=print, only: set[str] | None = None) -> dict:
    """Grade the probe and every bug (those named in ``only``, if given):
    ``{"functions": {function: points}, "bugs": [...]}``."""
    tests = load_spec()
    points = {t.name: t.points for t in tests}
    started = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        reached, results = grade_probe(tests, Path(folder), slot=slot)
        wrong = [r.test.name for r in results if r.outcome.status != "passed"]
        if wrong:
            raise SystemExit(f"the reference fails {wrong}: fix that first")
        progress(f"probe: {time.perf_counter() - started:.0f} s")
        functions = {f: sum(points[n] for n in at_stake(frozenset({f}), reached))
                     for f in exercise_functions_flat()}
        bugs = []
        for bug in systematic_bugs():
            if only and bug.name not in only:
                continue
            rewritten = sample_functions(bug)
            names = at_stake(rewritten, reached, frozenset(BLIND_CALLERS.get(bug.name, ())))
            sample = build_buggy_sample(bug, Path(folder))
            graded = run_tests(sample, [t for t in tests if t.name in names], slot=slot)
            lost = {r.test.name: round(r.test.points - r.score, 4) for r in graded if r.score < r.test.points}
            keeps_more = sorted(r.test.name for r in graded
                                if r.outcome.status != "passed" and not loses_enough(r.test.points, r.score))
            bugs.append({"name": bug.name, "functions": sorted(rewritten), "at_stake": sum(points[n] for n in names),
                         "lost": round(sum(lost.values()), 4), "tests_lost": lost,
                         "failed_tests_keeping_more_than_half": keeps_more})
            progress(f"{bug.name}: loses {bugs[-1]['lost']:g} of {bugs[-1]['at_stake']:g}")
    return {"functions": functions, "bugs": bugs}


def short(function: str) -> str:
    """``module.qualname`` without the package's first folder: ``polygon_polygon.clip_segment_to_half_plane``."""
    return function.split(".", 1)[1] if function.count(".") > 1 else function


def format_tables(data: dict) -> str:
    lines = ["| systematic bug | function(s) | points at stake | lost | share |", "| --- | --- | --- | --- | --- |"]
    for bug in data["bugs"]:
        share = bug["lost"] / bug["at_stake"] if bug["at_stake"] else 1.0
        flag = "" if share >= 0.5 - 1e-9 else " **under half**"
        lines.append(f"| {bug['name']} | {', '.join(short(f) for f in bug['functions'])} | {bug['at_stake']:g} | "
                     f"{bug['lost']:g} | {share:.0%}{flag} |")
    lines += ["", "| exercise function | its points | bugs | least lost |", "| --- | --- | --- | --- |"]
    for function, points in data["functions"].items():
        mine = [b for b in data["bugs"] if function in b["functions"]]
        worst = min(mine, key=lambda b: b["lost"] / b["at_stake"] if b["at_stake"] else 1.0, default=None)
        least = f"{worst['lost']:g} of {worst['at_stake']:g} ({worst['name']})" if worst else "no bug sample"
        lines.append(f"| {short(function)} | {points:g} | {len(mine)} | {least} |")
    return "\n".join(lines)


def problems(data: dict) -> list[str]:
    out = [f"{b['name']} loses {b['lost']:g} of {b['at_stake']:g}: less than half" for b in data["bugs"]
           if b["lost"] < b["at_stake"] / 2 - 1e-9]
    out += [f"{b['name']}: {name} keeps more than half its points" for b in data["bugs"]
            for name in b["failed_tests_keeping_more_than_half"]]
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tools.function_losses", description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="out/function-losses")
    parser.add_argument("--slot", type=int, default=0, help="sandbox user slot (parallel graders use different ones)")
    parser.add_argument("--bug", action="append", default=None, help="only this bug (repeatable)")
    args = parser.parse_args(argv)
    data = measure(args.slot, progress=lambda text: print(text, file=sys.stderr, flush=True),
                   only=set(args.bug) if args.bug else None)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "function_losses.json").write_text(json.dumps(data, indent=1), encoding="utf-8")
    print(format_tables(data))
    found = problems(data)
    for problem in found:
        print(f"PROBLEM: {problem}")
    return int(bool(found))


if __name__ == "__main__":
    sys.exit(main())
