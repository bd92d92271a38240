"""Run a list of tests on one student package and score them.

Every check runs in the trusted process; the student's code runs in a sandboxed
worker (:mod:`grader.sandbox`), started once per submission and restarted after a
crash or a timeout.  Checks that measure speed also get a second sandbox holding the
reference engine, so that both are timed side by side in the same run.
"""
from __future__ import annotations

import inspect
import time
import traceback
from dataclasses import dataclass
from pathlib import Path

from .checks import load_all
from .outcome import Outcome, StudentCallFailed
from .sandbox import Limits, Sandbox
from .spec import TestSpec
from .student import StudentCode

REPO_ROOT = Path(__file__).resolve().parent.parent
REFERENCE_PACKAGE = REPO_ROOT / "solutions"


@dataclass
class TestResult:
    """A test, what its check found, and how long it took (s)."""

    test: TestSpec
    outcome: Outcome
    seconds: float

    @property
    def score(self) -> float:
        """Full points for a pass; for a failure, the share of right cases if the spec
        gives this test partial credit, else nothing."""
        if self.outcome.status == "passed":
            return float(self.test.points)
        if not self.test.partial_credit:
            return 0.0
        return round(self.test.points * max(0.0, min(1.0, self.outcome.fraction)), 6)


def run_check(test: TestSpec, student: StudentCode, reference: StudentCode | None) -> Outcome:
    """One check, with every failure of the student's code turned into an Outcome."""
    check = load_all()[test.name]
    try:
        if "reference" in inspect.signature(check).parameters:
            return check(student, reference=reference)
        return check(student)
    except StudentCallFailed as failure:
        return failure.outcome
    except Exception as exc:  # a bug in a check must not cost the student: say so plainly
        detail = "".join(traceback.format_exception_only(type(exc), exc)).strip()
        return Outcome("error", message=f"the grader itself failed on this test ({detail}); tell your instructor")


def package_folder(path: Path) -> Path:
    """The ``exercises`` package inside a submission folder (or the folder itself)."""
    path = Path(path)
    for candidate in (path / "exercises", path):
        if (candidate / "__init__.py").is_file():
            return candidate
    nested = [p.parent for p in path.glob("*/exercises/__init__.py")]
    if len(nested) == 1:
        return nested[0]
    raise FileNotFoundError(f"no exercises package (a folder 'exercises' with __init__.py) in {path}")


def run_tests(student_dir: Path, tests: list[TestSpec], limits: Limits = Limits(), slot: int = 0,
              isolation: str = "auto", reference_dir: Path | None = REFERENCE_PACKAGE,
              budget_seconds: float | None = None, progress=None) -> list[TestResult]:
    """Run ``tests`` on the package in ``student_dir``; never raises for student faults.

    ``budget_seconds`` bounds the whole submission: tests not started in time are
    reported as timeouts.  ``progress(result)`` is called after each test.
    """
    started = time.perf_counter()
    results: list[TestResult] = []
    needs_reference = reference_dir is not None and any(
        "reference" in inspect.signature(load_all()[t.name]).parameters for t in tests)
    # Two sandbox users per slot: a student's fork bomb cannot starve the reference.
    with Sandbox(package_folder(student_dir), limits, 2 * slot, isolation) as student_box:
        reference_box = Sandbox(reference_dir, limits, 2 * slot + 1, isolation) if needs_reference else None
        try:
            student = StudentCode(student_box)
            reference = StudentCode(reference_box) if reference_box else None
            for test in tests:
                t0 = time.perf_counter()
                if budget_seconds is not None and t0 - started > budget_seconds:
                    outcome = Outcome("timeout", message=f"not run: the submission used up its {budget_seconds:g} s")
                else:
                    outcome = run_check(test, student, reference)
                result = TestResult(test, outcome, time.perf_counter() - t0)
                results.append(result)
                if progress is not None:
                    progress(result)
        finally:
            if reference_box is not None:
                reference_box.close()
    return results
