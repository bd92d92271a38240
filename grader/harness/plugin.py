"""The pytest plugin of graded tests: markers, the ``student`` fixture, outcomes.

Graded tests are ordinary pytest modules under ``grader/tests/public`` (students hold
them) and ``grader/tests/hidden`` (the instructor's side only).  One test function is
one graded test::

    @pytest.mark.points(2)
    @pytest.mark.visibility("hidden")          # default "visible"
    def test_touching_boxes(student):
        pairs = student.call("broadphase.uniform_grid", "pairs_grid_every_cell", boxes, 1.0)
        assert set(map(tuple, pairs)) == brute_force_pairs(boxes), "touching boxes must pair"

Markers: ``points(n)`` (required), ``visibility(...)`` (Gradescope's: visible, hidden,
after_due_date, after_published), ``title("...")`` (default: the docstring's first
line), ``partial_credit`` (a failure earns a share of the points, see
:mod:`grader.harness.credit`), ``leaderboard("name")`` (a speed test's metric on Gradescope's
leaderboard).  A test's name is ``<exercise>.<function without test_>``, the exercise
being the module's name without ``test_``.

The ``student`` fixture is a :class:`~grader.harness.student_code.StudentCode`: calls cross to a
sandboxed worker as JSON, nothing of a test module runs in the sandbox, and every
expected value is computed here, in the trusted pytest process.  ``reference`` is the
reference engine in a sandbox of its own (speed tests time both side by side);
``metrics`` is a dict whose items are reported with the test (seconds, error); ``picture``
attaches a picture of the case (:mod:`grader.harness.figures`) that a failure shows.

Each test ends as an :class:`~grader.harness.outcome.Outcome`: passed; failed (an
``assert`` or :func:`grader.harness.credit.fail`, with its share of right cases and picture);
not implemented, error, timeout or crashed (a call into the student's code); not run
(the submission's time was used up).  ``grader check``, ``grader grade``, the reports
and Gradescope read these outcomes from :class:`GradedRun`.

Run directly, by an instructor::

    pytest grader/tests/public --student path/to/exercises -k sat --junitxml=out.xml
"""
from __future__ import annotations

import json
import sys
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import pytest

from .credit import GradedFailure
from .figure_caps import bounded
from .outcome import MESSAGE_LIMIT, Outcome, StudentCallFailed, StudentCallStopped, TestResult, capped
from .package import PackageNotFound, find_package, package_folder
from .replay import is_hypothesis_test, replaying
from ..sandbox.process import Limits, Sandbox, SandboxBroken
from .spec import EXERCISES, TESTS_DIR, VISIBILITIES, SpecError, TestSpec
from .student_code import StudentCode

GRADER_DIR = Path(__file__).resolve().parents[1]
REFERENCE_PACKAGE = GRADER_DIR.parent / "solutions"
MARKERS = {
    "points": "points(n): the graded test's weight (required)",
    "visibility": "visibility(v): visible, hidden, after_due_date or after_published (default visible)",
    "title": "title(text): the test's title in reports (default: the docstring's first line)",
    "partial_credit": "partial_credit: a failure earns points for a high share of right cases",
    "leaderboard": "leaderboard(name): put the test's seconds on Gradescope's leaderboard",
}
HYPOTHESIS_PROFILE = "grading"


def register_hypothesis_profile() -> None:
    """Reproducible, bounded Hypothesis runs: no database, no deadline, no 'explain'
    phase (it re-runs the student's code many times), one bug reported, 30 examples
    per test unless the test asks for another number (each is a round trip to the
    sandbox, and grading 100 submissions must stay within minutes).

    A graded run inside a longer process (the project's own tests grade samples in
    pytest's process) changes Hypothesis for that process; :func:`restore_hypothesis`
    undoes it when the run ends.
    """
    from hypothesis import HealthCheck, Phase, settings
    from hypothesis.internal.conjecture import engine, providers

    if not _SAVED_HYPOTHESIS:
        _SAVED_HYPOTHESIS.update(profile=settings._current_profile, local=providers._get_local_constants,
                                 shrinks=engine.MAX_SHRINKS, shrink_seconds=engine.MAX_SHRINKING_SECONDS)
    settings.register_profile(HYPOTHESIS_PROFILE, database=None, derandomize=True, deadline=None,
                              max_examples=30, report_multiple_bugs=False, print_blob=False,
                              phases=[Phase.explicit, Phase.generate, Phase.shrink],
                              suppress_health_check=list(HealthCheck))
    settings.load_profile(HYPOTHESIS_PROFILE)
    ignore_local_constants()
    bound_shrinking()


