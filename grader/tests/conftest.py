"""Graded tests use the grader's pytest plugin: markers, ``student``, ``reference``."""
from grader.harness.plugin import (metrics, picture, pytest_addoption, pytest_configure, pytest_unconfigure,  # noqa: F401
                           reference, student)
