"""The project's tests: they import graded test modules (for their strategies), so the
graded tests' markers are declared here too."""
from grader.harness.plugin import register_markers


def pytest_configure(config):
    register_markers(config)