#: What :func:`register_hypothesis_profile` changed, kept for :func:`restore_hypothesis`.
_SAVED_HYPOTHESIS: dict = {}


def restore_hypothesis() -> None:
    """Put back the profile, local constants and shrink limits a graded run replaced."""
    if not _SAVED_HYPOTHESIS:
        return
    from hypothesis import settings
    from hypothesis.internal.conjecture import engine, providers

    saved = dict(_SAVED_HYPOTHESIS)
    _SAVED_HYPOTHESIS.clear()
    settings.load_profile(saved["profile"] or "default")
    providers._get_local_constants = saved["local"]
    providers.CONSTANTS_CACHE.cache.clear()
    engine.MAX_SHRINKS, engine.MAX_SHRINKING_SECONDS = saved["shrinks"], saved["shrink_seconds"]


#: Graded test modules imported by a graded run, under the grading profile, by name.
_GRADED_IMPORTS: dict[str, object] = {}


def graded_test_modules() -> dict[str, object]:
    """The graded test modules (``test_*.py`` under :data:`TESTS_DIR`) now imported."""
    found = {}
    for name, module in list(sys.modules.items()):
        file = getattr(module, "__file__", None)
        if file and Path(file).name.startswith("test_") and Path(file).resolve().is_relative_to(TESTS_DIR):
            found[name] = module
    return found


def forget_tests_imported_elsewhere() -> None:
    """Make pytest import again the graded test modules another import left behind.

    Hypothesis binds a ``@given`` test to the settings in force when its module is
    imported, and pytest reuses a module already in ``sys.modules``.  The project's own
    tests import graded test modules for their strategies, under their own profile
    (100 examples on CI, random ones elsewhere); a graded run in that process would
    then draw those examples instead of the grading profile's fixed 30.
    """
    for name, module in graded_test_modules().items():
        if _GRADED_IMPORTS.get(name) is not module:
            del sys.modules[name]


def note_graded_imports() -> None:
    """Remember the graded test modules a graded run imported (they may be reused)."""
    _GRADED_IMPORTS.update(graded_test_modules())


def ignore_local_constants() -> None:
    """Make Hypothesis draw the same examples whatever modules are loaded.

    Hypothesis 6 mixes into its examples the literal constants of every local module
    already imported, so a student's public run and the instructor's public + hidden
    run (which also imports the reference) would draw different examples for one test.
    Graded runs use its global constants only.  Hypothesis caches the constants it may
    draw per kind of choice for the whole process, so the cache is emptied too: a test
    that ran earlier in the process (the project's own property tests) would otherwise
    leave its local constants in every later graded run, whose examples would then
    depend on which tests ran before it.
    """
    from hypothesis.internal.conjecture import providers

    empty = providers.Constants()
    providers._get_local_constants = lambda: empty
    providers.CONSTANTS_CACHE.cache.clear()


def bound_shrinking() -> None:
    """At most 200 successful shrinks and 3 s of shrinking per failing test.

    Whether a test fails is settled by the examples it generates; shrinking only makes
    the failing example shown smaller.  Hypothesis allows 500 shrinks and five minutes,
    which made one failing test of a buggy submission cost seconds of grading each.
    """
    from hypothesis.internal.conjecture import engine

    engine.MAX_SHRINKS = 200
    engine.MAX_SHRINKING_SECONDS = 3


