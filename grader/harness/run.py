"""Run graded tests (pytest, with :mod:`grader.harness.plugin`) on one student package.

Every test runs in this, the trusted process; the student's code runs in a sandboxed
worker (:mod:`grader.sandbox.process`) started once per run.  Tests that measure speed also
get a second sandbox holding the reference engine, so both are timed side by side.
pytest's own output is kept out of the way: the caller gets one
:class:`~grader.harness.plugin.TestResult` per test, as each finishes.
"""
from __future__ import annotations

import contextlib
import io
import os
from pathlib import Path

from .outcome import Outcome
from .package import package_folder
from .outcome import TestResult
from .plugin import GradedRun, forget_tests_imported_elsewhere, note_graded_imports
from .spec import TESTS_DIR
from ..sandbox.process import Limits
from .spec import SpecError, TestSpec, graded_test_folders

PYTEST_CONFIG = TESTS_DIR / "pytest.ini"
AUTOLOAD_VARIABLE = "PYTEST_DISABLE_PLUGIN_AUTOLOAD"


def pytest_main(arguments: list[str], plugin: GradedRun) -> tuple[int, str]:
    """``pytest.main`` on the graded tests' own configuration, its output captured."""
    import pytest

    # unraisableexception: its full garbage collection at the end costs 0.1 s a run.
    base = ["-c", str(PYTEST_CONFIG), "--rootdir", str(TESTS_DIR), "-q", "-p", "no:cacheprovider",
            "--no-header", "--tb=no", "-p", "no:warnings", "-p", "no:unraisableexception"]
    text = io.StringIO()
    # Only the plugins graded tests use: the installed ones (nbval, xdist...) cost
    # seconds of start-up and change nothing here.
    autoload = os.environ.get(AUTOLOAD_VARIABLE)
    os.environ[AUTOLOAD_VARIABLE] = "1"
    forget_tests_imported_elsewhere()
    with contextlib.redirect_stdout(text), contextlib.redirect_stderr(text):
        try:
            code = pytest.main(base + arguments, plugins=[plugin])
        finally:
            note_graded_imports()
            plugin.close()
            if autoload is None:
                os.environ.pop(AUTOLOAD_VARIABLE, None)
            else:
                os.environ[AUTOLOAD_VARIABLE] = autoload
    return int(code), text.getvalue()


def collect(folders: list[Path]) -> list[TestSpec]:
    """The graded tests in ``folders``, collected without running any."""
    run = GradedRun(collect_only=True)
    _, text = pytest_main([str(f) for f in folders], run)
    if not run.specs:
        raise SpecError(f"the graded tests in {', '.join(map(str, folders))} could not be collected:\n"
                        + text[-3000:])
    return run.specs


def run_tests(student_dir: Path, tests: list[TestSpec], limits: Limits = Limits(), slot: int = 0,
              isolation: str = "auto", reference_dir: Path | None = None,
              budget_seconds: float | None = None, progress=None, exitfirst: bool = False,
              withheld: dict[str, str] | None = None) -> list[TestResult]:
    """Run ``tests`` on the package in ``student_dir``; never raises for student faults
    (:class:`grader.sandbox.process.SandboxBroken` when the sandbox cannot start at all).

    ``budget_seconds`` bounds the whole run: tests not started in time end as
    ``not_run``.  ``progress(result)`` is called after each test.  ``exitfirst`` stops
    at the first test that does not pass (the others are left out of the results).
    ``withheld``: functions of the student's package answered "not implemented" without
    being called (see :class:`grader.sandbox.process.Sandbox`).
    """
    if not tests:
        return []
    run = GradedRun(package_dir=package_folder(student_dir), limits=limits, slot=slot, isolation=isolation,
                    reference_dir=reference_dir, budget_seconds=budget_seconds, progress=progress,
                    names={t.name for t in tests}, withheld=dict(withheld or {}))
    paths = list(dict.fromkeys(t.path for t in tests))  # pytest runs the modules in the order of ``tests``
    code, text = pytest_main((["-x"] if exitfirst else []) + paths, run)
    if run.broken is not None:
        raise run.broken
    if exitfirst and any(r.outcome.status != "passed" for r in run.results):
        return run.results
    done = {r.test.name for r in run.results}
    missing = [t for t in tests if t.name not in done]
    for test in missing:  # a test pytest never ran: the grader's own failure, said plainly
        outcome = Outcome("error", message="the grader could not run this test; tell your instructor\n"
                                           + text[-1500:])
        result = TestResult(test, outcome, 0.0)
        run.results.append(result)
        if progress is not None:
            progress(result)
    order = {t.name: i for i, t in enumerate(tests)}
    return sorted(run.results, key=lambda r: order.get(r.test.name, len(order)))


_CACHE: dict[tuple, list[TestSpec]] = {}


def load_spec(paths: list[Path] | None = None) -> list[TestSpec]:
    """Every graded test in ``paths`` (default: public, then hidden if present), collected
    once per process."""
    key = tuple(str(Path(p).resolve()) for p in (paths or graded_test_folders()))
    if key not in _CACHE:
        _CACHE[key] = collect([Path(p) for p in key])
    return list(_CACHE[key])
