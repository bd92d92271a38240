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
came back.  A failing geometric case comes with a picture (:mod:`grader.harness.figures`):
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
from dataclasses import dataclass, field
from pathlib import Path

from ..harness.outcome import Outcome, TestResult, status_of
from ..harness.results_model import STYLE_SHEET, SubmissionResults, badge, points
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


@dataclass
class CheckRow:
    """One test as the student sees it.

    ``score`` and ``points`` are in points; ``seconds`` is the test's wall-clock time;
    ``figure`` the plain-data picture of a failing case (None if there is none) and
    ``figure_path`` where it was saved (shell only).
    """

    name: str
    title: str
    exercise: str
    status: str
    score: float
    points: float
    message: str
    seconds: float = 0.0
    figure: dict | None = None
    figure_path: Path | None = None
    metrics: dict = field(default_factory=dict)
    #: What the student's code printed during the test (capped).
    output: str = ""

    @property
    def passed(self) -> bool:
        return self.status == "passed"

    def spec(self) -> TestSpec:
        return TestSpec(name=self.name, exercise=self.exercise, title=self.title, points=self.points,
                        visibility="visible")

    def outcome(self) -> Outcome:
        return Outcome(self.status, message=self.message, figure=self.figure, metrics=self.metrics,
                       output=self.output)

    @property
    def label(self) -> str:
        return status_of(self.status).label