@dataclass(eq=False)
class GradedRun:
    """One pytest session of graded tests on one student package (a pytest plugin).

    ``names``: run only these tests (None: every collected one).  ``progress(result)``
    is called after each test; ``results`` holds them all.  ``budget_seconds`` bounds
    the whole run: tests not started in time end as ``not_run``.
    """

    package_dir: Path | None = None
    limits: Limits = field(default_factory=Limits)
    slot: int = 0
    isolation: str = "auto"
    reference_dir: Path | None = None
    budget_seconds: float | None = None
    progress: Callable | None = None
    names: set | None = None
    withheld: dict = field(default_factory=dict)  # {"module:function": reason}, see Sandbox
    collect_only: bool = False
    specs: list = field(default_factory=list)
    results: list = field(default_factory=list)
    started: float = field(default_factory=time.perf_counter)
    broken: SandboxBroken | None = None   # the sandbox could not start: no test result stands
    _student: StudentCode | None = None
    _reference: StudentCode | None = None
    _boxes: list = field(default_factory=list)

    # Fixtures' objects ----------------------------------------------------------------
    def student(self) -> StudentCode:
        if self._student is None:
            try:
                package = find_package(None) if self.package_dir is None else package_folder(self.package_dir)
            except PackageNotFound as exc:
                raise pytest.UsageError(f"--student: {exc}") from None
            self.package_dir = package
            box = Sandbox(package, self.limits, 2 * self.slot, self.isolation, withheld=self.withheld)
            self._boxes.append(box)
            self._student = StudentCode(box)
        return self._student

    def reference(self) -> StudentCode:
        if self._reference is None:
            folder = self.reference_dir or REFERENCE_PACKAGE
            if not (Path(folder) / "__init__.py").is_file():
                pytest.skip("the reference engine is not here (instructor's side only)")
            # Two sandbox users per slot: a student's fork bomb cannot starve the reference.
            box = Sandbox(Path(folder), self.limits, 2 * self.slot + 1, self.isolation)
            self._boxes.append(box)
            self._reference = StudentCode(box)
        return self._reference

    def close(self) -> None:
        for box in self._boxes:
            box.close()
        self._boxes.clear()

    # Hooks -------------------------------------------------------------------------------
    @pytest.hookimpl(trylast=True)
    def pytest_collection_modifyitems(self, session, config, items):
        specs = {}
        for item in items:
            spec = spec_of(item)
            if spec.name in specs:
                raise SpecError(f"{item.nodeid}: two graded tests are called {spec.name!r}")
            specs[spec.name] = spec
            item.stash[SPEC_KEY] = spec
        if self.names is not None:
            chosen = [item for item in items if item.stash[SPEC_KEY].name in self.names]
            config.hook.pytest_deselected(items=[i for i in items if i not in chosen])
            items[:] = chosen
        self.specs = [item.stash[SPEC_KEY] for item in items]
        if self.collect_only:
            config.hook.pytest_deselected(items=list(items))
            items[:] = []
        for item in items:
            if is_hypothesis_test(getattr(item, "obj", None)):
                item.obj = replaying(item.obj)

    @pytest.hookimpl(hookwrapper=True, tryfirst=True)
    def pytest_runtest_protocol(self, item, nextitem):
        item.stash[START_KEY] = time.perf_counter()
        if self._student is not None:
            self._student.take_output()
        yield
        spec = item.stash.get(SPEC_KEY, None)
        outcome = item.stash.get(OUTCOME_KEY, None)
        if spec is None or outcome is None:
            return
        if self._student is not None:
            outcome.output = self._student.take_output()  # capped as it was kept
        result = TestResult(spec, outcome, time.perf_counter() - item.stash[START_KEY])
        self.results.append(result)
        if self.progress is not None:
            self.progress(result)

    def pytest_runtest_setup(self, item):
        if self.budget_seconds is not None and time.perf_counter() - self.started > self.budget_seconds:
            raise StudentCallStopped(Outcome("not_run", message=f"not run: the submission used up its "
                                                                f"{self.budget_seconds:g} s"))

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_makereport(self, item, call):
        report = (yield).get_result()
        broken = call.excinfo.value if call.excinfo is not None else None
        if isinstance(broken, BaseExceptionGroup) and broken.exceptions:
            broken = broken.exceptions[0]
        if isinstance(broken, SandboxBroken):
            self.broken = broken   # the grader's own failure: the run stops, and says so
            item.session.shouldstop = str(broken)
            return
        if call.when == "call" or (call.when == "setup" and report.outcome != "passed"):
            outcome = outcome_of(call.excinfo, item)
            if outcome.status == "failed" and outcome.figure is None and PICTURE_KEY in item.stash:
                outcome.figure = bounded(item.stash[PICTURE_KEY])
            item.stash[OUTCOME_KEY] = outcome
            spec = item.stash.get(SPEC_KEY, None)
            if spec is not None:
                score = TestResult(spec, outcome, 0.0).score
                item.user_properties += [("status", outcome.status), ("score", score), ("points", spec.points)]
                if outcome.figure is not None:  # the picture's data, for reports built from JUnit XML
                    item.user_properties.append(("figure", json.dumps(outcome.figure)))

    def pytest_sessionfinish(self, session):
        self.close()


