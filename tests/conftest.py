"""The project's tests: they import graded test modules (for their strategies), so the
graded tests' markers are declared here too (grader/plugin.py's table)."""
from grader.plugin import MARKERS


def pytest_configure(config):
    for name, text in MARKERS.items():
        config.addinivalue_line("markers", f"{name}: {text}" if not text.startswith(name) else text)
