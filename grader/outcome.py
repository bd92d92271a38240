"""The result of one grader test, in words a student understands."""
from __future__ import annotations

from dataclasses import dataclass, field

#: Statuses of a test: passed, failed (a wrong answer), not_implemented (a stub still
#: raises NotImplementedError), error (an exception in the student's code), timeout,
#: crashed (the worker died), forbidden (the code did something it may not do).
STATUSES = ("passed", "failed", "not_implemented", "error", "timeout", "crashed", "forbidden")


@dataclass
class Outcome:
    """What a check found.

    Attributes
    ----------
    status : str
        One of ``STATUSES``.
    fraction : float
        Share of the test's points earned, in [0, 1] (partial credit).
    message : str
        What was expected against what came back.
    figure : dict or None
        Plain data for a picture of the failing case (see :mod:`grader.figures`).
    metrics : dict
        Figures such as speed (``seconds``, ``reference_seconds``) and error.
    """

    status: str
    fraction: float = 0.0
    message: str = ""
    figure: dict | None = None
    metrics: dict = field(default_factory=dict)

    @classmethod
    def passed(cls, message: str = "", **metrics) -> "Outcome":
        return cls("passed", 1.0, message, metrics=metrics)

    @classmethod
    def failed(cls, message: str, figure: dict | None = None, fraction: float = 0.0, **metrics) -> "Outcome":
        return cls("failed", fraction, message, figure, metrics)


class StudentCallFailed(Exception):
    """A call into the student's code did not return a value; carries the Outcome."""

    def __init__(self, outcome: Outcome):
        super().__init__(outcome.message)
        self.outcome = outcome