SPEC_KEY = pytest.StashKey[TestSpec]()
OUTCOME_KEY = pytest.StashKey[Outcome]()
START_KEY = pytest.StashKey[float]()
METRICS_KEY = pytest.StashKey[dict]()
PICTURE_KEY = pytest.StashKey[dict]()


def _marker_arg(item, name: str, default=None):
    marker = item.get_closest_marker(name)
    if marker is None:
        return default
    if not marker.args:
        return True
    return marker.args[0]


def spec_of(item) -> TestSpec:
    """The graded test an item is, from its module name, function name and markers."""
    module = Path(str(item.fspath)).stem
    if not module.startswith("test_"):
        raise SpecError(f"{item.nodeid}: graded test modules are called test_<exercise>.py")
    exercise = module[len("test_"):]
    if exercise not in EXERCISES:
        raise SpecError(f"{item.nodeid}: exercise must be one of {EXERCISES}, got {exercise!r}")
    function = item.name[len("test_"):] if item.name.startswith("test_") else item.name
    points = _marker_arg(item, "points")
    if points is None or points is True:
        raise SpecError(f"{item.nodeid}: a graded test needs @pytest.mark.points(n)")
    try:
        points = float(points)
    except (TypeError, ValueError):
        raise SpecError(f"{item.nodeid}: points must be a number, got {points!r}") from None
    if not points >= 0:
        raise SpecError(f"{item.nodeid}: points must be >= 0, got {points}")
    visibility = _marker_arg(item, "visibility", "visible")
    if visibility not in VISIBILITIES:
        raise SpecError(f"{item.nodeid}: visibility must be one of {VISIBILITIES}, got {visibility!r}")
    doc = (getattr(item, "function", None).__doc__ or "") if hasattr(item, "function") else ""
    title = _marker_arg(item, "title") or (doc.strip().splitlines()[0].strip() if doc.strip() else function)
    leaderboard = _marker_arg(item, "leaderboard")
    return TestSpec(name=f"{exercise}.{function}", exercise=exercise, title=str(title), points=points,
                    visibility=str(visibility), leaderboard=leaderboard if isinstance(leaderboard, str) else None,
                    partial_credit=bool(_marker_arg(item, "partial_credit", False)), nodeid=item.nodeid,
                    path=str(item.fspath))


def _notes(exc: BaseException) -> str:
    notes = [str(n) for n in getattr(exc, "__notes__", []) or []]
    # Hypothesis's notes name the failing example: the input that made the test fail.
    return "\n".join(notes)


