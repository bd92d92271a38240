"""The course autograder: student checks, class grading, reports, Gradescope export."""

from .check import check  # noqa: E402  (notebooks: `from grader import check`)

__all__ = ["check"]
