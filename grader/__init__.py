"""The course autograder: student checks, class grading, reports, Gradescope export."""

from .student.check import check  # noqa: E402  (notebooks: `from grader import check`)
from .student.submit import submit  # noqa: E402  (notebooks: `from grader import submit`)

__all__ = ["check", "submit"]
