"""The result of one graded test, in words a student understands, and the one table of
test statuses every part of the grader uses (``grader check``, the reports, the
gradebook and Gradescope's results.json)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from .credit import partial_points
from .spec import TestSpec

@dataclass(frozen=True)
class Status:
    """How one status is said: ``meaning`` (a sentence; its words before the first colon
    are the status's :attr:`word`, used in sentences, badges and results.json), ``label``
    (the column of ``grader check``'s table), ``colour`` (an HTML badge's background, hex)
    and ``ansi`` (the terminal's SGR colour code)."""

    meaning: str
    label: str
    colour: str
    ansi: str

    @property
    def word(self) -> str:
        return self.meaning.split(":")[0]


#: Every status a graded test can end with, and how it is said.  The one table: the check
#: table, the reports, the feedback page, the gradebook and results.json all take their
#: words, labels and colours from here (see :func:`status_of`).
STATUS_MEANINGS = {
    "passed": Status("passed", "PASS", "#1a7f37", "32"),
    "failed": Status("wrong answer: a value differs from the reference's", "FAIL", "#cf222e", "31"),
    "not_implemented": Status("not implemented yet: a stub still raises NotImplementedError", "TO DO", "#6e7781",
                              "90"),
    "error": Status("raised an error: an exception in the student's code", "ERROR", "#bc4c00", "33"),
    "timeout": Status("timed out", "TIMEOUT", "#bc4c00", "33"),
    "crashed": Status("crashed: the worker process died", "CRASHED", "#bc4c00", "33"),
    "forbidden": Status("forbidden: the code did something it may not do", "FORBIDDEN", "#8250df", "35"),
    "not_run": Status("not run: the submission used up its time", "NOT RUN", "#6e7781", "90"),
}
STATUSES = tuple(STATUS_MEANINGS)
#: Characters of a message kept; longer ones are cut (the parent never stores more).
MESSAGE_LIMIT = 20_000
#: What the student's code printed kept per test: at most this many characters ...
OUTPUT_LIMIT = 2_000
#: ... and lines (a debug print in a loop must not bury the table), then a marker
#: "[... N more characters not shown]".
OUTPUT_LINES = 30
#: Room for that marker: printed output read back from a results file is at most
#: OUTPUT_LIMIT + OUTPUT_MARKER_ROOM characters.
OUTPUT_MARKER_ROOM = 64


def status_of(status: str) -> Status:
    """How ``status`` is said; a status not in the table (a results file written by
    something else) is said as it is written, in the colour of an error."""
    known = STATUS_MEANINGS.get(status)
    if known is not None:
        return known
    return Status(str(status).replace("_", " "), str(status).upper(), STATUS_MEANINGS["error"].colour, "0")


def capped(text: str, limit: int) -> str:
    """``text`` cut to ``limit`` characters, saying how much was left out."""
    text = str(text)
    if len(text) <= limit:
        return text
    return text[:limit] + not_shown(len(text) - limit)


def not_shown(count: int) -> str:
    """The marker put where ``count`` characters were cut."""
    return f"\n[... {count} more characters not shown]"


def capped_output(text: str, dropped: int = 0) -> str:
    """What a test's code printed, cut to OUTPUT_LINES lines and OUTPUT_LIMIT characters;
    the marker counts the characters left out, ``dropped`` (cut earlier) included."""
    lines = text.splitlines(keepends=True)
    if len(lines) > OUTPUT_LINES:
        kept = "".join(lines[:OUTPUT_LINES])
        dropped += len(text) - len(kept)
        text = kept
    if len(text) > OUTPUT_LIMIT:
        dropped += len(text) - OUTPUT_LIMIT
        text = text[:OUTPUT_LIMIT]
    return text.rstrip("\n") + not_shown(dropped) if dropped else text


@dataclass
class Outcome:
    """What a graded test found.

    Attributes
    ----------
    status : str
        One of ``STATUSES``.
    fraction : float
        Share of the right cases, in [0, 1]; it earns points only for a test marked
        ``partial_credit`` (see :mod:`grader.harness.credit`).
    message : str
        What was expected against what came back.
    figure : dict or None
        Plain data for a picture of the failing case (see :mod:`grader.harness.figures`).
    metrics : dict
        Figures such as speed (``seconds``, ``reference_seconds``) and error.
    output : str
        What the student's code printed during the test (capped).
    """

    status: str
    fraction: float = 0.0
    message: str = ""
    figure: dict | None = None
    metrics: dict = field(default_factory=dict)
    output: str = ""

    @classmethod
    def passed(cls, message: str = "", **metrics) -> "Outcome":
        return cls("passed", 1.0, message, metrics=metrics)

    @classmethod
    def failed(cls, message: str, figure: dict | None = None, fraction: float = 0.0, **metrics) -> "Outcome":
        return cls("failed", fraction, message, figure, metrics)

    def to_dict(self) -> dict:
        """Plain data (JSON) for the grading protocol and the results files."""
        return {"status": self.status, "fraction": float(self.fraction), "message": self.message,
                "figure": self.figure, "metrics": dict(self.metrics), "output": self.output}

    @classmethod
    def from_dict(cls, data: dict) -> "Outcome":
        """The outcome ``to_dict`` wrote; unknown statuses read as errors, sizes capped."""
        status = str(data.get("status", "error"))
        if status not in STATUSES:
            status = "error"
        try:
            fraction = min(1.0, max(0.0, float(data.get("fraction", 0.0))))
        except (TypeError, ValueError):
            fraction = 0.0
        if fraction != fraction:  # NaN
            fraction = 0.0
        figure = data.get("figure")
        metrics = data.get("metrics")
        return cls(status, fraction, capped(data.get("message", "") or "", MESSAGE_LIMIT),
                   figure if isinstance(figure, dict) else None, metrics if isinstance(metrics, dict) else {},
                   capped(data.get("output", "") or "", OUTPUT_LIMIT + OUTPUT_MARKER_ROOM))


class StudentCallFailed(Exception):
    """A call into the student's code did not return a value (it raised, or returned
    something unreadable); carries the Outcome.  An ordinary exception, so Hypothesis
    shrinks the input that made the student's code raise."""

    def __init__(self, outcome: Outcome):
        super().__init__(outcome.message)
        self.outcome = outcome


class StudentCallStopped(BaseException):
    """A call that cannot be retried usefully: not implemented, timed out, crashed.

    A ``BaseException``, so that Hypothesis stops at once instead of shrinking a case
    against a stub or a hung worker; the graded-test plugin turns it into the outcome.
    """

    def __init__(self, outcome: Outcome):
        super().__init__(outcome.message)
        self.outcome = outcome


@dataclass
class TestResult:
    """A test, what it found, and how long it took (s)."""

    test: TestSpec
    outcome: Outcome
    seconds: float
    #: Read back from a results file: the points it recorded, and the text the student
    #: read when the file does not keep the message apart (None: they follow from the
    #: test and the outcome, as for a result made by grading).
    recorded_score: float | None = None
    recorded_text: str | None = None

    @property
    def passed(self) -> bool:
        return self.outcome.status == "passed"

    @property
    def score(self) -> float:
        """Full points for a pass; for a failure of a partial-credit test, the points
        :func:`grader.harness.credit.partial_points` gives its share of right cases; else 0.
        A result read back from a results file has the points it recorded."""
        if self.recorded_score is not None:
            return self.recorded_score
        if self.outcome.status == "passed":
            return float(self.test.points)
        if self.outcome.status != "failed" or not self.test.partial_credit:
            return 0.0
        return partial_points(self.test.points, self.outcome.fraction)

    def to_dict(self) -> dict:
        """The one serialised form of a test result (plain data, JSON): the test's
        ``test`` (spec name) and ``exercise``, the ``seconds`` it took, and its outcome's
        keys (:meth:`Outcome.to_dict`).  A grading worker sends it to the batch's parent
        as it stands; results.json keeps it, within that file's size limits, as each
        test's ``extra_data`` (:func:`grader.harness.results_model.results_entry`)."""
        return {"test": self.test.name, "exercise": self.test.exercise, "seconds": float(self.seconds),
                **self.outcome.to_dict()}

    @classmethod
    def from_dict(cls, data: dict, test: TestSpec) -> "TestResult":
        """The result ``to_dict`` wrote, of ``test`` (the spec the reader knows it by):
        the outcome as :meth:`Outcome.from_dict` reads it, a time that is not a finite
        number as 0."""
        try:
            seconds = float(data.get("seconds", 0.0))
        except (TypeError, ValueError):
            seconds = 0.0
        if isinstance(data.get("seconds"), bool) or not math.isfinite(seconds):
            seconds = 0.0
        return cls(test, Outcome.from_dict(data), seconds)
