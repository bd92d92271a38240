"""``grader check``: the public tests of an exercise, run on a student's own code.

In a notebook cell::

    from grader import check
    check("grid")                          # your exercises/ package
    check("grid", package="solutions")     # the reference: everything passes

In a shell::

    grader check grid                      # or: python -m grader.student.check grid
    grader check grid --package path/to/exercises --figures pictures/

Each public test of the exercise runs in the sandboxed worker (:mod:`grader.harness.run`),
and each is shown with pass or fail, its points, and what was expected against what
came back.  The results are the grader's one result model
(:class:`~grader.harness.results_model.SubmissionResults`, made as the grading process
makes it); the shell's table and the notebook's are views of it.  A failing geometric case comes with a picture (:mod:`grader.harness.figures`):
inline in a notebook, saved as a PNG whose path is printed in a shell.  A function
still raising ``NotImplementedError`` reads "not implemented yet".  The shell
command exits with 0 when every test passed, 1 when one did not, and 2 when it could
not run (an unknown exercise, no package found).

The package is, first found: the ``package`` argument (``--package``), the
``GRADER_CHECK_PACKAGE`` environment variable, an ``exercises`` folder in the
current folder or one of its parents, the ``exercises`` folder of the course
repository.  A relative path is read from the current folder, then from the
repository root, so ``package="solutions"`` works anywhere in the repository.
"""
from __future__ import annotations

import argparse
import html
import os
import re
import shutil
import sys
import tempfile
import textwrap
import time
from dataclasses import dataclass, field
from pathlib import Path

from ..harness.outcome import TestResult, status_of
from ..harness.results_model import STYLE_SHEET, SubmissionResults, badge, picture_html, points
from ..harness.package import COURSE_ROOT as REPO_ROOT
from ..harness.package import PACKAGE_VARIABLE, PackageNotFound, find_package
from ..harness.spec import EXERCISES, TestSpec
#: The file at the top of a student edition (written by ``grader release``).
RELEASE_MARKER = ".course-release.json"
#: Folder (under the system's temporary folder) where the shell command saves pictures.
FIGURES_FOLDER = "check-figures"

NOT_IMPLEMENTED = re.compile(r"^(?P<module>[\w.]+)\.(?P<function>\w+): not implemented yet"
                             r"(: (?P<stub>[\w.<>]+) in (?P<file>[\w./]+\.py))?$")


class CheckError(ValueError):
    """``grader check`` cannot run: the message says why and what to do instead."""


def no_results() -> SubmissionResults:
    """The results before any test ran."""
    return SubmissionResults([], 0.0, 0.0)