@dataclass
class CheckReport:
    """The outcome of ``check``: one row per public test, and a readable rendering.

    In a notebook the report draws itself as an HTML table (``_repr_html_``); ``str``
    gives the plain-text table of the shell.
    """

    exercise: str | None
    package: Path
    rows: list[CheckRow]
    results: list = field(default_factory=list, repr=False)
    #: Show what the code printed under passing tests too (failing ones always show it).
    show_output: bool = False
    _shown: bool = field(default=False, repr=False)

    @property
    def score(self) -> float:
        return round(sum(r.score for r in self.rows), 6)

    @property
    def max_score(self) -> float:
        return round(sum(r.points for r in self.rows), 6)

    @property
    def passed(self) -> bool:
        """True when every test passed."""
        return all(r.passed for r in self.rows)

    @property
    def counts(self) -> dict[str, int]:
        return self.submission_results().counts()

    def submission_results(self) -> SubmissionResults:
        """The rows as the grader's one result model (what the table is a view of)."""
        results = [TestResult(row.spec(), row.outcome(), row.seconds, recorded_score=row.score) for row in self.rows]
        return SubmissionResults(results, self.score, self.max_score)

    def summary(self) -> str:
        """One sentence: the points and how many tests ended which way."""
        if not self.rows:
            return "No public tests to run."
        return (f"{self.submission_results().summary()}. "
                "These are the public tests; more tests run when your work is graded.")

    def text(self, color: bool = False, width: int | None = None) -> str:
        """The plain-text table of the shell command."""
        width = width or shutil.get_terminal_size((100, 24)).columns
        lines = [self.header()]
        for row in self.rows:
            lines.append(format_row(row, color, width, self.show_output))
        lines.append(self.summary())
        return "\n".join(lines)

    def header(self, tests: int | None = None) -> str:
        """The first line: what is checked, how many tests, which package."""
        what = f"exercise {self.exercise!r}" if self.exercise else "every exercise"
        tests = len(self.rows) if tests is None else tests
        return f"grader check: {what}, {tests} public tests, package {_shown_path(self.package)}\n"

    def html(self) -> str:
        """A self-contained HTML table (inline styles, figures as inline PNG)."""
        from ..harness.figures import figure_png_base64  # deferred: matplotlib, heavy to import

        out = ['<div class="report inline">', f"<style>{STYLE_SHEET}</style>",
               f"<p><b>{html.escape(self.header().strip())}</b></p>",
               "<table>",
               "<thead><tr>" + "".join(f"<th>{h}</th>" for h in ("Result", "Points", "Test",
                                                                "What happened")) + "</tr></thead>",
               "<tbody>"]
        for row in self.rows:
            picture = ""
            if row.figure is not None and not row.passed:
                try:
                    data = figure_png_base64(row.figure)
                    picture = (f'<br><img alt="picture of the failing case" src="data:image/png;base64,{data}">')
                except Exception as exc:  # a picture must never hide the message
                    picture = f"<br><i>(the picture could not be drawn: {html.escape(str(exc))})</i>"
            message = html.escape(student_message(row, self.show_output))
            out.append(
                "<tr>"
                f"<td>{badge(row.status, label=True)}</td>"
                f"<td class='num'>{points(row.score)} / {points(row.points)}</td>"
                f"<td>{html.escape(row.title)}<br><code>{html.escape(row.name)}</code></td>"
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

    def save_figures(self, folder: str | Path) -> list[Path]:
        """Save the picture of every failing test as ``folder/<test name>.png``."""
        return [p for p in (save_row_figure(row, Path(folder)) for row in self.rows) if p is not None]


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


def student_message(row: CheckRow, show_output: bool = False) -> str:
    """The row's message in a student's words (a stub names the function to write), and
    what the code printed when the test did not pass (or ``show_output``)."""
    message = row.message.strip()
    if row.status == "not_implemented":
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
        message = status_of(row.status).word
    if row.output.strip() and (show_output or not row.passed):
        message += "\nyour code printed:\n" + row.output.rstrip()
    return message


def format_row(row: CheckRow, color: bool = False, width: int = 100, show_output: bool = False) -> str:
    """One test as a block of plain text: label, points, title, then the message (see
    :func:`student_message` for ``show_output``)."""
    label = row.label
    ansi = status_of(row.status).ansi
    shown_label = f"\033[1;{ansi}m{label:<9}\033[0m" if color else f"{label:<9}"
    earned = f"{points(row.score)}/{points(row.points)}"
    lines = [f"{shown_label} {earned:>7}  {row.title}  [{row.name}]"]
    indent = " " * 19
    body = student_message(row, show_output).splitlines() or [""]
    for line in body:
        wrapped = textwrap.wrap(line, width=max(40, width - len(indent)), break_long_words=False,
                                break_on_hyphens=False, replace_whitespace=False) or [""]
        lines += [indent + w for w in wrapped]
    if row.figure_path is not None:
        lines.append(f"{indent}picture of the failing case: {row.figure_path}")
    return "\n".join(lines) + "\n"


def save_row_figure(row: CheckRow, folder: Path) -> Path | None:
    """Save a failing row's picture (and remove a stale one); return its path or None."""
    from ..harness.figures import save_figure  # deferred: matplotlib, heavy to import

    path = Path(folder) / f"{row.name}.png"
    if row.figure is None or row.passed:
        if path.is_file():
            path.unlink()
        return None
    try:
        row.figure_path = save_figure(row.figure, path)
    except Exception as exc:  # no picture, but the message still stands
        row.message += f"\n(the picture could not be drawn: {exc})"
        return None
    return row.figure_path


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


def row_of(result) -> CheckRow:
    """A :class:`~grader.harness.run.TestResult` as a row."""
    test, outcome = result.test, result.outcome
    return CheckRow(name=test.name, title=test.title, exercise=test.exercise, status=outcome.status,
                    score=result.score, points=test.points, message=outcome.message or "",
                    seconds=result.seconds, figure=outcome.figure, metrics=dict(outcome.metrics or {}),
                    output=outcome.output or "")


def run_check(exercise: str | None = None, package: str | Path | None = None, progress=None) -> CheckReport:
    """Run the public tests and return the report; ``progress(row)`` after each test."""
    from ..harness.run import run_tests  # deferred: pytest, heavy to import

    tests = select_tests(exercise)
    folder = find_package(package)
    rows: list[CheckRow] = []

    def collect(result):
        row = row_of(result)
        rows.append(row)
        if progress is not None:
            progress(row)

    results = run_tests(folder, tests, reference_dir=None, progress=collect)
    return CheckReport(exercise, folder, rows, results)


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
        ``"grid"``, ``"quadtree"``, ``"sat"``, ``"contacts"``, ``"momentum"``,
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
        ``.passed``, ``.score``, ``.max_score``, ``.rows``.

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
    report = CheckReport(exercise, folder, [], show_output=getattr(args, "show_output", False))
    print(report.header(len(tests)), file=out, flush=True)
    width = shutil.get_terminal_size((100, 24)).columns

    def show_row(result) -> None:
        row = row_of(result)
        save_row_figure(row, figures_folder)
        report.rows.append(row)
        print(format_row(row, color, width, report.show_output), file=out, flush=True)

    from ..harness.run import run_tests  # deferred: pytest, heavy to import

    try:
        report.results = run_tests(folder, tests, reference_dir=None, progress=show_row)
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