def outcome_of(excinfo, item) -> Outcome:
    """The outcome of a test from the exception it ended with (None: passed)."""
    metrics = dict(item.stash.get(METRICS_KEY, {}))
    if excinfo is None:
        return Outcome("passed", 1.0, "", metrics=metrics)
    exc = excinfo.value
    if isinstance(exc, BaseExceptionGroup) and exc.exceptions:
        exc = exc.exceptions[0]
    notes = _notes(exc)
    if isinstance(exc, (StudentCallFailed, StudentCallStopped)):
        found = exc.outcome
        message = found.message + (f"\n{notes}" if notes and found.status != "not_implemented" else "")
        return Outcome(found.status, 0.0, capped(message, MESSAGE_LIMIT), found.figure, {**metrics, **found.metrics})
    if isinstance(exc, GradedFailure):
        message = str(exc) + (f"\n{notes}" if notes else "")
        return Outcome("failed", exc.fraction, capped(message, MESSAGE_LIMIT), bounded(exc.figure), metrics)
    if isinstance(exc, AssertionError):
        # A test's own message stands alone: pytest's "assert ..." rewrite after it
        # repeats the test's internals, not the student's case.
        text = str(exc)
        if not text.startswith("assert ") and "\nassert " in text:
            text = text.split("\nassert ", 1)[0]
        message = text + (f"\n{notes}" if notes else "")
        return Outcome("failed", 0.0, capped(message, MESSAGE_LIMIT), None, metrics)
    if isinstance(exc, pytest.skip.Exception):
        return Outcome("error", 0.0, f"this test could not run here: {exc}", metrics=metrics)
    detail = "".join(traceback.format_exception_only(type(exc), exc)).strip()
    where = excinfo.traceback[-1] if len(excinfo.traceback) else None
    place = f" (at {Path(str(where.path)).name}:{where.lineno + 1})" if where is not None else ""
    return Outcome("error", 0.0, capped(f"the test could not use your answer: {detail}{place}"
                                        f"{chr(10) + notes if notes else ''}\nIf your answer has the documented "
                                        "form, tell your instructor.", MESSAGE_LIMIT), metrics=metrics)


# The hooks and fixtures a conftest imports --------------------------------------------------
def pytest_addoption(parser):
    group = parser.getgroup("grader", "graded tests of the collision course")
    group.addoption("--student", metavar="PATH", default=None,
                    help="the student's exercises package (a folder holding it, or a submission folder); "
                         "default: ./exercises or $GRADER_CHECK_PACKAGE")
    group.addoption("--isolation", default="auto", choices=("auto", "bwrap", "plain"),
                    help="how the student's code is isolated (default: bubblewrap when it works)")
    group.addoption("--call-timeout", type=float, default=None, metavar="SECONDS",
                    help="wall-clock seconds one call into the student's code may take")


def register_markers(config) -> None:
    """Declare the graded tests' markers (the table :data:`MARKERS`) to pytest."""
    for name, text in MARKERS.items():
        config.addinivalue_line("markers", f"{name}: {text}" if not text.startswith(name) else text)


def pytest_configure(config):
    register_markers(config)
    register_hypothesis_profile()
    if not any(isinstance(p, GradedRun) for p in config.pluginmanager.get_plugins()):
        student = config.getoption("--student")
        limits = Limits()
        timeout = config.getoption("--call-timeout")
        if timeout:
            limits = Limits(call_timeout=timeout)
        run = GradedRun(package_dir=Path(student).expanduser().resolve() if student else None, limits=limits,
                        isolation=config.getoption("--isolation"))
        config.pluginmanager.register(run, "grader-graded-run")


def pytest_unconfigure(config):
    restore_hypothesis()


def graded_run(config) -> GradedRun:
    for plugin in config.pluginmanager.get_plugins():
        if isinstance(plugin, GradedRun):
            return plugin
    raise RuntimeError("the grader's pytest plugin is not configured")


@pytest.fixture(scope="session")
def student(request) -> StudentCode:
    """The student's package, reached through the sandboxed worker."""
    return graded_run(request.config).student()


@pytest.fixture(scope="session")
def reference(request) -> StudentCode:
    """The reference engine in a sandbox of its own (instructor's side only)."""
    return graded_run(request.config).reference()


class Picture:
    """A picture of the case a test is on (plain data of :mod:`grader.harness.figures`); kept
    with the test's outcome when it fails and the failure carries no picture itself."""

    def __init__(self, node):
        self.node = node

    def attach(self, figure: dict) -> None:
        self.node.stash[PICTURE_KEY] = figure


@pytest.fixture
def picture(request) -> Picture:
    """``picture.attach(figure)``: the picture a failure of this test shows."""
    return Picture(request.node)


@pytest.fixture
def metrics(request) -> dict:
    """Figures reported with the test (``seconds``, ``reference_seconds``, errors)."""
    values: dict = {}
    request.node.stash[METRICS_KEY] = values
    return values