@dataclass
class CheckReport:
    """The outcome of ``check``: the public tests' results, and readable renderings of them.

    In a notebook the report draws itself as an HTML table (``_repr_html_``); ``str``
    gives the plain-text table of the shell.  Both are views of ``results``, one row
    per test (:attr:`rows`).
    """

    exercise: str | None
    package: Path
    results: SubmissionResults = field(default_factory=no_results, repr=False)
    #: Show what the code printed under passing tests too (failing ones always show it).
    show_output: bool = False
    #: By test name, where the picture of its failing case was saved (shell only), or
    #: a sentence saying why it could not be drawn.
    pictures: dict[str, Path | str] = field(default_factory=dict, repr=False)
    _shown: bool = field(default=False, repr=False)

    @property
    def rows(self) -> list[TestResult]:
        """One result per public test, in the order they ran."""
        return self.results.tests

    @property
    def score(self) -> float:
        return self.results.score

    @property
    def max_score(self) -> float:
        return self.results.max_score

    @property
    def passed(self) -> bool:
        """True when every test passed."""
        return self.results.passed

    @property
    def counts(self) -> dict[str, int]:
        return self.results.counts()

    def summary(self) -> str:
        """One sentence: the points and how many tests ended which way."""
        if not self.rows:
            return "No public tests to run."
        return f"{self.results.summary()}. These are the public tests; more tests run when your work is graded."

    def row_text(self, result: TestResult, color: bool = False, width: int = 100) -> str:
        """One test as the shell shows it (see :func:`format_row`)."""
        return format_row(result, color, width, self.show_output, self.pictures.get(result.test.name))

    def text(self, color: bool = False, width: int | None = None) -> str:
        """The plain-text table of the shell command."""
        width = width or shutil.get_terminal_size((100, 24)).columns
        lines = [self.header()]
        for result in self.rows:
            lines.append(self.row_text(result, color, width))
        lines.append(self.summary())
        return "\n".join(lines)

    def header(self, tests: int | None = None) -> str:
        """The first line: what is checked, how many tests, which package."""
        what = f"exercise {self.exercise!r}" if self.exercise else "every exercise"
        tests = len(self.rows) if tests is None else tests
        return f"grader check: {what}, {tests} public tests, package {_shown_path(self.package)}\n"

    def html(self) -> str:
        """A self-contained HTML table (the one style sheet, figures as inline PNG)."""
        out = ['<div class="report inline">', f"<style>{STYLE_SHEET}</style>",
               f"<p><b>{html.escape(self.header().strip())}</b></p>",
               "<table>",
               "<thead><tr>" + "".join(f"<th>{h}</th>" for h in ("Result", "Points", "Test",
                                                                "What happened")) + "</tr></thead>",
               "<tbody>"]
        for result in self.rows:
            test, outcome = result.test, result.outcome
            picture = "" if result.passed else picture_html(outcome.figure, "picture of the failing case")
            message = html.escape(student_message(result, self.show_output))
            out.append(
                "<tr>"
                f"<td>{badge(outcome.status, label=True)}</td>"
                f"<td class='num'>{points(result.score)} / {points(test.points)}</td>"
                f"<td>{html.escape(test.title)}<br><code>{html.escape(test.name)}</code></td>"
                f"<td><pre>{message}</pre>{picture}</td>"
                "</tr>")
        out += ["</tbody></table>", f"<p>{html.escape(self.summary())}</p>", "</div>"]
        return "\n".join(out)

    def _repr_html_(self) -> str | None:
        # Already displayed by check(): show only the one-line text repr, not the table twice.
        return None if self._shown else self.html()

    def __str__(self) -> str:
        return self.text()

    def __repr__(self) -> str:
        what = self.exercise or "all exercises"
        return f"<CheckReport {what}: {points(self.score)}/{points(self.max_score)} points, " \
               f"{sum(r.passed for r in self.rows)}/{len(self.rows)} tests passed>"

    def save_picture(self, result: TestResult, folder: Path) -> Path | None:
        """Save a failing test's picture as ``folder/<test name>.png`` (and remove a stale
        one); return its path, None when there is none (see :attr:`pictures`)."""
        from ..harness.figures import save_figure  # deferred: matplotlib, heavy to import

        name = result.test.name
        path = Path(folder) / f"{name}.png"
        self.pictures.pop(name, None)
        if result.outcome.figure is None or result.passed:
            if path.is_file():
                path.unlink()
            return None
        try:
            self.pictures[name] = save_figure(result.outcome.figure, path)
        except Exception as exc:  # no picture, but the message still stands
            self.pictures[name] = f"the picture could not be drawn: {exc}"
            return None
        return self.pictures[name]

    def save_figures(self, folder: str | Path) -> list[Path]:
        """Save the picture of every failing test as ``folder/<test name>.png``."""
        return [p for p in (self.save_picture(result, Path(folder)) for result in self.rows) if p is not None]


# Helpers ------------------------------------------------------------------------------
def _shown_path(path: Path) -> str:
    """The path relative to the current folder, else to the repository, else absolute:
    the same text on every machine for the repository's own packages."""
    resolved = Path(path).resolve()
    for base in (Path.cwd().resolve(), REPO_ROOT.resolve()):
        try:
            return str(resolved.relative_to(base)) or "."
        except ValueError:
            continue
    return str(path)


def in_student_edition() -> bool:
    """True when this grader is the student edition's (a course folder made by
    ``grader release``, whose README teaches ``bash run.sh``)."""
    return (REPO_ROOT / RELEASE_MARKER).is_file() and (REPO_ROOT / "run.sh").is_file()


def command_name(command: str) -> str:
    """How the user runs ``grader <command>`` here: ``bash run.sh <command>`` in the
    student edition, ``grader <command>`` elsewhere."""
    return f"{'bash run.sh' if in_student_edition() else 'grader'} {command}"


