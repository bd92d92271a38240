"""The course autograder: student checks, class grading, reports, Gradescope export."""

from .check import check  # noqa: E402  (notebooks: `from grader import check`)
from .submit import submit  # noqa: E402  (notebooks: `from grader import submit`)

__all__ = ["check", "submit"]
