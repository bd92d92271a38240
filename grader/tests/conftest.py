"""Graded tests use the grader's pytest plugin: markers, ``student``, ``reference``."""
from grader.plugin import (metrics, pytest_addoption, pytest_configure, reference,  # noqa: F401
                           student)