def student_message(result: TestResult, show_output: bool = False) -> str:
    """The test's message in a student's words (a stub names the function to write), and
    what the code printed when the test did not pass (or ``show_output``)."""
    outcome = result.outcome
    message = (outcome.message or "").strip()
    if outcome.status == "not_implemented":
        match = NOT_IMPLEMENTED.match(message)
        if match and match["stub"]:
            return (f"not implemented yet: write {match['stub']}() in exercises/{match['file']} "
                    f"(it still raises NotImplementedError; {match['function']}() calls it)"
                    if match["stub"].rsplit(".", 1)[-1] != match["function"] else
                    f"not implemented yet: write {match['stub']}() in exercises/{match['file']} "
                    "(it still raises NotImplementedError)")
        if match:
            module, function = match["module"], match["function"]
            return (f"not implemented yet: write {function}() in exercises/{module.replace('.', '/')}.py "
                    "(it still raises NotImplementedError)")
        return message if "not implemented yet" in message else f"not implemented yet: {message}"
    if not message:
        message = status_of(outcome.status).word
    printed = outcome.output or ""
    if printed.strip() and (show_output or not result.passed):
        message += "\nyour code printed:\n" + printed.rstrip()
    return message


def format_row(result: TestResult, color: bool = False, width: int = 100, show_output: bool = False,
               picture: Path | str | None = None) -> str:
    """One test as a block of plain text: label, points, title, then the message (see
    :func:`student_message` for ``show_output``) and the ``picture`` of its failing case
    (where it was saved, or why it could not be drawn)."""
    test, said = result.test, status_of(result.outcome.status)
    shown_label = f"\033[1;{said.ansi}m{said.label:<9}\033[0m" if color else f"{said.label:<9}"
    earned = f"{points(result.score)}/{points(test.points)}"
    lines = [f"{shown_label} {earned:>7}  {test.title}  [{test.name}]"]
    indent = " " * 19
    body = student_message(result, show_output).splitlines() or [""]
    if isinstance(picture, str):
        body.append(f"({picture})")
    for line in body:
        wrapped = textwrap.wrap(line, width=max(40, width - len(indent)), break_long_words=False,
                                break_on_hyphens=False, replace_whitespace=False) or [""]
        lines += [indent + w for w in wrapped]
    if isinstance(picture, Path):
        lines.append(f"{indent}picture of the failing case: {picture}")
    return "\n".join(lines) + "\n"


def default_figures_folder() -> Path:
    """``<temp>/check-figures``, or a fresh temporary folder if that one is not writable."""
    folder = Path(tempfile.gettempdir()) / FIGURES_FOLDER
    try:
        folder.mkdir(parents=True, exist_ok=True)
        if os.access(folder, os.W_OK):
            return folder
    except OSError:
        pass
    return Path(tempfile.mkdtemp(prefix=FIGURES_FOLDER + "-"))


def select_tests(exercise: str | None = None) -> list:
    """The public tests of ``exercise`` (an exercise name or one test's name; None: all)."""
    from ..harness.run import load_spec  # deferred: pytest, heavy to import

    # In chapter order (EXERCISES), each exercise's tests in the order of their module.
    public = sorted((t for t in load_spec() if t.public), key=lambda t: EXERCISES.index(t.exercise))
    if exercise is None:
        return public
    name = str(exercise).strip()
    chosen = [t for t in public if t.exercise == name] or [t for t in public if t.name == name]
    if not chosen:
        valid = [e for e in EXERCISES if any(t.exercise == e for t in public)]
        raise CheckError(f"unknown exercise {name!r}: choose one of {', '.join(valid)} "
                         "(or the name of one public test)")
    return chosen


def run_public_tests(tests: list[TestSpec], folder: Path, progress=None) -> SubmissionResults:
    """Run ``tests`` on the package in ``folder``: the grader's one result model, made as
    the grading process makes it; ``progress(result)`` after each test."""
    from ..harness.run import run_tests  # deferred: pytest, heavy to import

    started = time.perf_counter()
    results = run_tests(folder, tests, reference_dir=None, progress=progress)
    return SubmissionResults.graded(results, time.perf_counter() - started)


def run_check(exercise: str | None = None, package: str | Path | None = None, progress=None) -> CheckReport:
    """Run the public tests and return the report; ``progress(result)`` after each test
    (a :class:`~grader.harness.outcome.TestResult`)."""
    tests = select_tests(exercise)
    folder = find_package(package)
    return CheckReport(exercise, folder, run_public_tests(tests, folder, progress))


def _in_notebook() -> bool:
    """True inside a Jupyter kernel (IPython already imported and running a kernel)."""
    ipython = sys.modules.get("IPython")
    if ipython is None:
        return False
    try:
        shell = ipython.get_ipython()
    except Exception:
        return False
    return shell is not None and getattr(shell, "kernel", None) is not None


def check(exercise: str | None = None, package: str | Path | None = None, show: bool = True, *,
          figures: str | Path | None = None, show_output: bool = False) -> CheckReport:
    """Run the public tests of an exercise on your code and show what happened.

    Parameters
    ----------
    exercise : str, optional
        ``"grid"``, ``"quadtree"``, ``"dynamic_tree"``, ``"sat"``, ``"contacts"``, ``"momentum"``,
        ``"impulse"`` or ``"sequential"`` (or one test's name); None runs every public
        test, in the order of the chapters.
    package : str or Path, optional
        Folder of the package to check (default: your ``exercises`` folder, see the
        module docstring); ``"solutions"`` checks the reference.
    show : bool
        Display the result: an HTML table in a notebook, a text table (pictures saved
        as PNG files) elsewhere.
    figures : str or Path, optional
        Where to save pictures outside a notebook (default ``<temp>/check-figures``).
    show_output : bool
        Also show what your code printed during tests that passed (a failing test
        always shows it, cut after a few dozen lines).

    Returns
    -------
    CheckReport
        ``.passed``, ``.score``, ``.max_score``, ``.rows`` (one
        :class:`~grader.harness.outcome.TestResult` per test), ``.results`` (the
        :class:`~grader.harness.results_model.SubmissionResults` they belong to).

    Raises
    ------
    CheckError
        For an unknown exercise or when no package is found.
    """
    report = run_check(exercise, package)
    report.show_output = show_output
    if show:
        if _in_notebook():
            from IPython.display import HTML, display

            display(HTML(report.html()))
            report._shown = True
        else:
            report.save_figures(Path(figures) if figures is not None else default_figures_folder())
            print(report.text(color=_use_color(sys.stdout)))
    return report


# Shell command ----------------------------------------------------------------------
def _use_color(stream) -> bool:
    return hasattr(stream, "isatty") and stream.isatty() and "NO_COLOR" not in os.environ


def add_check_arguments(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """Add ``[EXERCISE] [--package PATH] [--figures DIR]`` to ``parser``; return it."""

    parser.add_argument("exercise", nargs="?", default=None,
                        help=f"{', '.join(EXERCISES[:-1])} or {EXERCISES[-1]} (or one test's name); "
                             "default: every exercise")
    parser.add_argument("--package", metavar="PATH", default=None,
                        help=f"the package to check (default: ./exercises, or ${PACKAGE_VARIABLE}); "
                             "'solutions' checks the reference")
    parser.add_argument("--show-output", action="store_true",
                        help="also show what your code printed during tests that passed (failing tests always "
                             "show it)")
    parser.add_argument("--figures", metavar="DIR", default=None,
                        help=f"where to save pictures of failing cases (default: <temp>/{FIGURES_FOLDER})")
    return parser


def main_check(args: argparse.Namespace) -> int:
    """Run ``grader check`` with parsed arguments; print the table; return the exit status.

    0: every test passed; 1: at least one did not; 2: the check could not run.
    """
    out = sys.stdout
    color = _use_color(out)
    try:
        tests = select_tests(getattr(args, "exercise", None))
        folder = find_package(getattr(args, "package", None))
    except (CheckError, PackageNotFound) as exc:
        print(f"grader check: {exc}", file=sys.stderr)
        return 2
    figures = getattr(args, "figures", None)
    figures_folder = Path(figures) if figures else default_figures_folder()
    exercise = getattr(args, "exercise", None)
    report = CheckReport(exercise, folder, show_output=getattr(args, "show_output", False))
    print(report.header(len(tests)), file=out, flush=True)
    width = shutil.get_terminal_size((100, 24)).columns

    def show_row(result: TestResult) -> None:
        report.save_picture(result, figures_folder)
        print(report.row_text(result, color, width), file=out, flush=True)

    try:
        report.results = run_public_tests(tests, folder, progress=show_row)
    except Exception as exc:
        if os.environ.get("GRADER_DEBUG"):
            raise
        print(f"grader check: could not run the tests ({type(exc).__name__}: {exc}); "
              "set GRADER_DEBUG=1 to see the details", file=sys.stderr)
        return 2
    print(report.summary(), file=out, flush=True)
    return 0 if report.passed else 1


def main(argv: list[str] | None = None) -> int:
    """``python -m grader.student.check [EXERCISE] [--package PATH] [--figures DIR]``."""
    parser = add_check_arguments(argparse.ArgumentParser(
        prog=command_name("check"), description="Run the public tests of an exercise on your code."))
    return main_check(parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
